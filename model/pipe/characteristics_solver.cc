#include "model/pipe/characteristics_solver.h"

#include <algorithm>
#include <cmath>

namespace mpdrig {

CharacteristicsSolver::CharacteristicsSolver(const PipeConfig& config, double p_bar_pa)
    : PipeSolver(config, p_bar_pa),
      dt_s_(config.dx_m() / config.wave_speed_mps),
      alpha_next_(config.cells + 1, 0.0),
      beta_next_(config.cells + 1, 0.0) {}

CharacteristicsSolver::Foot CharacteristicsSolver::AlphaFoot(int i) const {
  // Linear model: the foot is node i - 1. Quasi-linear: it is shifted by u dt = (u/c) dx.
  const int n = config_.cells;
  const double a1 = alpha_[i - 1];
  const double b1 = beta_[i - 1];
  if (config_.model == PipeModel::kLinear) return {a1, 0.5 * (a1 + b1)};
  const double theta = 0.5 * (a1 + b1) / config_.wave_speed_mps;
  // theta > 0: the foot lies between nodes i-2 and i-1 (clamped at the inlet node);
  // theta < 0: between i-1 and i.
  const int j = theta >= 0.0 ? std::max(i - 2, 0) : std::min(i, n);
  const double w = std::fabs(theta);
  const double a = (1.0 - w) * a1 + w * alpha_[j];
  const double b = (1.0 - w) * b1 + w * beta_[j];
  return {a, 0.5 * (a + b)};
}

CharacteristicsSolver::Foot CharacteristicsSolver::BetaFoot(int i) const {
  const int n = config_.cells;
  const double a1 = alpha_[i + 1];
  const double b1 = beta_[i + 1];
  if (config_.model == PipeModel::kLinear) return {b1, 0.5 * (a1 + b1)};
  // beta travels at u - c: with u > 0 its foot is between i and i+1, with u < 0 beyond i+1.
  const double theta = 0.5 * (a1 + b1) / config_.wave_speed_mps;
  const int j = theta >= 0.0 ? std::max(i, 0) : std::min(i + 2, n);
  const double w = std::fabs(theta);
  const double a = (1.0 - w) * a1 + w * alpha_[j];
  const double b = (1.0 - w) * b1 + w * beta_[j];
  return {b, 0.5 * (a + b)};
}

void CharacteristicsSolver::StepInteriorLinear() {
  // Branch-free loop over the interior nodes (vectorises); see the header for the formula.
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  const double f1 = config_.friction_f1_per_s;
  const double f2 = config_.friction_f2_per_m;
  const double* a = alpha_.data();
  const double* b = beta_.data();
  double* a_next = alpha_next_.data();
  double* b_next = beta_next_.data();
  for (int i = 1; i < n; ++i) {
    const double u_a = 0.5 * (a[i - 1] + b[i - 1]);
    const double u_b = 0.5 * (a[i + 1] + b[i + 1]);
    const double u_old = 0.5 * (a[i] + b[i]);
    const double f_a = f1 * u_a + f2 * u_a * std::fabs(u_a);
    const double f_b = f1 * u_b + f2 * u_b * std::fabs(u_b);
    const double lambda = f1 + f2 * std::fabs(u_old);
    const double u_p =
        (a[i - 1] + b[i + 1] - 0.5 * h * (f_a + f_b) - 2.0 * h * gs) / (2.0 + h * lambda);
    a_next[i] = a[i - 1] - 0.5 * h * (f_a + lambda * u_p) - h * gs;
    b_next[i] = b[i + 1] - 0.5 * h * (f_b + lambda * u_p) - h * gs;
  }
}

void CharacteristicsSolver::StepInteriorQuasiLinear() {
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  for (int i = 1; i < n; ++i) {
    const Foot fa = AlphaFoot(i);
    const Foot fb = BetaFoot(i);
    const double f_a = config_.Friction(fa.velocity);
    const double f_b = config_.Friction(fb.velocity);
    const double lambda = config_.friction_f1_per_s +
                          config_.friction_f2_per_m * std::fabs(0.5 * (alpha_[i] + beta_[i]));
    const double u_p =
        (fa.invariant + fb.invariant - 0.5 * h * (f_a + f_b) - 2.0 * h * gs) / (2.0 + h * lambda);
    alpha_next_[i] = fa.invariant - 0.5 * h * (f_a + lambda * u_p) - h * gs;
    beta_next_[i] = fb.invariant - 0.5 * h * (f_b + lambda * u_p) - h * gs;
  }
}

Status CharacteristicsSolver::Step(const PipeStepInputs& inputs, RangeViolation* violation) {
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;

  if (config_.model == PipeModel::kLinear) {
    StepInteriorLinear();
  } else {
    StepInteriorQuasiLinear();
  }

  // Inlet, x = 0 (6.7.1): the beta characteristic arrives from node 1; u(0) is imposed.
  {
    const Foot fb = BetaFoot(0);
    const double u0 = inputs.end.inlet_velocity_mps;
    beta_next_[0] =
        fb.invariant - 0.5 * h * (config_.Friction(fb.velocity) + config_.Friction(u0)) - h * gs;
    alpha_next_[0] = 2.0 * u0 - beta_next_[0];
  }

  // Outlet, x = L (6.6.1): the alpha characteristic arrives from node N-1; the choke sets u(L).
  // The friction at the new point needs u(L), which needs alpha(L): two passes settle it.
  {
    const Foot fa = AlphaFoot(n);
    const double f_a = config_.Friction(fa.velocity);
    double u_l = 0.5 * (alpha_[n] + beta_[n]);
    double alpha_l = 0.0;
    for (int pass = 0; pass < 2; ++pass) {
      alpha_l = fa.invariant - 0.5 * h * (f_a + config_.Friction(u_l)) - h * gs;
      u_l = choke_.SolveOutletVelocity(law_, alpha_l, inputs.end.choke);
    }
    alpha_next_[n] = alpha_l;
    beta_next_[n] = 2.0 * u_l - alpha_l;
  }

  alpha_.swap(alpha_next_);
  beta_.swap(beta_next_);
  if (!std::isfinite(alpha_[n]) || !std::isfinite(beta_[0])) {
    return Status::Error("pipe state is no longer finite (check the inputs for NaN)");
  }
  CheckRange(violation);
  return Status::Ok();
}

}  // namespace mpdrig
