#include "model/analysis/compare.h"

#include <memory>
#include <utility>

#include "model/analysis/compare_accumulator.h"
#include "model/analysis/log_file_replay.h"
#include "model/analysis/log_stream.h"

namespace mpdrig {

const ChannelMetrics* Comparison::Find(Channel channel) const {
  for (const ChannelMetrics& metrics : channels) {
    if (metrics.channel == channel) return &metrics;
  }
  return nullptr;
}

Status CompareOptions::Validate() const {
  const std::pair<const char*, int> at_least[] = {{"residual_lags", residual_lags},
                                                  {"trace_columns", trace_columns},
                                                  {"band_half_width_bins", band_half_width_bins}};
  for (const auto& [name, value] : at_least) {
    if (value < 1) {
      return Status::Error("compare options: " + std::string(name) + " = " + std::to_string(value) +
                           " must be >= 1");
    }
  }
  if (welch_segment_samples < 8) {
    return Status::Error("compare options: welch_segment_samples = " +
                         std::to_string(welch_segment_samples) + " must be >= 8");
  }
  return Status::Ok();
}

Result<Comparison> CompareTraces(const MeasuredLog& log, const ModelTraces& model,
                                 const CompareOptions& options, const CompareProgress& progress) {
  const std::size_t n = log.time_s().size();
  if (model.values_si.size() != log.channels.size()) {
    return Status::Error("model traces: " + std::to_string(model.values_si.size()) +
                         " channels for " + std::to_string(log.channels.size()) + " measured");
  }
  for (const auto& values : model.values_si) {
    if (values.size() != n) return Status::Error("model traces: length differs from the log's");
  }
  if (n < 4) return Status::Error(log.path + ": needs at least 4 samples to compare");
  if (log.channels.size() > kComparedChannelCount) {
    return Status::Error(log.path + ": more channels than P1 P2 PT1..PT10 C2 FT1 FT3 FT4");
  }
  MPDRIG_RETURN_IF_ERROR(options.Validate());

  // Pass 1: what the metrics need of the whole log.
  MemoryRowSource first_source(log);
  LogScanner scanner(first_source.channels(), options);
  RowPipeline first_pass(options.piston_smoothing_s, std::nullopt,
                         [&](const PipelineSample& sample) { scanner.Add(sample); });
  MPDRIG_RETURN_IF_ERROR(RunPipeline(&first_source, &first_pass));
  auto summary = scanner.Finish(log.path);
  if (!summary.ok()) return summary.status();

  // Pass 2: the metrics.
  ComparisonAccumulator accumulator(*summary, options);
  std::vector<double> model_si(summary->channels.size());
  PercentProgress percent(progress, "analyse", static_cast<long>(n));
  // Pass 2 sees the inputs the model was fed, as CompareLog's replay pass does.
  ReplayOptions replayed;
  replayed.reconstruct_inputs = model.inputs_reconstructed;
  replayed.piston_smoothing_s = options.piston_smoothing_s;
  RowPipeline second_pass(PipelineSmoothingS(replayed), std::nullopt,
                          [&](const PipelineSample& sample) {
                            const auto i = static_cast<std::size_t>(sample.index);
                            for (std::size_t c = 0; c < model_si.size(); ++c) {
                              model_si[c] = model.values_si[summary->channels[c].source_index][i];
                            }
                            accumulator.Add(sample, model_si.data());
                            percent.Done(sample.index + 1);
                          });
  const MeasuredLog* replayed_log = &log;
  MeasuredLog reconstructed;
  if (model.inputs_reconstructed && log.reconstructed_inputs.time_s.size() != n) {
    reconstructed = log;
    ReconstructInputs(&reconstructed);
    replayed_log = &reconstructed;
  }
  MemoryRowSource second_source(
      *replayed_log, model.inputs_reconstructed ? InputView::kReconstructed : InputView::kMeasured);
  MPDRIG_RETURN_IF_ERROR(RunPipeline(&second_source, &second_pass));
  auto result = accumulator.Finish(log.path, model.first_range_event);
  if (result.ok()) {
    result->atmospheric_pressure_pa = log.atmospheric_pressure_pa;
    if (model.inputs_reconstructed) result->input_reconstruction = replayed_log->reconstruction;
    result->warmup = model.warmup;
    result->measured_start = model.profile;
  }
  return result;
}

namespace {

// What CompareLog's first pass learns of the file: the metrics' summary of the whole log, its
// first rows (for the reconstruction's plan, the replay's start and levels) and its atmospheric
// pressure.
struct FileScan {
  LogSummary summary;
  ReconstructionPlanner planner;
  double atmospheric_pressure_pa = 0.0;
};

// Pass 1: reads the file (checking every line) for what the metrics need up front.
Result<FileScan> ScanFile(const std::string& path, const CompareOptions& options,
                          const CompareProgress& progress) {
  auto source = FileRowSource::Open(path, progress, options.read);
  if (!source.ok()) return source.status();
  FileScan scan;
  LogScanner scanner((*source)->channels(), options);
  RowPipeline first_pass(options.piston_smoothing_s, std::nullopt,
                         [&](const PipelineSample& sample) {
                           scanner.Add(sample);
                           scan.planner.Add(*sample.row);
                         });
  MPDRIG_RETURN_IF_ERROR(RunPipeline(source->get(), &first_pass));
  auto summary = scanner.Finish(path);
  if (!summary.ok()) return summary.status();
  scan.summary = std::move(summary).value();
  scan.atmospheric_pressure_pa = (*source)->atmospheric_pressure_pa();
  return scan;
}

// Pass 2: the file's rows again, the model replayed in lock step, into the metrics. A file whose
// rows differ in number or reach from pass 1's is refused.
Result<Comparison> ReplayAndAccumulate(LogRowSource* source, const std::string& path,
                                       const LogSummary& summary, const RigParams& params,
                                       const SimulationOptions& sim_options,
                                       const CompareOptions& options, const ReplayOptions& replay,
                                       const CompareProgress& progress) {
  ComparisonAccumulator accumulator(summary, options);
  std::vector<double> model_si(summary.channels.size());
  PercentProgress percent(progress, "replay", summary.samples);
  RowPipeline pipeline(
      PipelineSmoothingS(replay),
      ReplaySetup{params, sim_options, summary.t1_s, replay.warmup, replay.profile},
      [&](const PipelineSample& sample) {
        for (std::size_t c = 0; c < model_si.size(); ++c) {
          model_si[c] = sample.model->values[Index(summary.channels[c].channel)];
        }
        accumulator.Add(sample, model_si.data());
        percent.Done(sample.index + 1);
      });
  LogRow row;
  while (true) {
    auto more = source->Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    if (pipeline.rows_pushed() >= summary.samples || row.time_s > summary.t1_s) {
      return Status::Error(path + ": the file changed between the two passes");
    }
    MPDRIG_RETURN_IF_ERROR(pipeline.Push(row).Within(path));
  }
  if (pipeline.rows_pushed() != summary.samples) {
    return Status::Error(path + ": the file changed between the two passes");
  }
  MPDRIG_RETURN_IF_ERROR(pipeline.Finish().Within(path));
  const RigSampler* sampler = pipeline.sampler();
  return accumulator.Finish(
      path, sampler != nullptr ? sampler->simulator().first_range_event() : std::nullopt);
}

}  // namespace

Result<Comparison> CompareLog(const std::string& path, const RigParams& params,
                              const SimulationOptions& sim_options, const CompareOptions& options,
                              const CompareProgress& progress) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  MPDRIG_RETURN_IF_ERROR(sim_options.Validate());
  const auto scan = ScanFile(path, options, progress);
  if (!scan.ok()) return scan.status();
  auto file = FileRowSource::Open(path, {}, options.read);
  if (!file.ok()) return file.status();
  std::unique_ptr<LogRowSource> source = std::move(file).value();
  std::optional<InputReconstruction> plan;
  if (options.reconstruct_inputs) plan = scan->planner.Plan();
  ReplayOptions replay;
  replay.reconstruct_inputs = options.reconstruct_inputs;
  replay.piston_smoothing_s = options.piston_smoothing_s;
  replay.estimate_levels = options.estimate_levels;
  replay.choose_warmup = options.choose_warmup;
  MPDRIG_RETURN_IF_ERROR(PrepareStreamedReplay(scan->planner, source->channels(), path,
                                               scan->atmospheric_pressure_pa, params, sim_options,
                                               &replay, &plan));
  if (plan) source = std::make_unique<ReconstructingRowSource>(std::move(source), *plan);
  auto result = ReplayAndAccumulate(source.get(), path, scan->summary, params, sim_options, options,
                                    replay, progress);
  if (result.ok()) {
    result->atmospheric_pressure_pa = scan->atmospheric_pressure_pa;
    result->input_reconstruction = plan;
    result->warmup = replay.warmup;
    result->measured_start = replay.profile;
  }
  return result;
}

}  // namespace mpdrig
