#include "model/pipe/characteristics_solver.h"

#include <algorithm>
#include <cmath>

namespace mpdrig {

CharacteristicsSolver::CharacteristicsSolver(const PipeConfig& config, double p_bar_pa)
    : PipeSolver(config, p_bar_pa),
      dt_s_(config.dx_m() / config.wave_speed_mps),
      alpha_next_(config.cells + 1, 0.0),
      beta_next_(config.cells + 1, 0.0),
      velocity_(config.cells + 1, 0.0) {}

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
  return {(1.0 - w) * a1 + w * alpha_[j], 0.5 * (a1 + b1)};
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
  return {(1.0 - w) * b1 + w * beta_[j], 0.5 * (a1 + b1)};
}

namespace {

// One interior node: the two characteristic equations closed by the trapezoidal rule with the
// new point's friction linearised as lambda u_P (see the header). Straight-line code, so the
// loops below vectorise.
struct NodeUpdate {
  double h, gs, f1, f2;
  inline void operator()(double alpha_foot, double u_alpha_foot, double beta_foot,
                         double u_beta_foot, double u_old, double* __restrict alpha_new,
                         double* __restrict beta_new) const {
    const double f_a = f1 * u_alpha_foot + f2 * u_alpha_foot * std::fabs(u_alpha_foot);
    const double f_b = f1 * u_beta_foot + f2 * u_beta_foot * std::fabs(u_beta_foot);
    const double lambda = f1 + f2 * std::fabs(u_old);
    const double u_p =
        (alpha_foot + beta_foot - 0.5 * h * (f_a + f_b) - 2.0 * h * gs) / (2.0 + h * lambda);
    *alpha_new = alpha_foot - 0.5 * h * (f_a + lambda * u_p) - h * gs;
    *beta_new = beta_foot - 0.5 * h * (f_b + lambda * u_p) - h * gs;
  }
};

}  // namespace

// The two interior loops are most of the run time. They are built twice, for AVX2 (4 doubles a
// vector) and for baseline x86-64 (2), and the loader picks what the CPU has: one portable binary.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define MPDRIG_HOT_LOOP __attribute__((target_clones("avx2", "default")))
#else
#define MPDRIG_HOT_LOOP
#endif

MPDRIG_HOT_LOOP void CharacteristicsSolver::StepInteriorLinear() {
  // The feet are the neighbouring nodes.
  const int n = config_.cells;
  const NodeUpdate update{dt_s_, config_.gravity_slope_mps2, config_.friction_f1_per_s,
                          config_.friction_f2_per_m};
  const double* __restrict a = alpha_.data();
  const double* __restrict b = beta_.data();
  double* __restrict a_next = alpha_next_.data();
  double* __restrict b_next = beta_next_.data();
  for (int i = 1; i < n; ++i) {
    update(a[i - 1], 0.5 * (a[i - 1] + b[i - 1]), b[i + 1], 0.5 * (a[i + 1] + b[i + 1]),
           0.5 * (a[i] + b[i]), &a_next[i], &b_next[i]);
  }
}

MPDRIG_HOT_LOOP void CharacteristicsSolver::StepInteriorQuasiLinear() {
  const int n = config_.cells;
  const NodeUpdate update{dt_s_, config_.gravity_slope_mps2, config_.friction_f1_per_s,
                          config_.friction_f2_per_m};
  const double inv_c = 1.0 / config_.wave_speed_mps;
  const double* __restrict a = alpha_.data();
  const double* __restrict b = beta_.data();
  double* __restrict a_next = alpha_next_.data();
  double* __restrict b_next = beta_next_.data();
  auto at_boundary = [&](int i) {
    const Foot fa = AlphaFoot(i);
    const Foot fb = BetaFoot(i);
    update(fa.invariant, fa.velocity, fb.invariant, fb.velocity, 0.5 * (a[i] + b[i]), &a_next[i],
           &b_next[i]);
  };
  // Nodes next to the boundaries may need a clamped foot: the general functions handle them.
  at_boundary(1);
  if (n - 1 > 1) at_boundary(n - 1);
  // Interior: the interpolation of AlphaFoot/BetaFoot without branches, so it vectorises. The
  // far neighbour's weight is max(theta, 0) = (theta + |theta|)/2 on one side and
  // max(-theta, 0) = (|theta| - theta)/2 on the other, theta = u/c. The friction at the foot
  // uses the neighbouring node's velocity: the foot is |u|/c ~ 3e-4 of a cell from that node, so
  // f(u) differs by f'(u) du 3e-4, far below the scheme's O(dt^2) error, and it saves two
  // interpolations per node (a fifth of the run time).
  double* __restrict u = velocity_.data();
  for (int i = 0; i <= n; ++i) u[i] = 0.5 * (a[i] + b[i]);
  for (int i = 2; i <= n - 2; ++i) {
    const double theta_a = u[i - 1] * inv_c;
    const double wa_left = 0.5 * (theta_a + std::fabs(theta_a));
    const double wa_right = 0.5 * (std::fabs(theta_a) - theta_a);
    const double wa = 1.0 - std::fabs(theta_a);
    const double alpha_a = wa * a[i - 1] + wa_left * a[i - 2] + wa_right * a[i];
    const double theta_b = u[i + 1] * inv_c;
    const double wb_near = 0.5 * (theta_b + std::fabs(theta_b));
    const double wb_far = 0.5 * (std::fabs(theta_b) - theta_b);
    const double wb = 1.0 - std::fabs(theta_b);
    const double beta_b = wb * b[i + 1] + wb_near * b[i] + wb_far * b[i + 2];
    update(alpha_a, u[i - 1], beta_b, u[i + 1], u[i], &a_next[i], &b_next[i]);
  }
}

namespace {

// p(0) as a function of u(0) once beta(0) is known: alpha(0) = 2 u - beta(0).
class InletRelation final : public BoundaryRelation {
 public:
  InletRelation(const PipeLaw& law, double beta) : law_(law), beta_(beta) {}
  double PressurePa(double u) const override {
    return law_.PressureFromDifference(2.0 * (u - beta_));
  }
  double DPressureDVelocity(double u) const override {
    return -law_.DPressureDVelocityAtPressure(PressurePa(u));
  }

 private:
  const PipeLaw& law_;
  double beta_;
};

// p(L) as a function of u(L) once alpha(L) is known.
class OutletRelation final : public BoundaryRelation {
 public:
  OutletRelation(const PipeLaw& law, double alpha) : law_(law), alpha_(alpha) {}
  double PressurePa(double u) const override { return law_.PressureFromAlpha(alpha_, u); }
  double DPressureDVelocity(double u) const override {
    return law_.DPressureDVelocityAtPressure(PressurePa(u));
  }

 private:
  const PipeLaw& law_;
  double alpha_;
};

}  // namespace

Status CharacteristicsSolver::Step(const PipeStepInputs& inputs, RangeViolation* violation) {
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  // Extra momentum sources from the state before the step (pipe_extension.h); none by default.
  const bool has_sources = EvaluateMomentumSources();
  // S = a + b u at a boundary node whose new velocity is u.
  const auto source_at = [&](int i, double u) {
    return has_sources ? source_explicit_[i] + source_implicit_[i] * u : 0.0;
  };

  if (config_.model == PipeModel::kLinear) {
    StepInteriorLinear();
  } else {
    StepInteriorQuasiLinear();
  }
  if (has_sources) {
    // The node update without S gave u_P0 with 2 u_P0 D = alpha_A + beta_B - ..., D = 2 + h lambda
    // (NodeUpdate). With S = a + b u_P in both characteristic equations:
    //   u_P = (D u_P0 - 2 h a) / (D + 2 h b),
    //   alpha_P = alpha_P0 - h lambda (u_P - u_P0)/2 - h (a + b u_P), beta_P likewise,
    // which keeps alpha_P + beta_P = 2 u_P.
    for (int i = 1; i < n; ++i) {
      const double u_old = 0.5 * (alpha_[i] + beta_[i]);
      const double lambda =
          config_.friction_f1_per_s + config_.friction_f2_per_m * std::fabs(u_old);
      const double d = 2.0 + h * lambda;
      const double u_p0 = 0.5 * (alpha_next_[i] + beta_next_[i]);
      const double a = source_explicit_[i];
      const double b = source_implicit_[i];
      const double u_p = (d * u_p0 - 2.0 * h * a) / (d + 2.0 * h * b);
      const double change = 0.5 * h * lambda * (u_p - u_p0) + h * (a + b * u_p);
      alpha_next_[i] -= change;
      beta_next_[i] -= change;
    }
  }

  // Inlet, x = 0 (6.7.1): the beta characteristic arrives from node 1; u(0) is imposed by the
  // piston, or by an extension's closure. With a closure the friction at the new point needs
  // u(0), which needs beta(0): two passes settle it, as at the outlet.
  {
    const Foot fb = BetaFoot(0);
    const double f_b = config_.Friction(fb.velocity);
    double u0 = inputs.end.inlet_velocity_mps;
    if (inlet_closure_ != nullptr) u0 = 0.5 * (alpha_[0] + beta_[0]);
    const InletInputs inlet{inputs.end.inlet_velocity_mps * config_.area_m2, config_.area_m2, h};
    for (int pass = 0; pass < (inlet_closure_ != nullptr ? 2 : 1); ++pass) {
      beta_next_[0] =
          fb.invariant - 0.5 * h * (f_b + config_.Friction(u0)) - h * gs - h * source_at(0, u0);
      if (inlet_closure_ != nullptr) {
        u0 = inlet_closure_->SolveInletVelocity(InletRelation(law_, beta_next_[0]), inlet);
      }
    }
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
      alpha_l = fa.invariant - 0.5 * h * (f_a + config_.Friction(u_l)) - h * gs - h * source_at(n, u_l);
      u_l = outlet_closure_ != nullptr
                ? outlet_closure_->SolveOutletVelocity(OutletRelation(law_, alpha_l),
                                                       inputs.end.choke, h, u_l)
                : choke_.SolveOutletVelocity(law_, alpha_l, inputs.end.choke, u_l);
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
