// mpdrig fit: bounded nonlinear least squares of base or effect parameters against a rig log
// (model/identification/fit.h); estimates with standard errors and correlations as JSON, a
// summary on stdout, progress on stderr, and optionally the fitted config for simulate/compare.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "model/config/rig_config.h"
#include "model/effects/param_by_key.h"
#include "model/identification/fit.h"
#include "tools/cli/commands.h"
#include "tools/cli/fit_resonances.h"
#include "tools/cli/model_options.h"
#include "tools/report/json.h"

namespace mpdrig::cli {
namespace {

using report::Json;
using report::JsonNumber;
using report::JsonNumbers;
using report::JsonText;

constexpr int kFitDefaultCells = 50;  // a fit replays the log dozens of times

struct FitArgs {
  ModelOptions model;
  std::string log_path;
  riglog::ReadOptions read;
  std::vector<std::string> params;
  std::vector<std::string> bounds;
  std::string window;
  std::string json_path;
  std::string out_config_path;
  int max_iterations = 30;
  double relative_step = 1.0e-3;
  InputReplayOptions replay;
  std::string weights = "variation";
  bool quiet = false;
};

// "key=lo:hi" -> key, lo, hi.
Result<FitParameter> ParseBounds(const std::string& spec) {
  auto bounds = ParseBoundsSpec(spec);
  if (!bounds.ok()) return bounds.status();
  FitParameter parameter;
  parameter.key = bounds->key;
  parameter.lower = bounds->lower;
  parameter.upper = bounds->upper;
  return parameter;
}

// "t0:t1", either side may be empty (the log's start or end).
Status ParseWindow(const std::string& spec, FitOptions* options) {
  const std::size_t colon = spec.find(':');
  if (colon == std::string::npos) {
    return Status::Error("--window-s expects T0:T1 in seconds (either may be empty), got '" + spec +
                         "'");
  }
  const std::string begin = spec.substr(0, colon), end = spec.substr(colon + 1);
  if (!begin.empty()) {
    auto value = ParseFiniteNumber(begin, "--window-s");
    if (!value.ok()) return value.status();
    options->window_begin_s = *value;
  }
  if (!end.empty()) {
    auto value = ParseFiniteNumber(end, "--window-s");
    if (!value.ok()) return value.status();
    options->window_end_s = *value;
  }
  if (!(options->window_begin_s < options->window_end_s)) {
    return Status::Error("--window-s " + spec + ": T0 must be before T1");
  }
  return Status::Ok();
}

std::string FitJson(const FitResult& fit, const std::vector<FitParameter>& parameters,
                    const FitArgs& args, const FitOptions& options) {
  Json params = Json::object();
  for (std::size_t j = 0; j < fit.keys.size(); ++j) {
    params[fit.keys[j]] = {{"initial", JsonNumber(fit.initial[j])},
                           {"estimate", JsonNumber(fit.estimates[j])},
                           {"std_error", JsonNumber(fit.standard_errors[j])},
                           {"held", static_cast<bool>(fit.held[j])},
                           {"lower", JsonNumber(parameters[j].lower)},
                           {"upper", JsonNumber(parameters[j].upper)}};
  }
  Json matrix = Json::array();
  for (const auto& row : fit.correlation) matrix.push_back(JsonNumbers(row));
  const Json json = {{"log", args.log_path},
                     {"params", params},
                     {"correlation", {{"keys", fit.keys}, {"matrix", matrix}}},
                     {"error_before", JsonNumber(fit.error_before)},
                     {"error_after", JsonNumber(fit.error_after)},
                     {"iterations", fit.iterations},
                     {"replays", fit.replays},
                     {"converged", fit.converged},
                     {"window_s", Json::array({JsonNumber(options.window_begin_s),
                                               JsonNumber(options.window_end_s)})},
                     {"cells", options.simulation.cells},
                     {"solver_report", fit.solver_report}};
  return JsonText(json, 2);
}

void PrintSummary(const FitResult& fit, const std::vector<FitParameter>& parameters,
                  const FitArgs& args) {
  std::size_t width = 9;
  for (const std::string& key : fit.keys) width = std::max(width, key.size());
  const int w = static_cast<int>(width);
  std::printf("%-*s  %12s  %12s  %11s  %s\n", w, "parameter", "initial", "estimate", "std error",
              "bounds");
  for (std::size_t j = 0; j < fit.keys.size(); ++j) {
    const bool at_bound =
        fit.estimates[j] <= parameters[j].lower || fit.estimates[j] >= parameters[j].upper;
    std::printf("%-*s  %12.6g  %12.6g  +- %8.3g  [%g, %g]%s\n", w, fit.keys[j].c_str(),
                fit.initial[j], fit.estimates[j], fit.standard_errors[j], parameters[j].lower,
                parameters[j].upper,
                fit.held[j] ? "  held: no influence on this log"
                : at_bound  ? "  at a bound"
                            : "");
  }
  if (fit.keys.size() > 1) {
    std::printf("correlation:\n");
    for (std::size_t i = 0; i < fit.keys.size(); ++i) {
      std::printf("  %-*s", w, fit.keys[i].c_str());
      for (double r : fit.correlation[i]) std::printf(" %6.3f", r);
      std::printf("\n");
    }
  }
  std::printf("error (mean NRMSE): %.4g -> %.4g; %d iterations, %d replays, %s\n", fit.error_before,
              fit.error_after, fit.iterations, fit.replays,
              fit.converged ? "converged" : "NOT converged");
  if (!args.out_config_path.empty()) {
    std::printf("fitted config: %s (check: mpdrig compare %s --config %s --cells %d)\n",
                args.out_config_path.c_str(), args.log_path.c_str(), args.out_config_path.c_str(),
                args.model.cells);
  }
}

int RunFit(const FitArgs& args) {
  const std::string name = "fit";
  auto start = args.model.LoadNtnuRigParams("fit");
  if (!start.ok()) return Fail(name, start.status());
  auto simulation = args.model.LoadSimulationOptions();
  if (!simulation.ok()) return Fail(name, simulation.status());

  // Parameters with their default bounds, then the --bounds given.
  std::vector<FitParameter> parameters;
  for (const std::string& key : args.params) {
    if (key.empty()) return Fail(name, Status::Error("--params: empty key"));
    auto parameter = DefaultFitParameter(key);
    if (!parameter.ok()) return Fail(name, parameter.status().Within("--params"));
    auto value = GetParamValue(*start, key);
    if (!value.ok()) return Fail(name, value.status().Within("--params"));
    parameters.push_back(*parameter);
  }
  for (const std::string& spec : args.bounds) {
    auto bounds = ParseBounds(spec);
    if (!bounds.ok()) return Fail(name, bounds.status());
    bool found = false;
    for (FitParameter& parameter : parameters) {
      if (parameter.key == bounds->key) parameter = *bounds, found = true;
    }
    if (!found) {
      return Fail(name, Status::Error("--bounds " + spec + ": '" + bounds->key +
                                      "' is not one of --params"));
    }
  }

  FitOptions options;
  options.simulation = *simulation;
  options.replay = args.replay;
  options.weighting =
      args.weights == "noise" ? ChannelWeighting::kNoise : ChannelWeighting::kVariation;
  options.max_iterations = args.max_iterations;
  options.relative_step = args.relative_step;
  // The model reads no environment; the command line passes this debugging switch on.
  options.solver_log = std::getenv("MPDRIG_CERES_LOG") != nullptr;
  if (!args.window.empty()) {
    Status window = ParseWindow(args.window, &options);
    if (!window.ok()) return Fail(name, window);
  }
  if (!args.quiet) {
    options.progress = [](int iteration, double error) {
      std::fprintf(stderr, "mpdrig fit: iteration %2d  error %.6g\n", iteration, error);
    };
  }

  auto log = LoadMeasuredLog(args.log_path, {}, args.read);
  if (!log.ok()) return Fail(name, log.status());
  if (!args.quiet) {
    std::fprintf(stderr, "mpdrig fit: %zu samples, %zu compared channels; %s\n",
                 log->time_s().size(), log->channels.size(), args.model.Describe(*start).c_str());
  }
  const Status prepared = PrepareReplay(&*log, *start, options.simulation, &options.replay,
                                        args.quiet, InputLevels::kAfterTheFit);
  if (!prepared.ok()) return Fail(name, prepared);
  auto fit = FitParametersAndInputLevels(&*log, *start, parameters, options);
  if (!fit.ok()) return Fail(name, fit.status().Within(args.log_path));
  if (!args.quiet && fit->input_levels.applied()) {
    std::fprintf(stderr, "%s (at the first fit's parameters; refitted on them)\n",
                 fit->input_levels.Describe().c_str());
  }

  if (!args.out_config_path.empty()) {
    Status written = WriteText(args.out_config_path, FormatRigConfig(fit->params));
    if (!written.ok()) return Fail(name, written);
  }
  Status written = WriteText(args.json_path, FitJson(*fit, parameters, args, options));
  if (!written.ok()) return Fail(name, written);
  if (args.json_path != "-") PrintSummary(*fit, parameters, args);
  return 0;
}

}  // namespace

void AddFitCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<FitArgs>();
  args->model.cells = kFitDefaultCells;
  CLI::App* command = app->add_subcommand(
      "fit", "Fit model or effect parameters to a rig log (bounded least squares, Ceres)");
  command->footer(
      "Replays the log's inputs through the model and adjusts the --params to minimise the mean\n"
      "squared NRMSE over the measured channels (P1 P2 PT1..PT10 C2 FT1 FT3 FT4), within bounds\n"
      "(defaults: a plausible tuning range, e.g. wave_speed_mps 300..1500, friction_f1_per_s\n"
      "0..5, choke_leak_m2 0..1e-5; an effect's own bounds from `mpdrig effects`). The start\n"
      "values are the config's (thesis defaults, --config, --effect, --set). Reports estimates\n"
      "with standard errors (from J^T J at the optimum), their correlations, and the error\n"
      "before and after. A parameter that does not change the replay at all (the choke leak\n"
      "while the choke is open: it is only the characteristic's floor) is held at its start\n"
      "value and marked `held`. Runs at 50 cells unless --cells says otherwise (a fit replays the "
      "log\n"
      "dozens of times); compare the fitted config at the same --cells.\n"
      "Example (the thesis's chapter 8-9 tuning):\n"
      "  mpdrig fit lab.csv --params wave_speed_mps,friction_f1_per_s,choke_leak_m2 \\\n"
      "      --json fit.json --out-config fitted.pbtxt\n"
      "  mpdrig compare lab.csv --config fitted.pbtxt --cells 50 --report after.html\n"
      "An effect's parameter (the effect must be on):\n"
      "  mpdrig fit lab.csv --effect sensor_lag --params sensor_lag.time_constant_s \\\n"
      "      --bounds sensor_lag.time_constant_s=0:0.5 --window-s 0:60 --json -\n"
      "To the rig's measured first resonances (frequency domain; no log):\n"
      "  mpdrig fit --resonances docs/examples/thesis-resonances.csv --set wave_speed_mps=1173 \\\n"
      "      --hold wave_speed_mps --effect topside_compliance --effect gas_entrainment --json -\n"
      "  JSON: params, configurations[].{configuration, measured_hz, base_model_hz, model_hz,\n"
      "  response (analytic or simulated)}, chi2_before, chi2_after, max_error_hz.\n"
      "JSON: params.<key>.{initial, estimate, std_error, held, lower, upper}, correlation.{keys,\n"
      "matrix}, error_before, error_after, iterations, replays, converged, window_s, cells,\n"
      "solver_report (docs/fitting.md, 'Output'). Progress goes to stderr.");
  args->model.AddAll(command);
  command->add_option("log", args->log_path, "measured rig log (rig-log-format.md)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--params", args->params,
                   "parameters to fit, comma separated: keys of `mpdrig params` or EFFECT.KEY "
                   "(--resonances: default wave_speed_mps and the effects' fitted parameters)")
      ->delimiter(',')
      ->type_name("KEY,KEY,...");
  command
      ->add_option("--bounds", args->bounds,
                   "search bounds of one fitted parameter, e.g. wave_speed_mps=700:1300 "
                   "(repeatable)")
      ->type_name("KEY=LOWER:UPPER");
  command
      ->add_option("--window-s", args->window,
                   "fit only the samples in [T0, T1] s (the replay still starts at the log's "
                   "start), e.g. 0:60 or 30:")
      ->type_name("T0:T1");
  command->add_option("--json", args->json_path, "result as JSON ('-' for stdout)");
  auto resonance_args = std::make_shared<ResonanceFitArgs>();
  command
      ->add_option("--resonances", resonance_args->resonances_path,
                   "fit to measured first resonances instead of a log: CSV "
                   "configuration,frequency_hz,uncertainty_hz (docs/rig-measurements.md)")
      ->check(CLI::ExistingFile);
  AddResonanceOptions(command, &resonance_args->hold, &resonance_args->method,
                      &resonance_args->outlet_barg);
  command->add_option("--out-config", args->out_config_path,
                      "write the fitted configuration (Protobuf text) for simulate/compare "
                      "--config");
  command->add_option("--max-iterations", args->max_iterations, "solver iterations at most")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  command
      ->add_option("--relative-step", args->relative_step,
                   "finite-difference step relative to the parameter (or 1% of its range)")
      ->check(CLI::Range(1.0e-7, 0.1))
      ->capture_default_str();
  command
      ->add_option("--weights", args->weights,
                   "how the channels weigh: variation (each by its own variation, compare's "
                   "NRMSE) or noise (each by its estimated white noise: maximum likelihood)")
      ->check(CLI::IsMember({"variation", "noise"}))
      ->capture_default_str();
  AddInputReplayOptions(command, &args->replay);
  AddLogReadOptions(command, &args->read);
  command->add_flag("--quiet", args->quiet, "no progress on stderr");
  command->callback([args, resonance_args, exit_code]() {
    if (!resonance_args->resonances_path.empty()) {
      if (!args->log_path.empty()) {
        *exit_code = Fail("fit", Status::Error("give a log or --resonances, not both"));
        return;
      }
      resonance_args->params = args->params;
      resonance_args->bounds = args->bounds;
      resonance_args->json_path = args->json_path;
      resonance_args->quiet = args->quiet;
      resonance_args->max_iterations = std::max(args->max_iterations, 1);
      *exit_code = RunFitResonances(args->model, *resonance_args);
      return;
    }
    if (args->log_path.empty() || args->params.empty() || args->json_path.empty()) {
      *exit_code = Fail("fit", Status::Error("fitting a log needs the log, --params and --json "
                                             "(or fit --resonances FILE)"));
      return;
    }
    *exit_code = RunFit(*args);
  });
}

}  // namespace mpdrig::cli
