// The pressure part of the Riemann invariants when the pipe's contents are more compressible than
// the liquid alone (e.g. entrained gas, thesis 8.3): a pressure-dependent wave speed c(p) <= c.
//
// Continuity and momentum (5.2) with the mixture's compressibility
//   C(p) = 1/(rho(p) c^2) + C_x(p)        [1/Pa]   (liquid + what the extensions add),
// rho(p) the liquid's density of the model variant (5.2.1, or rho_ref for the linear model), give
// the local wave speed and the invariants (generalising 6.1.8-6.1.9):
//   c(p) = 1 / sqrt(rho(p) C(p)),     W(p) = integral dp / (rho(p) c(p)) = integral sqrt(C/rho) dp,
//   alpha = W(p) + u along dx/dt = u + c(p),   beta = -W(p) + u along dx/dt = u - c(p).
// With C_x = 0, W is the model's own PressureTerm (PipeLaw), up to a constant.
//
// W is tabulated once, on a uniform grid in ln p over [1 Pa, 1 GPa] (8192 intervals, nodes from
// 3-point Gauss-Legendre quadrature of dW/d(ln p) = p sqrt(C/rho)), and interpolated by cubic
// Hermite polynomials with the exact derivatives at the nodes (relative error ~1e-12). Outside
// the table W continues linearly in ln p. The inverse is a bracketed Newton iteration on that
// cubic, started from the inverse's own cubic Hermite on the interval (about 1e-13 from the
// root in ln p): one Newton step leaves the pressure within round-off (about 1e-15 relative) of
// the exact inverse of the table.
#pragma once

#include <functional>
#include <limits>
#include <vector>

#include "model/core/pipe_law.h"

namespace mpdrig {

class MixtureLaw {
 public:
  // `extra_compressibility_per_pa(p)` is C_x(p) >= 0 (MPDRIG_CHECKed at every table point).
  MixtureLaw(const PipeLaw& law, double density_kgpm3, double k_pa,
             const std::function<double(double)>& extra_compressibility_per_pa);

  double W(double pressure_pa) const;
  // W and the wave speed c(p) from the table alone (the derivative of the interpolant: relative
  // error ~1e-9), for the step's loop over the nodes.
  double WAndWaveSpeed(double pressure_pa, double* wave_speed_mps) const;
  // The same with ln p known (the solver keeps it from the step that computed p).
  double WAndWaveSpeedAtLog(double pressure_pa, double log_pressure, double* wave_speed_mps) const;
  // dW/dp = 1 / (rho c) [m/s/Pa]: the inverse of the local impedance.
  double DW(double pressure_pa) const;
  // The pressure whose W is w, starting the search in the table interval of `guess_pa` (or the
  // next one; elsewhere by bisection of the table).
  double Pressure(double w, double guess_pa) const;
  // The same with the guess as ln p (kNoGuess: none); also returns ln p of the result.
  static constexpr double kNoGuess = std::numeric_limits<double>::quiet_NaN();
  double PressureAndLog(double w, double guess_log_pressure, double* log_pressure) const;
  // c(p) [m/s].
  double WaveSpeed(double pressure_pa) const;

 private:
  double LiquidDensity(double pressure_pa) const;
  double Slope(double x) const;  // dW/dx at x = ln p, exact
  double Interpolate(int interval, double x, double* slope) const;

  PipeModel model_;
  double c_;
  double density_;
  double k_;
  std::function<double(double)> extra_;
  double x_lo_;
  double step_;
  std::vector<double> w_;      // W at the grid nodes
  std::vector<double> slope_;  // dW/dx at the grid nodes
};

}  // namespace mpdrig
