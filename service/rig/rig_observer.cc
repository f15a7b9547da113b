#include "service/rig/rig_observer.h"

#include <algorithm>
#include <cmath>

namespace mpdrig::service {

observer::TopsideMeasurement RigObserver::Topside(const RigSample& sample) {
  observer::TopsideMeasurement m;
  m.outlet_pressure_pa = sample[Channel::kC2];
  m.outlet_flow_m3ps = sample[Channel::kFT1];
  return m;
}

// y = u(1) up to a constant (p_sp = 0): the tracker removes its own running mean, so the
// observer's set point does not matter to it.
double RigObserver::UpWave(const observer::TopsideMeasurement& m) const {
  return observer_.gains().coordinates.UpWave(1.0, m.outlet_pressure_pa, m.outlet_flow_m3ps, 0.0);
}

Result<RigObserver> RigObserver::Create(const RigParams& params, const RigObserverOptions& options,
                                        const RigSample& first) {
  // The service chooses the frequency; the observer's own tracker stays off.
  observer::ObserverOptions o = options.observer;
  o.track_frequency = false;
  const observer::TopsideMeasurement m = Topside(first);
  auto created = observer::BacksteppingObserver::Create(params, o, m, first.time_s);
  if (!created.ok()) return created.status();
  observer::FrequencyTrackerOptions tracking;
  tracking.initial_hz = o.disturbance_hz;
  tracking.min_hz = std::min(tracking.min_hz, o.disturbance_hz);
  tracking.max_hz = std::max(tracking.max_hz, o.disturbance_hz);
  const double y0 =
      created->gains().coordinates.UpWave(1.0, m.outlet_pressure_pa, m.outlet_flow_m3ps, 0.0);
  auto tracker = observer::FrequencyTracker::Create(tracking, first.time_s, y0);
  if (!tracker.ok()) return tracker.status();
  RigObserver rig_observer(std::move(created).value(), std::move(tracker).value(), first.time_s, m,
                           options.noise_window_s);
  rig_observer.noise_estimated_ =
      !(options.noise_window_s > 0.0) || o.gain_design != observer::GainDesign::kNoise;
  if (!rig_observer.noise_estimated_) {
    rig_observer.window_time_s_.push_back(first.time_s);
    rig_observer.window_pressure_pa_.push_back(m.outlet_pressure_pa);
    rig_observer.window_flow_m3ps_.push_back(m.outlet_flow_m3ps);
  }
  return rig_observer;
}

Status RigObserver::EstimateNoise() {
  noise_estimated_ = true;
  auto estimated =
      observer::EstimateTopsideNoise(window_time_s_, window_pressure_pa_, window_flow_m3ps_);
  window_time_s_ = {};
  window_pressure_pa_ = {};
  window_flow_m3ps_ = {};
  if (!estimated.ok()) return Status::Ok();  // too few samples: keep the configured noise
  const observer::MeasurementNoise& in_use = observer_.options().noise;
  observer::MeasurementNoise noise = *estimated;
  noise.outlet_pressure_pa = std::max(noise.outlet_pressure_pa, in_use.outlet_pressure_pa);
  noise.outlet_flow_m3ps = std::max(noise.outlet_flow_m3ps, in_use.outlet_flow_m3ps);
  if (noise.outlet_pressure_pa == in_use.outlet_pressure_pa &&
      noise.outlet_flow_m3ps == in_use.outlet_flow_m3ps) {
    return Status::Ok();
  }
  return observer_.SetMeasurementNoise(noise);
}

Status RigObserver::Update(const RigSample& sample, std::optional<double> commanded_sine_hz) {
  const observer::TopsideMeasurement now = Topside(sample);
  const double t0 = last_time_s_;
  const double span = sample.time_s - t0;
  if (span > 0.0) {
    const double dt = observer_.time_step_s();
    // Steps ending at or before the sample (a relative 1e-9 of a step absorbs rounding).
    while (observer_.time_s() + dt <= sample.time_s + 1e-9 * dt) {
      const double t = observer_.time_s() + dt;
      const double w = std::clamp((t - t0) / span, 0.0, 1.0);
      observer::TopsideMeasurement m;
      m.outlet_pressure_pa = (1.0 - w) * last_.outlet_pressure_pa + w * now.outlet_pressure_pa;
      m.outlet_flow_m3ps = (1.0 - w) * last_.outlet_flow_m3ps + w * now.outlet_flow_m3ps;
      MPDRIG_RETURN_IF_ERROR(observer_.Step(m));
      tracker_.Update(t, UpWave(m));
    }
    last_time_s_ = sample.time_s;
    last_ = now;
    if (!noise_estimated_) {
      window_time_s_.push_back(sample.time_s);
      window_pressure_pa_.push_back(now.outlet_pressure_pa);
      window_flow_m3ps_.push_back(now.outlet_flow_m3ps);
      if (sample.time_s >= noise_window_end_s_) MPDRIG_RETURN_IF_ERROR(EstimateNoise());
    }
  }

  // The frequency in use: the commanded sine's, else the tracker's once locked, else unchanged.
  const double in_use = observer_.options().disturbance_hz;
  double wanted = in_use;
  if (commanded_sine_hz && *commanded_sine_hz > 0.0) {
    wanted = *commanded_sine_hz;
    source_ = FrequencySource::kPistonSine;
  } else if (tracker_.locked()) {
    wanted = tracker_.frequency_hz();
    source_ = FrequencySource::kTracked;
  } else {
    source_ = FrequencySource::kUnlocked;
  }
  if (std::fabs(wanted - in_use) > observer_.options().retune_fraction * in_use) {
    MPDRIG_RETURN_IF_ERROR(observer_.SetDisturbanceFrequency(wanted));
  }
  return Status::Ok();
}

RigObserverEstimate RigObserver::Estimate() const { return {observer_.Estimate(), source_}; }

}  // namespace mpdrig::service
