#include "model/signal/input_reconstruction.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include <Eigen/Dense>

#include "model/common/status.h"
#include "model/signal/spectrum.h"

namespace mpdrig {
namespace {

// Welch segments for the piston's band: about 40 s (resolution 0.025 Hz), 4096..65536 samples.
constexpr double kBandSegmentS = 40.0;
constexpr std::size_t kMinBandSegmentSamples = 4096;
constexpr std::size_t kMaxBandSegmentSamples = 65536;

double Tricube(double u) {
  const double a = 1.0 - std::fabs(u) * u * u;
  return a > 0.0 ? a * a * a : 0.0;
}

// Gain at x = f h of the tricube local quadratic's equivalent kernel in the interior,
// K(u) = w(u) (m4 - m2 u^2) / (m0 m4 - m2^2) with m_k = int w(u) u^k du over [-1, 1].
double TricubeQuadraticGain(double x) {
  constexpr int kPoints = 4000;
  double m0 = 0.0, m2 = 0.0, m4 = 0.0, c0 = 0.0, c2 = 0.0;
  for (int k = 0; k < kPoints; ++k) {
    const double u = -1.0 + (k + 0.5) * (2.0 / kPoints);
    const double w = Tricube(u);
    const double c = std::cos(2.0 * std::numbers::pi * x * u);
    m0 += w, m2 += w * u * u, m4 += w * u * u * u * u;
    c0 += w * c, c2 += w * u * u * c;
  }
  return (m4 * c0 - m2 * c2) / (m0 * m4 - m2 * m2);
}

// x = f h at which the gain has fallen to 1 - kBandGainTolerance (bisection; the gain falls
// monotonically from 1 over the passband).
double PassbandEdge() {
  double lo = 0.0, hi = 0.5;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (TricubeQuadraticGain(mid) > 1.0 - kBandGainTolerance ? lo : hi) = mid;
  }
  return lo;
}

// The sums of a local linear least-squares fit in the sample offset d = m - i: the estimate at
// d = 0 and its variance in units of the noise variance.
struct LinearSums {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, y0 = 0.0, y1 = 0.0;
  // Intercept and its variance factor; a local mean where the slope is not determined.
  void Estimate(double* value, double* variance) const {
    const double det = s0 * s2 - s1 * s1;
    if (s0 >= 2.0 && det > 1e-12 * s0 * s2) {
      *value = (s2 * y0 - s1 * y1) / det;
      *variance = s2 / det;
    } else {
      *value = y0 / s0;
      *variance = 1.0 / s0;
    }
  }
};

// sum_{d=1}^{x} d^2, extended to x < 0 so that sum_{d=lo}^{hi} d^2 = SquareSum(hi) -
// SquareSum(lo - 1) for any integers lo <= hi + 1.
double SquareSum(double x) { return x * (x + 1.0) * (2.0 * x + 1.0) / 6.0; }

// The ICI rule over one side's nested windows: the largest window whose confidence interval
// still meets all the smaller ones'.
struct IciChoice {
  double value = 0.0;
  double variance = 0.0;  // in units of sigma^2
};
// half_width_per_std: Gamma sigma, the interval's half width per unit of the variance factor's
// root.
IciChoice Ici(const std::vector<LinearSums>& windows, double half_width_per_std) {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  IciChoice choice;
  bool any = false;
  for (const LinearSums& sums : windows) {
    double value = 0.0, variance = 0.0;
    sums.Estimate(&value, &variance);
    const double half = half_width_per_std * std::sqrt(variance);
    lower = std::max(lower, value - half);
    upper = std::min(upper, value + half);
    if (any && lower > upper) break;
    choice = {value, variance};
    any = true;
  }
  return choice;
}

}  // namespace

double WhiteNoiseSigma(const std::vector<double>& values) {
  if (values.size() < 3) return 0.0;
  std::vector<double> d2(values.size() - 2);
  for (std::size_t i = 1; i + 1 < values.size(); ++i) {
    d2[i - 1] = std::fabs(values[i - 1] - 2.0 * values[i] + values[i + 1]);
  }
  const auto middle = d2.begin() + static_cast<std::ptrdiff_t>(d2.size() / 2);
  std::nth_element(d2.begin(), middle, d2.end());
  return 1.482602218505602 * *middle / std::sqrt(6.0);
}

double HighestSignalFrequencyHz(const std::vector<double>& values, double dt_s, double sigma) {
  MPDRIG_CHECK(dt_s > 0.0);
  const std::size_t n = values.size();
  if (n < 16) return 0.0;
  if (!(sigma > 0.0)) return 0.5 / dt_s;  // noise-free: every band is above the floor
  std::size_t segment_length = kMinBandSegmentSamples;
  while (segment_length < kMaxBandSegmentSamples &&
         static_cast<double>(segment_length) * dt_s < kBandSegmentS) {
    segment_length *= 2;
  }
  const std::size_t length = std::min(segment_length, n);
  const std::size_t hop = length / 2;
  std::vector<double> window(length);
  double window_power = 0.0;
  for (std::size_t k = 0; k < length; ++k) {
    const double phase =
        2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(length - 1);
    window[k] = 0.35875 - 0.48829 * std::cos(phase) + 0.14128 * std::cos(2.0 * phase) -
                0.01168 * std::cos(3.0 * phase);
    window_power += window[k] * window[k];
  }
  RealFft fft(length);
  std::vector<double> power(length / 2 + 1, 0.0), segment(length);
  std::vector<std::complex<double>> spectrum;
  std::size_t segments = 0;
  // Segments every `hop` samples, and one more ending at the last sample.
  std::vector<std::size_t> starts;
  for (std::size_t start = 0; start + length <= n; start += hop) starts.push_back(start);
  if (starts.back() + length < n) starts.push_back(n - length);
  for (const std::size_t start : starts) {
    double mean = 0.0;
    for (std::size_t k = 0; k < length; ++k) mean += values[start + k];
    mean /= static_cast<double>(length);
    for (std::size_t k = 0; k < length; ++k) segment[k] = (values[start + k] - mean) * window[k];
    fft.Forward(segment, &spectrum);
    for (std::size_t k = 0; k < power.size(); ++k) power[k] += std::norm(spectrum[k]);
    ++segments;
  }
  // White noise of variance sigma^2 gives E|X_k|^2 = sigma^2 sum w^2 in every bin.
  const double floor = sigma * sigma * window_power * static_cast<double>(segments);
  // The window's main lobe spreads a line over +-4 bins: a line in the lowest bins (a slow heave
  // in a short log) is only known to lie below bin 5.
  constexpr std::size_t kMainLobeBins = 5;
  for (std::size_t k = power.size(); k-- > 0;) {
    if (power[k] > kBandDetectionRatio * floor) {
      return static_cast<double>(std::max(k, kMainLobeBins)) / (static_cast<double>(length) * dt_s);
    }
  }
  return 0.0;
}

double BandLimitedHalfWidthS(double f_hz) {
  static const double edge = PassbandEdge();
  if (!(f_hz > 0.0)) return std::numeric_limits<double>::infinity();
  return edge / f_hz;
}

std::vector<double> SmoothBandLimited(const std::vector<double>& time_s,
                                      const std::vector<double>& values, double half_width_s) {
  MPDRIG_CHECK(time_s.size() == values.size());
  const std::size_t n = values.size();
  if (!(half_width_s > 0.0) || n < 4) return values;
  std::vector<double> smoothed(n);
  std::size_t lo = 0, hi = 0;  // samples with |t_j - t_i| < h: [lo, hi)
  for (std::size_t i = 0; i < n; ++i) {
    while (time_s[i] - time_s[lo] >= half_width_s) ++lo;
    while (hi < n && time_s[hi] - time_s[i] < half_width_s) ++hi;
    // Normal equations in tau = (t - t_i)/h, well conditioned on (-1, 1).
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    int weighted = 0;
    for (std::size_t j = lo; j < hi; ++j) {
      const double tau = (time_s[j] - time_s[i]) / half_width_s;
      const double w = Tricube(tau);
      if (w <= 0.0) continue;
      ++weighted;
      const Eigen::Vector3d basis(1.0, tau, tau * tau);
      normal += w * basis * basis.transpose();
      rhs += w * basis * values[j];
    }
    if (weighted < 4) {  // a quadratic needs three points and one degree of freedom
      smoothed[i] = values[i];
      continue;
    }
    smoothed[i] = normal.ldlt().solve(rhs)(0);
  }
  return smoothed;
}

RunningSum RunningSums::Push(double y) {
  RunningSum entry = Next();
  if (count_ % kSumSegmentSamples == 0) y_ = ny_ = 0.0;
  y_ += y;
  ny_ += static_cast<double>(count_ % kSumSegmentSamples) * y;
  ++count_;
  return entry;
}

RunningSum RunningSums::Next() const {
  RunningSum entry;
  if (count_ % kSumSegmentSamples == 0) {
    entry.prev_y = y_, entry.prev_ny = ny_;  // y, ny stay 0: a new segment starts here
  } else {
    entry.y = y_, entry.ny = ny_;
  }
  return entry;
}

std::vector<double> SmoothKeepingSteps(const std::vector<double>& values,
                                       const std::vector<RunningSum>& sums, long first_index,
                                       const StepKeepingOptions& options) {
  const long n = static_cast<long>(values.size());
  MPDRIG_CHECK(static_cast<long>(sums.size()) == n + 1);
  if (!(options.sigma > 0.0) || options.max_half_width_samples < 2 || n < 3) return values;
  constexpr long kSegment = kSumSegmentSamples;
  MPDRIG_CHECK(2 * options.max_half_width_samples < kSegment);
  // Sum of y and of (m - i) y over local samples [a, b), from the running sums; a window spans
  // at most two segments.
  auto window = [&](long a, long b, long i) {
    LinearSums w;
    const double lo = static_cast<double>(a - i), hi = static_cast<double>(b - 1 - i);
    w.s0 = static_cast<double>(b - a);
    w.s1 = 0.5 * (lo + hi) * w.s0;
    w.s2 = SquareSum(hi) - SquareSum(lo - 1.0);
    const long ga = first_index + a, gb = first_index + b, gi = first_index + i;
    auto part = [&](long from, long to) {  // local [from, to), one segment
      const long segment_start = ((first_index + from) / kSegment) * kSegment;
      const bool ends_at_next = (first_index + to) % kSegment == 0 && to > from;
      const double end_y = ends_at_next ? sums[to].prev_y : sums[to].y;
      const double end_ny = ends_at_next ? sums[to].prev_ny : sums[to].ny;
      const double y0 = end_y - sums[from].y;
      w.y0 += y0;
      w.y1 += (end_ny - sums[from].ny) - static_cast<double>(gi - segment_start) * y0;
    };
    const long next_segment = (ga / kSegment + 1) * kSegment;
    if (gb <= next_segment) {
      part(a, b);
    } else {
      const long c = next_segment - first_index;
      part(a, c);
      part(c, b);
    }
    return w;
  };
  std::vector<long> halves;
  for (long half = 2; half <= options.max_half_width_samples; half *= 2) halves.push_back(half);
  std::vector<double> smoothed(values.size());
  std::vector<LinearSums> left(halves.size()), right(halves.size()), centred(halves.size());
  const double half_width_per_std = options.threshold * options.sigma;
  for (long i = 0; i < n; ++i) {
    for (std::size_t k = 0; k < halves.size(); ++k) {
      const long a = std::max(0L, i - halves[k] + 1), b = std::min(n, i + halves[k]);
      left[k] = window(a, i + 1, i);
      right[k] = window(i, b, i);
      centred[k] = window(a, b, i);
    }
    // Fuse the three sides by inverse variance.
    double weighted = 0.0, weights = 0.0;
    for (const auto* side : {&left, &right, &centred}) {
      const IciChoice choice = Ici(*side, half_width_per_std);
      weighted += choice.value / choice.variance;
      weights += 1.0 / choice.variance;
    }
    smoothed[static_cast<std::size_t>(i)] = weighted / weights;
  }
  return smoothed;
}

std::vector<double> SmoothKeepingSteps(const std::vector<double>& values,
                                       const StepKeepingOptions& options) {
  RunningSums running;
  std::vector<RunningSum> sums;
  sums.reserve(values.size() + 1);
  for (double y : values) sums.push_back(running.Push(y));
  sums.push_back(running.Next());
  return SmoothKeepingSteps(values, sums, 0, options);
}

}  // namespace mpdrig
