// The backstepping observer (thesis 10, Aamo 2013) run beside a live rig: it takes the rig's
// sensor samples as they come, uses only the topside channels a real rig has without a downhole
// transmitter, C2 (= p(l)) and the pipe outlet flow FT1, and estimates the bottom-hole pressure,
// the heave velocity and the pressure along the pipe. Transport-free, like RigHost.
//
// Streaming: the observer steps on its own characteristic grid (dt = l / (c N), 5.3 ms at the
// defaults), independent of the sensor period. On each sample it takes every step whose end lies
// at or before the sample's time, with C2 and FT1 interpolated linearly between the previous
// sample and this one (as RunObserver does for a log). The estimate therefore lags the sample by
// less than one observer step; RigEstimate carries both times.
//
// Disturbance frequency omega (10.2.10), which the thesis's observer must be told:
//   - while the heave generator runs a sine, its commanded frequency (the rig knows it);
//   - otherwise the online FrequencyTracker on the measured up-going wave y = u(1) (beyond the
//     thesis; frequency_tracker.h), once it has seen enough periods; until then the last
//     frequency in use (the tracker's starting guess at first).
// The gains are retuned (BacksteppingObserver::SetDisturbanceFrequency) when the frequency in use
// moves by more than ObserverOptions::retune_fraction.
//
// Measurement noise (GainDesign::kNoise, measurement_noise.h): the observer starts with the
// configured noise (ObserverOptions::noise; zero by default: the thesis's poles). Over the first
// noise_window_s of samples it collects C2 and FT1; at the window's end it estimates their noise
// (1.4826 median|second difference| / sqrt(6)) and, per channel, takes the larger of the
// configured and the estimated level; if that differs from what is in use, the gains and the
// prefilter are recomputed (BacksteppingObserver::SetMeasurementNoise). On a noise-free rig the
// estimate is far below anything that would slow the thesis's poles, so they stay.
#pragma once

#include <optional>
#include <vector>

#include "model/common/status.h"
#include "model/observer/backstepping_observer.h"
#include "model/observer/frequency_tracker.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::service {

struct RigObserverOptions {
  // cells, poles, friction; disturbance_hz is the starting frequency when no sine is commanded.
  // The service's default runs the plant's quadratic friction in the observer's pipe copy
  // (docs/observer.md: 0.07 % instead of 3.6 % BHP error at 0.1 m strokes).
  observer::ObserverOptions observer;
  double noise_window_s = 5.0;  // start-up window for the noise estimate; 0: configured only
  RigObserverOptions() { observer.quadratic_friction = true; }
};

enum class FrequencySource { kPistonSine, kTracked, kUnlocked };

struct RigObserverEstimate {
  observer::ObserverEstimate estimate;  // SI, absolute pressure; time_s is the observer's
  FrequencySource frequency_source = FrequencySource::kUnlocked;
};

class RigObserver {
 public:
  // Starts at rest on the first sample (BacksteppingObserver::Create).
  static Result<RigObserver> Create(const RigParams& params, const RigObserverOptions& options,
                                    const RigSample& first);

  // Advances to `sample.time_s`. `commanded_sine_hz`: the heave generator's sine frequency while
  // one runs (nullopt otherwise). Fails if the observer's state stops being finite; the caller
  // reports that and stops using this observer.
  Status Update(const RigSample& sample, std::optional<double> commanded_sine_hz);

  RigObserverEstimate Estimate() const;
  const observer::ObserverGains& gains() const { return observer_.gains(); }
  const observer::ObserverOptions& options() const { return observer_.options(); }
  double PressureAtPa(double x_m) const { return observer_.PressureAtPa(x_m); }

 private:
  RigObserver(observer::BacksteppingObserver observer, observer::FrequencyTracker tracker,
              double time_s, observer::TopsideMeasurement last, double noise_window_s)
      : observer_(std::move(observer)),
        tracker_(std::move(tracker)),
        last_time_s_(time_s),
        last_(last),
        noise_window_end_s_(time_s + noise_window_s) {}
  Status EstimateNoise();
  static observer::TopsideMeasurement Topside(const RigSample& sample);
  double UpWave(const observer::TopsideMeasurement& m) const;

  observer::BacksteppingObserver observer_;
  observer::FrequencyTracker tracker_;
  double last_time_s_;
  observer::TopsideMeasurement last_;
  FrequencySource source_ = FrequencySource::kUnlocked;
  // Start-up window of topside samples for the noise estimate (emptied when it is done).
  double noise_window_end_s_;
  bool noise_estimated_ = false;
  std::vector<double> window_time_s_, window_pressure_pa_, window_flow_m3ps_;
};

}  // namespace mpdrig::service
