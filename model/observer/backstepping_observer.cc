#include "model/observer/backstepping_observer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mpdrig::observer {

BacksteppingObserver::BacksteppingObserver(const RigParams& params, const ObserverOptions& options,
                                           ObserverGains gains, KernelSolution kernel)
    : params_(params), options_(options), gains_(std::move(gains)), kernel_(std::move(kernel)) {}

Result<BacksteppingObserver> BacksteppingObserver::Create(const RigParams& params,
                                                          const ObserverOptions& options,
                                                          const TopsideMeasurement& initial,
                                                          double start_time_s) {
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  if (!std::isfinite(initial.outlet_pressure_pa) || !std::isfinite(initial.outlet_flow_m3ps) ||
      !std::isfinite(start_time_s)) {
    return Status::Error("observer: initial measurement must be finite");
  }
  const double f1 =
      std::isnan(options.friction_f1_per_s) ? params.friction_f1_per_s : options.friction_f1_per_s;
  const double sigma = ObserverCoordinates::Create(params, f1).sigma;
  auto kernel = KernelSolution::Solve(sigma, options.cells);
  if (!kernel.ok()) return kernel.status();
  auto gains = ObserverGains::Compute(params, options, *kernel);
  if (!gains.ok()) return gains.status();

  BacksteppingObserver obs(params, options, std::move(gains).value(), std::move(kernel).value());
  const ObserverCoordinates& co = obs.gains_.coordinates;
  const int n = options.cells;
  obs.dt_s_ = params.pipe_length_m / (params.wave_speed_mps * n);
  obs.start_time_s_ = start_time_s;
  // p_sp: P(l) = 0 at the first sample, so the observer starts at rest with the measured outlet
  // pressure and a hydrostatic profile below it.
  obs.p_sp_pa_ = co.GravityFree(1.0, initial.outlet_pressure_pa, 0.0);
  obs.c1_.resize(n + 1);
  obs.c2_.resize(n + 1);
  obs.e_plus_.resize(n + 1);
  obs.e_minus_.resize(n + 1);
  for (int i = 0; i <= n; ++i) {
    const double x = static_cast<double>(i) / n;
    obs.c1_[i] = co.C1(x);
    obs.c2_[i] = co.C2(x);
    obs.e_plus_[i] = std::exp(co.sigma * x);
    obs.e_minus_[i] = std::exp(-co.sigma * x);
  }
  obs.half_f2_over_a_ =
      options.quadratic_friction ? 0.5 * params.friction_f2_per_m / co.area_m2 : 0.0;
  obs.q_.assign(n + 1, 0.0);
  obs.u_.assign(n + 1, 0.0);
  obs.v_.assign(n + 1, 0.0);
  obs.u_next_.assign(n + 1, 0.0);
  obs.v_next_.assign(n + 1, 0.0);
  obs.pressure_filter_.Reset(initial.outlet_pressure_pa);
  obs.flow_filter_.Reset(initial.outlet_flow_m3ps);
  obs.v_[n] = obs.MeasuredDown(initial);
  obs.error_ = obs.MeasuredUp(initial) - obs.u_[n];
  if (options.track_frequency) {
    FrequencyTrackerOptions tracker;
    tracker.initial_hz = options.disturbance_hz;
    tracker.min_hz = std::min(tracker.min_hz, options.disturbance_hz);
    tracker.max_hz = std::max(tracker.max_hz, options.disturbance_hz);
    auto created = FrequencyTracker::Create(tracker, start_time_s, obs.MeasuredUp(initial));
    if (!created.ok()) return created.status();
    obs.tracker_ = std::move(created).value();
  }
  return obs;
}

double BacksteppingObserver::MeasuredUp(const TopsideMeasurement& m) const {
  return gains_.coordinates.UpWave(1.0, m.outlet_pressure_pa, m.outlet_flow_m3ps, p_sp_pa_);
}
double BacksteppingObserver::MeasuredDown(const TopsideMeasurement& m) const {
  return gains_.coordinates.DownWave(1.0, m.outlet_pressure_pa, m.outlet_flow_m3ps, p_sp_pa_);
}

Status BacksteppingObserver::SetDisturbanceFrequency(double frequency_hz) {
  ObserverOptions options = options_;
  options.disturbance_hz = frequency_hz;
  return Redesign(options);
}

Status BacksteppingObserver::SetMeasurementNoise(const MeasurementNoise& noise) {
  ObserverOptions options = options_;
  options.noise = noise;
  return Redesign(options);
}

// The gains for new options; the observer keeps its old ones (and options) if they fail.
Status BacksteppingObserver::Redesign(const ObserverOptions& options) {
  auto gains = ObserverGains::Compute(params_, options, kernel_);
  if (!gains.ok()) return gains.status();
  gains_ = std::move(gains).value();
  options_ = options;
  return Status::Ok();
}

Status BacksteppingObserver::Step(const TopsideMeasurement& raw) {
  if (!std::isfinite(raw.outlet_pressure_pa) || !std::isfinite(raw.outlet_flow_m3ps)) {
    std::ostringstream out;
    out << "observer: non-finite measurement at t = " << time_s() + dt_s_ << " s";
    return Status::Error(out.str());
  }
  const double tau = gains_.design.prefilter_tau_s;
  TopsideMeasurement at_end;
  at_end.outlet_pressure_pa = pressure_filter_.Step(raw.outlet_pressure_pa, dt_s_, tau);
  at_end.outlet_flow_m3ps = flow_filter_.Step(raw.outlet_flow_m3ps, dt_s_, tau);
  const double y = MeasuredUp(at_end);
  const double e_old = error_;
  for (int i = 0; i <= options_.cells; ++i) q_[i] = u_[i] * e_minus_[i] + v_[i] * e_plus_[i];

  const double e_new = StepOutletNode(y, MeasuredDown(at_end), e_old);
  StepInteriorNodes(e_old, e_new);
  StepDisturbanceModel(e_old, e_new);
  StepInletNode(e_old,
                e_new);  // after the disturbance model: its boundary is C X^ at the new level
  u_.swap(u_next_);
  v_.swap(v_next_);
  error_ = e_new;
  ++steps_;
  if (tracker_) MPDRIG_RETURN_IF_ERROR(TrackFrequency(y));
  if (!std::isfinite(u_[0]) || !std::isfinite(x_hat_(0)) || !std::isfinite(x_hat_(1))) {
    std::ostringstream out;
    out << "observer state is no longer finite at t = " << time_s() << " s";
    return Status::Error(out.str());
  }
  return Status::Ok();
}

// Old-level source terms at a foot (q_ holds the old level's q^):
// S_u = c_1 v + p1 e - kf q|q| e^{sigma x}, S_v = c_2 u + p2 e - kf q|q| e^{-sigma x}.
double BacksteppingObserver::OldSourceU(int i, double e_old) const {
  return c1_[i] * v_[i] + gains_.p1[i] * e_old -
         half_f2_over_a_ * q_[i] * std::fabs(q_[i]) * e_plus_[i];
}
double BacksteppingObserver::OldSourceV(int i, double e_old) const {
  return c2_[i] * u_[i] + gains_.p2[i] * e_old -
         half_f2_over_a_ * q_[i] * std::fabs(q_[i]) * e_minus_[i];
}

// Outlet node: v^(1) = U (10.1.4); u^(1) from its characteristic, implicit in the new error.
// New-level friction kappa q_new e^{sigma} with q_new = u e^{-sigma} + U e^{sigma}. Returns the
// new error y - u^(1).
double BacksteppingObserver::StepOutletNode(double y, double big_u, double e_old) {
  const int n = options_.cells;
  const double hdt = 0.5 * dt_s_;
  const double kappa = half_f2_over_a_ * std::fabs(q_[n]);
  const double ep = e_plus_[n];
  v_next_[n] = big_u;
  u_next_[n] = (u_[n - 1] + hdt * OldSourceU(n - 1, e_old) +
                hdt * ((c1_[n] - kappa * ep * ep) * big_u + gains_.p1[n] * y)) /
               (1.0 + hdt * (gains_.p1[n] + kappa));
  return y - u_next_[n];
}

// Interior nodes: u from the left, v from the right; the new-level coupling is a 2x2 solve:
//   u (1 + hdt kappa) = fu + hdt (c_1 - kappa e^{2 sigma x}) v
//   v (1 + hdt kappa) = fv + hdt (c_2 - kappa e^{-2 sigma x}) u
void BacksteppingObserver::StepInteriorNodes(double e_old, double e_new) {
  const double hdt = 0.5 * dt_s_;
  const double* ep = e_plus_.data();
  const double* em = e_minus_.data();
  const std::vector<double>& p1 = gains_.p1;
  const std::vector<double>& p2 = gains_.p2;
  for (int i = 1; i < options_.cells; ++i) {
    const double kappa = half_f2_over_a_ * std::fabs(q_[i]);
    const double damp = 1.0 / (1.0 + hdt * kappa);
    const double fu = (u_[i - 1] + hdt * OldSourceU(i - 1, e_old) + hdt * p1[i] * e_new) * damp;
    const double fv = (v_[i + 1] + hdt * OldSourceV(i + 1, e_old) + hdt * p2[i] * e_new) * damp;
    const double a = hdt * (c1_[i] - kappa * ep[i] * ep[i]) * damp;
    const double b = hdt * (c2_[i] - kappa * em[i] * em[i]) * damp;
    const double u_new = (fu + a * fv) / (1.0 - a * b);
    u_next_[i] = u_new;
    v_next_[i] = fv + b * u_new;
  }
}

// Disturbance model (10.1.5), Crank-Nicolson.
void BacksteppingObserver::StepDisturbanceModel(double e_old, double e_new) {
  const double hdt = 0.5 * dt_s_;
  const SinusoidDisturbance& d = gains_.disturbance;
  const Eigen::Matrix2d identity = Eigen::Matrix2d::Identity();
  const Eigen::Vector2d rhs =
      (identity + hdt * d.a) * x_hat_ + hdt * gains_.disturbance_gain * (e_old + e_new);
  x_hat_ = (identity - hdt * d.a).partialPivLu().solve(rhs);
}

// Inlet node: u^(0) = -v^(0) + C X^ (10.1.3), so q^(0) = C X^ is known; v^(0) from its
// characteristic.
void BacksteppingObserver::StepInletNode(double e_old, double e_new) {
  const double hdt = 0.5 * dt_s_;
  const double cx = gains_.disturbance.c * x_hat_;
  const double fv = v_[1] + hdt * OldSourceV(1, e_old) + hdt * gains_.p2[0] * e_new -
                    hdt * half_f2_over_a_ * cx * std::fabs(cx);
  const double b = hdt * c2_[0];
  const double v0 = (fv + b * cx) / (1.0 + b);
  v_next_[0] = v0;
  u_next_[0] = -v0 + cx;
}

// Retunes the gains when the tracked heave frequency has moved by more than retune_fraction.
Status BacksteppingObserver::TrackFrequency(double y) {
  tracker_->Update(time_s(), y);
  const double f = tracker_->frequency_hz();
  if (std::fabs(f - options_.disturbance_hz) > options_.retune_fraction * options_.disturbance_hz) {
    return SetDisturbanceFrequency(f);
  }
  return Status::Ok();
}

void BacksteppingObserver::Locate(double x_m, int* index, double* weight) const {
  const int n = options_.cells;
  const double s = std::clamp(x_m / params_.pipe_length_m, 0.0, 1.0) * n;
  *index = std::min(static_cast<int>(s), n - 1);
  *weight = s - *index;
}

double BacksteppingObserver::PressureAtPa(double x_m) const {
  int i;
  double w;
  Locate(x_m, &i, &w);
  const double n = options_.cells;
  const ObserverCoordinates& co = gains_.coordinates;
  return (1.0 - w) * co.Pressure(i / n, u_[i], v_[i], p_sp_pa_) +
         w * co.Pressure((i + 1) / n, u_[i + 1], v_[i + 1], p_sp_pa_);
}

double BacksteppingObserver::FlowAtM3ps(double x_m) const {
  int i;
  double w;
  Locate(x_m, &i, &w);
  const double n = options_.cells;
  const ObserverCoordinates& co = gains_.coordinates;
  return (1.0 - w) * co.Flow(i / n, u_[i], v_[i]) + w * co.Flow((i + 1) / n, u_[i + 1], v_[i + 1]);
}

ObserverEstimate BacksteppingObserver::Estimate() const {
  ObserverEstimate e;
  e.time_s = time_s();
  e.bhp_pa = PressureAtPa(0.0);
  for (int k = 0; k < 10; ++k) e.pt_pa[k] = PressureAtPa(params_.pipe_length_m * k / 9.0);
  e.inlet_flow_m3ps = FlowAtM3ps(0.0);
  e.disturbance_state = x_hat_;
  e.piston_velocity_mps = gains_.disturbance.c_bar * x_hat_;
  e.piston_position_m = -x_hat_(0) / gains_.disturbance.omega_radps;
  e.output_error_m3ps = error_;
  e.disturbance_hz = options_.disturbance_hz;
  return e;
}

namespace {

ObserverEstimate Blend(const ObserverEstimate& a, const ObserverEstimate& b, double t) {
  const double w = b.time_s > a.time_s ? (t - a.time_s) / (b.time_s - a.time_s) : 0.0;
  auto mix = [w](double p, double q) { return (1.0 - w) * p + w * q; };
  ObserverEstimate out;
  out.time_s = t;
  out.bhp_pa = mix(a.bhp_pa, b.bhp_pa);
  for (int k = 0; k < 10; ++k) out.pt_pa[k] = mix(a.pt_pa[k], b.pt_pa[k]);
  out.inlet_flow_m3ps = mix(a.inlet_flow_m3ps, b.inlet_flow_m3ps);
  out.piston_velocity_mps = mix(a.piston_velocity_mps, b.piston_velocity_mps);
  out.piston_position_m = mix(a.piston_position_m, b.piston_position_m);
  out.disturbance_state = (1.0 - w) * a.disturbance_state + w * b.disturbance_state;
  out.output_error_m3ps = mix(a.output_error_m3ps, b.output_error_m3ps);
  out.disturbance_hz = b.disturbance_hz;
  return out;
}

ObserverEstimate NanEstimate(double t) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ObserverEstimate e;
  e.time_s = t;
  e.bhp_pa = e.inlet_flow_m3ps = e.piston_velocity_mps = e.piston_position_m = nan;
  e.output_error_m3ps = e.disturbance_hz = nan;
  e.pt_pa.fill(nan);
  e.disturbance_state = Eigen::Vector2d(nan, nan);
  return e;
}

}  // namespace

Result<std::vector<ObserverEstimate>> RunObserver(const RigParams& params,
                                                  const ObserverOptions& options,
                                                  const TopsideSeries& series,
                                                  const std::vector<double>& output_times) {
  const std::size_t rows = series.time_s.size();
  if (rows < 2 || series.outlet_pressure_pa.size() != rows ||
      series.outlet_flow_m3ps.size() != rows) {
    return Status::Error("observer: need at least two topside samples of equal length");
  }
  for (std::size_t r = 0; r < rows; ++r) {
    if (!std::isfinite(series.time_s[r]) || !std::isfinite(series.outlet_pressure_pa[r]) ||
        !std::isfinite(series.outlet_flow_m3ps[r])) {
      return Status::Error("observer: topside sample " + std::to_string(r) + " is not finite");
    }
    if (r > 0 && !(series.time_s[r] > series.time_s[r - 1])) {
      return Status::Error("observer: topside times must be strictly increasing");
    }
  }
  for (std::size_t k = 1; k < output_times.size(); ++k) {
    if (!(output_times[k] > output_times[k - 1])) {
      return Status::Error("observer: output times must be strictly increasing");
    }
  }
  const double t0 = series.time_s.front();
  const double t_end = series.time_s.back();
  std::size_t cursor = 0;
  auto measure = [&](double t) {
    while (cursor + 2 < rows && series.time_s[cursor + 1] < t) ++cursor;
    const double ta = series.time_s[cursor], tb = series.time_s[cursor + 1];
    const double w = std::clamp((t - ta) / (tb - ta), 0.0, 1.0);
    TopsideMeasurement m;
    m.outlet_pressure_pa =
        (1.0 - w) * series.outlet_pressure_pa[cursor] + w * series.outlet_pressure_pa[cursor + 1];
    m.outlet_flow_m3ps =
        (1.0 - w) * series.outlet_flow_m3ps[cursor] + w * series.outlet_flow_m3ps[cursor + 1];
    return m;
  };
  auto created = BacksteppingObserver::Create(params, options, measure(t0), t0);
  if (!created.ok()) return created.status();
  BacksteppingObserver& obs = *created;

  std::vector<ObserverEstimate> out;
  out.reserve(output_times.size());
  std::size_t next = 0;
  while (next < output_times.size() && output_times[next] < t0) {
    out.push_back(NanEstimate(output_times[next++]));
  }
  ObserverEstimate previous = obs.Estimate();
  long step = 0;
  while (next < output_times.size() && output_times[next] <= t_end) {
    const ObserverEstimate current = obs.Estimate();
    while (next < output_times.size() && output_times[next] <= current.time_s &&
           output_times[next] <= t_end) {
      out.push_back(step == 0 ? current : Blend(previous, current, output_times[next]));
      ++next;
    }
    if (next == output_times.size() || output_times[next] > t_end) break;
    previous = current;
    // Past the end of the series the last sample is held (only to reach the last output time).
    MPDRIG_RETURN_IF_ERROR(obs.Step(measure(std::min(t0 + (step + 1) * obs.time_step_s(), t_end))));
    ++step;
  }
  while (next < output_times.size()) out.push_back(NanEstimate(output_times[next++]));
  return out;
}

}  // namespace mpdrig::observer
