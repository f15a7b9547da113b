// Kernels of the backstepping observer transformation (thesis 10.1.6-10.1.7, 10.2.12-10.2.19;
// Aamo 2013), solved by the method of characteristics on a run-time grid (thesis 10.2.1).
//
// With epsilon_1 = epsilon_2 = c/l and c_1, c_2 of (10.2.4)-(10.2.5), the kernels of interest
// satisfy on the triangle T = {0 <= x <= xi <= 1}:
//   P^uu_x + P^uu_xi = -sigma exp(2 sigma x)  P^vu                      (10.2.12)
//   P^vu_x - P^vu_xi =  sigma exp(-2 sigma x) P^uu                      (10.1.10 with 10.2.5)
//   P^uu(0, xi) = -P^vu(0, xi)                                          (10.2.16)
//   P^vu(x, x)  = (sigma / 2) exp(-2 sigma x)                           (10.2.18)
// NOTE: the thesis prints (10.2.14) with exp(+2 sigma x) (and 10.2.13 with exp(-2 sigma x)).
// Substituting (10.2.4)-(10.2.5) into the general kernel equations (10.1.9)-(10.1.10) gives the
// opposite signs: -c_2(x)/epsilon = sigma exp(-2 sigma x). We solve the derived form; the
// difference is O(sigma^2) (sigma = f1 l / (2c) = 0.079 with the thesis defaults).
//
// Only P^uu and P^vu enter the gains (10.1.16)-(10.1.17). On the diagonal, which is itself a
// characteristic of (10.2.12), P^uu has the closed form P^uu(x, x) = -(sigma/2)(1 + sigma x).
//
// Grid: x_i = i h, xi_j = j h, h = 1/M, 0 <= i <= j <= M. P^uu is integrated along the
// diagonals (direction (1, 1)), P^vu along the antidiagonals (direction (1, -1)) starting from
// the main diagonal, sweeping the antidiagonals k = i + j = 0..2M (thesis Fig. 10.2.1). Unlike
// the thesis's Euler steps, both characteristic integrals use the trapezoidal rule; at each node
// the two implicit trapezoid equations are linear in (P^uu, P^vu) and are solved exactly, so the
// scheme is second order in h. Antidiagonals with odd k meet the main diagonal between nodes, at
// x = xi = k h / 2, where both kernels are known in closed form: they start from there with a
// half step.
#pragma once

#include <vector>

#include "model/common/status.h"

namespace mpdrig::observer {

class KernelSolution {
 public:
  // Solves the kernel equations for `sigma` (dimensionless, 10.2.7) on M = `cells` intervals.
  static Result<KernelSolution> Solve(double sigma, int cells);

  int cells() const { return cells_; }
  double sigma() const { return sigma_; }
  double h() const { return 1.0 / cells_; }
  // Node values, 0 <= i <= j <= cells.
  double Puu(int i, int j) const { return puu_[Index(i, j)]; }
  double Pvu(int i, int j) const { return pvu_[Index(i, j)]; }

 private:
  KernelSolution(double sigma, int cells);
  int Index(int i, int j) const { return i * (cells_ + 1) + j; }

  double sigma_;
  int cells_;
  std::vector<double> puu_;  // full (M+1)^2 storage; only i <= j is used
  std::vector<double> pvu_;
};

}  // namespace mpdrig::observer
