// mpdrig params: every parameter with its value, unit and meaning.
#include <cstdio>
#include <memory>

#include "model/common/units.h"
#include "model/config/rig_config.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

struct ParamsArgs {
  ModelOptions model;
  std::string format = "table";
};

int RunParams(const ParamsArgs& args) {
  auto params = args.model.LoadParams();
  if (!params.ok()) return Fail("params", params.status());
  if (args.format == "pbtxt") {
    std::fputs(FormatRigConfig(*params).c_str(), stdout);
    return 0;
  }
  std::printf("%-34s %-14s %-12s %s\n", "key", "value", "unit", "meaning");
  for (const ParamInfo& info : ParamTable()) {
    std::printf("%-34.*s %-14.7g %-12.*s %.*s\n", static_cast<int>(info.key.size()),
                info.key.data(), (*params).*info.member, static_cast<int>(info.unit.size()),
                info.unit.data(), static_cast<int>(info.description.size()),
                info.description.data());
  }
  std::printf(
      "\nchoke characteristic G(opening), linear between points, floored at "
      "choke_leak_m2 (Table 8.4.1):\n  opening_deg  g_m2\n");
  for (const ChokePoint& point : params->choke_characteristic) {
    std::printf("  %11.4g  %.4g\n", units::ChokeFracToDeg(point.opening_frac), point.g_m2);
  }
  std::printf(
      "\nderived: pipe area A = %.6g m^2, piston displacement area A_d - A_d2 = %.6g m^2, "
      "sin(gamma) = %.6g, k = c^2 rho - p_ref = %.6g Pa\n",
      params->PipeAreaM2(), params->PistonDisplacementAreaM2(), params->SinInclination(),
      params->QuasiLinearK());
  return 0;
}

}  // namespace

void AddParamsCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<ParamsArgs>();
  CLI::App* command =
      app->add_subcommand("params", "Print every rig parameter with its value, unit and meaning");
  command->footer(
      "Values: the thesis defaults, then --config, then --set. `--format pbtxt` prints a\n"
      "complete config file to start from:\n"
      "  mpdrig params --format pbtxt > rig.pbtxt");
  args->model.AddParamOptions(command);
  command->add_option("--format", args->format, "table or pbtxt")
      ->check(CLI::IsMember({"table", "pbtxt"}))
      ->capture_default_str();
  command->callback([args, exit_code]() { *exit_code = RunParams(*args); });
}

}  // namespace mpdrig::cli
