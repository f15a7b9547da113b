#include "model/signal/smoothing.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// i / rate, not accumulated, so sample spacing has no drift.
std::vector<double> UniformTimes(int count, double rate_hz) {
  std::vector<double> t(count);
  for (int i = 0; i < count; ++i) t[i] = i / rate_hz;
  return t;
}

// Uniform grid with every sample moved by up to +-30% of the spacing (still strictly increasing).
std::vector<double> JitteredTimes(int count, double rate_hz, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<double> t(count);
  for (int i = 0; i < count; ++i) t[i] = (i + jitter(rng)) / rate_hz;
  return t;
}

std::vector<double> Apply(const std::vector<double>& t, double (*f)(double)) {
  std::vector<double> y(t.size());
  std::transform(t.begin(), t.end(), y.begin(), f);
  return y;
}

double Quadratic(double t) { return 3.0 - 2.0 * t + 0.7 * t * t; }

// The fit is exact for a quadratic; what is left is the rounding of a 3x3 solve on values of
// order 1 to 5: 1e-9 is far above it and far below any real smoothing error.
TEST(SmoothLocalQuadratic, QuadraticPassesUnchanged) {
  const std::vector<double> t = UniformTimes(501, 100.0);
  const std::vector<double> y = Apply(t, Quadratic);
  for (double window : {0.035, 0.05, 0.205, 1.0}) {
    const std::vector<double> smoothed = SmoothLocalQuadratic(t, y, window);
    ASSERT_EQ(smoothed.size(), y.size());
    for (std::size_t i = 0; i < y.size(); ++i) {
      ASSERT_NEAR(smoothed[i], y[i], 1e-9) << "window " << window << ", sample " << i;
    }
  }
}

TEST(SmoothLocalQuadratic, QuadraticPassesUnchangedWithNonUniformSampling) {
  const std::vector<double> t = JitteredTimes(501, 100.0, 7);
  const std::vector<double> y = Apply(t, Quadratic);
  const std::vector<double> smoothed = SmoothLocalQuadratic(t, y, 0.08);
  for (std::size_t i = 0; i < y.size(); ++i) ASSERT_NEAR(smoothed[i], y[i], 1e-9) << i;
}

double Sine02Hz(double t) { return std::sin(kTwoPi * 0.2 * t); }

// A 0.2 Hz sine at 100 Hz, window 0.05 s (m = 5 samples): the centred fit's error is of order
// (omega h)^4 ~ 4e-7 of the amplitude times a small coefficient; near the ends the window is
// one-sided and the error is of order (omega h)^3. Both stay below 1e-6 of the amplitude.
TEST(SmoothLocalQuadratic, SlowSineIsKept) {
  const std::vector<double> t = UniformTimes(2001, 100.0);
  const std::vector<double> y = Apply(t, Sine02Hz);
  const std::vector<double> smoothed = SmoothLocalQuadratic(t, y, 0.05);
  double max_error = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    max_error = std::max(max_error, std::abs(smoothed[i] - y[i]));
  }
  EXPECT_LT(max_error, 1e-6);
}

TEST(SmoothLocalQuadratic, SlowSineIsKeptWithNonUniformSampling) {
  const std::vector<double> t = JitteredTimes(2001, 100.0, 11);
  const std::vector<double> y = Apply(t, Sine02Hz);
  const std::vector<double> smoothed = SmoothLocalQuadratic(t, y, 0.05);
  double max_error = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    max_error = std::max(max_error, std::abs(smoothed[i] - y[i]));
  }
  // Jitter makes some windows hold 4..6 samples placed unevenly; the error order is unchanged,
  // its coefficient grows a little.
  EXPECT_LT(max_error, 1e-5);
}

// For a centred least-squares quadratic over m equally spaced samples, the value at the centre
// has noise variance s^2 * 3 (3 m^2 - 7) / (4 m (m^2 - 4)), which tends to 9 / (4 m). The window
// 0.205 s at 100 Hz holds m = 21 samples (the half width 0.1025 s falls between samples, so
// rounding of the times cannot change m): factor 0.1076. 40000 samples with a fixed seed estimate
// the variance to about 2% (the smoothed samples are correlated over m); the band is +-15%.
TEST(SmoothLocalQuadratic, WhiteNoiseVarianceIsReduced) {
  const int count = 40000;
  const int m = 21;
  const std::vector<double> t = UniformTimes(count, 100.0);
  std::mt19937 rng(20130601);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> y(count);
  for (double& v : y) v = noise(rng);
  const std::vector<double> smoothed = SmoothLocalQuadratic(t, y, 0.205);

  auto variance = [&](const std::vector<double>& v) {
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    for (int i = m; i < count - m; ++i) {  // full windows only
      sum += v[i];
      sum2 += v[i] * v[i];
      ++n;
    }
    const double mean = sum / n;
    return sum2 / n - mean * mean;
  };
  const double ratio = variance(smoothed) / variance(y);
  const double exact = 3.0 * (3.0 * m * m - 7.0) / (4.0 * m * (m * m - 4.0));
  EXPECT_NEAR(exact, 9.0 / (4.0 * m), 0.01);  // the asymptotic rule of the header
  EXPECT_NEAR(ratio, exact, 0.15 * exact);
}

TEST(SmoothLocalQuadratic, NonPositiveWindowReturnsTheInput) {
  const std::vector<double> t = JitteredTimes(200, 100.0, 3);
  std::vector<double> y(t.size());
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (double& v : y) v = noise(rng);
  EXPECT_EQ(SmoothLocalQuadratic(t, y, 0.0), y);
  EXPECT_EQ(SmoothLocalQuadratic(t, y, -0.1), y);
}

TEST(SmoothLocalQuadratic, WindowTooSmallOrTooFewSamplesReturnsTheInput) {
  const std::vector<double> t = UniformTimes(50, 100.0);
  std::vector<double> y(t.size());
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = (i % 2) ? 1.0 : -1.0;
  // +-0.015 s holds 3 samples: no quadratic with a spare degree of freedom fits.
  EXPECT_EQ(SmoothLocalQuadratic(t, y, 0.03), y);
  const std::vector<double> t3 = {0.0, 0.01, 0.02};
  const std::vector<double> y3 = {1.0, -1.0, 1.0};
  EXPECT_EQ(SmoothLocalQuadratic(t3, y3, 10.0), y3);
  EXPECT_TRUE(SmoothLocalQuadratic({}, {}, 1.0).empty());
}

TEST(PiecewiseLinear, InterpolatesAndHoldsBeyondTheEnds) {
  const PiecewiseLinear f({0.0, 1.0, 3.0}, {0.0, 2.0, -2.0});
  EXPECT_EQ(f(0.0), 0.0);
  EXPECT_EQ(f(1.0), 2.0);
  EXPECT_EQ(f(3.0), -2.0);
  EXPECT_DOUBLE_EQ(f(0.25), 0.5);
  EXPECT_DOUBLE_EQ(f(2.0), 0.0);
  EXPECT_DOUBLE_EQ(f(2.5), -1.0);
  EXPECT_EQ(f(-5.0), 0.0);
  EXPECT_EQ(f(3.5), -2.0);
  EXPECT_EQ(f(1e9), -2.0);
}

TEST(PiecewiseLinear, SinglePointIsConstant) {
  const PiecewiseLinear f({2.0}, {7.0});
  EXPECT_EQ(f(0.0), 7.0);
  EXPECT_EQ(f(2.0), 7.0);
  EXPECT_EQ(f(9.0), 7.0);
}

}  // namespace
}  // namespace mpdrig
