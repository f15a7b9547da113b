#include "model/analysis/log_stream.h"

#include "model/sim/log_inputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "model/signal/smoothing.h"

namespace mpdrig {
namespace {

// Samples smoothed per SmoothLocalQuadratic call: the window's margins are computed twice, a few
// percent of the work at 1 kHz; the pipeline holds about this many rows.
constexpr std::size_t kSmoothingBlock = 4096;

}  // namespace

// ---- Sources ----------------------------------------------------------------------------------

Result<std::unique_ptr<FileRowSource>> FileRowSource::Open(const std::string& path,
                                                           const CompareProgress& progress,
                                                           const riglog::ReadOptions& read) {
  // A regular file is opened here so that its read position gives the progress in percent;
  // anything else (and every error message) is the reader's.
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  std::istream* stream = nullptr;
  std::optional<Result<riglog::RigLogReader>> opened;
  if (!error && size > 0 && std::filesystem::is_regular_file(path, error)) {
    auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (file->is_open()) {
      stream = file.get();
      opened.emplace(riglog::RigLogReader::FromStream(std::move(file), path, read));
    }
  }
  if (!opened) opened.emplace(riglog::RigLogReader::Open(path, read));
  if (!opened->ok()) return opened->status();
  std::unique_ptr<FileRowSource> source(new FileRowSource(std::move(*opened).value()));
  source->stream_ = stream;
  source->file_size_ = stream != nullptr ? static_cast<double>(size) : 0.0;
  source->path_ = path;
  source->progress_ = progress;
  const riglog::RigLogReader& reader = source->reader_;
  const std::int64_t header_line = reader.line_number();
  const auto piston = reader.FindColumn("piston_position");
  const auto choke = reader.FindColumn("choke_position");
  for (const auto& [slot, name] :
       {std::pair{piston, "piston_position"}, std::pair{choke, "choke_position"}}) {
    if (!slot) {
      return Status::Error(path + ":" + std::to_string(header_line) +
                           ":1: required input column '" + name +
                           "_<unit>' is missing from the header");
    }
  }
  source->piston_ = *piston;
  source->choke_ = *choke;
  source->pump_ = reader.FindColumn("FT2");
  source->outlet_ = reader.FindColumn("C1");
  for (Channel channel : ComparedChannels()) {
    if (auto column = reader.FindColumn(riglog::ChannelName(channel))) {
      source->compared_columns_.push_back(*column);
      source->channels_.push_back({channel, reader.columns()[*column].unit});
    }
  }
  return source;
}

Result<bool> FileRowSource::Next(LogRow* row) {
  auto more = reader_.Next(&values_);
  if (!more.ok()) return more.status();
  if (!*more) {
    if (progress_ && stream_ != nullptr) progress_("read", 1.0);
    return false;
  }
  // Inputs must be measured on every row: the model cannot run on a gap.
  for (const auto& [slot, required] :
       {std::pair{std::optional(piston_), true}, std::pair{std::optional(choke_), true},
        std::pair{pump_, false}, std::pair{outlet_, false}}) {
    if (slot && !std::isfinite(values_[*slot])) {
      std::ostringstream out;
      out << path_ << ":" << reader_.line_number() << ": input column "
          << reader_.columns()[*slot].name << " (column " << *slot + 1
          << ") is not measured (empty or nan); the model needs "
          << (required ? "every" : "every (or no)") << " input sample";
      return Status::Error(out.str());
    }
  }
  row->time_s = values_[reader_.time_index()];
  row->piston_position_m = values_[piston_];
  row->choke_opening_frac = values_[choke_];
  row->pump_flow_m3ps = pump_ ? values_[*pump_] : 0.0;
  row->outlet_pressure_pa = outlet_ ? values_[*outlet_] : reader_.atmospheric_pressure_pa();
  row->measured_inputs = {row->piston_position_m, row->choke_opening_frac, row->pump_flow_m3ps,
                          row->outlet_pressure_pa};
  for (std::size_t i = 0; i < compared_columns_.size(); ++i) {
    row->measured_si[i] = values_[compared_columns_[i]];
  }
  if (progress_) ReportProgress();
  return true;
}

// The share of the file's bytes read, checked every 16384 samples, reported every percent; a
// sample count every 100 000 samples where the length is unknown (standard input).
void FileRowSource::ReportProgress() {
  const auto samples = static_cast<double>(reader_.samples_read());
  if (stream_ == nullptr) {
    if (samples >= next_report_) progress_("read", -samples), next_report_ += 100000.0;
    return;
  }
  if (reader_.samples_read() % 16384 != 1) return;
  const auto position = static_cast<double>(stream_->tellg());
  if (!(position >= 0.0)) return;
  const double fraction = std::min(1.0, position / file_size_);
  if (fraction >= next_report_) {
    progress_("read", fraction);
    next_report_ = std::floor(fraction * 100.0 + 1.0) / 100.0;
  }
}

MemoryRowSource::MemoryRowSource(const MeasuredLog& log, InputView view)
    : log_(log), inputs_(view == InputView::kMeasured ? log.inputs : log.reconstructed_inputs) {
  MPDRIG_CHECK(inputs_.time_s.size() == log.inputs.time_s.size());
  MPDRIG_CHECK(log.channels.size() <= kComparedChannelCount);
  for (const MeasuredChannel& channel : log.channels) {
    channels_.push_back({channel.channel, channel.unit});
  }
}

Result<bool> MemoryRowSource::Next(LogRow* row) {
  const LogInputColumns& in = inputs_;
  if (next_ >= in.time_s.size()) return false;
  const std::size_t i = next_++;
  row->time_s = in.time_s[i];
  row->piston_position_m = in.piston_position_m[i];
  row->choke_opening_frac = in.choke_opening_frac[i];
  row->pump_flow_m3ps = in.pump_flow_m3ps[i];
  row->outlet_pressure_pa = in.outlet_pressure_pa[i];
  const LogInputColumns& raw = log_.inputs;
  row->measured_inputs = {raw.piston_position_m[i], raw.choke_opening_frac[i],
                          raw.pump_flow_m3ps[i], raw.outlet_pressure_pa[i]};
  for (std::size_t c = 0; c < log_.channels.size(); ++c) {
    row->measured_si[c] = log_.channels[c].values_si[i];
  }
  return true;
}

// ---- Input reconstruction --------------------------------------------------------------------

void ReconstructionPlanner::Add(const LogRow& row) {
  if (head_.time_s.size() >= kReconstructionPlanSamples + kPlannerMarginSamples) return;
  head_.time_s.push_back(row.time_s);
  head_.piston_position_m.push_back(row.piston_position_m);
  head_.choke_opening_frac.push_back(row.choke_opening_frac);
  head_.pump_flow_m3ps.push_back(row.pump_flow_m3ps);
  head_.outlet_pressure_pa.push_back(row.outlet_pressure_pa);
  measured_.push_back(row.measured_si);
}

Result<MeasuredLog> ReconstructionPlanner::HeadLog(const std::vector<SourceChannel>& channels,
                                                   const std::string& path,
                                                   double atmospheric_pressure_pa) const {
  MeasuredLog log;
  log.path = path;
  log.atmospheric_pressure_pa = atmospheric_pressure_pa;
  log.inputs = head_;
  for (std::size_t c = 0; c < channels.size(); ++c) {
    MeasuredChannel channel{channels[c].channel, channels[c].unit, {}};
    for (const auto& row : measured_) channel.values_si.push_back(row[c]);
    log.channels.push_back(std::move(channel));
  }
  ReconstructInputs(&log);
  return log;
}

ReconstructingRowSource::ReconstructingRowSource(std::unique_ptr<LogRowSource> source,
                                                 InputReconstruction plan)
    : source_(std::move(source)), plan_(plan) {}

Result<bool> ReconstructingRowSource::Next(LogRow* row) {
  while (ready_.empty()) {
    if (source_done_ && pending_ >= held_.size()) return false;
    if (!source_done_) {
      // Blocks of at least 4 reaches: each pass recomputes the margins (about 1.5x the work).
      const std::size_t block =
          std::max(kSmoothingBlock, 4 * static_cast<std::size_t>(plan_.level_reach_samples()));
      for (std::size_t k = 0; k < block; ++k) {
        Held next;
        auto more = source_->Next(&next.row);
        if (!more.ok()) return more.status();
        if (!*more) {
          source_done_ = true;
          break;
        }
        next.choke = choke_sums_.Push(next.row.choke_opening_frac);
        next.pump = pump_sums_.Push(next.row.pump_flow_m3ps);
        next.outlet = outlet_sums_.Push(next.row.outlet_pressure_pa);
        held_.push_back(next);
      }
    }
    ReconstructHeld(source_done_);
  }
  *row = ready_.front();
  ready_.pop_front();
  return true;
}

// A row's reconstruction is the whole log's when every row within reach of it is held: those
// behind it are kept below, those ahead are there once enough rows follow it (or the source has
// ended).
void ReconstructingRowSource::ReconstructHeld(bool last_block) {
  if (pending_ >= held_.size()) return;
  const double piston_reach_s = plan_.piston_half_width_s;
  const auto level_reach = static_cast<std::size_t>(plan_.level_reach_samples());
  LogInputColumns raw;
  LevelInputSums sums;
  for (const Held& held : held_) {
    const LogRow& row = held.row;
    raw.time_s.push_back(row.time_s);
    raw.piston_position_m.push_back(row.piston_position_m);
    raw.choke_opening_frac.push_back(row.choke_opening_frac);
    raw.pump_flow_m3ps.push_back(row.pump_flow_m3ps);
    raw.outlet_pressure_pa.push_back(row.outlet_pressure_pa);
    sums.choke.push_back(held.choke), sums.pump.push_back(held.pump);
    sums.outlet.push_back(held.outlet);
  }
  sums.choke.push_back(choke_sums_.Next()), sums.pump.push_back(pump_sums_.Next());
  sums.outlet.push_back(outlet_sums_.Next());
  const LogInputColumns done = ReconstructInputBlock(raw, sums, front_index_, plan_);
  const double last_time = held_.back().row.time_s;
  while (pending_ < held_.size()) {
    const bool reach_held = held_.size() - 1 - pending_ >= level_reach &&
                            last_time - held_[pending_].row.time_s > piston_reach_s;
    if (!last_block && !reach_held) break;
    LogRow row = held_[pending_].row;
    row.piston_position_m = done.piston_position_m[pending_];
    row.choke_opening_frac = done.choke_opening_frac[pending_];
    row.pump_flow_m3ps = done.pump_flow_m3ps[pending_];
    row.outlet_pressure_pa = done.outlet_pressure_pa[pending_];
    ready_.push_back(row);
    ++pending_;
  }
  // Keep what the next pending row reaches back to (or, all done, what a later one could).
  const double from_s = pending_ < held_.size() ? held_[pending_].row.time_s : last_time;
  while (!held_.empty() && pending_ > level_reach &&
         from_s - held_.front().row.time_s > piston_reach_s) {
    held_.pop_front();
    --pending_;
    ++front_index_;
  }
}

// ---- Pipeline ---------------------------------------------------------------------------------

RowPipeline::RowPipeline(double smoothing_s, std::optional<ReplaySetup> replay, Sink sink,
                         long smoothing_block_rows)
    : smoothing_s_(smoothing_s),
      replay_(std::move(replay)),
      sink_(std::move(sink)),
      smoothing_block_rows_(std::max(1L, smoothing_block_rows)),
      next_smoothing_(smoothing_block_rows_) {
  if (replay_) replay_->options.choke_input = ChokeInput::kMeasured;
}

Status RowPipeline::Push(const LogRow& row) {
  MPDRIG_CHECK(!finished_);
  rows_.push_back({row, 0.0});
  ++pushed_;
  window_time_s_.push_back(row.time_s);
  window_position_m_.push_back(row.piston_position_m);
  if (pushed_ >= next_smoothing_) {
    // Not again before another block has come in (a window longer than a block would otherwise
    // be smoothed again at every row).
    next_smoothing_ = pushed_ + smoothing_block_rows_;
    Smooth(false);
    return Emit();
  }
  return Status::Ok();
}

Status RowPipeline::Finish() {
  finished_ = true;
  if (pushed_ == 0) return Status::Ok();
  Smooth(true);
  return Emit();
}

// SmoothLocalQuadratic on the rows held: the value of sample i depends only on the samples within
// +-window/2 of it (its [lo, hi) in smoothing.cc), so it is the whole log's value when the block
// starts at or before its window (kept below) and ends after it, or at the log's end.
void RowPipeline::Smooth(bool last_block) {
  if (window_time_s_.empty()) return;
  const std::vector<double> smoothed =
      SmoothLocalQuadratic(window_time_s_, window_position_m_, smoothing_s_);
  const double half = 0.5 * smoothing_s_;
  const double last_time = window_time_s_.back();
  while (smoothed_ < pushed_) {
    const auto k = static_cast<std::size_t>(smoothed_ - window_start_);
    if (!last_block && !(last_time - window_time_s_[k] > half)) break;
    rows_[static_cast<std::size_t>(smoothed_ - base_)].smoothed_m = smoothed[k];
    if (smoothed_ == 0) first_ = rows_.front();
    ++smoothed_;
  }
  // Keep what the next sample's window reaches back to.
  std::size_t drop = 0;
  if (smoothed_ < pushed_) {
    const double t_next = window_time_s_[static_cast<std::size_t>(smoothed_ - window_start_)];
    while (t_next - window_time_s_[drop] > half) ++drop;
  } else {
    drop = window_time_s_.size();
  }
  window_time_s_.erase(window_time_s_.begin(), window_time_s_.begin() + drop);
  window_position_m_.erase(window_position_m_.begin(), window_position_m_.begin() + drop);
  window_start_ += static_cast<long>(drop);
}

double RowPipeline::Interpolate(double t, double Entry::*value) const {
  const Entry& last = rows_.back();
  if (t <= first_.row.time_s) return first_.*value;
  if (t >= replay_->end_time_s) {
    MPDRIG_CHECK(last.row.time_s == replay_->end_time_s);
    return last.*value;
  }
  // The bracket time[j - 1] <= t < time[j]; requests move forward, so start at the last one.
  std::size_t j = std::min(std::max<std::size_t>(hint_, 1), rows_.size() - 1);
  while (j > 1 && rows_[j - 1].row.time_s > t) --j;
  while (j < rows_.size() && rows_[j].row.time_s <= t) ++j;
  MPDRIG_CHECK(j < rows_.size() && rows_[j - 1].row.time_s <= t &&
               static_cast<long>(j) + base_ < smoothed_);
  hint_ = j;
  const Entry& a = rows_[j - 1];
  const Entry& b = rows_[j];
  return InterpolateLinear(t, a.row.time_s, a.*value, b.row.time_s, b.*value);
}

double RowPipeline::InterpolateRow(double t, double LogRow::*value) const {
  // Same bracket and formula as Interpolate, on a raw input.
  const Entry& last = rows_.back();
  if (t <= first_.row.time_s) return first_.row.*value;
  if (t >= replay_->end_time_s) {
    MPDRIG_CHECK(last.row.time_s == replay_->end_time_s);
    return last.row.*value;
  }
  std::size_t j = std::min(std::max<std::size_t>(hint_, 1), rows_.size() - 1);
  while (j > 1 && rows_[j - 1].row.time_s > t) --j;
  while (j < rows_.size() && rows_[j].row.time_s <= t) ++j;
  MPDRIG_CHECK(j < rows_.size() && rows_[j - 1].row.time_s <= t);
  hint_ = j;
  const LogRow& a = rows_[j - 1].row;
  const LogRow& b = rows_[j].row;
  return InterpolateLinear(t, a.time_s, a.*value, b.time_s, b.*value);
}

// As SimulateEach's step inputs (PistonVelocityAtStepEnd: the same window, slid inside the log).
StepInputs RowPipeline::StepInputsAt(double t_b, double dt) const {
  StepInputs step;
  step.piston_velocity_mps =
      PistonVelocityAtStepEnd(t_b, dt, first_.row.time_s, replay_->end_time_s,
                              [this](double t) { return Interpolate(t, &Entry::smoothed_m); });
  step.piston_position_m = Interpolate(t_b, &Entry::smoothed_m);
  step.rig.choke_opening_frac = InterpolateRow(t_b, &LogRow::choke_opening_frac);
  step.rig.pump_flow_m3ps = InterpolateRow(t_b, &LogRow::pump_flow_m3ps);
  step.rig.outlet_pressure_pa = InterpolateRow(t_b, &LogRow::outlet_pressure_pa);
  return step;
}

Status RowPipeline::Emit() {
  while (emitted_ < smoothed_ && !stop_requested_) {
    const long i = emitted_;
    const Entry& entry = At(i);
    if (replay_ && !sampler_) {
      // The initial steady state from the inputs' mean over the log's first
      // kInitialInputWindowS (log_inputs.h), not from its first, noisy row. Every row of the
      // first smoothing block is still held here, and that block spans the window unless the
      // log is sampled above 8 kHz (then the rows it has).
      InitialInputs initial;
      for (const Entry& held : rows_) {
        if (held.row.time_s > first_.row.time_s + kInitialInputWindowS) break;
        initial.Add(held.row.time_s, {held.row.choke_opening_frac, held.row.pump_flow_m3ps,
                                      held.row.outlet_pressure_pa});
      }
      auto simulator = replay_->warmup
                           ? CreateWarmedUp(replay_->params, replay_->options, first_.row.time_s,
                                            *replay_->warmup)
                           : RigSimulator::Create(replay_->params, replay_->options, initial.Mean(),
                                                  first_.smoothed_m, first_.row.time_s);
      if (!simulator.ok()) return simulator.status();
      MPDRIG_CHECK(!(replay_->warmup && replay_->profile));
      if (replay_->profile) MPDRIG_RETURN_IF_ERROR(simulator->SetPipeProfile(*replay_->profile));
      sampler_.emplace(std::move(simulator).value());
    }
    // Everything the step inputs up to row i can reach (one step and a half past it) must be
    // smoothed, and the next row for the centred difference.
    if (!finished_) {
      const double reach_s = sampler_ ? 2.0 * sampler_->simulator().time_step_s() : 0.0;
      if (!(smoothed_ > i + 1 && At(smoothed_ - 1).row.time_s > entry.row.time_s + reach_s)) break;
    }
    const long a = i == 0 ? 0 : i - 1;
    const long b = finished_ && i + 1 == pushed_ ? i : i + 1;
    PipelineSample sample;
    sample.index = i;
    sample.row = &entry.row;
    sample.piston_position_m = entry.smoothed_m;
    sample.piston_velocity_mps =
        (At(b).smoothed_m - At(a).smoothed_m) / (At(b).row.time_s - At(a).row.time_s);
    std::optional<RigSample> model;
    if (sampler_) {
      auto sampled = sampler_->SampleAt(
          entry.row.time_s, [this](double t_b, double dt) { return StepInputsAt(t_b, dt); });
      if (!sampled.ok()) return sampled.status();
      model = std::move(sampled).value();
      sample.model = &*model;
    }
    sink_(sample);
    ++emitted_;
    // Drop rows nobody reaches back to: the centred difference needs row i - 1, the step
    // inputs nothing before the solver's time minus one step.
    const double keep_from_s =
        sampler_ ? sampler_->simulator().time_s() - 2.0 * sampler_->simulator().time_step_s()
                 : entry.row.time_s;
    while (rows_.size() > 2 && base_ < emitted_ - 1 && rows_[1].row.time_s <= keep_from_s) {
      rows_.pop_front();
      ++base_;
      if (hint_ > 1) --hint_;
    }
  }
  return Status::Ok();
}

Status RunPipeline(LogRowSource* source, RowPipeline* pipeline) {
  LogRow row;
  while (true) {
    auto more = source->Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    MPDRIG_RETURN_IF_ERROR(pipeline->Push(row));
    if (pipeline->stopped()) return Status::Ok();
  }
  return pipeline->Finish();
}

}  // namespace mpdrig
