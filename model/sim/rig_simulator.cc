#include "model/sim/rig_simulator.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace mpdrig {

Status SimulationOptions::Validate() const {
  if (cells < 2 || cells > 200000) {
    return Status::Error("cells must be in [2, 200000], got " + std::to_string(cells));
  }
  return Status::Ok();
}

std::string RangeEvent::Describe() const {
  std::ostringstream out;
  out.precision(4);
  out << "absolute pressure fell to " << pressure_pa / 1e5 << " bar(a) at x = " << position_m
      << " m, t = " << time_s << " s: below zero absolute pressure the model is not valid "
      << "(thesis 11.5)";
  return out.str();
}

RigSimulator::RigSimulator(const RigParams& params, const SimulationOptions& options,
                           std::unique_ptr<PipeSolver> pipe)
    : params_(params),
      options_(options),
      pipe_(std::move(pipe)),
      characteristic_(params),
      actuator_(params),
      piston_(params) {}

Result<RigSimulator> RigSimulator::Create(const RigParams& params, const SimulationOptions& options,
                                          const RigInputs& initial_inputs,
                                          double initial_piston_position_m, double start_time_s) {
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  for (double x : options.pressure_positions_m) {
    if (!(x >= 0.0 && x <= params.pipe_length_m)) {
      std::ostringstream out;
      out << "pressure position " << x << " m is outside the pipe [0, " << params.pipe_length_m
          << "] m";
      return Status::Error(out.str());
    }
  }
  const RigInputs& in = initial_inputs;
  if (!std::isfinite(in.choke_opening_frac) || !std::isfinite(in.pump_flow_m3ps) ||
      !std::isfinite(in.outlet_pressure_pa) || !std::isfinite(initial_piston_position_m)) {
    return Status::Error("initial inputs must be finite");
  }
  if (in.outlet_pressure_pa <= 0.0) {
    return Status::Error("outlet pressure must be above zero absolute");
  }

  const ChokeCharacteristic characteristic(params);
  const double opening = std::clamp(in.choke_opening_frac, 0.0, 1.0);
  const double g = characteristic.FlowCoefficientM2(opening);
  if (g <= 0.0 && in.pump_flow_m3ps != 0.0) {
    return Status::Error(
        "the choke is tight (G = 0, no leak) with pump flow: there is no steady "
        "initial state; open the choke or set choke_leak_m2 > 0");
  }
  // (5.3.2) at rest: all pump flow through the choke.
  const double q = in.pump_flow_m3ps;
  const double outlet_pressure =
      in.outlet_pressure_pa +
      (g > 0.0 ? params.choke_density_kgpm3 * q * std::fabs(q) / (g * g) : 0.0);

  const PipeConfig config = PipeConfig::FromParams(params, options.model, options.cells);
  auto pipe = MakePipeSolver(options.scheme, config, outlet_pressure);
  if (!pipe.ok()) return pipe.status();
  const double dt = (*pipe)->time_step_s();
  auto effects = CreateEffects(params, config, dt);
  if (!effects.ok()) return effects.status();

  RigSimulator simulator(params, options, std::move(pipe).value());
  simulator.effects_ = std::move(effects).value();
  std::vector<const PipeExtension*> extensions;
  if (params.layout.inlet == RigLayout::Inlet::kReservoir) {
    simulator.reservoir_ = std::make_unique<ReservoirInlet>(
        params.atmospheric_pressure_pa +
        params.density_kgpm3 * params.gravity_mps2 * params.layout.reservoir_head_m);
    extensions.push_back(simulator.reservoir_.get());
    MPDRIG_RETURN_IF_ERROR(simulator.pipe_->SetExtensions(extensions).Within("reservoir inlet"));
  }
  for (std::size_t i = 0; i < simulator.effects_.size(); ++i) {
    extensions.push_back(simulator.effects_[i].get());
    MPDRIG_RETURN_IF_ERROR(
        simulator.pipe_->SetExtensions(extensions).Within("effect " + params.effects[i].name));
    simulator.filters_sensors_ |= simulator.effects_[i]->filters_sensors();
  }
  if (!params.layout.is_ntnu_rig()) {
    simulator.start_time_s_ = start_time_s;
    simulator.last_inputs_.rig = in;
    MPDRIG_RETURN_IF_ERROR(simulator.StartFromSteadyFlow());
    return simulator;
  }
  // With a pump that answers the choke pressure (pump_curve), the initial pump flow and choke
  // pressure settle together: the fixed point of q = pump(p(q)), damped, from the command.
  double pump_flow = in.pump_flow_m3ps;
  double outlet_pressure_pa = outlet_pressure;
  const auto choke_pressure = [&](double q) {
    return in.outlet_pressure_pa +
           (g > 0.0 ? params.choke_density_kgpm3 * q * std::fabs(q) / (g * g) : 0.0);
  };
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double next = simulator.DeliveredPumpFlow(in.pump_flow_m3ps, outlet_pressure_pa);
    if (std::fabs(next - pump_flow) <= 1e-12 * (1.0 + std::fabs(pump_flow))) break;
    pump_flow = 0.5 * (pump_flow + next);
    outlet_pressure_pa = choke_pressure(pump_flow);
  }
  simulator.pipe_->SetRestState(outlet_pressure_pa);

  simulator.start_time_s_ = start_time_s;
  simulator.choke_opening_frac_ = opening;
  simulator.last_inputs_.piston_velocity_mps = 0.0;
  simulator.last_inputs_.piston_position_m = initial_piston_position_m;
  simulator.last_inputs_.rig = in;
  simulator.boundary_.inlet_velocity_mps = 0.0;
  simulator.boundary_.choke = {g, pump_flow, in.outlet_pressure_pa};
  const ChannelValues initial = simulator.ModelChannels();
  for (auto& effect : simulator.effects_) effect->Initialize(*simulator.pipe_, initial);
  simulator.sensor_values_ = initial;
  return simulator;
}

// The scheme's own steady state at V0 (exact for the linear model): along both characteristics
// W(p) + u and -W(p) + u change by -dt (f(V0) + g sin(gamma)) per cell (6.1.16-17, 7.0.10-11),
// so with u = V0 everywhere W falls by that per cell from the reservoir's p(0); the valve's G_0
// then passes V0 at p(L) by the orifice equation (5.3.2): G_0 = A V0 sqrt(rho_L / (p(L) - p_d)).
Status RigSimulator::StartFromSteadyFlow() {
  const RigLayout& layout = params_.layout;
  const PipeConfig& config = pipe_->config();
  const PipeLaw& law = pipe_->law();
  const double v0 = layout.steady_velocity_mps;
  const double drop = pipe_->time_step_s() * (config.Friction(v0) + config.gravity_slope_mps2);
  const double w0 = law.PressureTerm(reservoir_->pressure_pa());
  std::vector<double> pressure(config.cells + 1), velocity(config.cells + 1, v0);
  for (int i = 0; i <= config.cells; ++i) {
    pressure[i] = law.PressureFromDifference(2.0 * (w0 - i * drop));
  }
  valve_downstream_pressure_pa_ =
      params_.atmospheric_pressure_pa +
      params_.density_kgpm3 * params_.gravity_mps2 * layout.valve.downstream_head_m;
  const double valve_drop_pa = pressure.back() - valve_downstream_pressure_pa_;
  if (!(valve_drop_pa > 0.0) || !(pressure.back() > 0.0)) {
    std::ostringstream out;
    out.precision(4);
    out << "no steady flow of " << v0 << " m/s from the reservoir to the valve: friction and the "
        << "rise leave p(L) = " << pressure.back() / 1e5 << " bar(a), not above the downstream "
        << valve_downstream_pressure_pa_ / 1e5
        << " bar(a); raise the reservoir head, lower the valve's downstream_head_m or V0";
    return Status::Error(out.str());
  }
  valve_full_g_m2_ = config.area_m2 * v0 * std::sqrt(config.choke_density_kgpm3 / valve_drop_pa);
  pipe_->SetState(pressure, velocity);
  choke_opening_frac_ = layout.valve.RelativeOpening(start_time_s_);
  boundary_.inlet_velocity_mps = v0;
  boundary_.choke = {valve_full_g_m2_ * choke_opening_frac_, 0.0, valve_downstream_pressure_pa_};
  last_inputs_.piston_velocity_mps = 0.0;
  const ChannelValues initial = ModelChannels();
  for (auto& effect : effects_) effect->Initialize(*pipe_, initial);
  sensor_values_ = initial;
  return Status::Ok();
}

std::vector<double> PipeProfile::AtNodes(const std::vector<double>& values, int cells) {
  const std::size_t n = values.size();
  MPDRIG_CHECK(n >= 2 && cells >= 1);
  // Natural cubic spline on the unit spacing: second derivatives m from the tridiagonal system
  // m_{k-1} + 4 m_k + m_{k+1} = 6 (y_{k-1} - 2 y_k + y_{k+1}), m_0 = m_{n-1} = 0 (Thomas).
  std::vector<double> m(n, 0.0);
  if (n > 2) {
    std::vector<double> diagonal(n, 4.0), rhs(n, 0.0);
    for (std::size_t k = 1; k + 1 < n; ++k) {
      rhs[k] = 6.0 * (values[k - 1] - 2.0 * values[k] + values[k + 1]);
    }
    for (std::size_t k = 2; k + 1 < n; ++k) {
      const double w = 1.0 / diagonal[k - 1];
      diagonal[k] -= w;
      rhs[k] -= w * rhs[k - 1];
    }
    for (std::size_t k = n - 2; k >= 1; --k) {
      m[k] = (rhs[k] - (k + 2 < n ? m[k + 1] : 0.0)) / diagonal[k];
    }
  }
  std::vector<double> nodes(cells + 1);
  for (int i = 0; i <= cells; ++i) {
    const double s = static_cast<double>(i) * static_cast<double>(n - 1) / cells;
    const std::size_t k = std::min(n - 2, static_cast<std::size_t>(s));
    const double b = s - static_cast<double>(k), a = 1.0 - b;
    nodes[i] = a * values[k] + b * values[k + 1] +
               ((a * a * a - a) * m[k] + (b * b * b - b) * m[k + 1]) / 6.0;
  }
  return nodes;
}

Status RigSimulator::SetPipeProfile(const PipeProfile& profile) {
  MPDRIG_CHECK(steps_ == 0);
  if (profile.pressure_pa.size() < 2 || profile.velocity_mps.size() < 2) {
    return Status::Error("a pipe profile needs at least 2 points");
  }
  for (const auto* values : {&profile.pressure_pa, &profile.velocity_mps}) {
    for (double v : *values) {
      if (!std::isfinite(v)) return Status::Error("a pipe profile's values must be finite");
    }
  }
  const int cells = pipe_->config().cells;
  pipe_->SetState(PipeProfile::AtNodes(profile.pressure_pa, cells),
                  PipeProfile::AtNodes(profile.velocity_mps, cells));
  boundary_.inlet_velocity_mps = pipe_->VelocityAt(0.0);
  last_inputs_.piston_velocity_mps = profile.piston_velocity_mps;
  const ChannelValues initial = ModelChannels();
  for (auto& effect : effects_) effect->Initialize(*pipe_, initial);
  sensor_values_ = initial;
  return Status::Ok();
}

Status RigSimulator::Step(const StepInputs& inputs) {
  const RigInputs& in = inputs.rig;
  if (!std::isfinite(inputs.piston_velocity_mps) || !std::isfinite(in.choke_opening_frac) ||
      !std::isfinite(in.pump_flow_m3ps) || !std::isfinite(in.outlet_pressure_pa)) {
    std::ostringstream out;
    out << "non-finite input at t = " << time_s() << " s";
    return Status::Error(out.str());
  }
  const double dt = pipe_->time_step_s();
  PipeStepInputs step;
  step.start = boundary_;
  if (has_valve()) {
    // The valve's closure law at the step's end; the reservoir closes the inlet.
    choke_opening_frac_ = params_.layout.valve.RelativeOpening(next_step_end_s());
    step.end.inlet_velocity_mps = 0.0;
    step.end.choke = {valve_full_g_m2_ * choke_opening_frac_, 0.0, valve_downstream_pressure_pa_};
  } else {
    const double reference = std::clamp(in.choke_opening_frac, 0.0, 1.0);
    choke_opening_frac_ = options_.choke_input == ChokeInput::kReference
                              ? actuator_.Advance(choke_opening_frac_, reference, dt)
                              : reference;
    step.end.inlet_velocity_mps = piston_.InletVelocityMps(inputs.piston_velocity_mps);
    step.end.choke.flow_coefficient_m2 = characteristic_.FlowCoefficientM2(choke_opening_frac_);
    step.end.choke.pump_flow_m3ps =
        DeliveredPumpFlow(in.pump_flow_m3ps, pipe_->PressureAt(params_.pipe_length_m));
    step.end.choke.outlet_pressure_pa = in.outlet_pressure_pa;
  }

  RangeViolation violation;
  MPDRIG_RETURN_IF_ERROR(pipe_->Step(step, &violation));
  ++steps_;
  last_inputs_ = inputs;
  boundary_ = step.end;
  const StepRecord record{boundary_, dt};
  for (auto& effect : effects_) effect->AfterStep(*pipe_, record);
  if (filters_sensors_) {
    sensor_values_ = ModelChannels();
    for (auto& effect : effects_) {
      if (effect->filters_sensors()) effect->FilterSensors(&sensor_values_, dt);
    }
  }
  if (violation.occurred) {
    RangeEvent event{time_s(), violation.position_m, violation.min_pressure_pa};
    if (options_.stop_on_range_violation) return Status::ModelRangeError(event.Describe());
    if (!first_range_event_) first_range_event_ = event;
  }
  return Status::Ok();
}

double RigSimulator::DeliveredPumpFlow(double commanded_m3ps, double choke_pressure_pa) const {
  double flow = commanded_m3ps;
  for (const auto& effect : effects_) {
    if (effect->changes_pump_flow()) flow = effect->PumpFlowM3ps(flow, choke_pressure_pa);
  }
  return flow;
}

RigSample RigSimulator::Sample() const {
  RigSample sample;
  sample.time_s = time_s();
  sample.values = filters_sensors_ ? sensor_values_ : ModelChannels();
  for (double x : options_.pressure_positions_m) {
    sample.pressure_at_positions_pa.push_back(pipe_->PressureAt(x));
  }
  return sample;
}

ChannelValues RigSimulator::ModelChannels() const {
  ChannelValues v{};
  const double length = params_.pipe_length_m;
  const double area = params_.PipeAreaM2();
  const double v_d = last_inputs_.piston_velocity_mps;
  const double p_inlet = pipe_->PressureAt(0.0);
  const double u_outlet = pipe_->VelocityAt(length);
  const double q_b = boundary_.choke.pump_flow_m3ps;  // delivered (pump_curve may change it)

  v[Index(Channel::kTime)] = time_s();
  v[Index(Channel::kPistonPosition)] = last_inputs_.piston_position_m;
  v[Index(Channel::kChokePosition)] = choke_opening_frac_;
  v[Index(Channel::kP2)] = p_inlet;
  v[Index(Channel::kP1)] = piston_.BelowPistonPressurePa(p_inlet, v_d);
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    const double x = length * k / (kPipeTransmitterCount - 1);
    v[Index(Channel::kPT1) + k] = pipe_->PressureAt(x);
  }
  v[Index(Channel::kC1)] =
      has_valve() ? valve_downstream_pressure_pa_ : last_inputs_.rig.outlet_pressure_pa;
  v[Index(Channel::kC2)] = pipe_->PressureAt(length);
  v[Index(Channel::kFT1)] = area * u_outlet;
  v[Index(Channel::kFT2)] = q_b;
  v[Index(Channel::kFT3)] = q_b + area * u_outlet;
  v[Index(Channel::kFT4)] = area * pipe_->VelocityAt(0.0);
  return v;
}

namespace {

RigSample Interpolate(const RigSample& a, const RigSample& b, double t) {
  RigSample out;
  out.time_s = t;
  const double w = b.time_s > a.time_s ? (t - a.time_s) / (b.time_s - a.time_s) : 0.0;
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    out.values[i] = (1.0 - w) * a.values[i] + w * b.values[i];
  }
  for (std::size_t i = 0; i < a.pressure_at_positions_pa.size(); ++i) {
    out.pressure_at_positions_pa.push_back((1.0 - w) * a.pressure_at_positions_pa[i] +
                                           w * b.pressure_at_positions_pa[i]);
  }
  return out;
}

}  // namespace

RigSampler::RigSampler(RigSimulator simulator)
    : simulator_(std::move(simulator)), current_(simulator_.Sample()) {
  previous_ = current_;
}

Result<RigSample> RigSampler::SampleAt(double time_s, const StepInputsFn& step_inputs) {
  if (time_s < previous_.time_s) {
    std::ostringstream out;
    out << "sample time " << time_s << " s lies before the rig's last step (" << previous_.time_s
        << " s): times must not decrease";
    return Status::Error(out.str());
  }
  // Only the two grid samples around time_s are read: the steps before them are not sampled (a
  // sample reads every channel, about a fifth of a step at N = 1000). On entry and on success
  // current_ is the sample of the simulator's present time.
  if (current_.time_s < time_s) {
    for (;;) {
      const bool last = simulator_.next_step_end_s() >= time_s;
      if (last) previous_ = simulator_.time_s() == current_.time_s ? current_ : simulator_.Sample();
      const StepInputs step = step_inputs(simulator_.next_step_end_s(), simulator_.time_step_s());
      MPDRIG_RETURN_IF_ERROR(simulator_.Step(step));
      ++steps_;
      if (last) {
        current_ = simulator_.Sample();
        break;
      }
    }
  }
  if (steps_ == 0 || time_s == current_.time_s) return current_;
  return Interpolate(previous_, current_, time_s);
}

double PeriodicWarmup::PistonPositionM(double t, double t0) const {
  const double w = 2.0 * std::numbers::pi / period_s;
  double x = mean_m;
  for (std::size_t k = 0; k < cos_m.size(); ++k) {
    const double phase = static_cast<double>(k + 1) * w * (t - t0);
    x += cos_m[k] * std::cos(phase) + sin_m[k] * std::sin(phase);
  }
  return x;
}

Result<RigSimulator> CreateWarmedUp(const RigParams& params, const SimulationOptions& options,
                                    double t0, const PeriodicWarmup& warmup) {
  MPDRIG_CHECK(warmup.period_s > 0.0 && warmup.duration_s >= 0.0);
  // The time step depends only on the parameters and the options: learn it from a first build.
  auto probe =
      RigSimulator::Create(params, options, warmup.levels, warmup.PistonPositionM(t0, t0), t0);
  if (!probe.ok()) return probe.status();
  const double dt = probe->time_step_s();
  const long steps = static_cast<long>(std::ceil(warmup.duration_s / dt));
  if (steps == 0) return probe;
  const double start = t0 - static_cast<double>(steps) * dt;
  auto simulator = RigSimulator::Create(params, options, warmup.levels,
                                        warmup.PistonPositionM(start, t0), start);
  if (!simulator.ok()) return simulator.status();
  for (long k = 0; k < steps; ++k) {
    const double t_b = simulator->next_step_end_s();
    StepInputs step;
    step.piston_position_m = warmup.PistonPositionM(t_b, t0);
    step.piston_velocity_mps =
        (warmup.PistonPositionM(t_b + 0.5 * dt, t0) - warmup.PistonPositionM(t_b - 0.5 * dt, t0)) /
        dt;
    step.rig = warmup.levels;
    auto stepped = simulator->Step(step);
    if (!stepped.ok()) return stepped.Within("warm-up before t = " + std::to_string(t0) + " s");
  }
  return simulator;
}

Result<RunSummary> SimulateEach(const RigParams& params, const SimulationOptions& options,
                                const InputSignals& inputs, const std::vector<double>& output_times,
                                const std::function<void(const RigSample&)>& sink,
                                const std::function<void(double)>& progress) {
  if (output_times.empty()) return Status::Error("no output times");
  for (std::size_t i = 1; i < output_times.size(); ++i) {
    if (!(output_times[i] > output_times[i - 1])) {
      return Status::Error("output times must be strictly increasing");
    }
  }
  const double t0 = output_times.front();
  const double t_end = output_times.back();

  // Inputs at the end of each step.
  const auto step_inputs = [&](double t_b, double dt) {
    StepInputs step;
    step.piston_velocity_mps =
        PistonVelocityAtStepEnd(t_b, dt, t0, t_end, inputs.piston_position_m);
    step.piston_position_m = inputs.piston_position_m(t_b);
    step.rig = inputs.rig(t_b);
    return step;
  };

  const RigInputs initial = inputs.initial.value_or(inputs.rig(t0));
  MPDRIG_CHECK(!(inputs.warmup && inputs.profile));
  auto simulator = inputs.warmup ? CreateWarmedUp(params, options, t0, *inputs.warmup)
                                 : RigSimulator::Create(params, options, initial,
                                                        inputs.piston_position_m(t0), t0);
  if (!simulator.ok()) return simulator.status();
  if (inputs.profile) MPDRIG_RETURN_IF_ERROR(simulator->SetPipeProfile(*inputs.profile));
  RigSampler sampler(std::move(simulator).value());

  double next_progress = 0.05;
  for (double t : output_times) {
    auto sample = sampler.SampleAt(t, step_inputs);
    if (!sample.ok()) return sample.status();
    sink(*sample);
    if (progress && t_end > t0 && (t - t0) / (t_end - t0) >= next_progress) {
      progress((t - t0) / (t_end - t0));
      next_progress += 0.05;
    }
  }
  RunSummary summary;
  summary.steps = sampler.steps();
  summary.time_step_s = sampler.simulator().time_step_s();
  summary.first_range_event = sampler.simulator().first_range_event();
  return summary;
}

Result<RunResult> Simulate(const RigParams& params, const SimulationOptions& options,
                           const InputSignals& inputs, const std::vector<double>& output_times,
                           const std::function<void(double)>& progress) {
  RunResult result;
  result.samples.reserve(output_times.size());
  auto summary = SimulateEach(
      params, options, inputs, output_times,
      [&result](const RigSample& sample) { result.samples.push_back(sample); }, progress);
  if (!summary.ok()) return summary.status();
  static_cast<RunSummary&>(result) = *summary;
  return result;
}

}  // namespace mpdrig
