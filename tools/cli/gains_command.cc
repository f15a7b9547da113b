// mpdrig gains: the backstepping observer's output-injection gains p1(x), p2(x)
// (thesis 10.1.16-10.1.17) and the disturbance gain L (pole placement, 10.3).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "model/observer/observer_gains.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

struct GainsArgs {
  ModelOptions model;
  double disturbance_hz = 0.0;
  int cells = 200;
  std::vector<double> pole{-40.0, 20.0};
  double friction_f1_per_s = std::nan("");
  std::string out_path;
};

std::string Describe(const observer::ObserverOptions& o) {
  std::ostringstream out;
  out << "observer gains (thesis 10.1.16-10.1.17), " << o.disturbance_hz << " Hz, poles "
      << o.pole.real() << " +- " << std::fabs(o.pole.imag()) << "i rad/s, " << o.cells << " cells";
  return out.str();
}

int RunGains(const GainsArgs& args) {
  const std::string name = "gains";
  auto params = args.model.LoadNtnuRigParams("gains");
  if (!params.ok()) return Fail(name, params.status());
  if (args.pole.size() != 2) return Fail(name, Status::Error("--pole takes two numbers: RE IM"));
  observer::ObserverOptions options_value;
  options_value.cells = args.cells;
  options_value.disturbance_hz = args.disturbance_hz;
  options_value.pole = {args.pole[0], args.pole[1]};
  options_value.friction_f1_per_s = args.friction_f1_per_s;
  const observer::ObserverOptions* options = &options_value;
  auto gains = observer::ObserverGains::Compute(*params, *options);
  if (!gains.ok()) return Fail(name, gains.status());
  std::ofstream file;
  std::ostream* out = &std::cout;
  if (args.out_path != "-") {
    file.open(args.out_path);
    if (!file) return Fail(name, Status::Error(args.out_path + ": cannot write"));
    out = &file;
  }
  const auto& g = *gains;
  out->precision(10);
  *out << "# " << Describe(*options) << "\n"
       << "# sigma: " << g.coordinates.sigma << "\n"
       << "# epsilon_per_s: " << g.coordinates.epsilon_per_s << "\n"
       << "# delay_s: " << g.delay_s << "\n"
       << "# L1: " << g.disturbance.l(0) << "\n"
       << "# L2: " << g.disturbance.l(1) << "\n"
       << "# expAaL1: " << g.disturbance_gain(0) << "\n"
       << "# expAaL2: " << g.disturbance_gain(1) << "\n"
       << "x_m,x,p1_per_s,p2_per_s,p1_without_kernel_per_s\n";
  for (std::size_t i = 0; i < g.x.size(); ++i) {
    *out << g.x[i] * params->pipe_length_m << "," << g.x[i] << "," << g.p1[i] << "," << g.p2[i]
         << "," << g.p1_without_kernel[i] << "\n";
  }
  if (!*out) return Fail(name, Status::Error(args.out_path + ": write failed"));
  if (args.out_path != "-") {
    std::printf(
        "%s: sigma %.4g, L = [%.6g, %.6g], p1(0) = %.5g, p1(1) = %.5g, max|p2| = %.3g "
        "-> %s\n",
        Describe(*options).c_str(), g.coordinates.sigma, g.disturbance.l(0), g.disturbance.l(1),
        g.p1.front(), g.p1.back(), std::max(std::fabs(g.p2.front()), std::fabs(g.p2.back())),
        args.out_path.c_str());
  }
  return 0;
}

}  // namespace

void AddGainsCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<GainsArgs>();
  CLI::App* command = app->add_subcommand(
      "gains", "Observer output-injection gains p1(x), p2(x) and L (thesis 10.1.16-10.1.17)");
  command->footer(
      "CSV columns x_m, x (= x_m / l), p1_per_s, p2_per_s, p1_without_kernel_per_s (the\n"
      "thesis's approximation C exp(A h(x)) L); L, exp(A a) L, sigma and the delay a = l/c as\n"
      "'# key: value' lines before the header.\n"
      "  mpdrig gains --disturbance-hz 0.25 --out gains.csv");
  args->model.AddParamOptions(command);
  command->add_option("--disturbance-hz", args->disturbance_hz, "heave frequency [Hz] (10.2.10)")
      ->required();
  command->add_option("--cells", args->cells, "kernel grid cells")->capture_default_str();
  command
      ->add_option("--pole", args->pole,
                   "poles of A - LC [rad/s]: RE IM for the pair RE +- IM i (thesis 10.3: -40 20)")
      ->expected(2)
      ->capture_default_str();
  command->add_option("--friction-f1", args->friction_f1_per_s,
                      "linear friction f1 used by the observer [1/s] (default: the rig's)");
  command->add_option("--out", args->out_path, "output CSV ('-' for stdout)")->required();
  command->callback([args, exit_code]() { *exit_code = RunGains(*args); });
}

}  // namespace mpdrig::cli
