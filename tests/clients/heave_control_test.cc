// The blocks of a BHP controller in the client library (clients/client/heave_control.h), without
// a rig, against closed forms: the heave fit recovers known harmonics under the lab's noise, the
// set point learnt over whole heave periods is the signal's mean, and the adaptive canceller
// converges to theta* = -D/G exactly when its plant model is within 90 degrees of the true plant
// (Re{G/G^} > 0), and not otherwise.
#include "clients/client/heave_control.h"

#include <cmath>
#include <complex>
#include <deque>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;
// PT1's noise at the lab (thesis Table 4.1.1, serve's --sensor-noise lab): 0.024 bar.
constexpr double kPt1NoiseBar = 0.024;
constexpr double kRateHz = 100.0;

// A fundamental and a second harmonic under white noise: the fit's amplitude and periodic RMS
// are the closed forms a1 and sqrt((a1^2 + a2^2) / 2), within 4 sigma sqrt(2/N) (the noise's
// contribution to an amplitude estimate from N samples).
TEST(HeaveFit, RecoversKnownHarmonicsUnderTheLabsNoise) {
  struct Case {
    double frequency_hz, a1, a2;
  };
  // 0.13 and 0.15 Hz do not fit whole periods into the 20 s window; 0.005 bar is a controlled
  // rig's swing, 15x below the noise.
  for (const Case c : {Case{0.2, 0.38, 0.05}, Case{0.15, 0.27, 0.02}, Case{0.13, 0.005, 0.003}}) {
    for (unsigned seed : {1u, 2u, 3u}) {
      SCOPED_TRACE(::testing::Message() << c.frequency_hz << " Hz, seed " << seed);
      std::mt19937 random(seed);
      std::normal_distribution<double> noise(0.0, kPt1NoiseBar);
      client::HeaveFit fit;
      const double w = 2.0 * kPi * c.frequency_hz;
      const int n = 2000;  // 20 s at 100 Hz, from t = 60 s
      for (int i = 0; i < n; ++i) {
        const double t = 60.0 + i / kRateHz;
        fit.Add(t,
                3.66 + c.a1 * std::sin(w * t + 0.7) + c.a2 * std::sin(2.0 * w * t - 1.1) +
                    noise(random),
                c.frequency_hz);
      }
      const auto [fundamental, rms] = fit.Amplitudes();
      const double tolerance = 4.0 * kPt1NoiseBar * std::sqrt(2.0 / n);
      EXPECT_NEAR(fundamental, c.a1, tolerance);
      EXPECT_NEAR(rms, std::sqrt((c.a1 * c.a1 + c.a2 * c.a2) / 2.0), tolerance);
    }
  }
}

TEST(HeaveFit, SaysNaNWithoutAFrequencyOrEnoughSamples) {
  client::HeaveFit none;
  for (int i = 0; i < 100; ++i) none.Add(i / kRateHz, 1.0, 0.0);
  EXPECT_TRUE(std::isnan(none.Amplitudes().first));
  client::HeaveFit few;
  for (int i = 0; i < 10; ++i) few.Add(i / kRateHz, 1.0, 0.2);
  EXPECT_TRUE(std::isnan(few.Amplitudes().second));
}

// A BHP of mean m under a heave of 0.38 bar at f, with the lab's noise: the learnt set point is m
// (whole periods: no bias from a part period; the noise moves a mean of N samples by
// sigma/sqrt(N), under 0.002 bar here), learnt after max(10 s, 2 periods) plus the window.
TEST(SetpointLearner, LearnsTheMeanOverWholeHeavePeriods) {
  for (const double f : {0.1, 0.13, 0.15, 0.2}) {
    for (unsigned seed : {4u, 5u}) {
      SCOPED_TRACE(::testing::Message() << f << " Hz, seed " << seed);
      std::mt19937 random(seed);
      std::normal_distribution<double> noise(0.0, kPt1NoiseBar);
      std::normal_distribution<double> choke_noise(0.0, 0.1);
      client::SetpointLearner learner;
      double learnt_at_s = -1.0;
      for (int i = 1; i <= 6000 && learnt_at_s < 0.0; ++i) {
        const double t = i / kRateHz;
        const double bhp = 3.66 + 0.38 * std::sin(2.0 * kPi * f * t + 0.3) + noise(random);
        if (learner.Add(t, bhp, 31.0 + choke_noise(random), f)) learnt_at_s = t;
      }
      ASSERT_TRUE(learner.learnt());
      EXPECT_NEAR(learner.setpoint_barg(), 3.66, 0.005);
      EXPECT_NEAR(learner.choke_deg(), 31.0, 0.02);
      const double settle_s = std::max(10.0, 2.0 / f);
      const double window_s = std::max(1.0, std::round(10.0 * f)) / f;
      // From the first sample (t = 0.01 s), to within two samples.
      EXPECT_NEAR(learnt_at_s, 0.01 + settle_s + window_s, 2.0 / kRateHz);
    }
  }
}

// The canceller alone (no PI) on a plant whose BHP error is Re{D z} minus g times the choke's
// motion delayed by tau: e(t) = Re{D z(t)} - g u(t - tau) + noise, z = |z| exp(j omega t). In the
// steady state W = D + G theta with G = -g exp(-j omega tau), and theta' = -gamma W / G^ settles
// at theta* = -D/G exactly when Re{G/G^} > 0: the model's phase within 90 degrees of the plant's.
struct PlantRun {
  double residual_bar;  // the error's amplitude at omega over the last 20 s
  Complex theta;
};

PlantRun RunPlant(double frequency_hz, double true_delay_s, Complex d, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, kPt1NoiseBar);
  const double g = 0.7, dt = 1.0 / kRateHz, omega = 2.0 * kPi * frequency_hz;
  const double z_abs = omega * 0.1;  // a 0.1 m heave
  client::HeaveCanceller canceller;  // its model: g^ = 0.7 bar/deg, tau^ = 1.3 s
  std::deque<double> pipe(static_cast<std::size_t>(std::lround(true_delay_s / dt)), 0.0);
  client::HeaveFit fit;
  const double end_s = 100.0;
  for (int i = 0; i * dt < end_s; ++i) {
    const double t = i * dt;
    const Complex z = std::polar(z_abs, omega * t);
    const double e = (d * z).real() - g * pipe.front() + noise(random);
    pipe.pop_front();
    pipe.push_back(canceller.Update(e, z, frequency_hz, dt));
    if (t > end_s - 20.0) fit.Add(t, e, frequency_hz);
  }
  return {fit.Amplitudes().first, canceller.theta()};
}

TEST(HeaveCanceller, ConvergesToMinusDOverGWhenItsModelIsWithin90Degrees) {
  // D: 0.38 bar of swing at 0.2 Hz for a 0.1 m heave, at some phase.
  const double f = 0.2;
  const Complex d = std::polar(0.38 / (2.0 * kPi * f * 0.1), 2.0);
  // True delays 1.06 s (l/c alone), 1.3 s (the model's) and 1.6 s: the model's phase is off by
  // +17, 0 and -22 degrees at 0.2 Hz.
  for (const double tau : {1.06, 1.3, 1.6}) {
    SCOPED_TRACE(::testing::Message() << "true delay " << tau << " s");
    const PlantRun run = RunPlant(f, tau, d, 7);
    const Complex g_true = -0.7 * std::exp(Complex(0.0, -2.0 * kPi * f * tau));
    const Complex expected = -d / g_true;
    EXPECT_LT(std::abs(run.theta - expected), 0.02 * std::abs(expected));
    // 0.38 bar without it; the noise leaves about 0.001 bar in a 20 s amplitude.
    EXPECT_LT(run.residual_bar, 0.01);
  }
  // 120 degrees off (a true delay of 1.3 s + (1/3)/0.2 s): Re{G/G^} < 0, the gradient step
  // pushes theta away from theta*, and the swing is not cancelled.
  const PlantRun wrong = RunPlant(f, 1.3 + (1.0 / 3.0) / f, d, 7);
  EXPECT_GT(wrong.residual_bar, 0.38);
}

TEST(HeaveCanceller, DoesNothingWhileTheHeaveIsUnknown) {
  client::HeaveCanceller canceller;
  EXPECT_EQ(canceller.Update(0.5, Complex(0.0, 0.0), 0.2, 0.01), 0.0);
  EXPECT_EQ(canceller.Update(0.5, Complex(0.1, 0.0), 0.0, 0.01), 0.0);
  EXPECT_EQ(canceller.theta(), Complex(0.0, 0.0));
  client::Estimate e;
  e.piston_velocity_est_mps = 0.05;
  e.piston_position_est_m = 0.08;
  e.disturbance_frequency_hz = 0.2;
  const Complex z = client::HeaveCanceller::Phasor(e);
  EXPECT_DOUBLE_EQ(z.real(), 0.05);
  EXPECT_DOUBLE_EQ(z.imag(), 2.0 * kPi * 0.2 * 0.08);  // omega x_d
}

}  // namespace
}  // namespace mpdrig
