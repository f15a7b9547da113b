// SolveDecreasing against roots known in closed form, including the cases its safeguards are for:
// a zero slope at the start, a derivative of the wrong sign, a start far from the root.
#include "model/common/root_finding.h"

#include <cmath>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

// Its stopping rule: a step below 1e-13 relative; a few ulps more for the last step's rounding.
constexpr double kRootTolerance = 1e-12;

TEST(SolveDecreasing, FindsACubeRootFromAFlatStart) {
  // g(u) = 2 - u^3 is flat at u = 0: the first step is `scale`, then Newton.
  const auto g = [](double u) { return 2.0 - u * u * u; };
  const auto dg = [](double u) { return -3.0 * u * u; };
  EXPECT_NEAR(SolveDecreasing(0.0, 0.5, g, dg), std::cbrt(2.0), kRootTolerance);
}

TEST(SolveDecreasing, BisectsWhenTheDerivativeIsWrong) {
  // A derivative of the wrong sign (as a closure's estimate may be): bracketing still converges.
  const auto g = [](double u) { return std::exp(-u) - 0.25; };  // root ln 4
  const auto wrong = [](double) { return 1.0; };
  EXPECT_NEAR(SolveDecreasing(0.0, 1.0, g, wrong), std::log(4.0), kRootTolerance);
}

TEST(SolveDecreasing, ReachesAFarRootFromEitherSide) {
  // Linear g: Newton lands on the root in one step from any start.
  const auto g = [](double u) { return 3.0 - 0.5 * u; };  // root 6
  const auto dg = [](double) { return -0.5; };
  EXPECT_NEAR(SolveDecreasing(-1000.0, 0.01, g, dg), 6.0, kRootTolerance);
  EXPECT_NEAR(SolveDecreasing(1000.0, 0.01, g, dg), 6.0, kRootTolerance);
  // A strongly curved g started far off: the bracket keeps Newton's overshoot in check.
  const auto atan_g = [](double u) { return -std::atan(u - 2.0); };
  const auto atan_dg = [](double u) { return -1.0 / (1.0 + (u - 2.0) * (u - 2.0)); };
  EXPECT_NEAR(SolveDecreasing(10.0, 0.1, atan_g, atan_dg), 2.0, kRootTolerance);
}

}  // namespace
}  // namespace mpdrig
