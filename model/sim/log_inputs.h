// A rig log's inputs as the simulator's time functions (design.md, "Replaying a log"), shared by
// `mpdrig simulate --inputs` and `mpdrig compare`.
//
// Inputs (rig-log-format.md): piston_position and choke_position are required and must be
// measured (finite) on every row; FT2 (pump flow q_b) and C1 (outlet pressure p_0) are optional:
// absent means 0 and atmospheric, present means measured on every row. Every input is a noisy
// measurement (errors in variables): by default a replay first reconstructs the inputs under the
// noise (InputReconstruction below, model/signal/input_reconstruction.h), with the noise levels
// and the piston's band estimated from the log itself. Without it (`--raw-inputs`) the inputs are
// used as measured, but for the piston position, smoothed by a local quadratic fit over
// `piston_smoothing_s` before the simulator differentiates it. The choke position is the opening
// (ChokeInput::kMeasured). Between samples every input is linear in time, beyond the ends held.
// The replay starts from the steady state (5.3.2) of the inputs' mean over the log's first
// kInitialInputWindowS, not of its first row: one noisy sample of FT2 (0.4 % of 8 L/min) would
// set the initial pressure 0.06 bar off, and that offset decays only at the pipe friction's rate
// (seconds), so a fit would bend f1 to follow the noise of one sample.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/rig_log.h"
#include "model/signal/input_reconstruction.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// Window over which a replay averages the log's rig inputs for its initial steady state.
inline constexpr double kInitialInputWindowS = 0.5;

// The mean of a log's rig inputs over its first kInitialInputWindowS: what every replay (Simulate
// on SignalsFromColumns, compare's RowPipeline) starts its steady state from. Rows in time order;
// those past the window are ignored.
class InitialInputs {
 public:
  void Add(double time_s, const RigInputs& row);
  RigInputs Mean() const;  // after at least one row

 private:
  double first_time_s_ = 0.0;
  long count_ = 0;
  RigInputs sum_{0.0, 0.0, 0.0};
};

// An input between two samples (t_a, a) and (t_b, b), t_a <= t < t_b: linear in time. The one
// formula of both replays of a log (SignalsFromColumns, RowPipeline), so they give the same
// doubles.
inline double InterpolateLinear(double t, double t_a, double a, double t_b, double b) {
  const double w = (t - t_a) / (t_b - t_a);
  return (1.0 - w) * a + w * b;
}

// How a replay feeds a log's inputs to the model.
struct InputReplayOptions {
  // Reconstruct the inputs under their measurement noise (InputReconstruction); false: as measured.
  bool reconstruct_inputs = true;
  // Without reconstruction: the window of the local quadratic that smooths the measured piston
  // position before it is differentiated (0: none).
  double piston_smoothing_s = 0.05;
  // Start after this warm-up instead of from the steady state: for a log that starts in the middle
  // of a periodic excitation (PlanPeriodicWarmup; ChooseWarmup in model/analysis/log_replay.h
  // decides from the measured pressures).
  std::optional<PeriodicWarmup> warmup;
  // Start from this state of the pipe instead (not with a warm-up): for a log that starts in the
  // middle of an excitation that is not periodic (EstimatePipeProfile and ChooseReplayStart in
  // model/analysis/log_replay.h).
  std::optional<PipeProfile> profile;
  // Commands that have the measured log let ChooseReplayStart set `warmup` or `profile`; false:
  // always the steady state.
  bool choose_warmup = true;
  // Commands that have the measured log correct the reconstructed choke and FT2 levels from the
  // measured pressures (EstimateInputLevels); false: the levels as reconstructed.
  bool estimate_levels = true;
};

// The input columns of a log, SI, one value per row of `time_s`.
struct LogInputColumns {
  std::vector<double> time_s;
  std::vector<double> piston_position_m;   // as measured (not smoothed)
  std::vector<double> choke_opening_frac;  // u_c
  std::vector<double> pump_flow_m3ps;      // q_b (FT2), 0 if the log has none
  std::vector<double> outlet_pressure_pa;  // p_0 (C1), absolute; atmospheric if the log has none
};

// How a log's inputs are reconstructed: each input's white-noise level and the piston's band,
// estimated from the log's first kReconstructionPlanSamples samples (all of a log up to 11 min at
// 100 Hz; a longer one is assumed to keep its noise and band), and the smoothers' windows that
// follow from them (model/signal/input_reconstruction.h):
// - piston position: tricube local quadratic passing its highest carried frequency with < 0.1 %
//   loss (one window: position and velocity stay consistent);
// - choke opening, pump flow, outlet pressure: LPA-ICI local linear fits, left, right and centred,
//   windows doubling from 2 samples to level_max_half_width_samples (steps stay sharp).
// An input whose noise is 0 (or that is absent: FT2, C1) passes unchanged.
inline constexpr std::size_t kReconstructionPlanSamples = 65536;
// The level windows: up to kMaxLevelHalfWidthS on a side, and at most this many samples (the
// window sums are O(1), so the cap is about the sums' segments, kSumSegmentSamples).
inline constexpr double kMaxLevelHalfWidthS = 40.0;
inline constexpr long kMaxLevelHalfWidthSamples = 8192;
// The piston's window: at most this many samples on a side (its cost grows with it; a 0.2 Hz
// heave at 100 Hz wants 57).
inline constexpr double kMaxPistonHalfWidthSamples = 256;

// The choke's and FT2's levels, corrected from the measured pressures (EstimateInputLevels in
// model/analysis/log_replay.h). Reconstructed, a flat input still errs by about sigma / sqrt(N)
// over its windows, more near the log's ends where the windows are one-sided (0.003-0.01 L/min of
// FT2 at 100 Hz), and through the choke's steady law (dp/p = 2 dq/q; G steep at small openings)
// that moves every pipe pressure by 0.01-0.05 bar: a channel that swings little (PT4 at 0.33 Hz and
// 28 deg, PT5 near the half-wave resonance) then fits several points worse than the same model fed
// the true inputs. The pressures know the level far better (0.024 bar per sample on a dozen
// channels), so the correction, a mean and a linear trend over the log's head, is the maximum a
// posteriori estimate under both (the reconstruction's own error as the prior), bounded by
// kMaxLevelOffsetSigmas of that prior: an offset the inputs' noise cannot explain is the model's to
// show, not the replay's to hide.
inline constexpr double kMaxLevelOffsetSigmas = 3.0;

struct InputLevelCorrection {
  // Added to the reconstructed choke opening and FT2 at time t:
  // offset + trend * tau, tau = (t - center_s) / half_span_s held within [-1, 1].
  double choke_offset_frac = 0.0;
  double pump_offset_m3ps = 0.0;
  double choke_trend_frac = 0.0;
  double pump_trend_m3ps = 0.0;
  double center_s = 0.0;
  double half_span_s = 0.0;
  // The prior standard deviations: of each input's mean (sigma / sqrt N) and of its trend (the
  // one-sided windows' error at the ends, 2 sigma / sqrt W).
  double choke_sigma_frac = 0.0;
  double pump_sigma_m3ps = 0.0;
  double choke_trend_sigma_frac = 0.0;
  double pump_trend_sigma_m3ps = 0.0;
  // The mean pressure residual (measured - model) over the pressure channels, and its trend (at
  // tau = 1), before and after (as predicted by the steady law's sensitivities).
  double residual_before_pa = 0.0;
  double residual_after_pa = 0.0;
  double residual_trend_before_pa = 0.0;
  double residual_trend_after_pa = 0.0;
  bool at_bound = false;  // a term was clipped to kMaxLevelOffsetSigmas
  bool applied() const {
    return choke_offset_frac != 0.0 || pump_offset_m3ps != 0.0 || choke_trend_frac != 0.0 ||
           pump_trend_m3ps != 0.0;
  }
  double Tau(double t) const;  // 0 without a span
  double ChokeAt(double t) const { return choke_offset_frac + choke_trend_frac * Tau(t); }
  double PumpAt(double t) const { return pump_offset_m3ps + pump_trend_m3ps * Tau(t); }
  // One line for a person, in lab units.
  std::string Describe() const;
};

struct InputReconstruction {
  double sample_interval_s = 0.0;  // median interval of the plan's samples
  double piston_noise_m = 0.0;     // white-noise standard deviations, as estimated
  double choke_noise_frac = 0.0;
  double pump_noise_m3ps = 0.0;
  double outlet_noise_pa = 0.0;
  double piston_band_hz = 0.0;            // highest frequency the piston carries above its noise
  double piston_half_width_s = 0.0;       // 0: the piston passes unchanged
  long level_max_half_width_samples = 0;  // ICI's longest window for choke, pump, outlet
  // Added to the reconstructed choke and FT2 levels (none until EstimateInputLevels sets it).
  InputLevelCorrection levels;
  // How far from a sample the samples it depends on lie: within the piston's half width in time
  // and within the level windows' in samples.
  long level_reach_samples() const { return level_max_half_width_samples; }
  // One line for a person, in lab units.
  std::string Describe() const;
};

// The plan from the first kReconstructionPlanSamples rows of `columns` (fewer if it has fewer).
InputReconstruction PlanInputReconstruction(const LogInputColumns& columns);

// The reconstructed columns (same times), with plan.levels added (the choke kept within [0, 1],
// FT2 at or above 0). Each value depends only on the samples within plan.piston_half_width_s and
// plan.level_reach_samples() of it.
LogInputColumns ReconstructInputColumns(const LogInputColumns& columns,
                                        const InputReconstruction& plan);

// The same in two parts, to the bit: the smoothing, which does not depend on plan.levels, and the
// levels added to it. ReconstructInputColumns(columns, plan) is
// WithInputLevels(SmoothInputColumns(columns, plan), plan.levels): a replay that tries other
// levels on the same inputs (EstimateInputLevels, ApplyInputLevels) smooths once.
LogInputColumns SmoothInputColumns(const LogInputColumns& columns, const InputReconstruction& plan);
LogInputColumns WithInputLevels(LogInputColumns smoothed, const InputLevelCorrection& levels);
// A fingerprint of `columns` and of what the smoothing reads of the plan (not its levels): equal
// fingerprints mean the same inputs and smoothing, so the same SmoothInputColumns, but for a 64-bit
// hash collision (FNV-1a over every value's mixed bits).
std::uint64_t SmoothingFingerprint(const LogInputColumns& columns, const InputReconstruction& plan);

// The running sums of the level inputs (RunningSums, model/signal/input_reconstruction.h) for a
// block of a long log: one entry per row and one after the last, built from the log's first row.
struct LevelInputSums {
  std::vector<RunningSum> choke, pump, outlet;
};
// A block of a log (its rows from global index first_index) with every row that a row to be kept
// depends on: the same doubles as ReconstructInputColumns on the whole log there.
LogInputColumns ReconstructInputBlock(const LogInputColumns& block, const LevelInputSums& sums,
                                      long first_index, const InputReconstruction& plan);

// A log that starts in the middle of a periodic excitation (a heave already running when the
// recording started) is replayed after a warm-up (PeriodicWarmup, rig_simulator.h): for
// kReplayWarmupS, the piston's periodic excitation fitted to its first periods (kWarmupHarmonics
// harmonics), the other inputs at their means. Periodic means: the piston moves (its standard
// deviation over the first two periods is over 10 times its noise), its dominant period (largest
// spectral line, refined by least squares on x(t) - x(t + P)) is at most kMaxWarmupPeriodS, and
// over the first period every input repeats one period later to within 5 % of the piston's
// standard deviation (piston) or three times its noise (choke, pump, outlet), reconstructed as
// the replay will be. Otherwise (a log from rest, steps in the first periods) none: the replay
// starts from the steady state, as a recording from rest does.
// 30 s: the pipe's acoustic modes decay as exp(-f1 t / 2) under linear friction (f1 = 0.15 1/s,
// Table 9.4.1): a start-up transient falls to 10 %, and the choke's damping takes most of the rest.
inline constexpr double kReplayWarmupS = 30.0;
inline constexpr double kMaxWarmupPeriodS = 20.0;
// The warm-up's piston: harmonics of the period fitted to up to this many periods of the log.
inline constexpr int kWarmupHarmonics = 5;
inline constexpr int kWarmupFitPeriods = 4;

// From the log's first kReconstructionPlanSamples rows, as measured; `reconstruct` as the replay.
std::optional<PeriodicWarmup> PlanPeriodicWarmup(const LogInputColumns& head, bool reconstruct);

// Takes the input columns out of a whole log, checking them as described above. Errors name
// `path`, the column and the data row.
Result<LogInputColumns> InputColumnsFromLog(const riglog::RigLog& log, const std::string& path);

// Time functions of the inputs, reconstructed or smoothed as `options` say; the columns are moved
// into shared storage (one copy of time). Needs at least 2 rows. Reconstructed by `plan` where
// given (e.g. a MeasuredLog's, with its level correction), else by a plan made here.
// Simulate on these is the reference replay of a log; RowPipeline (model/analysis/log_stream.h)
// streams the same doubles in bounded memory, and tests/model/analysis/compare_test.cc
// (ReplayGivesExactlyWhatSimulateGives) checks that they agree: change both together.
Result<InputSignals> SignalsFromColumns(LogInputColumns columns, const std::string& path,
                                        const InputReplayOptions& options,
                                        const InputReconstruction* plan = nullptr);

// InputColumnsFromLog + SignalsFromColumns.
Result<InputSignals> SignalsFromLog(const riglog::RigLog& log, const std::string& path,
                                    const InputReplayOptions& options);

// The smoothed piston position used by SignalsFromColumns (SmoothLocalQuadratic over
// smoothing_s), for tools that need the same signal the model was fed.
std::vector<double> SmoothedPistonPosition(const LogInputColumns& columns, double smoothing_s);

}  // namespace mpdrig
