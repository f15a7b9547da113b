// The pipe's state variables and the Riemann invariants that carry them, for both model variants.
//
// Quasi-linear (thesis 5.2, 6.1): density rho = rho_ref + (p - p_ref)/c^2 (5.2.1), k = c^2 rho_ref
// - p_ref, so k + p = c^2 rho(p). Riemann invariants (6.1.8)-(6.1.9), with u_bar = 0:
//   alpha = c ln((k + p)/(k + p_bar)) + u,   beta = -c ln((k + p)/(k + p_bar)) + u,
//   p = (k + p_bar) exp((alpha - beta)/(2c)) - k   (6.1.12),   u = (alpha + beta)/2   (6.1.13).
// alpha travels at u + c (upwards, towards the choke), beta at u - c (6.1.16)-(6.1.17).
//
// Linear (thesis 7.0): alpha = (p - p_bar)/(rho c) + u,  beta = -(p - p_bar)/(rho c) + u (7.0.6)-
// (7.0.7); p = p_bar + rho c (alpha - beta)/2 (7.0.9); speeds +-c (7.0.4).
//
// Along either characteristic: d(alpha)/dt = d(beta)/dt = -g sin(gamma) - f(u)  (6.1.16, 7.0.10).
#pragma once

#include <cmath>

namespace mpdrig {

enum class PipeModel { kQuasiLinear, kLinear };

class PipeLaw {
 public:
  // p_bar: the pressure at which alpha = beta = 0 when u = 0 [Pa abs].
  PipeLaw(PipeModel model, double wave_speed_mps, double density_kgpm3, double k_pa,
          double p_bar_pa)
      : model_(model),
        c_(wave_speed_mps),
        rho_c_(density_kgpm3 * wave_speed_mps),
        k_plus_p_bar_(k_pa + p_bar_pa),
        k_(k_pa),
        p_bar_(p_bar_pa) {}

  PipeModel model() const { return model_; }
  double wave_speed_mps() const { return c_; }

  double Velocity(double alpha, double beta) const { return 0.5 * (alpha + beta); }

  // Pressure from the difference alpha - beta (= 2 c ln(...) or 2 (p - p_bar)/(rho c)).
  double PressureFromDifference(double alpha_minus_beta) const {
    if (model_ == PipeModel::kLinear) return p_bar_ + 0.5 * rho_c_ * alpha_minus_beta;
    return k_plus_p_bar_ * std::exp(alpha_minus_beta / (2.0 * c_)) - k_;
  }
  double Pressure(double alpha, double beta) const { return PressureFromDifference(alpha - beta); }

  // The pressure part of the invariants: alpha = W(p) + u, beta = -W(p) + u.
  double PressureTerm(double pressure_pa) const {
    if (model_ == PipeModel::kLinear) return (pressure_pa - p_bar_) / rho_c_;
    return c_ * std::log((k_ + pressure_pa) / k_plus_p_bar_);
  }
  double Alpha(double pressure_pa, double velocity_mps) const {
    return PressureTerm(pressure_pa) + velocity_mps;
  }
  double Beta(double pressure_pa, double velocity_mps) const {
    return -PressureTerm(pressure_pa) + velocity_mps;
  }

  // Pressure at a point where the upward invariant alpha arrives and the velocity is u.
  double PressureFromAlpha(double alpha, double velocity_mps) const {
    return PressureFromDifference(2.0 * (alpha - velocity_mps));
  }
  // d p / d u at fixed alpha (always negative), given the pressure there: the pipe's outlet
  // impedance seen by the choke. Linear: -rho c; quasi-linear: -(k + p)/c.
  double DPressureDVelocityAtPressure(double pressure_pa) const {
    if (model_ == PipeModel::kLinear) return -rho_c_;
    return -(pressure_pa + k_) / c_;
  }

  // alpha - beta at which the absolute pressure reaches zero: the model's range ends there
  // (thesis 11.5: the model can produce negative absolute pressures).
  double ZeroPressureDifference() const { return 2.0 * PressureTerm(0.0); }

 private:
  PipeModel model_;
  double c_;
  double rho_c_;
  double k_plus_p_bar_;
  double k_;
  double p_bar_;
};

}  // namespace mpdrig
