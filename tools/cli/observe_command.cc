// mpdrig observe: the backstepping observer (thesis 10) on a rig log's topside channels.
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "model/common/units.h"
#include "model/observer/backstepping_observer.h"
#include "model/observer/measurement_noise.h"
#include "model/riglog/rig_log.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

struct ObserverArgs {
  ModelOptions model;
  double disturbance_hz = 0.0;
  int cells = 200;
  std::vector<double> pole{-40.0, 20.0};
  std::string gains = "noise";
  double pressure_noise_bar = std::nan("");
  double flow_noise_lpm = std::nan("");
  bool pole_given = false;
  bool quadratic_friction = false;
  bool track_frequency = false;
  double friction_f1_per_s = std::nan("");
  std::string log_path;
  std::string out_path;
  riglog::ReadOptions read;
};

void AddObserverOptions(CLI::App* command, ObserverArgs* args) {
  args->model.AddParamOptions(command);
  command->add_option("--disturbance-hz", args->disturbance_hz, "heave frequency [Hz] (10.2.10)")
      ->required();
  command->add_option("--cells", args->cells, "observer and kernel grid cells")
      ->capture_default_str();
  command
      ->add_option("--gains", args->gains,
                   "noise: the disturbance gain is the steady-state Kalman gain for the noise of "
                   "C2 and FT1 (estimated from the log unless given), never faster than the "
                   "thesis's poles, and C2, FT1 are smoothed by a zero-lag filter when the noise "
                   "limits the design; thesis: the poles -40 +- 20i of thesis 10.3 (or --pole), "
                   "no filter (right for noise-free data only)")
      ->check(CLI::IsMember({"noise", "thesis"}))
      ->capture_default_str();
  command
      ->add_option("--pole", args->pole,
                   "place the poles of A - LC at RE +- IM i [rad/s] (implies --gains thesis; "
                   "thesis 10.3: -40 20)")
      ->expected(2)
      ->each([args](const std::string&) { args->pole_given = true; });
  command
      ->add_option("--pressure-noise-bar", args->pressure_noise_bar,
                   "standard deviation of C2's white noise at the log's rate [bar] (default: "
                   "estimated from the log, 1.4826 median|second difference| / sqrt(6); lab "
                   "transmitters: 0.024)")
      ->check(CLI::NonNegativeNumber);
  command
      ->add_option("--flow-noise-lpm", args->flow_noise_lpm,
                   "standard deviation of the outlet flow's (FT1) white noise [L/min] (default: "
                   "estimated from the log)")
      ->check(CLI::NonNegativeNumber);
  command->add_flag("--quadratic-friction", args->quadratic_friction,
                    "also run the plant's f2 u|u| friction in the observer's pipe copy (beyond "
                    "the thesis; removes the observer's main error at 0.1 m strokes)");
  command->add_flag("--track-frequency", args->track_frequency,
                    "estimate the heave frequency online, starting from --disturbance-hz, and "
                    "retune the gains as it moves (beyond the thesis)");
  command->add_option("--friction-f1", args->friction_f1_per_s,
                      "linear friction f1 used by the observer [1/s] (default: the rig's)");
}

Result<observer::ObserverOptions> MakeOptions(const ObserverArgs& args) {
  observer::ObserverOptions o;
  o.cells = args.cells;
  o.disturbance_hz = args.disturbance_hz;
  if (args.pole.size() != 2) return Status::Error("--pole takes two numbers: RE IM");
  o.pole = {args.pole[0], args.pole[1]};
  o.gain_design = (args.gains == "thesis" || args.pole_given) ? observer::GainDesign::kPoles
                                                              : observer::GainDesign::kNoise;
  o.quadratic_friction = args.quadratic_friction;
  o.track_frequency = args.track_frequency;
  o.friction_f1_per_s = args.friction_f1_per_s;
  MPDRIG_RETURN_IF_ERROR(o.Validate());
  return o;
}

std::string Describe(const observer::ObserverOptions& o, const observer::NoiseDesign& d) {
  std::ostringstream out;
  out << "backstepping observer (thesis 10), " << o.disturbance_hz << " Hz, poles ";
  if (d.poles[0].imag() != 0.0) {
    out << d.poles[0].real() << " +- " << std::fabs(d.poles[0].imag()) << "i rad/s";
  } else {
    out << d.poles[0].real() << ", " << d.poles[1].real() << " rad/s";
  }
  if (o.gain_design == observer::GainDesign::kPoles) {
    out << " (given)";
  } else if (o.noise.IsZero() || d.prefilter_tau_s == 0.0) {
    out << " (thesis's: noise negligible)";
  } else {
    out << " (Kalman gain for the noise), C2/FT1 prefilter tau " << d.prefilter_tau_s << " s";
  }
  if (o.gain_design == observer::GainDesign::kNoise) {
    out << ", noise C2 " << units::PaToBar(o.noise.outlet_pressure_pa) << " bar, FT1 "
        << units::M3psToLpm(o.noise.outlet_flow_m3ps) << " L/min at " << o.noise.sample_period_s
        << " s";
  }
  out << ", " << o.cells << " cells" << (o.quadratic_friction ? ", quadratic friction" : "")
      << (o.track_frequency ? ", frequency tracked" : "");
  return out.str();
}

// The topside channels: C2 = p(l), and the outlet flow FT1, or FT3 - FT2 (5.3.1). Samples where
// either is not measured are left out (the observer interpolates over them) and counted.
Result<observer::TopsideSeries> TopsideFromLog(const riglog::RigLog& log, const std::string& path,
                                               std::size_t* skipped) {
  const std::vector<double>* c2 = log.Find(riglog::Channel::kC2);
  const std::vector<double>* ft1 = log.Find(riglog::Channel::kFT1);
  const std::vector<double>* ft2 = log.Find(riglog::Channel::kFT2);
  const std::vector<double>* ft3 = log.Find(riglog::Channel::kFT3);
  if (c2 == nullptr) return Status::Error(path + ": needs a C2 column");
  if (ft1 == nullptr && (ft2 == nullptr || ft3 == nullptr)) {
    return Status::Error(path + ": needs FT1, or FT3 and FT2");
  }
  observer::TopsideSeries series;
  *skipped = 0;
  for (std::size_t r = 0; r < log.num_rows(); ++r) {
    const double q = ft1 != nullptr ? (*ft1)[r] : (*ft3)[r] - (*ft2)[r];
    if (!std::isfinite((*c2)[r]) || !std::isfinite(q)) {
      ++*skipped;
      continue;
    }
    series.time_s.push_back(log.time_s[r]);
    series.outlet_pressure_pa.push_back((*c2)[r]);
    series.outlet_flow_m3ps.push_back(q);
  }
  return series;
}

// The noise the gains are designed for: estimated from the topside channels, unless given.
Status SetNoiseFromLog(const ObserverArgs& args, const observer::TopsideSeries& series,
                       observer::ObserverOptions* options) {
  if (options->gain_design != observer::GainDesign::kNoise) return Status::Ok();
  auto noise = observer::EstimateTopsideNoise(series.time_s, series.outlet_pressure_pa,
                                              series.outlet_flow_m3ps);
  if (!noise.ok()) return noise.status();
  if (!std::isnan(args.pressure_noise_bar)) {
    noise->outlet_pressure_pa = units::BarToPa(args.pressure_noise_bar);
  }
  if (!std::isnan(args.flow_noise_lpm)) {
    noise->outlet_flow_m3ps = units::LpmToM3ps(args.flow_noise_lpm);
  }
  options->noise = *noise;
  return Status::Ok();
}

// The estimates as extra columns beside the log's own.
Status AddEstimateColumns(const std::vector<observer::ObserverEstimate>& estimates,
                          riglog::RigLog* log) {
  using riglog::Unit;
  using E = observer::ObserverEstimate;
  const auto add = [&](std::string_view channel, Unit unit, auto value) -> Status {
    auto column = riglog::MakeColumn(channel, unit);
    if (!column.ok()) return column.status();
    std::vector<double> values(log->num_rows());
    for (std::size_t r = 0; r < values.size(); ++r) values[r] = value(estimates[r]);
    return log->AddColumn(*column, std::move(values));
  };
  MPDRIG_RETURN_IF_ERROR(add("BHP_est", Unit::kBarg, [](const E& e) { return e.bhp_pa; }));
  for (int k = 0; k < 10; ++k) {
    MPDRIG_RETURN_IF_ERROR(add("PT" + std::to_string(k + 1) + "_est", Unit::kBarg,
                               [k](const E& e) { return e.pt_pa[k]; }));
  }
  MPDRIG_RETURN_IF_ERROR(add("FT4_est", Unit::kLpm, [](const E& e) { return e.inlet_flow_m3ps; }));
  MPDRIG_RETURN_IF_ERROR(
      add("piston_position_est", Unit::kM, [](const E& e) { return e.piston_position_m; }));
  return add("FT1_innovation", Unit::kLpm, [](const E& e) { return e.output_error_m3ps; });
}

int RunObserve(const ObserverArgs& args) {
  const std::string name = "observe";
  auto params = args.model.LoadNtnuRigParams("observe");
  if (!params.ok()) return Fail(name, params.status());
  auto options = MakeOptions(args);
  if (!options.ok()) return Fail(name, options.status());
  auto log = riglog::ReadRigLog(args.log_path, args.read);
  if (!log.ok()) return Fail(name, log.status());
  std::size_t skipped = 0;
  auto series = TopsideFromLog(*log, args.log_path, &skipped);
  if (!series.ok()) return Fail(name, series.status());
  const Status noise = SetNoiseFromLog(args, *series, &*options);
  if (!noise.ok()) return Fail(name, noise.Within(args.log_path));
  auto design = observer::DesignForNoise(*params, *options);
  if (!design.ok()) return Fail(name, design.status().Within(args.log_path));
  auto estimates = observer::RunObserver(*params, *options, *series, log->time_s);
  if (!estimates.ok()) return Fail(name, estimates.status().Within(args.log_path));

  const Status added = AddEstimateColumns(*estimates, &*log);
  if (!added.ok()) return Fail(name, added.Within(args.log_path));
  log->metadata.push_back({"observer", Describe(*options, *design)});
  const double final_hz = estimates->empty() ? std::nan("") : estimates->back().disturbance_hz;
  if (options->track_frequency) {
    log->metadata.push_back({"observer_final_frequency_hz", riglog::FormatNumber(final_hz)});
  }
  log->metadata.push_back(
      {"observer_note",
       "FT4_est = estimated inlet flow = -(A_d - A_d2) v_d; piston_position_est = -X1/omega "
       "(zero-mean); FT1_innovation = up-going wave error y - u^(1) in m3/s units"});
  const Status written = riglog::WriteRigLog(*log, args.out_path);
  if (!written.ok()) return Fail(name, written);
  if (args.out_path != "-") {
    std::printf("%s: %zu samples of %s (%zu without C2/outlet flow) -> %s\n",
                Describe(*options, *design).c_str(), log->num_rows(), args.log_path.c_str(),
                skipped, args.out_path.c_str());
    if (options->track_frequency) {
      std::printf("tracked heave frequency at the end: %.4g Hz\n", final_hz);
    }
  }
  return 0;
}

}  // namespace

void AddObserveCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<ObserverArgs>();
  CLI::App* command = app->add_subcommand(
      "observe", "Backstepping observer (thesis 10): bottom-hole pressure from C2 and FT1");
  command->footer(
      "Runs the observer of thesis chapter 10 (Aamo 2013) on the topside channels of a rig log\n"
      "(C2 and FT1, or FT3 - FT2) and writes the log with estimate columns added:\n"
      "BHP_est_barg, PT1_est_barg..PT10_est_barg, FT4_est_lpm (inlet flow = -(A_d-A_d2) v_d),\n"
      "piston_position_est_m (zero-mean heave), FT1_innovation_lpm.\n"
      "\n"
      "Gains (default --gains noise): the thesis's poles -40 +- 20i inject the topside noise\n"
      "almost unfiltered into the BHP estimate (fit 43 % at lab noise, 0.2 Hz). By default the\n"
      "noise of C2 and FT1 is estimated from the log (1.4826 median|second difference|/sqrt(6),\n"
      "or --pressure-noise-bar / --flow-noise-lpm), the disturbance gain is the steady-state\n"
      "Kalman gain of the heave model (process noise: the heave velocity amplitude may drift 1 %\n"
      "per period) for that noise, and C2, FT1 pass a zero-lag filter (1 + 2 tau s)/(1 + tau s)^2\n"
      "whose error at the heave frequency is <= 2 %. With negligible noise the Kalman poles would\n"
      "be faster than the thesis's: then the thesis's poles are used, unfiltered.\n"
      "Lab noise (Table 4.1.1): BHP fit 94-98 % after 20 s at 0.1-0.33 Hz. --gains thesis or\n"
      "--pole RE IM: the poles as given (the thesis's: --pole -40 20), no filter.\n"
      "  mpdrig observe run.csv --disturbance-hz 0.2 --out est.csv");
  AddObserverOptions(command, args.get());
  command->add_option("log", args->log_path, "input rig log ('-' for stdin)")->required();
  command->add_option("--out", args->out_path, "output rig log ('-' for stdout)")->required();
  AddLogReadOptions(command, &args->read);
  command->callback([args, exit_code]() { *exit_code = RunObserve(*args); });
}

}  // namespace mpdrig::cli
