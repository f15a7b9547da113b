#include "model/analysis/log_file_replay.h"

#include <cmath>
#include <memory>
#include <utility>

#include "model/analysis/log_replay.h"

namespace mpdrig {

Status PrepareStreamedReplay(const ReconstructionPlanner& head,
                             const std::vector<SourceChannel>& channels, const std::string& path,
                             double atmospheric_pressure_pa, const RigParams& params,
                             const SimulationOptions& sim_options, InputReplayOptions* replay,
                             std::optional<InputReconstruction>* plan) {
  const bool estimate_levels = plan->has_value() && replay->estimate_levels;
  if (!replay->choose_warmup && !estimate_levels) return Status::Ok();
  auto head_log = head.HeadLog(channels, path, atmospheric_pressure_pa);
  if (!head_log.ok()) return head_log.status();
  if (replay->choose_warmup) {
    MPDRIG_RETURN_IF_ERROR(ChooseReplayStart(*head_log, params, sim_options, replay));
  }
  if (estimate_levels) {
    auto levels = EstimateInputLevels(*head_log, params, sim_options, *replay);
    if (!levels.ok()) return levels.status();
    (*plan)->levels = *levels;
    ApplyInputLevels(*levels, replay);
  }
  return Status::Ok();
}

Result<LogFileReplay> LogFileReplay::Prepare(const std::string& path, const RigParams& params,
                                             const SimulationOptions& sim_options,
                                             const InputReplayOptions& replay,
                                             const riglog::ReadOptions& read) {
  auto source = FileRowSource::Open(path, {}, read);
  if (!source.ok()) return source.status();
  LogFileReplay prepared;
  prepared.path_ = path;
  prepared.params_ = params;
  prepared.sim_options_ = sim_options;
  prepared.replay_ = replay;
  prepared.read_ = read;
  prepared.atmospheric_pressure_pa_ = (*source)->atmospheric_pressure_pa();
  ReconstructionPlanner head;
  bool measured = false;  // a compared channel has a value somewhere (CheckMeasuredLog)
  const std::size_t channel_count = (*source)->channels().size();
  LogRow row;
  while (true) {
    auto more = (*source)->Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    if (prepared.rows_ == 0) prepared.start_s_ = row.time_s;
    prepared.end_s_ = row.time_s;
    ++prepared.rows_;
    head.Add(row);
    for (std::size_t c = 0; c < channel_count && !measured; ++c) {
      measured = std::isfinite(row.measured_si[c]);
    }
  }
  if (prepared.rows_ < 2) return Status::Error(path + ": needs at least 2 samples");
  if (replay.reconstruct_inputs) prepared.plan_ = head.Plan();
  // A log the comparison would refuse (too short, nothing measured) has no pressures to decide
  // the start and the levels from.
  prepared.prepared_ = measured && prepared.rows_ >= 4;
  if (prepared.prepared_) {
    MPDRIG_RETURN_IF_ERROR(PrepareStreamedReplay(head, (*source)->channels(), path,
                                                 prepared.atmospheric_pressure_pa_, params,
                                                 sim_options, &prepared.replay_, &prepared.plan_));
  }
  return prepared;
}

Result<RunSummary> LogFileReplay::Run(const std::function<void(const RigSample&)>& sink,
                                      const std::function<void(double)>& progress) const {
  auto file = FileRowSource::Open(path_, {}, read_);
  if (!file.ok()) return file.status();
  std::unique_ptr<LogRowSource> source = std::move(file).value();
  if (plan_) source = std::make_unique<ReconstructingRowSource>(std::move(source), *plan_);
  const double span_s = end_s_ - start_s_;
  double next_progress = 0.05;
  RowPipeline pipeline(PipelineSmoothingS(replay_),
                       ReplaySetup{params_, sim_options_, end_s_, replay_.warmup, replay_.profile},
                       [&](const PipelineSample& sample) {
                         sink(*sample.model);
                         const double done = (sample.row->time_s - start_s_) / span_s;
                         if (progress && span_s > 0.0 && done >= next_progress) {
                           progress(done);
                           next_progress += 0.05;
                         }
                       });
  const auto changed = [&] {
    return Status::Error(path_ +
                         ": the file changed between the two "
                         "passes");
  };
  LogRow row;
  while (true) {
    auto more = source->Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    if (pipeline.rows_pushed() >= rows_ || row.time_s > end_s_) return changed();
    MPDRIG_RETURN_IF_ERROR(pipeline.Push(row));
  }
  if (pipeline.rows_pushed() != rows_) return changed();
  MPDRIG_RETURN_IF_ERROR(pipeline.Finish());
  const RigSampler* sampler = pipeline.sampler();
  MPDRIG_CHECK(sampler != nullptr);
  RunSummary summary;
  summary.steps = sampler->steps();
  summary.time_step_s = sampler->simulator().time_step_s();
  summary.first_range_event = sampler->simulator().first_range_event();
  return summary;
}

}  // namespace mpdrig
