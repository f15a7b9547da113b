// mpdrig compare: replay a measured log's inputs through the model; write the metrics as JSON and
// a self-contained HTML report (model/analysis/compare.h, tools/report/).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "model/analysis/compare.h"
#include "model/analysis/measured_log.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"
#include "tools/report/comparison_json.h"
#include "tools/report/html_report.h"

namespace mpdrig::cli {
namespace {

struct CompareArgs {
  ModelOptions model;
  std::string log_path;
  std::string json_path;
  std::string report_path;
  InputReplayOptions replay;
  riglog::ReadOptions read;
  int residual_lags = 25;
  bool quiet = false;
};

int RunCompare(const CompareArgs& args) {
  const std::string name = "compare";
  if (args.json_path.empty() && args.report_path.empty()) {
    return Fail(name, Status::Error("give --json OUT.json and/or --report OUT.html"));
  }
  auto params = args.model.LoadNtnuRigParams("compare");
  if (!params.ok()) return Fail(name, params.status());
  auto sim_options = args.model.LoadSimulationOptions();
  if (!sim_options.ok()) return Fail(name, sim_options.status());

  CompareOptions options;
  options.piston_smoothing_s = args.replay.piston_smoothing_s;
  options.reconstruct_inputs = args.replay.reconstruct_inputs;
  options.choose_warmup = args.replay.choose_warmup;
  options.estimate_levels = args.replay.estimate_levels;
  options.residual_lags = args.residual_lags;
  options.read = args.read;
  int last_percent = -1;
  std::string last_stage;
  const CompareProgress progress = [&](std::string_view stage, double fraction) {
    if (args.quiet) return;
    if (fraction < 0.0) {  // reading: a sample count (the length is unknown while streaming)
      std::fprintf(stderr, "mpdrig compare: read %.0f samples\n", -fraction);
      return;
    }
    const int percent = static_cast<int>(100.0 * fraction);
    if (stage == last_stage && percent / 10 == last_percent / 10) return;
    last_stage = std::string(stage);
    last_percent = percent;
    std::fprintf(stderr, "mpdrig compare: %.*s %3d%%\n", static_cast<int>(stage.size()),
                 stage.data(), percent);
  };

  // Two passes over the file in bounded memory (compare.h): an hour at 1 kHz is fine.
  auto comparison = CompareLog(args.log_path, *params, *sim_options, options, progress);
  if (!comparison.ok()) return Fail(name, comparison.status());

  report::ReportContext context;
  context.log_path = args.log_path;
  context.model_description = args.model.Describe(*params);
  if (!args.model.config_path.empty()) context.config = "--config " + args.model.config_path;
  for (const std::string& assignment : args.model.overrides) {
    context.config += (context.config.empty() ? "" : " ") + std::string("--set ") + assignment;
  }
  context.atmospheric_pressure_pa = comparison->atmospheric_pressure_pa;
  if (comparison->first_range_event) {
    std::fprintf(stderr, "mpdrig compare: warning: %s\n",
                 comparison->first_range_event->Describe().c_str());
  }
  if (!args.json_path.empty()) {
    Status written = WriteText(args.json_path, report::ComparisonJson(*comparison, context));
    if (!written.ok()) return Fail(name, written);
  }
  if (!args.report_path.empty()) {
    Status written = WriteText(args.report_path, report::ComparisonHtml(*comparison, context));
    if (!written.ok()) return Fail(name, written);
  }
  if (args.json_path != "-" && args.report_path != "-") {
    std::printf("compared %zu channels over %.6g s: error (mean NRMSE) %.4g",
                comparison->channels.size(), comparison->duration_s, comparison->error);
    const ChannelMetrics* worst = nullptr;
    std::size_t constant = 0;
    for (const ChannelMetrics& channel : comparison->channels) {
      if (!std::isfinite(channel.nrmse)) {
        ++constant;  // nothing to explain on it
        continue;
      }
      if (worst == nullptr || channel.nrmse > worst->nrmse) worst = &channel;
    }
    if (worst != nullptr) {
      std::printf(", worst %s (fit %.1f %%)",
                  std::string(riglog::ChannelName(worst->channel)).c_str(), worst->fit_percent);
    }
    if (constant > 0) {
      std::printf("; %zu channel%s constant (within rounding: nothing to explain, left out)",
                  constant, constant == 1 ? "" : "s");
    }
    std::printf("\n");
  }
  return 0;
}

}  // namespace

void AddCompareCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* command = app->add_subcommand(
      "compare", "Replay a measured log through the model; metrics (JSON) and an HTML report");
  command->footer(
      "Replays the log's inputs (piston_position, choke_position, FT2, C1) through the model and\n"
      "compares every measured channel present (P1 P2 PT1..PT10 C2 FT1 FT3 FT4): fit %, NRMSE,\n"
      "RMS error and bias (in the log's units), lag, error per frequency band, the error along\n"
      "the pipe and a residual analysis. Field names: docs/compare.md, 'JSON fields'.\n"
      "The log is read twice (a check and a replay pass) in memory that does not grow with it.\n"
      "  mpdrig compare lab.csv --json lab.json --report lab.html\n"
      "  mpdrig compare lab.csv --set wave_speed_mps=1000 --json - | jq .channels.PT1\n"
      "Progress goes to stderr.");
  args->model.AddAll(command);
  command->add_option("log", args->log_path, "measured rig log (rig-log-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--json", args->json_path, "metrics as JSON ('-' for stdout)");
  command->add_option("--report", args->report_path, "self-contained HTML report");
  AddInputReplayOptions(command, &args->replay);
  AddLogReadOptions(command, &args->read);
  command
      ->add_option("--residual-lags", args->residual_lags,
                   "lags (samples) of the residual correlations, as MATLAB resid's M")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  command->add_flag("--quiet", args->quiet, "no progress on stderr");
  command->callback([args, exit_code]() { *exit_code = RunCompare(*args); });
}

}  // namespace mpdrig::cli
