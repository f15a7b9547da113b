#include "tools/cli/model_options.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <regex>
#include <sstream>
#include <utility>

#include "model/config/rig_config.h"
#include "model/effects/effect.h"

namespace mpdrig::cli {

void ModelOptions::AddParamOptions(CLI::App* command) {
  command
      ->add_option("--config", config_path,
                   "rig configuration, Protobuf text format (see `mpdrig params --format pbtxt`)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--effect", effects,
                   "switch a physical effect on, e.g. --effect unsteady_friction:k=0.05 "
                   "(repeatable; `mpdrig effects` lists names, parameters and units)")
      ->type_name("NAME[:KEY=VALUE,...]");
  command
      ->add_option("--set", overrides,
                   "override a parameter, e.g. --set wave_speed_mps=1100 (repeatable; "
                   "`mpdrig params` lists keys and units)")
      ->type_name("KEY=VALUE");
}

void ModelOptions::AddAll(CLI::App* command) {
  AddParamOptions(command);
  command->add_option("--model", model, "pipe model: quasilinear (thesis 6) or linear (thesis 7)")
      ->check(CLI::IsMember({"quasilinear", "linear"}))
      ->capture_default_str();
  command->add_option("--cells", cells, "number of pipe cells N (time step = L / (N c))")
      ->check(CLI::Range(2, 200000))
      ->capture_default_str();
  command
      ->add_option("--scheme", scheme,
                   "characteristics: method of characteristics (fast, exact transport); "
                   "mol: the thesis's method of lines, integrated by SUNDIALS ARKODE")
      ->check(CLI::IsMember({"characteristics", "mol"}))
      ->capture_default_str();
}

Result<RigParams> ModelOptions::LoadParams() const {
  RigParams params;
  if (!config_path.empty()) {
    auto loaded = LoadRigConfig(config_path);
    if (!loaded.ok()) return loaded.status();
    params = *loaded;
  }
  for (const std::string& spec : effects) {
    MPDRIG_RETURN_IF_ERROR(ApplyEffectSpec(&params, spec).Within("--effect"));
  }
  for (const std::string& assignment : overrides) {
    MPDRIG_RETURN_IF_ERROR(ApplyOverride(&params, assignment).Within("--set"));
  }
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(params));
  return params;
}

Result<RigParams> ModelOptions::LoadNtnuRigParams(std::string_view command) const {
  auto params = LoadParams();
  if (!params.ok() || params->layout.is_ntnu_rig()) return params;
  return Status::Error(
      (config_path.empty() ? std::string("the configuration") : "--config " + config_path) +
      " describes " + params->layout.Describe() + ": `mpdrig " + std::string(command) +
      "` works on the NTNU rig only (its piston, choke and pump); that rig runs "
      "in `mpdrig simulate --config`, driven by its valve's closure law");
}

Result<SimulationOptions> ModelOptions::LoadSimulationOptions() const {
  SimulationOptions options;
  options.model = model == "linear" ? PipeModel::kLinear : PipeModel::kQuasiLinear;
  options.scheme = scheme == "mol" ? PipeScheme::kMethodOfLines : PipeScheme::kCharacteristics;
  options.cells = cells;
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  return options;
}

std::string ModelOptions::Describe(const RigParams& params) const {
  std::ostringstream out;
  out.precision(3);
  out << model << ", " << cells << " cells, " << scheme << " (dt "
      << 1e3 * params.pipe_length_m / (cells * params.wave_speed_mps) << " ms)";
  for (const EffectSetting& effect : params.effects) out << ", + " << effect.name;
  return out.str();
}

Status WriteText(const std::string& path, const std::string& text) {
  if (path == "-") {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return std::fflush(stdout) == 0 ? Status::Ok() : Status::Error("cannot write stdout");
  }
  std::ofstream out(path, std::ios::binary);
  if (!out) return Status::Error(path + ": cannot open for writing");
  out << text;
  out.close();
  if (!out) return Status::Error(path + ": write failed");
  return Status::Ok();
}

std::string CommandLineWording(std::string message) {
  // The model says what is wrong in its own terms; the remedy a user types is a flag.
  static const std::pair<std::regex, std::string> kRemedies[] = {
      {std::regex(R"(effect '([A-Za-z0-9_]+)' is not switched on)"), "$& (add --effect $1)"},
      {std::regex(R"(a longer gap limit admits it)"), "raise the limit with --max-gap-s"},
      {std::regex(R"(set the pump flow to 0)"), "use --pump-lpm 0"},
  };
  for (const auto& [pattern, replacement] : kRemedies) {
    message = std::regex_replace(message, pattern, replacement);
  }
  return message;
}

int Fail(const std::string& command, const Status& status) {
  const std::string message = CommandLineWording(status.message());
  std::fprintf(stderr, "mpdrig %s: %s\n", command.c_str(), message.c_str());
  return 1;
}

Result<double> ParseFiniteNumber(const std::string& text, const std::string& what) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (text.empty() || used != text.size() || !std::isfinite(value)) {
    return Status::Error(what + ": '" + text + "' is not a finite number");
  }
  return value;
}

Result<BoundsSpec> ParseBoundsSpec(const std::string& spec) {
  const std::size_t equals = spec.find('=');
  const std::size_t colon = spec.find(':', equals == std::string::npos ? 0 : equals);
  if (equals == std::string::npos || colon == std::string::npos) {
    return Status::Error("--bounds expects KEY=LOWER:UPPER, got '" + spec + "'");
  }
  BoundsSpec bounds;
  bounds.key = spec.substr(0, equals);
  auto lower = ParseFiniteNumber(spec.substr(equals + 1, colon - equals - 1), "--bounds " + spec);
  if (!lower.ok()) return lower.status();
  auto upper = ParseFiniteNumber(spec.substr(colon + 1), "--bounds " + spec);
  if (!upper.ok()) return upper.status();
  if (!(*lower < *upper)) {
    return Status::Error("--bounds " + spec + ": LOWER must be below UPPER");
  }
  bounds.lower = *lower;
  bounds.upper = *upper;
  return bounds;
}

void AddLogReadOptions(CLI::App* command, riglog::ReadOptions* options) {
  command
      ->add_option("--max-gap-s", options->max_gap_s,
                   "longest step in time between two samples of the log [s]; a longer gap (an "
                   "interrupted recording, a wrong time) is an error at its line ('inf': no "
                   "limit; the model is replayed across the whole gap)")
      ->check([min_step_s = options->min_step_s](const std::string& text) {
        // Validators see the text before it is stored.
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || *end != '\0' || !(value > min_step_s)) {
          return "'" + text + "' must be a number of seconds above the shortest time step, " +
                 riglog::FormatNumber(min_step_s) + " s ('inf': no limit)";
        }
        return std::string();
      })
      ->capture_default_str();
}

void AddInputReplayOptions(CLI::App* command, InputReplayOptions* options) {
  command->add_flag_callback(
      "--raw-inputs", [options]() { options->reconstruct_inputs = false; },
      "replay the log's inputs as measured; by default they are reconstructed under their noise "
      "(noise levels and the piston's band estimated from the log, steps kept)");
  command->add_flag_callback(
      "--levels-as-measured", [options]() { options->estimate_levels = false; },
      "keep the reconstructed choke and FT2 levels; by default they are corrected from the "
      "measured pressures, within what the inputs' own noise allows (their mean over N samples "
      "errs by sigma/sqrt(N), which the choke's steep law turns into pressure offsets)");
  command->add_flag_callback(
      "--steady-start", [options]() { options->choose_warmup = false; },
      "start the replay from the steady state even where the log starts in the middle of a "
      "heave (by default such a log is replayed after a 30 s warm-up on its first period, or from "
      "the pipe's state estimated from the pressures of its first travel times, if its pressures "
      "fit that start better)");
  command
      ->add_option("--piston-smoothing-s", options->piston_smoothing_s,
                   "with --raw-inputs: window of the local quadratic fit that smooths the measured "
                   "piston position before it is differentiated (0: none)")
      ->capture_default_str();
}

void DescribeReplay(const InputReconstruction* reconstruction, const InputReplayOptions& options,
                    InputLevels levels) {
  if (options.reconstruct_inputs && reconstruction != nullptr) {
    std::fprintf(stderr, "%s\n", reconstruction->Describe().c_str());
    if (options.estimate_levels && levels == InputLevels::kWithTheseParams) {
      std::fprintf(stderr, "%s\n", reconstruction->levels.Describe().c_str());
    }
  }
  if (options.warmup) {
    std::fprintf(stderr,
                 "the log starts mid-heave: replayed after a %.0f s warm-up on its periodic "
                 "excitation (period %.4f s)\n",
                 options.warmup->duration_s, options.warmup->period_s);
  }
  if (options.profile) {
    std::fprintf(stderr,
                 "the log starts mid-excitation: replayed from the pipe's state estimated from "
                 "its pressures over the first %.0f travel times\n",
                 kProfileFitTravelTimes);
  }
}

Status PrepareReplay(MeasuredLog* log, const RigParams& params, const SimulationOptions& simulation,
                     InputReplayOptions* options, bool quiet, InputLevels levels) {
  MPDRIG_RETURN_IF_ERROR(PrepareLogReplay(log, params, simulation, options, levels));
  if (!quiet) DescribeReplay(&log->reconstruction, *options, levels);
  return Status::Ok();
}

}  // namespace mpdrig::cli
