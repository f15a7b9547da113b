// The observer on simulator data: bottom-hole pressure from topside measurements (thesis 10.3).
#include "model/observer/backstepping_observer.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "model/effects/effect.h"

#include "model/common/units.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig::observer {
namespace {

using mpdrig::testing::Drive;
using mpdrig::testing::Held;
using mpdrig::testing::RunSteps;

// Thesis 10.3-like setup: back-pressure pump 20 L/min through a 45 deg choke (choke pressure
// 4.6 bar gauge), choke outlet C1 = 1 bar gauge, a piston sine of `amplitude_m`.
struct Record {
  TopsideSeries topside;
  std::vector<double> bhp_pa;  // PT1 = p(0) of the plant
  double frequency_hz = 0.0;
};

Record SimulatePlant(const RigParams& params, PipeModel model, double frequency_hz,
                     double amplitude_m, double periods, double choke_amplitude_deg = 0.0,
                     double choke_hz = 0.2) {
  SimulationOptions options;
  options.model = model;
  options.cells = 200;
  Drive drive;
  drive.piston_position_m = [=](double t) {
    return amplitude_m * std::sin(2 * M_PI * frequency_hz * t);
  };
  drive.rig = [=](double t) {
    return Held(45.0 + choke_amplitude_deg * std::sin(2 * M_PI * choke_hz * t), 20.0, 1.0);
  };
  Record r;
  r.frequency_hz = frequency_hz;
  RunSteps(params, options, drive, periods / frequency_hz, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    r.topside.time_s.push_back(s.time_s);
    r.topside.outlet_pressure_pa.push_back(s[Channel::kC2]);
    r.topside.outlet_flow_m3ps.push_back(s[Channel::kFT1]);
    r.bhp_pa.push_back(s[Channel::kPT1]);
  });
  return r;
}

struct ErrorStats {
  double max_error_pa = 0.0;  // after `settle_periods`
  double amplitude_pa = 0.0;  // half peak-to-peak of the true BHP over the same window
  double relative() const { return max_error_pa / amplitude_pa; }
};

ErrorStats Evaluate(const Record& r, const std::vector<ObserverEstimate>& est,
                    double settle_periods) {
  ErrorStats s;
  double lo = 1e300, hi = -1e300;
  const double t_settle = settle_periods / r.frequency_hz;
  for (std::size_t k = 0; k < est.size(); ++k) {
    if (r.topside.time_s[k] < t_settle) continue;
    EXPECT_TRUE(std::isfinite(est[k].bhp_pa));
    s.max_error_pa = std::max(s.max_error_pa, std::fabs(est[k].bhp_pa - r.bhp_pa[k]));
    lo = std::min(lo, r.bhp_pa[k]);
    hi = std::max(hi, r.bhp_pa[k]);
  }
  s.amplitude_pa = 0.5 * (hi - lo);
  return s;
}

std::vector<ObserverEstimate> Observe(const RigParams& params, const Record& r,
                                      const ObserverOptions& options) {
  auto est = RunObserver(params, options, r.topside, r.topside.time_s);
  EXPECT_TRUE(est.ok()) << est.status().message();
  return est.ok() ? *est : std::vector<ObserverEstimate>{};
}

// Exactly the observer's model (linear pipe, linear friction): the estimate must become exact up
// to the discretisation, since the error system is the exponentially stable target system
// (convergence in 2 l / c plus the A - L C transient).
TEST(BacksteppingObserverTest, ConvergesOnLinearPlant) {
  const RigParams params = mpdrig::testing::LinearFrictionParams();
  const Record r = SimulatePlant(params, PipeModel::kLinear, 0.2, 0.1, 5.0);
  ObserverOptions options;
  options.disturbance_hz = 0.2;
  const auto est = Observe(params, r, options);
  const ErrorStats s = Evaluate(r, est, 3.0);
  std::printf("linear plant 0.2 Hz: max error %.4g Pa, amplitude %.4g Pa (%.3g %%)\n",
              s.max_error_pa, s.amplitude_pa, 100 * s.relative());
  EXPECT_GT(s.amplitude_pa, 1e4);
  EXPECT_LT(s.relative(), 1e-3);
  // The estimated disturbance is the piston's: v_d = 0.1 m * 2 pi 0.2 Hz cos(2 pi 0.2 t).
  const double omega = 2 * M_PI * 0.2;
  for (std::size_t k = 0; k < est.size(); k += 97) {
    const double t = r.topside.time_s[k];
    if (t < 15.0) continue;
    EXPECT_NEAR(est[k].piston_velocity_mps, 0.1 * omega * std::cos(omega * t), 1e-3 * 0.1 * omega);
    EXPECT_NEAR(est[k].piston_position_m, 0.1 * std::sin(omega * t), 1e-3 * 0.1);
  }

  // The kernel terms matter for the transient: with them the error system is the target system,
  // which converges in finite time 2 l / c = 2.12 s (plus the A - L C transient, e^{-40 t}).
  // With the thesis's approximation of 10.3 (p2 = 0, p1 = C e^{Ah} L) it still converges (the
  // copy is exact), but slowly: measured 13.8 Pa vs 2.5 kPa on [2.5, 4.5] s.
  options.use_kernel = false;
  const auto approx = Observe(params, r, options);
  double with_kernel = 0.0, without_kernel = 0.0;
  for (std::size_t k = 0; k < est.size(); ++k) {
    if (r.topside.time_s[k] < 2.5 || r.topside.time_s[k] > 4.5) continue;
    with_kernel = std::max(with_kernel, std::fabs(est[k].bhp_pa - r.bhp_pa[k]));
    without_kernel = std::max(without_kernel, std::fabs(approx[k].bhp_pa - r.bhp_pa[k]));
  }
  std::printf("error on [2.5, 4.5] s: with kernels %.4g Pa, without %.4g Pa\n", with_kernel,
              without_kernel);
  EXPECT_LT(with_kernel, 1e-3 * s.amplitude_pa);
  EXPECT_GT(without_kernel, 1e-2 * s.amplitude_pa);
}

// The quasi-linear plant with the thesis's friction f1 u + f2 u|u| (8.6.8), 0.1 m piston strokes
// (the lab's usual amplitude, thesis 8.6.1). The criterion: after 3 disturbance periods
// the BHP error is below 2 % of the BHP oscillation amplitude, for 0.1, 0.2 and 0.3 Hz.
//  - With f2 u|u| carried in the observer's copy (quadratic_friction) it holds with a wide margin
//    (measured 0.10 / 0.073 / 0.077 %: what is left is the quasi-linearity).
//  - The thesis's linear observer (f1 only) misses it at 0.1 m strokes (measured 2.96 / 3.59 /
//    2.60 %): the plant's quadratic friction is as large as the linear one there, and it is
//    absent from the observer. At 0.02 m strokes it holds (0.87 / 0.83 / 0.65 %).
class QuasiLinearPlantTest : public ::testing::TestWithParam<double> {};

TEST_P(QuasiLinearPlantTest, BhpErrorBelowTwoPercentAfterThreePeriods) {
  const double hz = GetParam();
  const RigParams params;
  const Record r = SimulatePlant(params, PipeModel::kQuasiLinear, hz, 0.1, 6.0);
  ObserverOptions options;
  options.disturbance_hz = hz;
  options.quadratic_friction = true;
  const ErrorStats s = Evaluate(r, Observe(params, r, options), 3.0);
  options.quadratic_friction = false;
  const ErrorStats thesis = Evaluate(r, Observe(params, r, options), 3.0);
  const Record small = SimulatePlant(params, PipeModel::kQuasiLinear, hz, 0.02, 6.0);
  const ErrorStats thesis_small = Evaluate(small, Observe(params, small, options), 3.0);
  std::printf(
      "%.1f Hz: BHP amplitude %.3g bar; error with f2 %.3g %%, thesis observer %.3g %% "
      "(0.02 m strokes: %.3g %%)\n",
      hz, s.amplitude_pa / 1e5, 100 * s.relative(), 100 * thesis.relative(),
      100 * thesis_small.relative());
  EXPECT_GT(s.amplitude_pa, 2e4);
  EXPECT_LT(s.relative(), 0.02);
  EXPECT_LT(thesis_small.relative(), 0.02);
  // The f2 term is what the thesis observer misses: the error falls at least tenfold with it.
  EXPECT_GT(thesis.relative(), 10.0 * s.relative());
}

INSTANTIATE_TEST_SUITE_P(Frequencies, QuasiLinearPlantTest, ::testing::Values(0.1, 0.2, 0.3));

// Robustness (docs/observer.md table): a wrong assumed frequency (+-10 %) and sensor noise degrade
// the estimate but nothing diverges; the error stays bounded over 20 periods.
struct Robustness {
  double assumed_factor;     // assumed frequency / true frequency
  double noise_pressure_pa;  // standard deviation of white noise on C2
  double noise_flow_lpm;     // standard deviation of white noise on FT1
  bool track = false;        // ObserverOptions::track_frequency
};

struct RobustnessResult {
  ErrorStats max;            // max error after 3 periods
  double rms_pa = 0.0;       // RMS error after 3 periods
  double late_rms_pa = 0.0;  // RMS error over the last 2 periods
};

RobustnessResult RunRobustness(const Record& r, const Robustness& c, std::complex<double> pole) {
  const RigParams params;
  Record noisy = r;
  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (std::size_t k = 0; k < noisy.bhp_pa.size(); ++k) {
    noisy.topside.outlet_pressure_pa[k] += c.noise_pressure_pa * n01(rng);
    noisy.topside.outlet_flow_m3ps[k] += units::LpmToM3ps(c.noise_flow_lpm) * n01(rng);
  }
  ObserverOptions options;
  options.disturbance_hz = r.frequency_hz * c.assumed_factor;
  options.quadratic_friction = true;
  options.pole = pole;
  options.track_frequency = c.track;
  const auto est = Observe(params, noisy, options);
  RobustnessResult out;
  out.max = Evaluate(r, est, 3.0);  // against the noise-free truth
  const double t_settle = 3.0 / r.frequency_hz;
  const double t_late = r.topside.time_s.back() - 2.0 / r.frequency_hz;
  double sum = 0.0, late_sum = 0.0;
  int count = 0, late_count = 0;
  for (std::size_t k = 0; k < est.size(); ++k) {
    const double t = r.topside.time_s[k];
    const double e2 = std::pow(est[k].bhp_pa - r.bhp_pa[k], 2);
    if (t >= t_settle) sum += e2, ++count;
    if (t >= t_late) late_sum += e2, ++late_count;
  }
  out.rms_pa = std::sqrt(sum / count);
  out.late_rms_pa = std::sqrt(late_sum / late_count);
  return out;
}

// Noise: white, one independent sample per simulator step (189 Hz), 0.01 bar on C2 and
// 0.05 L/min on FT1.
TEST(BacksteppingObserverRobustnessTest, DegradesGracefullyAndStaysBounded) {
  const Record r = SimulatePlant(RigParams(), PipeModel::kQuasiLinear, 0.2, 0.1, 20.0);
  const std::vector<Robustness> cases = {
      {1.0, 0.0, 0.0},     {0.9, 0.0, 0.0},       {1.1, 0.0, 0.0},          {1.0, 1000.0, 0.05},
      {1.1, 1000.0, 0.05}, {0.9, 0.0, 0.0, true}, {1.1, 1000.0, 0.05, true}};
  for (std::complex<double> pole : {std::complex<double>(-40, 20), {-4, 2}}) {
    for (const Robustness& c : cases) {
      const RobustnessResult res = RunRobustness(r, c, pole);
      const double amp = res.max.amplitude_pa;
      std::printf("| %g+-%gi | %.1f%s | %.0f Pa, %.2f L/min | %.3g %% | %.3g %% | %.3g %% |\n",
                  pole.real(), pole.imag(), c.assumed_factor, c.track ? " tracked" : "",
                  c.noise_pressure_pa, c.noise_flow_lpm, 100 * res.max.relative(),
                  100 * res.rms_pa / amp, 100 * res.late_rms_pa / amp);
      ASSERT_TRUE(std::isfinite(res.rms_pa));
      // Bounded: the last two of 20 periods are no worse than the whole run after 3 periods
      // (up to the sampling of the noise), and the error stays below the oscillation itself.
      EXPECT_LE(res.late_rms_pa, 1.3 * res.rms_pa);
      EXPECT_LT(res.rms_pa, amp);
    }
  }
}

// Beyond the thesis: the observer told a frequency 10 % off, with online tracking, ends up as
// good as the one told the right frequency, while the untracked one keeps a ~7 % RMS error.
TEST(BacksteppingObserverTrackingTest, TrackedFrequencyRecoversKnownFrequencyAccuracy) {
  const RigParams params;
  const Record r = SimulatePlant(params, PipeModel::kQuasiLinear, 0.2, 0.1, 20.0);
  auto rms_late = [&](const std::vector<ObserverEstimate>& est) {
    const double t_late = r.topside.time_s.back() - 5.0 / r.frequency_hz;
    double sum = 0.0;
    int count = 0;
    for (std::size_t k = 0; k < est.size(); ++k) {
      if (r.topside.time_s[k] < t_late) continue;
      sum += std::pow(est[k].bhp_pa - r.bhp_pa[k], 2);
      ++count;
    }
    return std::sqrt(sum / count);
  };
  ObserverOptions options;
  options.quadratic_friction = true;
  options.disturbance_hz = 0.2;
  const double known = rms_late(Observe(params, r, options));
  options.disturbance_hz = 0.22;
  const double wrong = rms_late(Observe(params, r, options));
  options.track_frequency = true;
  const auto tracked_est = Observe(params, r, options);
  const double tracked = rms_late(tracked_est);
  const double amp = Evaluate(r, tracked_est, 3.0).amplitude_pa;
  std::printf(
      "RMS BHP error over the last 5 of 20 periods: known 0.2 Hz %.3g %%, told 0.22 Hz %.3g %%, "
      "told 0.22 Hz + tracking %.3g %% (tracked %.4f Hz)\n",
      100 * known / amp, 100 * wrong / amp, 100 * tracked / amp, tracked_est.back().disturbance_hz);
  EXPECT_NEAR(tracked_est.back().disturbance_hz, 0.2, 0.002);
  EXPECT_LT(tracked, 0.02 * amp);
  EXPECT_LT(tracked, 0.2 * wrong);
}

// Thesis 10.3's figure 10.3.2: the choke moved sinusoidally at 0.2 Hz (here +-5 deg around
// 45 deg) under a 0.25 Hz heave. The observer takes the measured C2 and FT1 as its boundary, so
// the choke needs no model: the criterion still holds. The frequency tracker, in contrast, sees
// two oscillations in y; it is not asserted here (docs/observer.md).
TEST(BacksteppingObserverTest, ChokeMovingDoesNotMatter) {
  const RigParams params;
  const Record r = SimulatePlant(params, PipeModel::kQuasiLinear, 0.25, 0.1, 6.0, 5.0, 0.2);
  ObserverOptions options;
  options.disturbance_hz = 0.25;
  options.quadratic_friction = true;
  const ErrorStats s = Evaluate(r, Observe(params, r, options), 3.0);
  options.track_frequency = true;
  const auto tracked_est = Observe(params, r, options);
  const ErrorStats tracked = Evaluate(r, tracked_est, 3.0);
  std::printf(
      "choke 45 +- 5 deg at 0.2 Hz, heave 0.25 Hz: error %.3g %% of %.3g bar; tracked "
      "%.3g %% (ends at %.4g Hz)\n",
      100 * s.relative(), s.amplitude_pa / 1e5, 100 * tracked.relative(),
      tracked_est.back().disturbance_hz);
  EXPECT_LT(s.relative(), 0.02);
}

// Model error in the plant: the plant's wave speed or linear
// friction differs from the observer's by 10 % / a factor 2. The error grows with the mismatch
// but stays bounded (the last 2 of 20 periods no worse than the whole run after 3 periods).
TEST(BacksteppingObserverRobustnessTest, PlantParameterMismatchStaysBounded) {
  struct Mismatch {
    const char* name;
    double wave_speed_mps;
    double f1_per_s;
  };
  for (const Mismatch& m : {Mismatch{"c +10 %", 935.0, 0.15}, Mismatch{"c -10 %", 765.0, 0.15},
                            Mismatch{"f1 x2", 850.0, 0.30}}) {
    RigParams plant;
    plant.wave_speed_mps = m.wave_speed_mps;
    plant.friction_f1_per_s = m.f1_per_s;
    const Record r = SimulatePlant(plant, PipeModel::kQuasiLinear, 0.2, 0.1, 20.0);
    ObserverOptions options;
    options.disturbance_hz = 0.2;
    options.quadratic_friction = true;
    const auto est = Observe(RigParams(), r, options);
    const ErrorStats all = Evaluate(r, est, 3.0);
    const ErrorStats late = Evaluate(r, est, 18.0);
    std::printf("plant %s: max error after 3 periods %.3g %%, last 2 periods %.3g %%\n", m.name,
                100 * all.relative(), 100 * late.max_error_pa / all.amplitude_pa);
    EXPECT_LE(late.max_error_pa, all.max_error_pa);
    EXPECT_LT(all.relative(), 1.0);
  }
}

// Robustness to a plant the observer does not model: the plant has one physical effect
// at its default strength (model/effects), the observer does not know it. Bounded: the last 2 of
// 20 periods no worse than the whole run after 3 periods, and below the oscillation amplitude.
TEST(BacksteppingObserverRobustnessTest, PlantWithACatalogueEffectStaysBounded) {
  for (const EffectInfo* info : EffectCatalogue()) {
    RigParams plant;
    ASSERT_TRUE(ApplyEffectSpec(&plant, info->name).ok());
    const Record r = SimulatePlant(plant, PipeModel::kQuasiLinear, 0.2, 0.1, 20.0);
    ObserverOptions options;
    options.disturbance_hz = 0.2;
    options.quadratic_friction = true;
    const auto est = Observe(RigParams(), r, options);
    const ErrorStats all = Evaluate(r, est, 3.0);
    const ErrorStats late = Evaluate(r, est, 18.0);
    std::printf("plant with %s: max error after 3 periods %.3g %%, last 2 periods %.3g %%\n",
                std::string(info->name).c_str(), 100 * all.relative(),
                100 * late.max_error_pa / all.amplitude_pa);
    EXPECT_LE(late.max_error_pa, all.max_error_pa * 1.0001) << info->name;
    EXPECT_LT(all.relative(), 1.0) << info->name;
  }
}

}  // namespace
}  // namespace mpdrig::observer
