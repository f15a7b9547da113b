// weighted_friction: convolution-based unsteady friction (Zielke 1968; Vardy & Brown 2003, 2004).
// The wall shear of an unsteady flow is the quasi-steady one plus a convolution of the past
// accelerations of the mean velocity V with a weighting function W:
//   tau_wu(t) = (4 rho nu / D) integral_0^t W(tau(t - s)) dV/ds(s) ds,   tau(t) = 4 nu t / D^2
// and in the momentum equation of the method of characteristics (next to f(u) of thesis 8.6.8,
// the pipe's quasi-steady friction) it is the source
//   S = 4 tau_wu / (rho D) = (16 nu / D^2) integral_0^t W dV/ds ds                 [m/s^2].
//
// Weighting functions:
//   laminar (Zielke 1968), exactly W(tau) = sum_{i>=1} exp(-j_i^2 tau), j_i the zeros of the
//     Bessel function J_2; Zielke's own evaluation (ZielkeWeighting): for tau <= 0.02
//     W = sum_{j=1..6} m_j tau^((j-2)/2), m = 0.282095, -1.25, 1.057855, 0.9375, 0.396696,
//     -0.351563, for tau > 0.02 the first five exponentials, n = 26.3744, 70.8493, 135.0198,
//     218.9216, 322.5544 (= j_1^2 .. j_5^2);
//   smooth-pipe turbulent (Vardy & Brown 2003): W(tau) = A* exp(-tau / C*) / sqrt(tau),
//     A* = 1 / (2 sqrt(pi)), C* = 12.86 / Re^kappa, kappa = log10(15.29 / Re^0.0567).
// (The constants as the review literature quotes them: Vitkovsky, Stephens, Bergant, Simpson &
// Lambert 2004, "Efficient and accurate calculation of Zielke and Vardy-Brown unsteady friction
// in pipe transients"; the original papers could not be read here.)
//
// Evaluation (Trikha 1975; Vitkovsky et al. 2004): W is approximated by a sum of exponentials,
// W(tau) ~ sum_k m_k exp(-n_k tau), so that the convolution is a sum of K states per node,
//   y_k(t) = m_k integral_0^t exp(-n_k (tau(t) - tau(s))) dV/ds ds,
// each advanced over a step dtau exactly for an acceleration constant over the step:
//   y_k <- exp(-n_k dtau) y_k + m_k (1 - exp(-n_k dtau)) / (n_k dtau) dV.
// O(N K) per step and no history. The exponentials come from quadrature, not a fit:
//   tau^(-1/2) = pi^(-1/2) integral_0^inf s^(-1/2) exp(-s tau) ds  (Vardy & Brown: every rate
//     shifted by 1 / C*), with s = e^x and the midpoint rule in x, whose error falls as
//     exp(-pi^2 / h) with the step h (Poisson summation);
//   Zielke: the first ten exponentials exactly (the zeros of J_2), the rest of the series as the
//     integral over the continuous index (Euler-Maclaurin about the midpoints, with its first
//     correction as two more exponentials) written over the rate, with McMahon's asymptotic
//     zeros for its density, by the same quadrature.
// The rates reach tau = 1e-4 dtau (the newest step's share of W) and, below, the rule's nodes
// down to where W has decayed (laminar: to the first ten terms; turbulent: 10 C*) are lumped
// into one exponential with their mass and first moment. With 32 exponentials W is within
// 1.2e-4 (Zielke) and 6e-6 (Vardy & Brown) of the functions for dtau <= tau <= 1
// (tests/model/effects/weighted_friction_test.cc).
#pragma once

#include <span>
#include <vector>

namespace mpdrig {

// W(tau) ~ sum_k weight_k exp(-rate_k tau).
struct ExponentialSum {
  std::vector<double> weights;
  std::vector<double> rates;
  double operator()(double tau) const;
};

// Zielke's weighting function as he evaluated it (header).
double ZielkeWeighting(double tau);
// Vardy & Brown's shear decay coefficient C* of a smooth pipe, and their weighting function.
double VardyBrownDecayCoefficient(double reynolds);
double VardyBrownWeighting(double tau, double reynolds);

// The exponential sums of `terms` exponentials for a step dtau (> 0). Zielke's needs terms >= 15
// (ten exact, two for Euler-Maclaurin's correction, the lumped lowest, two quadrature nodes),
// Vardy & Brown's terms >= 3.
ExponentialSum ZielkeExponentials(double dtau, int terms);
ExponentialSum VardyBrownExponentials(double reynolds, double dtau, int terms);

// The convolution integral_0^t W(tau(t - s)) dV/ds ds at `points` points, advanced a step dtau
// at a time, the acceleration constant over each step (header).
class WeightingConvolution {
 public:
  WeightingConvolution(const ExponentialSum& weighting, double dtau, int points);

  // All states back to 0: no past acceleration.
  void Reset();
  // Advances one step; velocity_change[i] = V_i(t + dt) - V_i(t), one per point.
  void Advance(std::span<const double> velocity_change);
  // The integral at point i [m/s].
  double Value(int point) const;
  // What Value(point) will be after the next step, with velocity change dv there:
  // Decayed(point) + newest_gain() dv (so that a source can take the newest step implicitly).
  double Decayed(int point) const;
  double newest_gain() const { return newest_gain_; }
  int terms() const { return static_cast<int>(decay_.size()); }

 private:
  std::vector<double> decay_;   // exp(-n_k dtau)
  std::vector<double> gain_;    // m_k (1 - exp(-n_k dtau)) / (n_k dtau)
  std::vector<double> states_;  // y_k at point i: states_[i * K + k]
  double newest_gain_ = 0.0;    // sum_k gain_k
};

}  // namespace mpdrig
