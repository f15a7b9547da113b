// The observer at the lab's sensor noise, where the thesis's own tuning fails: the noise estimate,
// the Kalman gain of the heave model, the zero-lag prefilter, and the bottom-hole pressure fit they
// give.
#include "model/observer/measurement_noise.h"

#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "model/observer/backstepping_observer.h"
#include "tests/model/observer/noisy_topside.h"

namespace mpdrig::observer {
namespace {

using mpdrig::testing::FitPercent;
using mpdrig::testing::SimulateTopside;
using mpdrig::testing::TopsideLog;
using mpdrig::testing::WithLabNoise;

// White noise of sigma 1 on a slow sine 100x larger: the second differences see the noise only.
// 6000 samples: the median's relative standard error is about 1.7 / sqrt(6000) = 2 %, so 6 % is
// three of them.
TEST(MeasurementNoiseTest, RobustSigmaSeesTheNoiseNotTheHeave) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<double> s(6000), clean(6000);
  for (std::size_t k = 0; k < s.size(); ++k) {
    clean[k] = 100.0 * std::sin(2 * M_PI * 0.2 * k * 0.01);
    s[k] = clean[k] + n01(rng);
  }
  EXPECT_NEAR(RobustNoiseSigma(s), 1.0, 0.06);
  // The sine alone: d2 = 100 (2 pi 0.2 0.01)^2 sin = 0.016 at most.
  EXPECT_LT(RobustNoiseSigma(clean), 0.02);
  EXPECT_EQ(RobustNoiseSigma({1.0, 2.0}), 0.0);
  // A channel that repeats each value 4 times (a meter updating at a quarter of the log's rate):
  // not 0, and of the order of the noise (the held samples make it neither white nor exact).
  std::vector<double> held(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) held[k] = s[k - k % 4];
  EXPECT_GT(RobustNoiseSigma(held), 0.3);
  EXPECT_LT(RobustNoiseSigma(held), 1.5);
}

// F(s) = (1 + 2 tau s) / (1 + tau s)^2: no lag on a ramp (1 - F has a double zero at s = 0), and
// a variance share of 5 dt / (4 tau) of white noise (measurement_noise.h; 20000 samples: the
// variance's relative standard error is ~ sqrt(2 tau / (20000 dt)) = 2 %, tolerance 8 %).
TEST(MeasurementNoiseTest, ZeroLagFilterHasNoDelayAndPassesItsShareOfNoise) {
  const double dt = 0.005, tau = 0.1;
  ZeroLagFilter ramp;
  ramp.Reset(0.0);
  double t = 0.0;
  for (int k = 0; k < 400; ++k) t += dt, ramp.Step(3.0 * t, dt, tau);
  EXPECT_NEAR(ramp.value(), 3.0 * t, 1e-6);
  ZeroLagFilter noise;
  noise.Reset(0.0);
  std::mt19937 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  double sum2 = 0.0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) sum2 += std::pow(noise.Step(n01(rng), dt, tau), 2);
  EXPECT_NEAR(sum2 / n, 5.0 * dt / (4.0 * tau), 0.08 * 5.0 * dt / (4.0 * tau));
  // tau = 0 passes through.
  EXPECT_EQ(noise.Step(7.0, dt, 0.0), 7.0);
}

// The Hamiltonian solution against the filter Riccati ODE dP/dt = A P + P A' + q I - P C'C P / r
// integrated to steady state (RK4), an independent method.
TEST(MeasurementNoiseTest, KalmanPoleSolvesTheRiccatiEquation) {
  for (double omega : {0.6, 1.3, 2.1}) {
    for (double ratio : {1e-2, 1.0, 1e3}) {
      const double q = 1e-4, r = q / ratio;
      auto poles = KalmanPoles(omega, q, r);
      ASSERT_TRUE(poles.ok()) << poles.status().message();
      const std::complex<double>* pole = &(*poles)[0];
      Eigen::Matrix2d a;
      a << 0.0, -omega, omega, 0.0;
      const Eigen::RowVector2d c(0.0, 1.0);
      auto rhs = [&](const Eigen::Matrix2d& p) {
        return Eigen::Matrix2d(a * p + p * a.transpose() + q * Eigen::Matrix2d::Identity() -
                               p * c.transpose() * c * p / r);
      };
      Eigen::Matrix2d p = Eigen::Matrix2d::Zero();
      const double h = 2e-3 / (omega + std::abs((*poles)[1]) + std::abs(*pole));
      for (int k = 0; k < 400000; ++k) {
        const Eigen::Matrix2d k1 = rhs(p), k2 = rhs(p + 0.5 * h * k1), k3 = rhs(p + 0.5 * h * k2),
                              k4 = rhs(p + h * k3);
        p += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      const Eigen::Matrix2d closed = a - p * c.transpose() * c / r;
      // Same characteristic polynomial s^2 + a1 s + a0 (the pole order does not matter).
      const std::complex<double> sum = (*poles)[0] + (*poles)[1];
      const std::complex<double> product = (*poles)[0] * (*poles)[1];
      EXPECT_NEAR(-sum.real(), -closed.trace(), 1e-6 * std::abs(sum)) << omega << " " << ratio;
      EXPECT_NEAR(product.real(), closed.determinant(), 1e-6 * std::abs(product))
          << omega << " " << ratio;
    }
  }
  EXPECT_FALSE(KalmanPoles(1.0, 0.0, 1.0).ok());
}

ObserverOptions Defaults(double hz, const TopsideSeries& measured, bool quadratic_friction) {
  ObserverOptions options;  // GainDesign::kNoise
  options.disturbance_hz = hz;
  options.quadratic_friction = quadratic_friction;
  auto noise =
      EstimateTopsideNoise(measured.time_s, measured.outlet_pressure_pa, measured.outlet_flow_m3ps);
  EXPECT_TRUE(noise.ok()) << noise.status().message();
  if (noise.ok()) options.noise = *noise;
  return options;
}

double BhpFit(const TopsideLog& log, const TopsideSeries& measured,
              const ObserverOptions& options) {
  const RigParams params;
  auto est = RunObserver(params, options, measured, log.truth.time_s);
  EXPECT_TRUE(est.ok()) << est.status().message();
  if (!est.ok()) return -1e9;
  std::vector<double> bhp(est->size());
  for (std::size_t k = 0; k < bhp.size(); ++k) bhp[k] = (*est)[k].bhp_pa;
  return FitPercent(log.truth.time_s, log.bhp_pa, bhp, 20.0);
}

// The criterion: at lab noise, the default observer's BHP fit against the true p(0) after
// 20 s is >= 90 %, for heaves of 0.1, 0.2 and 0.33 Hz, two choke openings, three noise seeds,
// with the noise estimated from the log, both for `observe`'s default (linear friction only, the
// thesis's observer) and the service's (quadratic friction in the copy). 60 s logs (40 s scored).
// Measured 93.9-97.6 % (docs/observer.md); 90 % leaves 3.9 points for other generators.
// The thesis's poles on the same data must fall well short (measured -155 % to 76 %): the check
// can fail, and what it checks is the gain choice.
class ObserverAtLabNoiseTest : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(ObserverAtLabNoiseTest, DefaultsFitTheTrueBhpAfter20s) {
  const auto [hz, choke_deg] = GetParam();
  const TopsideLog log = SimulateTopside(hz, choke_deg, 60.0);
  for (unsigned seed : {1u, 2u, 3u}) {
    const TopsideSeries noisy = WithLabNoise(log.truth, seed);
    for (bool quadratic : {false, true}) {
      ObserverOptions options = Defaults(hz, noisy, quadratic);
      auto design = DesignForNoise(RigParams(), options);
      ASSERT_TRUE(design.ok());
      const double fit = BhpFit(log, noisy, options);
      options.gain_design = GainDesign::kPoles;  // the thesis's -40 +- 20i
      const double thesis = BhpFit(log, noisy, options);
      std::printf(
          "| %.2f Hz | %2.0f deg | seed %u | %s | C2 %.0f Pa, FT1 %.3f L/min | pole %.2f%+.2fi, "
          "%.2f%+.2fi, tau %.3f s | default %.1f %% | thesis %.1f %% |\n",
          hz, choke_deg, seed, quadratic ? "f2 in copy" : "linear",
          options.noise.outlet_pressure_pa, units::M3psToLpm(options.noise.outlet_flow_m3ps),
          design->poles[0].real(), design->poles[0].imag(), design->poles[1].real(),
          design->poles[1].imag(), design->prefilter_tau_s, fit, thesis);
      EXPECT_GE(fit, 90.0) << hz << " Hz, " << choke_deg << " deg, seed " << seed;
      EXPECT_LT(thesis, 85.0) << hz << " Hz, " << choke_deg << " deg, seed " << seed;
      // The design is the noise's: slower than the thesis's poles, with the prefilter on.
      EXPECT_LT(std::abs(design->poles[1]), 0.5 * std::abs(std::complex<double>(-40, 20)));
      EXPECT_GT(design->prefilter_tau_s, 0.0);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(HeaveAndChoke, ObserverAtLabNoiseTest,
                         ::testing::Combine(::testing::Values(0.1, 0.2, 0.33),
                                            ::testing::Values(45.0, 60.0)));

// Noise-free data: the noise estimated from the log is far too small to slow the thesis's poles,
// so the default is the thesis's observer exactly (same estimates, bit for bit), and its fit is
// the noise-free one (measured 99.9 %).
TEST(ObserverAtLabNoiseTest, NoiseFreeLogKeepsTheThesisDesign) {
  const TopsideLog log = SimulateTopside(0.2, 45.0, 40.0);
  ObserverOptions options = Defaults(0.2, log.truth, true);
  auto design = DesignForNoise(RigParams(), options);
  ASSERT_TRUE(design.ok());
  // (Its Kalman filter's faster pole would be about -700 rad/s: not even computed, NaN.)
  std::printf("noise-free log: estimated C2 %.3g Pa, FT1 %.3g L/min; poles %g%+gi\n",
              options.noise.outlet_pressure_pa, units::M3psToLpm(options.noise.outlet_flow_m3ps),
              design->poles[0].real(), design->poles[0].imag());
  EXPECT_TRUE(std::isnan(design->kalman[0].real()));
  EXPECT_EQ(design->poles[0], std::complex<double>(-40, 20));
  EXPECT_EQ(design->prefilter_tau_s, 0.0);
  const RigParams params;
  auto by_noise = RunObserver(params, options, log.truth, log.truth.time_s);
  options.gain_design = GainDesign::kPoles;
  auto thesis = RunObserver(params, options, log.truth, log.truth.time_s);
  ASSERT_TRUE(by_noise.ok() && thesis.ok());
  for (std::size_t k = 0; k < thesis->size(); k += 50) {
    ASSERT_EQ((*by_noise)[k].bhp_pa, (*thesis)[k].bhp_pa);
  }
  EXPECT_GE(BhpFit(log, log.truth, options), 99.0);
}

// A tenth of the lab's noise still designs by the noise (the poles scale with its fourth root)
// and does at least as well as at full noise; bad noise values are refused.
TEST(ObserverAtLabNoiseTest, LessNoiseFitsBetterAndBadNoiseIsRefused) {
  const TopsideLog log = SimulateTopside(0.2, 45.0, 60.0);
  const TopsideSeries quiet = WithLabNoise(log.truth, 4, 0.1);
  const TopsideSeries lab = WithLabNoise(log.truth, 4, 1.0);
  const double fit_quiet = BhpFit(log, quiet, Defaults(0.2, quiet, true));
  const double fit_lab = BhpFit(log, lab, Defaults(0.2, lab, true));
  std::printf("0.2 Hz, 45 deg: fit at 0.1x lab noise %.1f %%, at lab noise %.1f %%\n", fit_quiet,
              fit_lab);
  EXPECT_GE(fit_quiet, fit_lab);
  // Vanishing noise (down to the last bits of a double) is negligible, never an error.
  for (double sigma : {1e-300, 1e-20, 1e-9, 1e-3}) {
    ObserverOptions tiny;
    tiny.noise.outlet_pressure_pa = sigma;
    tiny.noise.outlet_flow_m3ps = sigma * 1e-10;
    auto design = DesignForNoise(RigParams(), tiny);
    ASSERT_TRUE(design.ok()) << sigma << ": " << design.status().message();
    EXPECT_EQ(design->poles[0], std::complex<double>(-40, 20)) << sigma;
    EXPECT_EQ(design->prefilter_tau_s, 0.0) << sigma;
  }
  ObserverOptions bad;
  bad.noise.outlet_pressure_pa = -1.0;
  EXPECT_FALSE(bad.Validate().ok());
  bad.noise.outlet_pressure_pa = std::nan("");
  EXPECT_FALSE(bad.Validate().ok());
}

}  // namespace
}  // namespace mpdrig::observer
