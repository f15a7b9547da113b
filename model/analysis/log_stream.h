// A rig log as a stream of rows for the comparison (compare.h) and the replay (log_replay.h), in
// memory that does not grow with the log's length: rows come from a file (RigLogReader, one line
// at a time) or from a log already in memory (measured_log.h), go through the piston-position
// smoothing and, if asked, through the model replay, and leave in order, one at a time, with what
// the metrics need of each sample.
//
// RowPipeline reproduces `Simulate` on a log's inputs exactly (SignalsFromColumns + SimulateEach,
// model/sim): the same smoothing (SmoothLocalQuadratic, model/signal, run on blocks that hold
// every sample of each smoothed sample's window, so each value is the same double), the same
// linear interpolation of the inputs between samples (InterpolateLinear, log_inputs.h), the same
// initial state (InitialInputs, log_inputs.h), the same piston velocity at each step end (centred
// difference over one solver step, one-sided at the log's ends) and the same RigSampler.
// It keeps only a lookahead window: the smoothing window and two solver steps beyond the sample
// it hands out, plus one smoothing block (4096 samples).
//
// Two replays of a log, on purpose. Simulate on SignalsFromColumns is the reference (synthetic
// logs, the tests): the whole log in memory as time functions, which SimulateEach may ask at any
// time. RowPipeline is its streaming twin (compare, fit, diagnose, the shadow, and `mpdrig
// simulate --inputs` through LogFileReplay, log_file_replay.h). Neither can be written through the
// other: the reference lies in model/sim, below this folder in model/'s layer order, and a stream
// of rows cannot answer a time function; the other way, time functions hold every input column
// whole (at least 40 bytes a row: 144 MB for an hour at 1 kHz, where the stream holds a few
// thousand rows). What they can share they share (the smoothing, the reconstruction, InitialInputs,
// InterpolateLinear, the piston velocity's window PistonVelocityAtStepEnd); each still repeats by
// hand the bracket search between samples. tests/model/analysis/compare_test.cc holds them
// together: ReplayGivesExactlyWhatSimulateGives (the same doubles) and
// ReplayStartsFromTheMeanOfTheFirstInputs (the same start), and log_file_replay_test.cc every
// channel of simulate --inputs. A change to one is a change to both.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// P1 P2 PT1..PT10 C2 FT1 FT3 FT4 (ComparedChannels()).
inline constexpr std::size_t kComparedChannelCount = 16;

// One sample of a log: the inputs in SI (absolute pressure) and the compared channels the source
// has (LogRowSource::channels(), in that order; NaN where not measured).
struct LogRow {
  double time_s = 0.0;
  double piston_position_m = 0.0;  // as measured (not smoothed)
  double choke_opening_frac = 0.0;
  double pump_flow_m3ps = 0.0;
  double outlet_pressure_pa = 0.0;
  std::array<double, kComparedChannelCount> measured_si{};
  // The inputs as measured (piston, choke, pump, outlet), where the four above are reconstructed;
  // the same values otherwise.
  std::array<double, 4> measured_inputs{};
};

struct SourceChannel {
  Channel channel = Channel::kP1;
  riglog::Unit unit = riglog::Unit::kBarg;
};

class LogRowSource {
 public:
  virtual ~LogRowSource() = default;
  // The compared channels each row carries, in the order of ComparedChannels().
  virtual const std::vector<SourceChannel>& channels() const = 0;
  // The next row; false at the end. Errors name the file, line and column.
  virtual Result<bool> Next(LogRow* row) = 0;
};

// Streams a rig-log file. Open() refuses a header without piston_position or choke_position;
// Next() a row whose input is not measured (the model cannot run on a gap). FT2 absent is 0,
// C1 absent is atmospheric. `progress` gets ("read", fraction of the file's bytes) every percent,
// or ("read", -samples) every 100 000 samples from standard input ("-").
class FileRowSource final : public LogRowSource {
 public:
  // `read`: the reader's limits on the time axis (rig_log_reader.h).
  static Result<std::unique_ptr<FileRowSource>> Open(const std::string& path,
                                                     const CompareProgress& progress = {},
                                                     const riglog::ReadOptions& read = {});
  const std::vector<SourceChannel>& channels() const override { return channels_; }
  Result<bool> Next(LogRow* row) override;
  const riglog::Metadata& metadata() const { return reader_.metadata(); }
  double atmospheric_pressure_pa() const { return reader_.atmospheric_pressure_pa(); }

 private:
  explicit FileRowSource(riglog::RigLogReader reader) : reader_(std::move(reader)) {}
  void ReportProgress();
  riglog::RigLogReader reader_;
  std::istream* stream_ = nullptr;  // owned by reader_; null when reading standard input
  double file_size_ = 0.0;
  std::string path_;
  CompareProgress progress_;
  std::size_t piston_ = 0, choke_ = 0;
  std::optional<std::size_t> pump_, outlet_;
  std::vector<std::size_t> compared_columns_;  // reader column of each channels_ entry
  std::vector<SourceChannel> channels_;
  std::vector<double> values_;
  double next_report_ = 0.0;
};

// Which of a MeasuredLog's inputs a MemoryRowSource hands out.
enum class InputView { kMeasured, kReconstructed };

// Rows of a log in memory (a MeasuredLog; it must outlive the source).
class MemoryRowSource final : public LogRowSource {
 public:
  explicit MemoryRowSource(const MeasuredLog& log, InputView view = InputView::kMeasured);
  const std::vector<SourceChannel>& channels() const override { return channels_; }
  Result<bool> Next(LogRow* row) override;

 private:
  const MeasuredLog& log_;
  const LogInputColumns& inputs_;
  std::vector<SourceChannel> channels_;
  std::size_t next_ = 0;
};

// Collects the first kReconstructionPlanSamples rows of a stream and plans their reconstruction
// (PlanInputReconstruction): the same plan as for the whole log in memory. It keeps the
// reconstruction's longest reach beyond them (kPlannerMarginSamples), so that the head's
// reconstructed inputs are the whole log's, not a log cut there (whose last rows' windows are
// one-sided): the start and the levels decided on the head (ChooseReplayStart, EstimateInputLevels)
// are then those decided on the whole log, to the last bit.
class ReconstructionPlanner {
 public:
  // The most rows any reconstructed value reaches ahead (InputReconstruction: the level windows
  // and the piston's), and one more.
  static constexpr std::size_t kPlannerMarginSamples =
      static_cast<std::size_t>(kMaxLevelHalfWidthSamples) +
      static_cast<std::size_t>(kMaxPistonHalfWidthSamples) + 1;
  void Add(const LogRow& row);
  InputReconstruction Plan() const { return PlanInputReconstruction(head_); }
  // The rows collected, reconstructed, as a log in memory (for ChooseReplayStart and
  // EstimateInputLevels, which take its first kReconstructionPlanSamples rows): `channels` as the
  // source's.
  Result<MeasuredLog> HeadLog(const std::vector<SourceChannel>& channels, const std::string& path,
                              double atmospheric_pressure_pa) const;

 private:
  LogInputColumns head_;
  std::vector<std::array<double, kComparedChannelCount>> measured_;
};

// Another source's rows with their inputs reconstructed (ReconstructInputBlock), in blocks of
// 4096 rows or four level reaches with the reconstruction's reach as margin on each side (the
// piston's half width in time, the level windows in rows) and the level inputs' running sums
// carried from the first row: the same doubles as reconstructing the whole log, in memory that does
// not grow with it.
class ReconstructingRowSource final : public LogRowSource {
 public:
  ReconstructingRowSource(std::unique_ptr<LogRowSource> source, InputReconstruction plan);
  const std::vector<SourceChannel>& channels() const override { return source_->channels(); }
  Result<bool> Next(LogRow* row) override;

 private:
  struct Held {
    LogRow row;
    RunningSum choke, pump, outlet;  // the level inputs' running sums before this row
  };
  void ReconstructHeld(bool last_block);
  std::unique_ptr<LogRowSource> source_;
  InputReconstruction plan_;
  std::deque<Held> held_;    // raw rows: the margin behind, the pending ones, the margin ahead
  long front_index_ = 0;     // the log row index of held_.front()
  std::size_t pending_ = 0;  // index in held_ of the first row not yet reconstructed
  RunningSums choke_sums_, pump_sums_, outlet_sums_;
  std::deque<LogRow> ready_;  // reconstructed, to hand out
  bool source_done_ = false;
};

// What the pipeline hands out for each row, in order.
struct PipelineSample {
  long index = 0;
  const LogRow* row = nullptr;
  double piston_position_m = 0.0;    // smoothed, as the model is fed
  double piston_velocity_mps = 0.0;  // centred difference of the smoothed position (one-sided
                                     // at the ends), for the residual analysis
  const RigSample* model = nullptr;  // the model at row->time_s; null without replay
};

// The model side of a pipeline: what SimulateEach would be given.
struct ReplaySetup {
  RigParams params;
  SimulationOptions options;
  double end_time_s = 0.0;  // the log's last time: the piston velocity is one-sided there
  std::optional<PeriodicWarmup> warmup;  // as SimulateEach with InputSignals::warmup
  std::optional<PipeProfile> profile;    // as SimulateEach with InputSignals::profile
};

class RowPipeline {
 public:
  using Sink = std::function<void(const PipelineSample&)>;
  // smoothing_s: the piston smoothing window (ReplayOptions::piston_smoothing_s). Without
  // `replay` the rows pass with their smoothed piston only. The smoothing runs on blocks of
  // `smoothing_block_rows` rows: the default suits a file (few calls, the same doubles); a live
  // replay (the shadow model beside a running rig) wants a few rows, so its model stays within
  // the smoothing window and a block of the newest row. The smoothed values are the same either
  // way; the initial steady state averages the rows of the first kInitialInputWindowS held at
  // the first emission, which a short block may cut shorter.
  RowPipeline(double smoothing_s, std::optional<ReplaySetup> replay, Sink sink,
              long smoothing_block_rows = kDefaultSmoothingBlockRows);
  static constexpr long kDefaultSmoothingBlockRows = 4096;
  RowPipeline(const RowPipeline&) = delete;
  RowPipeline& operator=(const RowPipeline&) = delete;

  // Rows in order (strictly increasing time). Fails only on a replay failure.
  Status Push(const LogRow& row);
  // After the last row: hands out the rest.
  Status Finish();
  // Hands out no more samples, from the sample after the one the sink is handling (the sink may
  // call it): the rest of the replay is not run. Push and Finish then only take rows.
  void RequestStop() { stop_requested_ = true; }
  bool stopped() const { return stop_requested_; }
  long rows_pushed() const { return pushed_; }
  // The replay, once it has started.
  const RigSampler* sampler() const { return sampler_ ? &*sampler_ : nullptr; }

 private:
  struct Entry {
    LogRow row;
    double smoothed_m = 0.0;
  };
  void Smooth(bool last_block);
  Status Emit();
  const Entry& At(long index) const { return rows_[static_cast<std::size_t>(index - base_)]; }
  // The inputs between samples, linear in time, held beyond the ends (SharedInputs::At).
  double Interpolate(double t, double Entry::*value) const;
  double InterpolateRow(double t, double LogRow::*value) const;
  StepInputs StepInputsAt(double step_end_s, double dt_s) const;

  double smoothing_s_;
  std::optional<ReplaySetup> replay_;
  Sink sink_;
  std::deque<Entry> rows_;  // indices base_ .. pushed_ - 1
  long base_ = 0;
  long pushed_ = 0;
  long smoothed_ = 0;  // rows 0 .. smoothed_ - 1 have smoothed_m
  long emitted_ = 0;
  long smoothing_block_rows_;
  long next_smoothing_;  // rows pushed at the next block
  bool finished_ = false;
  bool stop_requested_ = false;
  std::vector<double> window_time_s_, window_position_m_;  // raw piston, from window_start_
  long window_start_ = 0;
  Entry first_;
  std::optional<RigSampler> sampler_;
  mutable std::size_t hint_ = 1;  // bracket search cache (relative to rows_)
};

// Pulls every row of `source` through `pipeline` (until its sink asks it to stop).
Status RunPipeline(LogRowSource* source, RowPipeline* pipeline);

// The pipeline's own piston smoothing for a replay fed as `replay` says: none on reconstructed
// inputs (already smoothed).
inline double PipelineSmoothingS(const InputReplayOptions& replay) {
  return replay.reconstruct_inputs ? 0.0 : replay.piston_smoothing_s;
}

// Reports `stage` at every whole percent of `total` samples.
class PercentProgress {
 public:
  PercentProgress(const CompareProgress& progress, std::string_view stage, long total)
      : progress_(progress), stage_(stage), total_(std::max(1L, total)) {}
  void Done(long samples) {
    if (!progress_ || samples < next_) return;
    progress_(stage_, static_cast<double>(samples) / static_cast<double>(total_));
    next_ = (samples * 100 / total_ + 1) * total_ / 100;
  }

 private:
  const CompareProgress& progress_;
  std::string_view stage_;
  long total_;
  long next_ = 0;
};

}  // namespace mpdrig
