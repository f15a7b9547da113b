// The model replayed on a measured log in memory (measured_log.h): the log's inputs drive the
// model (design.md, "Replaying a log"), and the model's values of the compared channels come back
// at the log's times, for CompareTraces (compare.h), fit and diagnose.
//
// ReplayModel is the same replay as CompareLog's streamed second pass (RowPipeline, log_stream.h):
// the same numbers. Before it runs, a replay decides from the log how it starts (ChooseReplayStart:
// the steady state, a periodic warm-up or the pipe's state estimated from the log's pressures) and
// at which input levels (EstimateInputLevels: the reconstructed choke and FT2 levels corrected from
// the measured pressures); PrepareLogReplay does both.
//
// Units: SI with absolute pressure (Pa, m^3/s, m, opening fraction).
#pragma once

#include <optional>
#include <vector>

#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

struct WindowReference;  // window_error.h

// Reconstructed inputs by default, or as measured (log_inputs.h).
using ReplayOptions = InputReplayOptions;

// The model's values of the compared channels at the log's times, in the order of
// log.channels. The same numbers Simulate() gives for the log's inputs (the test checks this),
// but only the compared channels are kept: 8 bytes per sample and channel.
struct ModelTraces {
  std::vector<std::vector<double>> values_si;
  bool inputs_reconstructed = false;     // fed MeasuredLog::reconstructed_inputs
  std::optional<PeriodicWarmup> warmup;  // the start, as ReplayOptions::warmup
  std::optional<PipeProfile> profile;    // the start, as ReplayOptions::profile
  std::optional<RangeEvent> first_range_event;
  long steps = 0;
  double time_step_s = 0.0;
};

// The choke input is forced to ChokeInput::kMeasured (design.md: a log's choke_position is the
// measured opening).
Result<ModelTraces> ReplayModel(const MeasuredLog& log, const RigParams& params,
                                const SimulationOptions& sim_options,
                                const ReplayOptions& replay = {},
                                const CompareProgress& progress = {});

// ReplayModel's replay scored as it goes on [begin_s, end_s] of `log`: WindowError's value (to the
// bit), or nullopt as soon as that is certain to exceed `stop_above` (WindowErrorAccumulator's
// bound has passed it), and the rest of the log is not replayed. For searches that only need to
// know whether a point beats others (diagnose's scans); +infinity never stops.
Result<std::optional<double>> ReplayWindowError(const MeasuredLog& log, const RigParams& params,
                                                const SimulationOptions& sim_options,
                                                const ReplayOptions& replay, double begin_s,
                                                double end_s, double stop_above);
// The same on the window `reference` measured (MeasureWindow of `log`): for the many replays of
// a search on one window.
Result<std::optional<double>> ReplayWindowError(const MeasuredLog& log, const RigParams& params,
                                                const SimulationOptions& sim_options,
                                                const ReplayOptions& replay,
                                                const WindowReference& reference,
                                                double stop_above);

// Whether a replay of `log` should start after a periodic warm-up (PlanPeriodicWarmup,
// log_inputs.h) or from the steady state: the inputs cannot tell a heave that was already running
// when the recording started from one that started with it, the pressures can. Where the log's
// start is periodic, both starts are replayed over its first two periods with `params`, and the
// warm-up is chosen if its squared error over the measured pressure channels is smaller (a start
// whose replay fails, e.g. leaves the model's range, is never chosen).
Result<std::optional<PeriodicWarmup>> ChooseWarmup(const MeasuredLog& log, const RigParams& params,
                                                   const SimulationOptions& sim_options,
                                                   const ReplayOptions& replay);

// The pipe's state at the log's first sample, from the log's own pressures (a recording that joins
// a running rig whose heave is not periodic: neither the steady state nor a periodic warm-up is its
// start). As MATLAB's `compare` estimates initial conditions: the state is a PipeProfile
// (rig_simulator.h) of kProfilePoints pressures and velocities along the pipe, first from the
// measurements at t0 (each pipe pressure channel's local quadratic over the first
// kProfileWindowTravelTimes L/c interpolated along the pipe; the velocity from continuity,
// dp/dt = -(k + p) du/dx (thesis 6.1.1 with (5.2.1)), integrated from the piston's inlet velocity,
// 5.4.1), then by Gauss-Newton on the replay's pressure error over the first
// kProfileFitTravelTimes L/c (the model is linear in its initial state to first order over so short
// a horizon: one Jacobian of 2 kProfilePoints replays). None when the log has fewer than two pipe
// pressure channels at distinct places (P2, PT1..PT10, C2) or a replay fails.
inline constexpr int kProfilePoints = kPipeTransmitterCount;
inline constexpr double kProfileWindowTravelTimes = 0.5;
inline constexpr double kProfileFitTravelTimes = 4.0;
Result<std::optional<PipeProfile>> EstimatePipeProfile(const MeasuredLog& log,
                                                       const RigParams& params,
                                                       const SimulationOptions& sim_options,
                                                       const ReplayOptions& replay);

// How a replay of `log` starts: the steady state, the periodic warm-up (where ChooseWarmup's
// candidate exists) or the measured pipe state (EstimatePipeProfile), whichever replays the log's
// measured pressures best over its first max(two periods, kStartChoiceTravelTimes L/c): the
// smallest median over the pressure channels of each one's squared error (a wrong start reaches
// every channel; a sensor's offset, which the measured state would partly absorb, one), a tie to
// the simpler start, a start whose replay fails never. Sets replay->warmup and replay->profile (at
// most one of them).
inline constexpr double kStartChoiceTravelTimes = 10.0;
Status ChooseReplayStart(const MeasuredLog& log, const RigParams& params,
                         const SimulationOptions& sim_options, ReplayOptions* replay);

// The choke's and FT2's level offsets that make the replay's mean pressures meet the measured
// ones, within what the inputs' noise allows (InputLevelCorrection, log_inputs.h): one replay of
// the log's first kReconstructionPlanSamples rows with `params` and `replay` (its warm-up
// included), the sensitivities from the steady law at the inputs' mean, the maximum a posteriori
// offsets with each input's sigma/sqrt(N) as the prior, clipped to kMaxLevelOffsetSigmas of it.
// None when the inputs are not reconstructed, replay.estimate_levels is false, the log has no
// pressure channel, or the replay fails (the replay itself will say why).
Result<InputLevelCorrection> EstimateInputLevels(const MeasuredLog& log, const RigParams& params,
                                                 const SimulationOptions& sim_options,
                                                 const ReplayOptions& replay);
// Puts the correction into the log's reconstruction (and its reconstructed inputs) and into the
// warm-up's levels, so that every replay after it feeds the corrected levels.
void ApplyInputLevels(const InputLevelCorrection& levels, MeasuredLog* log);
void ApplyInputLevels(const InputLevelCorrection& levels, ReplayOptions* replay);

// Everything a replay of a whole log in memory decides from the log before it runs: the start
// (ChooseReplayStart, where replay->choose_warmup) and, with kWithTheseParams, the input levels
// (EstimateInputLevels + ApplyInputLevels, where replay->estimate_levels). simulate --inputs
// calls it so, as CompareLog does on its streamed head; fit and diagnose with kAfterTheFit, as
// they estimate the levels at the parameters they fit (FitParametersAndInputLevels, Diagnose).
enum class InputLevels { kWithTheseParams, kAfterTheFit };
Status PrepareLogReplay(MeasuredLog* log, const RigParams& params,
                        const SimulationOptions& sim_options, ReplayOptions* replay,
                        InputLevels levels = InputLevels::kWithTheseParams);

}  // namespace mpdrig
