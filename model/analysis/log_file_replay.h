// The model replayed on a rig-log file's inputs, every channel at every row, in memory that does
// not grow with the log (`mpdrig simulate --inputs`): the streamed twin of Simulate on
// SignalsFromColumns after PrepareLogReplay (log_inputs.h, log_replay.h), which holds the whole log
// (about 520 bytes a row: 522 MB for 1e6 rows at 16 channels).
//
// Two passes over the file, as CompareLog's (compare.h):
//   1. Prepare reads and checks every row (a bad line fails before any output) and keeps the
//      first kReconstructionPlanSamples rows: the reconstruction's plan, the replay's start
//      (ChooseReplayStart) and input levels (EstimateInputLevels) are decided on them, as
//      PrepareLogReplay decides them on the whole log.
//   2. Run reads the rows again through ReconstructingRowSource and RowPipeline (log_stream.h),
//      which give the same doubles as the whole log in memory, and hands each row's RigSample to
//      a sink as it comes.
// tests/model/analysis/log_file_replay_test.cc holds the two replays together, sample for sample.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "model/analysis/log_stream.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// The replay's start (ChooseReplayStart, where replay->choose_warmup) and input levels
// (EstimateInputLevels where `plan` is set and replay->estimate_levels: into the plan's levels and
// the warm-up), decided on a file's first rows held by `head`, as PrepareLogReplay decides them on
// the whole log in memory. `channels`: the file's compared channels (LogRowSource::channels()).
Status PrepareStreamedReplay(const ReconstructionPlanner& head,
                             const std::vector<SourceChannel>& channels, const std::string& path,
                             double atmospheric_pressure_pa, const RigParams& params,
                             const SimulationOptions& sim_options, InputReplayOptions* replay,
                             std::optional<InputReconstruction>* plan);

class LogFileReplay {
 public:
  // Pass 1. `replay.choose_warmup` and `replay.estimate_levels` apply where the file has a
  // measured compared channel and at least 4 rows (as simulate --inputs always did: a log of
  // inputs alone starts from the steady state at its levels as reconstructed). Errors name the
  // file, line and column.
  static Result<LogFileReplay> Prepare(const std::string& path, const RigParams& params,
                                       const SimulationOptions& sim_options,
                                       const InputReplayOptions& replay,
                                       const riglog::ReadOptions& read = {});

  // Pass 2: every row's sample to `sink`, in order; `progress` (if given) gets the share of the
  // log's time span done, every 5 %, as SimulateEach's. Fails on a replay failure (the model's
  // range: Status::Code::kModelRange), or if the file changed since Prepare.
  Result<RunSummary> Run(const std::function<void(const RigSample&)>& sink,
                         const std::function<void(double)>& progress = {}) const;

  double atmospheric_pressure_pa() const { return atmospheric_pressure_pa_; }
  double start_s() const { return start_s_; }
  double end_s() const { return end_s_; }
  long rows() const { return rows_; }
  // The options the replay runs with: the chosen warm-up, if any.
  const InputReplayOptions& replay() const { return replay_; }
  // The reconstruction (with its level correction) where the inputs are reconstructed.
  const std::optional<InputReconstruction>& reconstruction() const { return plan_; }
  // Whether the start and the levels were decided from the log's pressures (see Prepare).
  bool prepared_from_measurements() const { return prepared_; }

 private:
  LogFileReplay() = default;
  std::string path_;
  RigParams params_;
  SimulationOptions sim_options_;
  InputReplayOptions replay_;
  riglog::ReadOptions read_;
  std::optional<InputReconstruction> plan_;
  double atmospheric_pressure_pa_ = 0.0;
  double start_s_ = 0.0;
  double end_s_ = 0.0;
  long rows_ = 0;
  bool prepared_ = false;
};

}  // namespace mpdrig
