// The assembled rig: heave generator -> copper pipe -> choke with back-pressure pump (thesis 5).
//
// RigSimulator advances in the pipe solver's fixed step (dt = dx / c) with inputs held over each
// step; it owns the choke actuator state and computes every lab channel. Simulate() drives it
// from time functions of the inputs (profiles or a replayed log) and interpolates the channels to
// the requested output times. Time is an argument: no wall clock here.
//
// Initial state (thesis 6.5, generalised): the steady state for the initial inputs, with the pipe
// at rest, all pump flow through the choke, so p(L) = p_0 + rho_L q_b |q_b| / G(u_c)^2 (5.3.2),
// and the hydrostatic profile below it (6.5.3).
//
// The ends are the rig's layout (RigParams::layout, model/params/rig_layout.h): the NTNU rig by
// default; or a reservoir (ReservoirInlet, the pipe's inlet hook) and a valve (the choke's orifice
// with G = tau(t) G_0 and no pump), starting from steady flow V0. With the valve, the step
// inputs' piston and choke are not used: the layout's closure law drives the run.
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/boundary/choke.h"
#include "model/boundary/piston.h"
#include "model/common/status.h"
#include "model/common/units.h"
#include "model/core/rig_channels.h"
#include "model/effects/effect.h"
#include "model/params/rig_params.h"
#include "model/pipe/pipe_solver.h"
#include "model/pipe/reservoir_inlet.h"

namespace mpdrig {

inline constexpr int kDefaultCells = 200;

// How the choke opening input is used.
enum class ChokeInput {
  kReference,  // a command: goes through the actuator lag and rate limit (the service, profiles)
  kMeasured,   // the measured position of a log: used as is (design.md, replaying a log)
};

struct SimulationOptions {
  PipeModel model = PipeModel::kQuasiLinear;
  PipeScheme scheme = PipeScheme::kCharacteristics;
  int cells = kDefaultCells;
  ChokeInput choke_input = ChokeInput::kReference;
  // Absolute pressure at or below zero leaves the model's range (thesis 11.5). By default the run
  // stops with an error naming the time and place; otherwise it goes on and reports it.
  bool stop_on_range_violation = true;
  // Extra pressure outputs along the pipe [m from the inlet], beside PT1..PT10 (thesis 6.8).
  std::vector<double> pressure_positions_m;

  Status Validate() const;
};

// The rig's inputs at one instant.
struct RigInputs {
  double choke_opening_frac = 0.0;  // u_c: reference or measured (SimulationOptions::choke_input)
  double pump_flow_m3ps = 0.0;      // q_b (FT2)
  double outlet_pressure_pa = units::kStandardAtmospherePa;  // p_0 (C1), absolute
};

// Inputs for one step: their values at the END of the step (the new time level). Between the
// previous step's values and these, the pipe solver sees them as it needs (see PipeStepInputs).
struct StepInputs {
  double piston_velocity_mps = 0.0;  // v_d, positive up
  double piston_position_m = 0.0;    // reported as a channel
  RigInputs rig;
};

// The piston velocity at a step's end t_b: the centred difference of the position over
// [t_b - dt/2, t_b + dt/2], second order, and the trapezoidal sum of these velocities displaces
// exactly the position's change. Near the ends of a run the window slides inside [t0, t_end] (a
// one-sided difference): a replayed log's inputs are not known beyond its ends. The one formula of
// both replays of a log (SimulateEach; RowPipeline, model/analysis/log_stream.h), so they give the
// same doubles; `position_m(t)` is the run's piston position at t.
template <typename PositionAt>
double PistonVelocityAtStepEnd(double t_b, double dt, double t0, double t_end,
                               const PositionAt& position_m) {
  double t_lo = t_b - 0.5 * dt;
  double t_hi = t_b + 0.5 * dt;
  if (t_hi > t_end) t_lo -= t_hi - t_end, t_hi = t_end;
  if (t_lo < t0) t_hi = std::min(t_end, t_hi + (t0 - t_lo)), t_lo = t0;
  if (!(t_hi > t_lo)) return 0.0;
  const double p_hi = position_m(t_hi);
  const double p_lo = position_m(t_lo);
  return (p_hi - p_lo) / (t_hi - t_lo);
}

struct RigSample {
  double time_s = 0.0;
  std::array<double, kChannelCount> values{};  // SI, absolute pressure; indexed by Channel
  // (values[kTime] == time_s)
  // Pressure [Pa abs] at SimulationOptions::pressure_positions_m, in that order (thesis 6.8).
  std::vector<double> pressure_at_positions_pa;
  double operator[](Channel channel) const { return values[Index(channel)]; }
};

// A departure from the model's range, with its time and place.
struct RangeEvent {
  double time_s = 0.0;
  double position_m = 0.0;
  double pressure_pa = 0.0;
  std::string Describe() const;
};

// The pipe's state at a run's first time, as measured (a log that joins a running rig with an
// excitation that is not periodic: neither the steady state nor a periodic warm-up is its start):
// pressure and velocity at n >= 2 points evenly spaced over the pipe, x_k = k L / (n - 1), between
// them a natural cubic spline (thesis 6.5's initial steady state generalised to any smooth state).
// EstimatePipeProfile (model/analysis/log_replay.h) makes one from a log's pressures.
struct PipeProfile {
  std::vector<double> pressure_pa;   // p(x_k), absolute
  std::vector<double> velocity_mps;  // u(x_k), positive towards the choke
  double piston_velocity_mps = 0.0;  // v_d at the first time (P1's term, 5.4.2)

  // The profile at the solver's N + 1 nodes x_i = i L / N.
  static std::vector<double> AtNodes(const std::vector<double>& values, int cells);
};

class RigSimulator {
 public:
  static Result<RigSimulator> Create(const RigParams& params, const SimulationOptions& options,
                                     const RigInputs& initial_inputs,
                                     double initial_piston_position_m = 0.0,
                                     double start_time_s = 0.0);

  double time_s() const { return start_time_s_ + steps_ * pipe_->time_step_s(); }
  // The time the next Step() ends at (start + (steps + 1) dt, without accumulated rounding).
  double next_step_end_s() const { return start_time_s_ + (steps_ + 1) * pipe_->time_step_s(); }
  double time_step_s() const { return pipe_->time_step_s(); }
  const PipeSolver& pipe() const { return *pipe_; }
  const RigParams& params() const { return params_; }
  double choke_opening_frac() const { return choke_opening_frac_; }

  // Replaces the pipe's state (before the first Step) by `profile`, the effects re-initialised
  // from it. Fails if the profile has fewer than 2 points or a value is not finite.
  Status SetPipeProfile(const PipeProfile& profile);

  // Advances one step. Fails on solver failure, or on a range violation when the options say so;
  // otherwise the first violation is kept in first_range_event().
  Status Step(const StepInputs& inputs);

  // Every channel at the current time (as the sensors report them: after the effects' sensor
  // filters, if any).
  RigSample Sample() const;
  // The physical effects of this run (RigParams::effects), in their order.
  const std::vector<std::unique_ptr<Effect>>& effects() const { return effects_; }
  double PressureAtPa(double x_m) const { return pipe_->PressureAt(x_m); }
  const std::optional<RangeEvent>& first_range_event() const { return first_range_event_; }

 private:
  RigSimulator(const RigParams& params, const SimulationOptions& options,
               std::unique_ptr<PipeSolver> pipe);
  // The model's channels at the current time, before any sensor filter.
  ChannelValues ModelChannels() const;
  // The pump's delivered flow for its command, through the effects that change it.
  double DeliveredPumpFlow(double commanded_m3ps, double choke_pressure_pa) const;
  // Reservoir - pipe - valve (RigParams::layout): the steady flow V0 in the pipe, G_0 of the valve.
  Status StartFromSteadyFlow();
  bool has_valve() const { return params_.layout.outlet == RigLayout::Outlet::kValve; }

  RigParams params_;
  SimulationOptions options_;
  std::unique_ptr<PipeSolver> pipe_;
  ChokeCharacteristic characteristic_;
  ChokeActuator actuator_;
  PistonBoundary piston_;
  double start_time_s_ = 0.0;
  long steps_ = 0;  // time = start + steps * dt: no accumulated rounding over long runs
  double choke_opening_frac_ = 0.0;
  StepInputs last_inputs_{};
  PipeBoundaryValues boundary_{};  // boundary inputs at the current time
  std::vector<std::unique_ptr<Effect>> effects_;
  bool filters_sensors_ = false;
  ChannelValues sensor_values_{};  // after the sensor filters (when filters_sensors_)
  std::optional<RangeEvent> first_range_event_;
  // Reservoir - pipe - valve layout only.
  std::unique_ptr<ReservoirInlet> reservoir_;
  double valve_full_g_m2_ = 0.0;               // G_0: the open valve passes V0 at the steady p(L)
  double valve_downstream_pressure_pa_ = 0.0;  // p_d
};

// Samples a RigSimulator at arbitrary, non-decreasing times: it steps the simulator on its own
// grid until the grid reaches the requested time and interpolates linearly between the two grid
// samples around it (second order, like the scheme). The inputs of each step come from
// `step_inputs(step_end_s, dt_s)`: their values at the step's end (see StepInputs).
class RigSampler {
 public:
  using StepInputsFn = std::function<StepInputs(double step_end_s, double dt_s)>;
  explicit RigSampler(RigSimulator simulator);

  Result<RigSample> SampleAt(double time_s, const StepInputsFn& step_inputs);
  RigSimulator& simulator() { return simulator_; }
  const RigSimulator& simulator() const { return simulator_; }
  long steps() const { return steps_; }

 private:
  RigSimulator simulator_;
  RigSample previous_;
  RigSample current_;
  long steps_ = 0;
};

// A replay's warm-up for a log that starts in the middle of a periodic excitation (a heave
// already running): the run starts duration_s before the first output time t0, driven by the
// excitation's periodic past, x(t) = mean + sum_k a_k cos(k w (t - t0)) + b_k sin(k w (t - t0)),
// w = 2 pi / period, with the other inputs held at `levels` (log_inputs.h fits it to the log's
// first periods). At t0 the pipe then carries the periodic response (to within the decay of the
// start-up transient over duration_s) instead of the steady state a run otherwise starts from.
struct PeriodicWarmup {
  double period_s = 0.0;
  double duration_s = 0.0;
  double mean_m = 0.0;
  std::vector<double> cos_m, sin_m;  // a_k, b_k for k = 1, 2, ...
  RigInputs levels;

  double PistonPositionM(double t, double t0) const;
};

// A simulator at t0 after the warm-up: created at t0 - n dt (n dt >= duration_s, whole steps, so
// its grid meets t0) from the steady state of `levels`, stepped n times with the periodic piston
// (its velocity the centred difference over each step, as a replay's).
Result<RigSimulator> CreateWarmedUp(const RigParams& params, const SimulationOptions& options,
                                    double t0, const PeriodicWarmup& warmup);

// Time functions of the inputs for a batch run.
struct InputSignals {
  std::function<double(double)> piston_position_m;  // continuous in time
  std::function<RigInputs(double)> rig;             // held values (choke, pump, outlet)
  // The inputs whose steady state the run starts from; rig(t0) if absent. A measured log's
  // replay gives its inputs' mean over the first moments (log_inputs.h).
  std::optional<RigInputs> initial;
  std::optional<PeriodicWarmup> warmup;  // none: the run starts from the steady state at t0
  std::optional<PipeProfile> profile;    // the pipe's state at t0 (not with a warm-up)
};

// What a run did besides its samples: what SimulateEach returns, which hands the samples to a
// sink as they come.
struct RunSummary {
  long steps = 0;
  double time_step_s = 0.0;
  std::optional<RangeEvent> first_range_event;
};

// The summary and every sample: what Simulate returns, for runs short enough to hold.
struct RunResult : RunSummary {
  std::vector<RigSample> samples;  // one per output time
};

// Runs the rig over [output_times.front(), output_times.back()] and hands every channel at each
// output time (strictly increasing) to `sink` as it goes, so a long run need not be held in
// memory. `progress`, if given, is called with the fraction done, every 5%.
Result<RunSummary> SimulateEach(const RigParams& params, const SimulationOptions& options,
                                const InputSignals& inputs, const std::vector<double>& output_times,
                                const std::function<void(const RigSample&)>& sink,
                                const std::function<void(double)>& progress = {});

// The same, collecting every sample.
Result<RunResult> Simulate(const RigParams& params, const SimulationOptions& options,
                           const InputSignals& inputs, const std::vector<double>& output_times,
                           const std::function<void(double)>& progress = {});

}  // namespace mpdrig
