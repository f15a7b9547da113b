// Noise-robust differentiation of a measured position (design.md: a log's piston_position is a
// noisy measurement, and the model needs the piston velocity).
//
// Each sample is replaced by the value at its own time of the least-squares quadratic through the
// samples within +-window/2 (Savitzky-Golay, written for non-uniform sampling). A quadratic is
// reproduced exactly, so a slow sine passes with a relative error of order (omega window)^4; white
// noise of variance s^2 leaves with about s^2 * 9/(4 m) for m samples in the window. The simulator
// then differentiates the smoothed, piecewise-linear position over each of its steps, which keeps
// the displaced volume exact.
#pragma once

#include <vector>

namespace mpdrig {

// `time_s` strictly increasing, same length as `values`. window_s <= 0 returns `values` unchanged.
std::vector<double> SmoothLocalQuadratic(const std::vector<double>& time_s,
                                         const std::vector<double>& values, double window_s);

// Linear interpolation in a strictly increasing table, held constant beyond its ends.
class PiecewiseLinear {
 public:
  PiecewiseLinear(std::vector<double> time_s, std::vector<double> values);
  double operator()(double t) const;

 private:
  std::vector<double> time_s_;
  std::vector<double> values_;
};

}  // namespace mpdrig
