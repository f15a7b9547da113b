// mpdrig diagnose: which physical effect is the model missing?
// mpdrig synth: a synthetic lab log with a hidden effect, to try diagnose on a known answer.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/identification/diagnose.h"
#include "model/identification/synthetic_log.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log.h"
#include "model/sim/sensor_noise.h"
#include "tools/cli/commands.h"
#include "tools/cli/diagnose_resonances.h"
#include "tools/cli/fit_resonances.h"
#include "tools/cli/model_options.h"
#include "tools/cli/parallel_tasks.h"
#include "tools/report/diagnosis_report.h"

namespace mpdrig::cli {
namespace {

struct DiagnoseArgs {
  ModelOptions model;
  std::string log_path;
  std::string json_path;
  std::string report_path;
  std::vector<std::string> base_params;
  std::vector<std::string> candidates;
  double fit_fraction = 0.6;
  bool no_regime_split = false;
  int max_iterations = 25;
  InputReplayOptions replay;
  bool quiet = false;
  riglog::ReadOptions read;
};

// The error step by step as the selected effects are added: the mean and per channel.
void PrintSelection(const Diagnosis& d, FILE* summary) {
  if (d.selected.empty()) return;
  std::fprintf(summary, "effects added one after the other (error on the scoring data, %%):\n");
  std::fprintf(summary, "  %-8s %10s", "channel", "base");
  for (const CandidateResult& step : d.selected) {
    std::fprintf(summary, " %20s", ("+ " + step.effect).c_str());
  }
  std::fprintf(summary, "\n  %-8s %10.3g", "mean", 100.0 * d.baseline.error);
  for (const CandidateResult& step : d.selected)
    std::fprintf(summary, " %20.3g", 100.0 * step.error);
  std::fprintf(summary, "\n");
  for (const auto& [channel, error] : d.baseline.channel_errors) {
    std::fprintf(summary, "  %-8s %10.3g", std::string(riglog::ChannelName(channel)).c_str(),
                 100.0 * error);
    for (const CandidateResult& step : d.selected) {
      double after = std::nan("");
      for (const auto& [c, e] : step.channel_errors) {
        if (c == channel) after = e;
      }
      std::fprintf(summary, " %20.3g", 100.0 * after);
    }
    std::fprintf(summary, "\n");
  }
}

// The log's regimes and how the split left them; what the best model leaves (the signature of
// its residual) and whether that is more than noise.
void PrintRegimesAndResidual(const Diagnosis& d, FILE* summary) {
  if (d.regimes.empty()) {
    std::fprintf(summary, "regimes: none (every input keeps one state)\n");
  } else {
    std::fprintf(summary, "regimes:");
    for (std::size_t i = 0; i < d.regimes.size(); ++i) {
      const Regime& r = d.regimes[i];
      std::fprintf(summary, "%s %s %.1f s (%.1f s fitted, %.1f s scored)", i ? ";" : "",
                   r.name.c_str(), r.duration_s, r.fit_s, r.score_s);
    }
    std::fprintf(summary, "\n");
    if (d.fit_end_s != d.requested_fit_end_s) {
      std::fprintf(summary,
                   "split moved from t = %.1f s to %.1f s so that every regime is on both "
                   "sides\n",
                   d.requested_fit_end_s, d.fit_end_s);
    }
    for (const std::string& note : d.one_sided_regimes) {
      std::fprintf(summary, "regime on one side of the split: %s\n", note.c_str());
    }
  }
  if (d.residual) std::fprintf(summary, "what is left: %s\n", d.residual->Summary().c_str());
}

// The base model's error, the candidates best first, the selection and the verdict.
void PrintSummary(const Diagnosis& d, double elapsed_s, FILE* summary) {
  std::fprintf(summary,
               "base model (fitted on t < %.1f s): error %.3g%% on the scoring data "
               "(noise floor %.3g%%)\n",
               d.fit_end_s, 100.0 * d.baseline.error, 100.0 * d.noise_floor);
  if (d.pressure_floors.present()) {
    std::fprintf(summary,
                 "pressures held at %.3g bar(a) and ended by a jump (column separation's "
                 "signature), %d times on %zu channels: ranked with the error there too\n",
                 d.pressure_floors.level_pa / 1e5, d.pressure_floors.holds,
                 d.pressure_floors.floors.size());
  }
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    std::fprintf(summary, "%2zu. %s\n", i + 1,
                 DescribeCandidate(d.candidates[i], d.baseline).c_str());
  }
  for (const CandidateResult& failed : d.failed) {
    std::fprintf(summary, "  - %s%s\n", DescribeCandidate(failed, d.baseline).c_str(),
                 failed.round > 1 ? (" (round " + std::to_string(failed.round) + ")").c_str() : "");
  }
  PrintSelection(d, summary);
  for (std::size_t i = 1; i < d.selected.size(); ++i) {
    std::fprintf(summary, "with %s: + %s\n", d.selected[i - 1].effect.c_str(),
                 DescribeCandidate(d.selected[i], d.selected[i - 1]).c_str());
  }
  if (d.next) {
    std::fprintf(
        summary, "next%s: %s\n",
        d.selected.empty() ? "" : (" (with " + d.selected.back().effect + ")").c_str(),
        DescribeCandidate(*d.next, d.selected.empty() ? d.baseline : d.selected.back()).c_str());
  }
  std::string selected;
  for (const CandidateResult& step : d.selected) {
    selected += (selected.empty() ? "" : " + ") + step.effect;
  }
  std::fprintf(summary, "selected: %s (%s)\n", selected.empty() ? "none" : selected.c_str(),
               d.selection_end.c_str());
  std::string equivalent;
  for (const std::string& name : d.equivalent) {
    equivalent += (equivalent.empty() ? "" : ", ") + name;
  }
  if (!equivalent.empty()) equivalent = "; as good: " + equivalent;
  PrintRegimesAndResidual(d, summary);
  std::fprintf(summary, "verdict: %s%s (%d model runs, %.1f s)\n",
               d.verdict ? d.verdict->c_str() : "no effect is significant", equivalent.c_str(),
               d.replays, elapsed_s);
}

int RunDiagnose(DiagnoseArgs args) {
  const std::string name = "diagnose";
  const auto started = std::chrono::steady_clock::now();
  auto params = args.model.LoadNtnuRigParams("diagnose");
  if (!params.ok()) return Fail(name, params.status());
  auto simulation = args.model.LoadSimulationOptions();
  if (!simulation.ok()) return Fail(name, simulation.status());
  auto log = LoadMeasuredLog(args.log_path, {}, args.read);
  if (!log.ok()) return Fail(name, log.status());

  DiagnoseOptions options;
  options.simulation = *simulation;
  options.simulation.stop_on_range_violation = false;  // a missing effect may be the reason
  if (!args.base_params.empty()) options.base_params = args.base_params;
  options.candidates = args.candidates;
  options.fit_fraction = args.fit_fraction;
  options.split_by_regimes = !args.no_regime_split;
  options.max_iterations = args.max_iterations;
  options.replay = args.replay;
  options.solver_log = std::getenv("MPDRIG_CERES_LOG") != nullptr;  // Ceres's iteration table
  const Status prepared = PrepareReplay(&*log, *params, options.simulation, &options.replay,
                                        args.quiet, InputLevels::kAfterTheFit);
  if (!prepared.ok()) return Fail(name, prepared);
  if (!args.quiet) {
    options.progress = [](std::string_view stage, double fraction) {
      std::fprintf(stderr, "diagnose: %3.0f%% %.*s\n", 100.0 * fraction,
                   static_cast<int>(stage.size()), stage.data());
    };
  }
  // The candidates are independent: one thread per core works through them, the longest first.
  options.run_tasks = LongestFirstRunner::Shared(/*workers=*/0, args.quiet);
  auto diagnosis = Diagnose(*log, *params, options);
  if (!diagnosis.ok()) return Fail(name, diagnosis.status());
  const Diagnosis& d = *diagnosis;
  if (!args.quiet && d.input_levels.applied()) {
    std::fprintf(stderr, "%s (at the fitted base model)\n", d.input_levels.Describe().c_str());
  }

  if (!args.json_path.empty()) {
    const Status written = WriteText(args.json_path, report::DiagnosisJson(d, args.log_path));
    if (!written.ok()) return Fail(name, written);
  }
  if (!args.report_path.empty()) {
    const Status written = WriteText(args.report_path, report::DiagnosisHtml(d, args.log_path));
    if (!written.ok()) return Fail(name, written);
  }
  FILE* summary = args.json_path == "-" || args.report_path == "-" ? stderr : stdout;
  PrintSummary(d, std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(),
               summary);
  return 0;
}

struct SynthArgs {
  SyntheticLogOptions options;
  std::vector<std::string> effects;  // NAME[:key=value,...] each, or none
  std::string sensor_noise = "lab";
  // Overrides of one part of --sensor-noise (the former per-kind flags).
  std::optional<double> pressure_noise_pa, flow_noise_m3ps, piston_noise_m, choke_noise_deg;
  std::string out_path;
  std::string truth_out_path;
  // Regimes: START:DURATION each, seconds.
  std::vector<std::string> pump_stops, choke_closures;
};

// "START:DURATION" (seconds) of --pump-stop / --choke-close; an error naming the flag otherwise.
Result<SyntheticInterval> ParseInterval(const std::string& text, const std::string& flag) {
  const std::size_t colon = text.find(':');
  SyntheticInterval interval;
  char* end = nullptr;
  const std::string start = text.substr(0, colon);
  const std::string duration = colon == std::string::npos ? "" : text.substr(colon + 1);
  interval.start_s = std::strtod(start.c_str(), &end);
  const bool start_ok = !start.empty() && *end == '\0';
  interval.duration_s = std::strtod(duration.c_str(), &end);
  const bool duration_ok = !duration.empty() && *end == '\0';
  if (!start_ok || !duration_ok || !std::isfinite(interval.start_s) ||
      !std::isfinite(interval.duration_s)) {
    return Status::Error(flag + " '" + text + "': expected START:DURATION in seconds, e.g. " +
                         flag + " 50:15");
  }
  return interval;
}

int RunSynth(const SynthArgs& args) {
  SyntheticLogOptions options = args.options;
  for (const std::string& effect : args.effects) {
    if (effect != "none") options.hidden_effects.push_back(effect);
  }
  auto noise = ParseSensorNoise(args.sensor_noise);
  if (!noise.ok()) return Fail("synth", noise.status().Within("--sensor-noise"));
  if (args.pressure_noise_pa) noise->pressure_pa = *args.pressure_noise_pa;
  if (args.flow_noise_m3ps) noise->flow_m3ps = *args.flow_noise_m3ps;
  if (args.piston_noise_m) noise->piston_m = *args.piston_noise_m;
  if (args.choke_noise_deg) noise->choke_deg = *args.choke_noise_deg;
  options.sensor_noise = *noise;
  for (const auto& [texts, intervals, flag] :
       {std::tuple{&args.pump_stops, &options.pump_stops, std::string("--pump-stop")},
        std::tuple{&args.choke_closures, &options.choke_closures, std::string("--choke-close")}}) {
    for (const std::string& text : *texts) {
      auto interval = ParseInterval(text, flag);
      if (!interval.ok()) return Fail("synth", interval.status());
      intervals->push_back(*interval);
    }
  }
  // The flags' limits (synthetic_log.h), named as the user wrote them.
  auto format = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    return std::string(text);
  };
  if (!(options.duration_s >= 10.0 && options.duration_s <= kMaxSyntheticDurationS)) {
    return Fail("synth",
                Status::Error("--duration " + format(options.duration_s) + " s must be in [10, " +
                              format(kMaxSyntheticDurationS) + "] s"));
  }
  if (!(options.rate_hz >= 10.0 && options.rate_hz <= kMaxSyntheticRateHz)) {
    return Fail("synth",
                Status::Error("--rate-hz " + format(options.rate_hz) + " Hz must be in [10, " +
                              format(kMaxSyntheticRateHz) + "] Hz"));
  }
  if (options.duration_s * options.rate_hz > kMaxSyntheticSamples) {
    return Fail("synth", Status::Error("--duration x --rate-hz = " +
                                       format(options.duration_s * options.rate_hz) +
                                       " samples, at most " + format(kMaxSyntheticSamples) +
                                       " (held in memory): shorten the log or lower the rate"));
  }
  auto made = MakeSyntheticLog(options);
  if (!made.ok()) return Fail("synth", made.status());
  made->log.metadata.push_back({"hidden", made->description});
  made->log.metadata.push_back(
      {"sensor_noise", noise->ToSpec() + ", seed " + std::to_string(options.seed)});
  const Status written = riglog::WriteRigLog(made->log, args.out_path);
  if (!written.ok()) return Fail("synth", written);
  if (!args.truth_out_path.empty()) {
    made->truth_log.metadata.push_back({"hidden", made->description});
    made->truth_log.metadata.push_back(
        {"sensor_noise", "none (the truth of " + args.out_path + ": the same run without noise)"});
    const Status truth = riglog::WriteRigLog(made->truth_log, args.truth_out_path);
    if (!truth.ok()) return Fail("synth", truth.Within("--truth-out"));
  }
  std::fprintf(stderr, "synth: %s; sensor noise %s -> %s%s%s\n", made->description.c_str(),
               noise->ToSpec().c_str(), args.out_path.c_str(),
               args.truth_out_path.empty() ? "" : ", noise-free truth -> ",
               args.truth_out_path.c_str());
  return 0;
}

}  // namespace

void AddDiagnoseCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<DiagnoseArgs>();
  args->model.cells = kDiagnoseCells;
  CLI::App* command = app->add_subcommand("diagnose",
                                          "Which physical effect is the model missing? Ranks the "
                                          "effect catalogue on a measured log");
  command->footer(
      "1. fits the base model (wave speed, pipe friction f1, choke leak) on the first part of\n"
      "   the log (moved so that each regime of the log is in both parts), 2. shows where it\n"
      "   still fails (compare's metrics), 3. adds each effect of `mpdrig effects` in turn,\n"
      "   fits it with the base parameters, and scores it on the rest\n"
      "   of the log (data it was not fitted on), with a price of 1% per extra parameter,\n"
      "4. ranks them and says what each explains. `significant`: better than the base model by\n"
      "   more than 10% and two standard errors (over 8 blocks of the scoring data); `as good`\n"
      "   names significant candidates the verdict does not beat by that 10%.\n"
      "5. then adds the verdict to the model and ranks the leading candidates again against it,\n"
      "   adding the next while it is significant by the same rule (at most 3 effects): the\n"
      "   summary shows the error falling step by step, per channel, and what the log could\n"
      "   show of the next effect.\n"
      "6. says what the best model leaves against the noise floor (sensor noise and the inputs'\n"
      "   noise replayed): where it stays far above it, that the model misses something the\n"
      "   catalogue does not hold, with the channels, bands, place along the pipe, steady or\n"
      "   dynamic, and the regime (pump stopped, choke closed, heave stopped) it shows in.\n"
      "  mpdrig synth --effect choke_inertia --seed 3 --out hidden.csv\n"
      "  mpdrig diagnose hidden.csv --json diag.json --report diag.html\n"
      "The rig's measured first resonances instead of a log (frequency domain): each effect is\n"
      "fitted to the peaks with the wave speed (unless held) and ranked by chi2; the next is\n"
      "added while its drop in chi2 passes a chi-square test (--significance):\n"
      "  mpdrig diagnose --resonances docs/examples/thesis-resonances.csv \\\n"
      "      --set wave_speed_mps=1173 --hold wave_speed_mps --json diag.json\n"
      "Progress on stderr; a summary on stdout.");
  args->model.AddAll(command);
  command->add_option("log", args->log_path, "measured rig log (rig-log-format.md)")
      ->check(CLI::ExistingFile);
  command->add_option("--json", args->json_path, "diagnosis as JSON ('-' for stdout)");
  command->add_option("--report", args->report_path, "self-contained HTML report");
  command
      ->add_option("--base-params", args->base_params,
                   "base parameters to fit (default wave_speed_mps,friction_f1_per_s,"
                   "choke_leak_m2)")
      ->delimiter(',');
  AddLogReadOptions(command, &args->read);
  command->add_option("--candidates", args->candidates, "effects to try (default: all)")
      ->delimiter(',');
  command
      ->add_option("--fit-fraction", args->fit_fraction,
                   "share of the log (from its start) used for fitting; the rest scores (moved "
                   "within 40-80 % where the log has regimes, see --no-regime-split)")
      ->check(CLI::Range(0.2, 0.9))
      ->capture_default_str();
  command->add_flag("--no-regime-split", args->no_regime_split,
                    "split at --fit-fraction even where a regime of the log (the pump stopped, "
                    "the choke closed, the heave stopped) then lies on one side only (it is "
                    "reported); by default the split moves within 40-80 % of the log to leave "
                    "each regime in both parts");
  command->add_option("--max-iterations", args->max_iterations, "solver iterations per fit")
      ->check(CLI::Range(1, 500))
      ->capture_default_str();
  AddInputReplayOptions(command, &args->replay);
  command->add_flag("--quiet", args->quiet, "no progress on stderr");
  auto resonance_args = std::make_shared<ResonanceDiagnoseArgs>();
  command
      ->add_option("--resonances", resonance_args->resonances_path,
                   "diagnose measured first resonances instead of a log: CSV "
                   "configuration,frequency_hz,uncertainty_hz (docs/rig-measurements.md)")
      ->check(CLI::ExistingFile);
  AddResonanceOptions(command, &resonance_args->hold, &resonance_args->method,
                      &resonance_args->outlet_barg);
  command
      ->add_option("--amplitude-m", resonance_args->amplitude_m,
                   "--resonances: piston amplitude of the simulated response [m]")
      ->check(CLI::Range(1.0e-6, 0.05))
      ->capture_default_str();
  command
      ->add_option("--max-effects", resonance_args->max_effects,
                   "--resonances: effects selected at most")
      ->check(CLI::Range(1, 5))
      ->capture_default_str();
  command
      ->add_option("--significance", resonance_args->significance,
                   "--resonances: level of the chi2 test an added effect must pass")
      ->check(CLI::Range(1.0e-6, 0.2))
      ->capture_default_str();
  command->add_flag("--thorough", resonance_args->thorough,
                    "--resonances: try the effects that need the simulated response in every "
                    "round, not only the first (minutes each)");
  command->callback([args, resonance_args, exit_code]() {
    if (!resonance_args->resonances_path.empty()) {
      if (!args->log_path.empty()) {
        *exit_code = Fail("diagnose", Status::Error("give a log or --resonances, not both"));
        return;
      }
      resonance_args->candidates = args->candidates;
      resonance_args->json_path = args->json_path;
      resonance_args->quiet = args->quiet;
      resonance_args->max_iterations = args->max_iterations;
      *exit_code = RunDiagnoseResonances(args->model, *resonance_args);
      return;
    }
    if (args->log_path.empty()) {
      *exit_code = Fail("diagnose", Status::Error("give a log to diagnose (or --resonances FILE)"));
      return;
    }
    *exit_code = RunDiagnose(*args);
  });

  auto synth = std::make_shared<SynthArgs>();
  CLI::App* synth_command = app->add_subcommand(
      "synth", "Write a synthetic lab log with a hidden effect (to try diagnose on)");
  synth_command->footer(
      "The model with the effects switched on at random strengths (or those given), perturbed\n"
      "base parameters,\n"
      "piston sines and a sweep, choke and pump steps, and the lab's sensor noise "
      "(--sensor-noise).\n"
      "The truth is written into the log's metadata (# hidden: ...). Same seed, same log.\n"
      "  mpdrig synth --effect sensor_lag --seed 7 --out lag.csv --truth-out lag_truth.csv\n"
      "  mpdrig synth --effect sensor_lag:time_constant_s=0.1 --effect unsteady_friction --out "
      "two.csv\n"
      "A floating rig's heave in an irregular sea instead of the lab's sines and sweep:\n"
      "  mpdrig synth --effect hose_compliance --heave sea --out sea.csv\n"
      "Regimes: the pump stopped and the choke closed over given intervals (a connection):\n"
      "  mpdrig synth --effect choke_inertia --pump-stop 50:20 --choke-close 52:16 --out stop.csv");
  synth_command->add_option("--effect", synth->effects,
                            "hidden effect NAME[:KEY=VALUE,...] (strengths not given are drawn), "
                            "repeatable for several at once; none: the base model");
  synth_command->add_option("--seed", synth->options.seed, "random seed")->capture_default_str();
  synth_command->add_option("--duration", synth->options.duration_s, "length [s]")
      ->capture_default_str();
  synth_command->add_option("--rate-hz", synth->options.rate_hz, "sample rate [Hz]")
      ->capture_default_str();
  synth_command
      ->add_option("--cells", synth->options.cells,
                   "pipe cells of the generating model (diagnose replays on 50: another grid "
                   "makes a log from a model that is not diagnose's own)")
      ->check(CLI::Range(2, 200000))
      ->capture_default_str();
  synth_command
      ->add_option("--sensor-noise", synth->sensor_noise,
                   "sensor noise: none, lab (thesis Table 4.1.1) or a SPEC such as "
                   "pressure=0.024bar,flow=2%+0.05lpm,piston=0.5mm,choke=0.1deg "
                   "(docs/sensor-noise.md)")
      ->capture_default_str();
  // The former per-kind flags: each overrides one part of --sensor-noise.
  const auto add_noise = [&](const char* name, std::optional<double>* sigma, const char* what,
                             const char* unit) {
    synth_command
        ->add_option(
            name, *sigma,
            std::string("override --sensor-noise: ") + what + ", standard deviation [" + unit + "]")
        ->check(CLI::NonNegativeNumber);
  };
  add_noise("--pressure-noise-pa", &synth->pressure_noise_pa, "pressure transmitters", "Pa");
  add_noise("--flow-noise-m3ps", &synth->flow_noise_m3ps,
            "flow meters, the part independent of the reading", "m^3/s");
  add_noise("--piston-noise-m", &synth->piston_noise_m, "piston position", "m");
  add_noise("--choke-noise-deg", &synth->choke_noise_deg, "choke position", "deg");
  synth_command
      ->add_option("--heave", synth->options.heave,
                   "the piston's motion: lab (two sines at two amplitudes, a sweep, the sines "
                   "again) or sea (an irregular sea: 24 tones of a Pierson-Moskowitz spectrum "
                   "peaking at 0.08-0.15 Hz, random phases, never periodic); default lab")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, SyntheticHeave>{{"lab", SyntheticHeave::kLabSeries},
                                                {"sea", SyntheticHeave::kIrregularSea}},
          CLI::ignore_case));
  synth_command->add_option("--pump-stop", synth->pump_stops,
                            "START:DURATION [s]: the back-pressure pump stopped (FT2 ramps to 0 "
                            "and back over 0.5 s), repeatable");
  synth_command->add_option("--choke-close", synth->choke_closures,
                            "START:DURATION [s]: the choke closed (to 0 deg, only its leak "
                            "passes, and back over 0.5 s), repeatable; with the pump running "
                            "the pressure rises fast");
  synth_command->add_option("--truth-out", synth->truth_out_path,
                            "also write the same run without sensor noise (same seed, excitation "
                            "and parameters): what a perfect model would say");
  synth_command->add_option("--out", synth->out_path, "rig log to write")->required();
  synth_command->callback([synth, exit_code]() { *exit_code = RunSynth(*synth); });
}

}  // namespace mpdrig::cli
