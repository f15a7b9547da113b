// Kernel equations (10.2.12)-(10.2.19): the characteristics solver against independent checks.
#include "model/observer/kernel.h"

#include <cmath>

#include <gtest/gtest.h>

namespace mpdrig::observer {
namespace {

// sigma of the thesis defaults: f1 l / (2 c) = 0.15 * 900 / (2 * 850).
constexpr double kThesisSigma = 0.15 * 900.0 / (2.0 * 850.0);

KernelSolution SolveOrDie(double sigma, int cells) {
  auto k = KernelSolution::Solve(sigma, cells);
  EXPECT_TRUE(k.ok()) << k.status().message();
  return std::move(k).value();
}

TEST(KernelTest, RejectsBadGrid) {
  EXPECT_FALSE(KernelSolution::Solve(0.1, 1).ok());
  EXPECT_FALSE(KernelSolution::Solve(std::nan(""), 10).ok());
  EXPECT_FALSE(KernelSolution::Solve(-0.1, 10).ok());
}

TEST(KernelTest, BoundaryConditionsHold) {
  const KernelSolution k = SolveOrDie(kThesisSigma, 64);
  const double s = kThesisSigma;
  for (int i = 0; i <= 64; ++i) {
    const double x = i / 64.0;
    // (10.2.18) and the closed form of P^uu on the diagonal.
    EXPECT_NEAR(k.Pvu(i, i), 0.5 * s * std::exp(-2 * s * x), 1e-15);
    EXPECT_NEAR(k.Puu(i, i), -0.5 * s * (1 + s * x), 1e-15);
    // (10.2.16): imposed exactly by the solver's node equation.
    EXPECT_NEAR(k.Puu(0, i), -k.Pvu(0, i), 1e-15);
  }
}

// Second-order expansion in sigma of the integral form along the characteristics:
//   P^vu(x, xi) = sigma/2 - sigma^2 (3x + xi)/4 + O(sigma^3)
//   P^uu(x, xi) = -sigma/2 + sigma^2 (xi - 3x)/4 + O(sigma^3)
// (from P^vu(x, xi) = P^vu(m, m) - int sigma e^{-2 sigma s} P^uu ds along the antidiagonal to
// m = (x + xi)/2, and P^uu(x, xi) = -P^vu(0, xi - x) - int sigma e^{2 sigma s} P^vu ds along the
// diagonal). With sigma = 0.01 the remainder is ~ sigma^3 = 1e-6; the grid error of the
// second-order solver at 64 cells is ~ sigma^2 h^2 ~ 2e-8.
TEST(KernelTest, MatchesSmallSigmaExpansion) {
  const double s = 0.01;
  const int m = 64;
  const KernelSolution k = SolveOrDie(s, m);
  double worst = 0.0;
  for (int i = 0; i <= m; ++i) {
    for (int j = i; j <= m; ++j) {
      const double x = double(i) / m, xi = double(j) / m;
      worst = std::max(worst, std::fabs(k.Pvu(i, j) - (s / 2 - s * s * (3 * x + xi) / 4)));
      worst = std::max(worst, std::fabs(k.Puu(i, j) - (-s / 2 + s * s * (xi - 3 * x) / 4)));
    }
  }
  EXPECT_LT(worst, 2.0 * s * s * s);  // remainder bound: |third-order terms| <= ~ sigma^3
}

// Richardson: the differences between M, 2M and 4M cells shrink by 4 (second order) and the
// extrapolated values agree; the solver is exact on the diagonal so compare off-diagonal nodes
// shared by all grids. Uses a large sigma (1.0) so that the grid error dominates round-off.
TEST(KernelTest, ConvergesAtSecondOrder) {
  const double s = 1.0;
  const KernelSolution k1 = SolveOrDie(s, 16), k2 = SolveOrDie(s, 32), k4 = SolveOrDie(s, 64);
  double d12 = 0.0, d24 = 0.0;
  for (int i = 0; i <= 16; ++i) {
    for (int j = i; j <= 16; ++j) {
      d12 = std::max(d12, std::fabs(k1.Puu(i, j) - k2.Puu(2 * i, 2 * j)));
      d24 = std::max(d24, std::fabs(k2.Puu(2 * i, 2 * j) - k4.Puu(4 * i, 4 * j)));
      d12 = std::max(d12, std::fabs(k1.Pvu(i, j) - k2.Pvu(2 * i, 2 * j)));
      d24 = std::max(d24, std::fabs(k2.Pvu(2 * i, 2 * j) - k4.Pvu(4 * i, 4 * j)));
    }
  }
  ASSERT_GT(d24, 0.0);
  const double order = std::log2(d12 / d24);
  EXPECT_GT(order, 1.8) << "d12 " << d12 << " d24 " << d24;
  EXPECT_LT(order, 2.3);
}

// The PDEs themselves, by centred differences along the two characteristic directions on a fine
// grid: (P^uu(i+1, j+1) - P^uu(i-1, j-1)) / 2h = -sigma e^{2 sigma x} P^vu, and
// (P^vu(i+1, j-1) - P^vu(i-1, j+1)) / 2h = sigma e^{-2 sigma x} P^uu (the derived sign, see
// kernel.h). Residual O(h^2) ~ 1e-5 for sigma = 1, h = 1/128; with the thesis's printed sign
// exp(+2 sigma x) in (10.2.14) the residual would be ~ 2 sinh(2 sigma x) sigma |P^uu| ~ 0.5.
TEST(KernelTest, SatisfiesPdes) {
  const double s = 1.0;
  const int m = 128;
  const double h = 1.0 / m;
  const KernelSolution k = SolveOrDie(s, m);
  double worst_uu = 0.0, worst_vu = 0.0;
  for (int i = 1; i < m; ++i) {
    for (int j = i + 2; j < m; ++j) {
      const double x = i * h;
      const double duu = (k.Puu(i + 1, j + 1) - k.Puu(i - 1, j - 1)) / (2 * h);
      worst_uu = std::max(worst_uu, std::fabs(duu + s * std::exp(2 * s * x) * k.Pvu(i, j)));
      const double dvu = (k.Pvu(i + 1, j - 1) - k.Pvu(i - 1, j + 1)) / (2 * h);
      worst_vu = std::max(worst_vu, std::fabs(dvu - s * std::exp(-2 * s * x) * k.Puu(i, j)));
    }
  }
  EXPECT_LT(worst_uu, 1e-3);
  EXPECT_LT(worst_vu, 1e-3);
}

}  // namespace
}  // namespace mpdrig::observer
