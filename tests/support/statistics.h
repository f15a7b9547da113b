// Sample statistics for tests that check noise: the standard deviation about the sample mean, and
// the tolerance a test of it can justify; compare's fit percentage of a trace.
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

// compare's fit of a model trace yhat to a measured y, in percent (MATLAB's `compare`):
// 100 (1 - |y - yhat| / |y - mean(y)|).
inline double FitPercent(const std::vector<double>& y, const std::vector<double>& yhat) {
  double mean = 0.0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(y.size());
  double err = 0.0, var = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    err += (y[i] - yhat[i]) * (y[i] - yhat[i]);
    var += (y[i] - mean) * (y[i] - mean);
  }
  return 100.0 * (1.0 - std::sqrt(err / var));
}

}  // namespace mpdrig::teststats
