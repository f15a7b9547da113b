// The model run beside a rig, in step with it (`mpdrig shadow`): each measured sample's inputs
// (piston position, choke position, FT2, C1) drive the model as a replayed log's do
// (RowPipeline), and the model's channels are compared with the measured ones over a sliding window
// with compare's metrics (compare.h):
//   NRMSE_k = ||y_k - yhat_k|| / ||y_k - mean(y_k)||   over the window, per compared channel,
//   error   = mean of the defined NRMSE_k                (as compare's `error`).
//
// Errors in variables: the inputs are measurements, as noisy as the outputs (thesis Table 4.1.1),
// and the choke's steep law turns the choke's and FT2's noise into pressure noise several times
// the transmitters' own. By default (reconstruct_inputs) the shadow runs lookahead_s behind the
// rig and feeds the model the inputs reconstructed as compare does (InputReconstruction,
// model/sim/log_inputs.h): a delayed, two-sided reconstruction over the rows held, whose windows
// reach back over the held rows and ahead over the look-ahead. The plan (each input's noise, the
// piston's band) is made from the first plan_s of rows; the level windows reach back at most
// reach_back_s (the rows held for it) and ahead the look-ahead. Each row is reconstructed once,
// when first fed, so a replay after a change feeds the very inputs the live model had (the error
// after a change compares with the one before). Without reconstruction the inputs are used as
// measured, the piston smoothed over smoothing_s before it is differentiated, with no delay.
//
// A change to the model (an effect on or off, a parameter) replays the rows held from the last
// warmup_s + window_s with the new model, so its error over the window is known at once, as if
// it had run all along: the replay starts from the steady state of those rows' inputs, and its
// first warmup_s (the pipe's acoustic transient, kReplayWarmupS) are not counted. The same holds
// when the shadow starts: no error until warmup_s of rows have passed.
// Transport-free: samples in, samples and metrics out; time is the samples' own.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "model/analysis/log_stream.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

struct ShadowOptions {
  SimulationOptions simulation;
  double window_s = 10.0;            // the error's sliding window
  double warmup_s = kReplayWarmupS;  // model output not compared after a (re)start
  double smoothing_s = 0.05;         // piston smoothing (compare's --piston-smoothing-s)
  long smoothing_block_rows = 8;     // latency of the model behind the rig: this many rows
  // Reconstruct the inputs under their noise (false: replay them as measured, the piston smoothed
  // over smoothing_s).
  bool reconstruct_inputs = true;
  double lookahead_s = 5.0;    // the model runs this far behind the rig (reconstructed inputs)
  double plan_s = 10.0;        // rows held before the first plan of the reconstruction
  double block_s = 0.25;       // the reconstruction runs on blocks of this much rig time
  double reach_back_s = 20.0;  // the level windows' longest reach back (rows held for it)
  // Rows held at least this long (for a fit on the last minutes, HeldLog); a change replays only
  // the warm-up and the window of them.
  double history_s = 0.0;

  Status Validate() const;
};

// One model sample, at a measured sample's time.
struct ShadowPoint {
  double time_s = 0.0;
  RigSample model;
};

class ShadowModel {
 public:
  static Result<std::unique_ptr<ShadowModel>> Create(RigParams params, ShadowOptions options);
  ShadowModel(const ShadowModel&) = delete;
  ShadowModel& operator=(const ShadowModel&) = delete;

  // A measured sample: SI, absolute pressure, NaN where not measured. A sample without a
  // measured piston or choke position is skipped (the model cannot run on a gap) and counted; a
  // sample at or before the last one's time (the rig restarted, a playback looped) starts the
  // shadow afresh. Fails only when the model fails.
  Status Push(const RigSample& measured);
  // The model samples computed since the last call (they lag the measured ones by the
  // smoothing window and a block of rows).
  std::vector<ShadowPoint> TakeOutput();

  // The error over the window (NaN while warming up or without a defined channel), and each
  // compared channel's NRMSE there (NaN where undefined), in ComparedChannels() order.
  double error() const;
  std::vector<std::pair<Channel, double>> ChannelNrmse() const;
  // The model's samples in the window so far.
  std::size_t window_samples() const { return window_.size(); }

  const RigParams& params() const { return params_; }
  const ShadowOptions& options() const { return options_; }
  // Runs the held rows again with `params` (checked first: a bad one changes nothing).
  Status SetParams(RigParams params);
  // Forgets every row: the model starts again from the next sample.
  void Reset();

  // The rows held from the last span_s (as measured; ReconstructInputs planned on them) as a log
  // in memory, for a fit on them. Fails with fewer than 4 rows or no compared channel measured.
  Result<MeasuredLog> HeldLog(double span_s) const;
  // Rig time spanned by the rows held.
  double held_span_s() const {
    return history_.empty() ? 0.0 : history_.back().time_s - history_.front().time_s;
  }

  double last_time_s() const { return last_time_s_; }
  long skipped_samples() const { return skipped_; }

 private:
  ShadowModel(RigParams params, ShadowOptions options);
  Status Rebuild();
  void Take(const PipelineSample& sample);
  // The held rows' inputs as columns, indices [first, end).
  LogInputColumns HeldColumns(std::size_t first, std::size_t end = SIZE_MAX) const;
  // Feeds the pipeline the held rows up to `until_s` (reconstructed where planned).
  Status FeedUntil(double until_s);
  bool Reconstructing() const { return options_.reconstruct_inputs; }

  struct WindowEntry {
    double time_s;
    std::array<double, kComparedChannelCount> measured, model;
  };

  RigParams params_;
  ShadowOptions options_;
  std::vector<Channel> channels_;  // ComparedChannels()
  std::deque<LogRow> history_;
  std::unique_ptr<RowPipeline> pipeline_;
  std::optional<InputReconstruction> plan_;  // made once plan_s of rows are held
  double fed_until_s_ = -1.0e300;            // the last row fed to the pipeline
  // Rows of history_ up to this time hold their reconstructed inputs (measured_inputs: raw).
  double reconstructed_until_s_ = -1.0e300;
  double start_time_s_ = 0.0;  // the pipeline's first row
  bool replaying_ = false;     // Rebuild is feeding held rows: no output
  std::deque<WindowEntry> window_;
  std::vector<ShadowPoint> output_;
  double last_time_s_ = -1.0e300;
  long skipped_ = 0;
};

}  // namespace mpdrig
