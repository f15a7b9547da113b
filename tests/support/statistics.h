// Sample statistics for tests that check noise: the standard deviation about the sample mean, and
// the tolerance a test of it can justify.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace mpdrig::teststats {

// Standard deviation about the sample mean (n - 1 in the denominator).
inline double SampleStdDev(const std::vector<double>& x) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double sum = 0.0;
  for (double v : x) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(x.size() - 1));
}

// The sample standard deviation of n normal draws spreads by 1 / sqrt(2 (n - 1)) of itself; four
// of those, as a relative tolerance, fail by chance once in 16000 runs (and seeds are fixed).
inline double StdDevTolerance(std::size_t n) {
  return 4.0 / std::sqrt(2.0 * static_cast<double>(n - 1));
}

}  // namespace mpdrig::teststats
