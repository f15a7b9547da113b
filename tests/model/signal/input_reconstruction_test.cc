// The building blocks of the input reconstruction (model/signal/input_reconstruction.h): the noise
// estimate, the piston's band, the band-limited smoother and the step-keeping smoother, on series
// whose truth is known. Noise at the lab's levels (thesis Table 4.1.1) where it matters.
#include "model/signal/input_reconstruction.h"

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

constexpr double kDt = 0.01;  // 100 Hz, the lab's logging rate

std::vector<double> Times(std::size_t n) {
  std::vector<double> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = static_cast<double>(i) * kDt;
  return t;
}

std::vector<double> Noise(std::size_t n, double sigma, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<double> e(n);
  for (double& v : e) v = normal(random);
  return e;
}

double Rms(const std::vector<double>& a, const std::vector<double>& b, std::size_t from,
           std::size_t to) {
  double sum = 0.0;
  for (std::size_t i = from; i < to; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum / static_cast<double>(to - from));
}

TEST(WhiteNoiseSigma, IgnoresASlowSignalAndSteps) {
  // A heave of 0.05 m at 0.2 Hz, 20 steps of 10 mm, and 0.5 mm of white noise: the median of the
  // second differences sees only the noise. The MAD's relative spread is about 1.7 / sqrt(n)
  // (1.2 % for 20000 samples): 5 % is four of those.
  const std::size_t n = 20000;
  const std::vector<double> e = Noise(n, 5e-4, 1);
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * kDt;
    x[i] = 0.05 * std::sin(2.0 * std::numbers::pi * 0.2 * t) + 0.01 * (i / 1000) + e[i];
  }
  EXPECT_NEAR(WhiteNoiseSigma(x), 5e-4, 0.05 * 5e-4);
  EXPECT_EQ(WhiteNoiseSigma(std::vector<double>(100, 3.0)), 0.0);
  EXPECT_EQ(WhiteNoiseSigma({1.0, 2.0}), 0.0);
}

TEST(HighestSignalFrequency, FindsTheHighestLineAboveTheNoise) {
  // The heave at 0.2 Hz and a small 1.3 Hz component, 120 s, 0.5 mm noise: the band ends at the
  // 1.3 Hz line, within the window's main lobe (5 bins of 100/4096 Hz) above it; the heave's
  // own side lobes (Blackman-Harris: -92 dB) do not count.
  const std::size_t n = 12000;
  const std::vector<double> e = Noise(n, 5e-4, 2);
  std::vector<double> x(n), still(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * kDt;
    x[i] = 0.1 * std::sin(2.0 * std::numbers::pi * 0.2 * t) +
           0.002 * std::sin(2.0 * std::numbers::pi * 1.3 * t) + e[i];
    still[i] = 0.3 + e[i];
  }
  const double band = HighestSignalFrequencyHz(x, kDt, 5e-4);
  EXPECT_GE(band, 1.3);
  EXPECT_LE(band, 1.3 + 5.0 / (4096 * kDt) + 1e-9);
  EXPECT_EQ(HighestSignalFrequencyHz(still, kDt, 5e-4), 0.0);  // a piston at rest
}

TEST(SmoothBandLimited, PassesItsBandAndRemovesTheNoise) {
  const std::size_t n = 12000;
  const double f = 0.3;
  const double h = BandLimitedHalfWidthS(f);
  ASSERT_GT(h, 0.0);
  const std::vector<double> t = Times(n);
  std::vector<double> x(n), noisy(n);
  const std::vector<double> e = Noise(n, 5e-4, 3);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = 0.05 * std::sin(2.0 * std::numbers::pi * f * t[i]);
    noisy[i] = x[i] + e[i];
  }
  // Noise-free: the gain at f is 1 - kBandGainTolerance, so the error is at most that share of
  // the amplitude in the interior (5 % slack for the sampled kernel).
  const std::vector<double> clean = SmoothBandLimited(t, x, h);
  const std::size_t margin = static_cast<std::size_t>(h / kDt) + 1;
  double worst = 0.0;
  for (std::size_t i = margin; i + margin < n; ++i) {
    worst = std::max(worst, std::fabs(clean[i] - x[i]));
  }
  EXPECT_LE(worst, 1.05 * kBandGainTolerance * 0.05);
  // Noisy: the tricube quadratic's effective sample count over +-h is about 0.6 * 2h/dt; ask
  // for a 4x smaller RMS error than the noise (the closed form gives about 6x at h = 0.53 s).
  const std::vector<double> smoothed = SmoothBandLimited(t, noisy, h);
  EXPECT_LT(Rms(smoothed, x, margin, n - margin), 5e-4 / 4.0);
  // A quadratic passes exactly, also at the ends.
  std::vector<double> q(n);
  for (std::size_t i = 0; i < n; ++i) q[i] = 1.0 + 2.0 * t[i] - 0.3 * t[i] * t[i];
  const std::vector<double> q_smoothed = SmoothBandLimited(t, q, h);
  for (std::size_t i = 0; i < n; ++i) ASSERT_NEAR(q_smoothed[i], q[i], 1e-9 * std::fabs(q[i]));
}

TEST(SmoothKeepingSteps, KeepsAStepSharpAndAveragesTheFlats) {
  // A choke position of 28 deg stepping to 33 deg, 0.1 deg noise (Table 4.1.1).
  const std::size_t n = 6000, step = 3000;
  const double sigma = 0.1;
  const std::vector<double> t = Times(n);
  const std::vector<double> e = Noise(n, sigma, 4);
  std::vector<double> x(n), noisy(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = i < step ? 28.0 : 33.0;
    noisy[i] = x[i] + e[i];
  }
  StepKeepingOptions options;
  options.sigma = sigma;
  options.max_half_width_samples = 1024;
  const std::vector<double> y = SmoothKeepingSteps(noisy, options);
  // Three samples from the step the estimate is already on the right level: a centred moving
  // average of the same reach would be half way (2.5 deg off).
  EXPECT_NEAR(y[step + 3], 33.0, 3.0 * sigma);
  EXPECT_NEAR(y[step - 4], 28.0, 3.0 * sigma);
  // Away from the step the noise is averaged: 10x lower RMS error on the flats (windows of
  // hundreds of samples give far more; ten leaves room for the ICI's early stops).
  EXPECT_LT(Rms(y, x, 0, step - 10), sigma / 10.0);
  EXPECT_LT(Rms(y, x, step + 10, n), sigma / 10.0);
}

TEST(SmoothKeepingSteps, FollowsARampWithoutLag) {
  // A pump flow ramp (a pump stop over 2 s) between flats: local linear fits are unbiased on it.
  const std::size_t n = 4000;
  const double sigma = 0.05;
  const std::vector<double> t = Times(n);
  const std::vector<double> e = Noise(n, sigma, 5);
  std::vector<double> x(n), noisy(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = t[i] < 15.0 ? 8.0 : t[i] < 17.0 ? 8.0 - 4.0 * (t[i] - 15.0) : 0.0;
    noisy[i] = x[i] + e[i];
  }
  StepKeepingOptions options;
  options.sigma = sigma;
  options.max_half_width_samples = 1024;
  const std::vector<double> y = SmoothKeepingSteps(noisy, options);
  EXPECT_LT(Rms(y, x, 1450, 1750), sigma / 2.0);  // across the ramp and its corners
  EXPECT_LT(Rms(y, x, 0, n), sigma / 4.0);
}

TEST(SmoothKeepingSteps, NoNoiseMeansNoChange) {
  std::vector<double> x(100);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(0.1 * static_cast<double>(i));
  StepKeepingOptions options;  // sigma 0
  options.max_half_width_samples = 64;
  EXPECT_EQ(SmoothKeepingSteps(x, options), x);
}

// A long series reconstructed in blocks (each with the windows' reach as margin, the running sums
// carried from the first sample) gives the same doubles as the whole series, also where the
// windows straddle a segment of the sums (kSumSegmentSamples).
TEST(SmoothKeepingSteps, BlocksGiveTheWholeSeriesDoubles) {
  const long n = kSumSegmentSamples + 5000;
  const std::vector<double> e = Noise(static_cast<std::size_t>(n), 0.2, 6);
  std::vector<double> x(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) x[static_cast<std::size_t>(i)] = (i / 3000 % 2 ? 8.0 : 5.0) + e[i];
  StepKeepingOptions options;
  options.sigma = 0.2;
  options.max_half_width_samples = 1024;
  const std::vector<double> whole = SmoothKeepingSteps(x, options);
  RunningSums running;
  std::vector<RunningSum> sums;
  for (double y : x) sums.push_back(running.Push(y));
  sums.push_back(running.Next());
  const long reach = options.max_half_width_samples;
  for (long begin : {0L, 30000L, kSumSegmentSamples - 2000, kSumSegmentSamples - 1}) {
    const long end = std::min(n, begin + 3000);
    const long from = std::max(0L, begin - reach), to = std::min(n, end + reach);
    const std::vector<double> block(x.begin() + from, x.begin() + to);
    std::vector<RunningSum> block_sums(sums.begin() + from, sums.begin() + to + 1);
    const std::vector<double> part = SmoothKeepingSteps(block, block_sums, from, options);
    for (long i = begin; i < end; ++i) {
      ASSERT_EQ(part[static_cast<std::size_t>(i - from)], whole[static_cast<std::size_t>(i)])
          << "sample " << i << ", block from " << from;
    }
  }
}

}  // namespace
}  // namespace mpdrig
