// A safeguarded Newton iteration for one unknown: the boundary closures (model/effects' inlet and
// outlet hooks) each solve a monotonic relation between a boundary node's velocity and the
// pressure there, and share this solver.
#pragma once

#include <cmath>

namespace mpdrig {

// Solves g(u) = 0 for a strictly decreasing g with derivative dg, starting at `guess`: Newton
// steps, with bisection once a bracket is known. Where the slope is not negative the step is
// `scale` towards the root; a step that leaves the bracket bisects it instead (or, before both
// ends are known, is again `scale` towards the root). Stops when a step changes u by less than
// 1e-13 relative, or after 60 iterations.
double SolveDecreasing(double guess, double scale, const auto& g, const auto& dg) {
  double u = guess;
  double lo = -1e300, hi = 1e300;  // g(lo) > 0 > g(hi)
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double value = g(u);
    if (value == 0.0) return u;
    if (value > 0.0) {
      lo = u;
    } else {
      hi = u;
    }
    const double slope = dg(u);
    double next = slope < 0.0 ? u - value / slope : u + (value > 0.0 ? scale : -scale);
    if (!(next > lo && next < hi)) {
      next = (lo > -1e299 && hi < 1e299) ? 0.5 * (lo + hi) : u + (value > 0.0 ? scale : -scale);
    }
    if (std::abs(next - u) <= 1e-13 * (1.0 + std::abs(u))) return next;
    u = next;
  }
  return u;
}

}  // namespace mpdrig
