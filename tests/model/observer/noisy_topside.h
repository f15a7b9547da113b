// Test logs at the lab's noise: a simulated run (quasi-linear plant, the thesis's parameters,
// back-pressure pump 20 L/min through the choke, C1 = 1 bar(g), a 0.1 m piston sine) sampled at
// the lab's 100 Hz logging rate, with white noise of thesis Table 4.1.1 added to the topside
// channels, and the noise-free bottom-hole pressure p(0) kept as the truth.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "model/common/units.h"
#include "model/observer/backstepping_observer.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig::testing {

// Table 4.1.1 as the project reads it (--sensor-noise lab): pressure transmitters 0.15 % of 16 bar,
// turbine flow meters 2 % of reading + 0.05 L/min (standard deviations, white at the logging rate).
inline constexpr double kLabPressureNoisePa = 2400.0;
inline constexpr double kLabFlowNoiseFraction = 0.02;
inline constexpr double kLabFlowNoiseLpm = 0.05;
inline constexpr double kLogPeriodS = 0.01;

struct TopsideLog {
  double heave_hz = 0.0;
  observer::TopsideSeries truth;  // noise-free C2 and FT1 at 100 Hz
  std::vector<double> bhp_pa;     // noise-free p(0) (PT1) at the same times
};

inline TopsideLog SimulateTopside(double heave_hz, double choke_deg, double duration_s,
                                  double stroke_m = 0.1) {
  const RigParams params;
  SimulationOptions options;
  options.cells = 200;
  Drive drive;
  drive.piston_position_m = [=](double t) { return stroke_m * std::sin(2 * M_PI * heave_hz * t); };
  drive.rig = [=](double) { return Held(choke_deg, 20.0, 1.0); };
  std::vector<double> t, p, q, b;
  RunSteps(params, options, drive, duration_s, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    t.push_back(s.time_s);
    p.push_back(s[Channel::kC2]);
    q.push_back(s[Channel::kFT1]);
    b.push_back(s[Channel::kPT1]);
  });
  // The simulator's step (5.3 ms) resampled to the logging period, linearly.
  TopsideLog log;
  log.heave_hz = heave_hz;
  std::size_t k = 0;
  for (long n = 0; n * kLogPeriodS <= t.back(); ++n) {
    const double tt = n * kLogPeriodS;
    while (k + 2 < t.size() && t[k + 1] < tt) ++k;
    const double w = (tt - t[k]) / (t[k + 1] - t[k]);
    auto at = [&](const std::vector<double>& v) { return (1 - w) * v[k] + w * v[k + 1]; };
    log.truth.time_s.push_back(tt);
    log.truth.outlet_pressure_pa.push_back(at(p));
    log.truth.outlet_flow_m3ps.push_back(at(q));
    log.bhp_pa.push_back(at(b));
  }
  return log;
}

// The topside channels with lab noise times `scale`, from `seed`.
inline observer::TopsideSeries WithLabNoise(const observer::TopsideSeries& truth, unsigned seed,
                                            double scale = 1.0) {
  observer::TopsideSeries noisy = truth;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (std::size_t k = 0; k < noisy.time_s.size(); ++k) {
    const double flow_sigma = kLabFlowNoiseFraction * std::fabs(truth.outlet_flow_m3ps[k]) +
                              units::LpmToM3ps(kLabFlowNoiseLpm);
    noisy.outlet_pressure_pa[k] += scale * kLabPressureNoisePa * n01(rng);
    noisy.outlet_flow_m3ps[k] += scale * flow_sigma * n01(rng);
  }
  return noisy;
}

// MATLAB compare's fit, 100 (1 - ||y - yhat|| / ||y - mean(y)||) %, over t > after_s.
inline double FitPercent(const std::vector<double>& time_s, const std::vector<double>& truth,
                         const std::vector<double>& estimate, double after_s) {
  double mean = 0.0;
  int count = 0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (time_s[k] > after_s) mean += truth[k], ++count;
  }
  mean /= count;
  double e2 = 0.0, d2 = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (time_s[k] <= after_s) continue;
    e2 += std::pow(truth[k] - estimate[k], 2);
    d2 += std::pow(truth[k] - mean, 2);
  }
  return 100.0 * (1.0 - std::sqrt(e2 / d2));
}

}  // namespace mpdrig::testing
