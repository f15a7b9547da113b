// Disturbance model of the backstepping observer: a sinusoidal piston velocity of known
// frequency omega, unknown amplitude and phase (thesis 10.2.8-10.2.11):
//   dX/dt = A X,   v_d = C_bar X,   A = [0 -omega; omega 0],   C_bar = [0 1]
// X = (X1, X2) in m/s: X2 is the piston velocity v_d, X1 = -omega * (piston position - mean), so
// the position is -X1 / omega (no integration, no drift).
//
// In the observer coordinates the disturbance enters the inlet boundary (10.1.3) through
//   C = -(A_d - A_d2) C_bar   [m^2]: C X = q(0) = -v_d (A_d - A_d2), the inlet flow (5.4.1).
// NOTE: the thesis writes C = -A_2 C_bar (10.2.6) with A_2 = (A_d - A_d2)/A (9.2.5). Since the
// coordinates (10.2.1)-(10.2.2) are built from the volumetric flow q (their pressure term carries
// the factor A / (rho c)), C must map X to a flow: the extra factor A is needed.
//
// The output-injection gain L places the eigenvalues of A - L C (Ackermann's formula for the
// observable pair (A, C)); default poles -40 +- 20i rad/s as in thesis 10.3.
#pragma once

#include <array>
#include <complex>

#include <Eigen/Dense>

#include "model/common/status.h"

namespace mpdrig::observer {

struct SinusoidDisturbance {
  double omega_radps = 0.0;
  Eigen::Matrix2d a;         // (10.2.10)
  Eigen::RowVector2d c_bar;  // (10.2.11)
  Eigen::RowVector2d c;      // C = -(A_d - A_d2) C_bar [m^2]
  Eigen::Vector2d l;         // output-injection gain, A - L C Hurwitz

  // exp(A t): a rotation by omega t.
  Eigen::Matrix2d Exp(double t_s) const;

  // Builds the model for `frequency_hz` > 0, displacement area A_d - A_d2 > 0 and a pole pair
  // `pole` (Re < 0); the second pole is its conjugate (Im may be 0: a double real pole).
  static Result<SinusoidDisturbance> Create(double frequency_hz, double displacement_area_m2,
                                            std::complex<double> pole);
  // The same for any stable pair: conjugate, or two real poles.
  static Result<SinusoidDisturbance> CreateWithPoles(
      double frequency_hz, double displacement_area_m2,
      const std::array<std::complex<double>, 2>& poles);
};

// Ackermann's formula for a 2-state single-output pair: L such that A - L C has the
// characteristic polynomial s^2 + a1 s + a0. Fails if (A, C) is not observable.
Result<Eigen::Vector2d> PlacePoles2(const Eigen::Matrix2d& a, const Eigen::RowVector2d& c,
                                    double a1, double a0);

}  // namespace mpdrig::observer
