#include "model/signal/smoothing.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "model/common/status.h"

namespace mpdrig {

std::vector<double> SmoothLocalQuadratic(const std::vector<double>& time_s,
                                         const std::vector<double>& values, double window_s) {
  MPDRIG_CHECK(time_s.size() == values.size());
  const std::size_t n = values.size();
  if (window_s <= 0.0 || n < 4) return values;
  std::vector<double> smoothed(n);
  const double half = 0.5 * window_s;
  std::size_t lo = 0, hi = 0;  // window [lo, hi)
  for (std::size_t i = 0; i < n; ++i) {
    while (time_s[i] - time_s[lo] > half) ++lo;
    while (hi < n && time_s[hi] - time_s[i] <= half) ++hi;
    if (hi - lo < 4) {  // too few points for a quadratic plus one degree of freedom
      smoothed[i] = values[i];
      continue;
    }
    // Normal equations in tau = (t - t_i)/half, well conditioned on [-1, 1].
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (std::size_t j = lo; j < hi; ++j) {
      const double tau = (time_s[j] - time_s[i]) / half;
      const Eigen::Vector3d basis(1.0, tau, tau * tau);
      normal += basis * basis.transpose();
      rhs += basis * values[j];
    }
    smoothed[i] = normal.ldlt().solve(rhs)(0);  // the quadratic at tau = 0
  }
  return smoothed;
}

PiecewiseLinear::PiecewiseLinear(std::vector<double> time_s, std::vector<double> values)
    : time_s_(std::move(time_s)), values_(std::move(values)) {
  MPDRIG_CHECK(!time_s_.empty() && time_s_.size() == values_.size());
}

double PiecewiseLinear::operator()(double t) const {
  if (t <= time_s_.front()) return values_.front();
  if (t >= time_s_.back()) return values_.back();
  const auto upper = std::upper_bound(time_s_.begin(), time_s_.end(), t);
  const std::size_t j = static_cast<std::size_t>(upper - time_s_.begin());
  const double w = (t - time_s_[j - 1]) / (time_s_[j] - time_s_[j - 1]);
  return (1.0 - w) * values_[j - 1] + w * values_[j];
}

}  // namespace mpdrig
