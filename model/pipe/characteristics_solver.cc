#include "model/pipe/characteristics_solver.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace mpdrig {

CharacteristicsSolver::CharacteristicsSolver(const PipeConfig& config, double p_bar_pa)
    : PipeSolver(config, p_bar_pa),
      dt_s_(config.dx_m() / config.wave_speed_mps),
      alpha_next_(config.cells + 1, 0.0),
      beta_next_(config.cells + 1, 0.0),
      velocity_(config.cells + 1, 0.0),
      leaving_alpha_(config.cells + 1, 0.0),
      leaving_beta_(config.cells + 1, 0.0),
      friction_share_(config.cells + 1, 0.0) {}

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

// The interior nodes of the default path, as two loops over arrays without a branch per node
// (structure of arrays; they vectorise at the machine's width).
//
// At an interior node i the two characteristic equations (6.1.16)-(6.1.17), closed by the
// trapezoidal rule with the new point's friction linearised as lambda_i u_P (lambda_i = f1 +
// f2 |u_i| at the old level, see the header), read
//   alpha_P = A - h lambda_i u_P / 2,    beta_P = B - h lambda_i u_P / 2,
//   u_P = (A + B) / (2 + h lambda_i),
//   A = alpha_foot - h f(u_(i-1)) / 2 - h g sin(gamma),
//   B = beta_foot - h f(u_(i+1)) / 2 - h g sin(gamma),
// so alpha_P = A - K_i (A + B) and beta_P = B - K_i (A + B), K_i = (h lambda_i / 2) /
// (2 + h lambda_i). A depends only on node i-1 (the foot of the alpha characteristic lies next
// to it, and the friction there uses its velocity: |u|/c ~ 3e-4 of a cell away, far below the
// scheme's O(dt^2) error) and B only on node i+1: the first loop computes, per node j, what
// leaves it along each characteristic (leaving_alpha_j = A of node j+1, leaving_beta_j = B of
// node j-1) and K_j; the second combines them per node. The foot (quasi-linear model):
// theta = u_j / c, the foot at x_j - theta dx, linear between the nodes on the upwind side,
//   alpha_foot = alpha_j - theta (theta >= 0 ? alpha_j - alpha_(j-1) : alpha_(j+1) - alpha_j),
// a select rather than a branch; beta's likewise (its foot is at x_j - theta dx too). Next to an
// end the foot is clamped to the end node (its outer difference is taken as 0). The linear
// model's feet are the nodes themselves (theta = 0).
// Per node and step: 23 vector operations in the first loop (one division), 6 in the second
// (with the range check's difference and minimum); bench/simulator_benchmark.cc counts them for
// the arithmetic limit.
struct InteriorArgs {
  const double* __restrict alpha;
  const double* __restrict beta;
  double* __restrict leaving_alpha;
  double* __restrict leaving_beta;
  double* __restrict friction_share;
  double* __restrict alpha_next;
  double* __restrict beta_next;
  int n;
  double h, h_gs, f1, f2, inv_c;
};

template <bool kQuasiLinear>
inline __attribute__((always_inline)) double InteriorLoops(const InteriorArgs& k) {
  // Everything in locals: the stores below cannot then alias the parameters, and both loops
  // vectorise.
  const int n = k.n;
  const double h = k.h, half_h = 0.5 * k.h, h_gs = k.h_gs, f1 = k.f1, f2 = k.f2, inv_c = k.inv_c;
  const double* __restrict a = k.alpha;
  const double* __restrict b = k.beta;
  double* __restrict leaving_a = k.leaving_alpha;
  double* __restrict leaving_b = k.leaving_beta;
  double* __restrict share = k.friction_share;
  const auto leaving = [&](int j, double da_left, double da_right, double db_left, double db_right)
      __attribute__((always_inline)) {
    const double u = 0.5 * (a[j] + b[j]);
    const double lambda = f1 + f2 * std::fabs(u);
    const double g = half_h * (u * lambda) + h_gs;  // h f(u) / 2 + h g sin(gamma)
    double shift_a = 0.0, shift_b = 0.0;
    if constexpr (kQuasiLinear) {
      const double theta = u * inv_c;
      const bool up = theta >= 0.0;
      shift_a = theta * (up ? da_left : da_right);
      shift_b = theta * (up ? db_left : db_right);
    }
    leaving_a[j] = a[j] - shift_a - g;
    leaving_b[j] = b[j] - shift_b - g;
    share[j] = half_h * lambda / (2.0 + h * lambda);
  };
  for (int j = 1; j < n; ++j) {
    leaving(j, a[j] - a[j - 1], a[j + 1] - a[j], b[j] - b[j - 1], b[j + 1] - b[j]);
  }
  // The end nodes: only what leaves them inwards, the foot clamped at the end.
  leaving(0, 0.0, a[1] - a[0], 0.0, b[1] - b[0]);
  leaving(n, a[n] - a[n - 1], 0.0, b[n] - b[n - 1], 0.0);
  // The new level, and its smallest alpha - beta (the range check, PipeSolver::CheckRange): a
  // running minimum of eight lanes in a vector of the compiler's (GCC and Clang), because a
  // scalar floating-point minimum is not reassociated into one by the vectoriser.
  double* __restrict a_next = k.alpha_next;
  double* __restrict b_next = k.beta_next;
  const auto update = [&](int i) __attribute__((always_inline)) {
    const double big_a = leaving_a[i - 1];
    const double big_b = leaving_b[i + 1];
    const double m = share[i] * (big_a + big_b);
    a_next[i] = big_a - m;
    b_next[i] = big_b - m;
    return a_next[i] - b_next[i];
  };
  using Lanes = double __attribute__((vector_size(8 * sizeof(double))));
  Lanes smallest_lanes;
  for (int l = 0; l < 8; ++l) smallest_lanes[l] = std::numeric_limits<double>::infinity();
  int i = 1;
  for (; i + 8 <= n; i += 8) {
    Lanes big_a, big_b, share_i;
    std::memcpy(&big_a, leaving_a + i - 1, sizeof(Lanes));
    std::memcpy(&big_b, leaving_b + i + 1, sizeof(Lanes));
    std::memcpy(&share_i, share + i, sizeof(Lanes));
    const Lanes m = share_i * (big_a + big_b);
    const Lanes new_a = big_a - m;
    const Lanes new_b = big_b - m;
    std::memcpy(a_next + i, &new_a, sizeof(Lanes));
    std::memcpy(b_next + i, &new_b, sizeof(Lanes));
    const Lanes difference = new_a - new_b;
    smallest_lanes = difference < smallest_lanes ? difference : smallest_lanes;
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (; i < n; ++i) smallest = std::min(smallest, update(i));
  for (int l = 0; l < 8; ++l) smallest = std::min(smallest, smallest_lanes[l]);
  return smallest;
}

// Built for AVX-512 (8 doubles a vector), AVX2 (4) and baseline x86-64 (2); the first the CPU
// has is chosen once: one portable binary.
double InteriorBaseline(const InteriorArgs& k, bool quasi_linear) {
  return quasi_linear ? InteriorLoops<true>(k) : InteriorLoops<false>(k);
}
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target("arch=x86-64-v3"))) double InteriorAvx2(const InteriorArgs& k,
                                                              bool quasi_linear) {
  return quasi_linear ? InteriorLoops<true>(k) : InteriorLoops<false>(k);
}
__attribute__((target("arch=x86-64-v4,prefer-vector-width=512"))) double InteriorAvx512(
    const InteriorArgs& k, bool quasi_linear) {
  return quasi_linear ? InteriorLoops<true>(k) : InteriorLoops<false>(k);
}
#endif

using InteriorFunction = double (*)(const InteriorArgs&, bool);

InteriorFunction ChooseInterior() {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  __builtin_cpu_init();
  if (__builtin_cpu_supports("x86-64-v4")) return InteriorAvx512;
  if (__builtin_cpu_supports("x86-64-v3")) return InteriorAvx2;
#endif
  return InteriorBaseline;
}

}  // namespace

double CharacteristicsSolver::StepInterior() {
  static const InteriorFunction interior = ChooseInterior();
  const InteriorArgs args{alpha_.data(),
                          beta_.data(),
                          leaving_alpha_.data(),
                          leaving_beta_.data(),
                          friction_share_.data(),
                          alpha_next_.data(),
                          beta_next_.data(),
                          config_.cells,
                          dt_s_,
                          dt_s_ * config_.gravity_slope_mps2,
                          config_.friction_f1_per_s,
                          config_.friction_f2_per_m,
                          1.0 / config_.wave_speed_mps};
  return interior(args, config_.model == PipeModel::kQuasiLinear);
}

namespace {

// The solver's relations get dp/du from the pressure: each says both in PressureAndSlope, and
// the slope alone is that (one formula per relation).
class SlopeFromPressure : public BoundaryRelation {
 public:
  double DPressureDVelocity(double u) const final {
    double slope = 0.0;
    PressureAndSlope(u, &slope);
    return slope;
  }
};

// p(0) as a function of u(0) once beta(0) is known: alpha(0) = 2 u - beta(0).
class InletRelation final : public SlopeFromPressure {
 public:
  InletRelation(const PipeLaw& law, double beta) : law_(law), beta_(beta) {}
  double PressurePa(double u) const override {
    return law_.PressureFromDifference(2.0 * (u - beta_));
  }
  double PressureAndSlope(double u, double* slope) const override {
    const double p = PressurePa(u);
    *slope = -law_.DPressureDVelocityAtPressure(p);
    return p;
  }

 private:
  const PipeLaw& law_;
  double beta_;
};

// p(L) as a function of u(L) once alpha(L) is known.
class OutletRelation final : public SlopeFromPressure {
 public:
  OutletRelation(const PipeLaw& law, double alpha) : law_(law), alpha_(alpha) {}
  double PressurePa(double u) const override { return law_.PressureFromAlpha(alpha_, u); }
  double PressureAndSlope(double u, double* slope) const override {
    const double p = PressurePa(u);
    *slope = law_.DPressureDVelocityAtPressure(p);
    return p;
  }

 private:
  const PipeLaw& law_;
  double alpha_;
};

}  // namespace

Status CharacteristicsSolver::Step(const PipeStepInputs& inputs, RangeViolation* violation) {
  if (general_) return StepGeneral(inputs, violation);
  // Extra momentum sources from the state before the step (pipe_extension.h); none by default.
  const bool has_sources = EvaluateMomentumSources();
  double interior_smallest = StepInterior();
  if (has_sources) {
    AddSourcesToInterior();
    interior_smallest = std::numeric_limits<double>::quiet_NaN();  // changed: CheckRange's own
  }
  StepInletNode(inputs, has_sources);
  StepOutletNode(inputs, has_sources);
  return AdvanceToNewLevel(violation, interior_smallest);
}

// S = a + b u at a boundary node whose new velocity is u.
double CharacteristicsSolver::SourceAt(bool has_sources, int i, double u) const {
  return has_sources ? source_explicit_[i] + source_implicit_[i] * u : 0.0;
}

// The node update without S gave u_P0 with 2 u_P0 D = alpha_A + beta_B - ..., D = 2 + h lambda
// (StepInterior). With S = a + b u_P in both characteristic equations:
//   u_P = (D u_P0 - 2 h a) / (D + 2 h b),
//   alpha_P = alpha_P0 - h lambda (u_P - u_P0)/2 - h (a + b u_P), beta_P likewise,
// which keeps alpha_P + beta_P = 2 u_P.
void CharacteristicsSolver::AddSourcesToInterior() {
  const double h = dt_s_;
  for (int i = 1; i < config_.cells; ++i) {
    const double u_old = 0.5 * (alpha_[i] + beta_[i]);
    const double lambda = config_.friction_f1_per_s + config_.friction_f2_per_m * std::fabs(u_old);
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
void CharacteristicsSolver::StepInletNode(const PipeStepInputs& inputs, bool has_sources) {
  const double h = dt_s_;
  const Foot fb = BetaFoot(0);
  const double f_b = config_.Friction(fb.velocity);
  double u0 = inputs.end.inlet_velocity_mps;
  if (inlet_closure_ != nullptr) u0 = 0.5 * (alpha_[0] + beta_[0]);
  const InletInputs inlet{inputs.end.inlet_velocity_mps * config_.area_m2, config_.area_m2, h};
  for (int pass = 0; pass < (inlet_closure_ != nullptr ? 2 : 1); ++pass) {
    beta_next_[0] = fb.invariant - 0.5 * h * (f_b + config_.Friction(u0)) -
                    h * config_.gravity_slope_mps2 - h * SourceAt(has_sources, 0, u0);
    if (inlet_closure_ != nullptr) {
      u0 = inlet_closure_->SolveInletVelocity(InletRelation(law_, beta_next_[0]), inlet);
    }
  }
  alpha_next_[0] = 2.0 * u0 - beta_next_[0];
}

// Outlet, x = L (6.6.1): the alpha characteristic arrives from node N-1; the choke sets u(L).
// The friction at the new point needs u(L), which needs alpha(L): two passes settle it.
void CharacteristicsSolver::StepOutletNode(const PipeStepInputs& inputs, bool has_sources) {
  const int n = config_.cells;
  const double h = dt_s_;
  const Foot fa = AlphaFoot(n);
  const double f_a = config_.Friction(fa.velocity);
  double u_l = 0.5 * (alpha_[n] + beta_[n]);
  double alpha_l = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    alpha_l = fa.invariant - 0.5 * h * (f_a + config_.Friction(u_l)) -
              h * config_.gravity_slope_mps2 - h * SourceAt(has_sources, n, u_l);
    u_l = outlet_closure_ != nullptr
              ? outlet_closure_->SolveOutletVelocity(OutletRelation(law_, alpha_l),
                                                     inputs.end.choke, h, u_l)
              : choke_.SolveOutletVelocity(law_, alpha_l, inputs.end.choke, u_l);
  }
  alpha_next_[n] = alpha_l;
  beta_next_[n] = 2.0 * u_l - alpha_l;
}

// Both paths end alike: the new level becomes the state, checked for NaN and for the model's
// range (with the interior nodes' smallest alpha - beta when the step already knows it).
Status CharacteristicsSolver::AdvanceToNewLevel(RangeViolation* violation,
                                                double interior_smallest_difference) {
  alpha_.swap(alpha_next_);
  beta_.swap(beta_next_);
  if (!std::isfinite(alpha_.back()) || !std::isfinite(beta_.front())) {
    return Status::Error("pipe state is no longer finite (check the inputs for NaN)");
  }
  if (std::isnan(interior_smallest_difference)) {
    CheckRange(violation);
  } else {
    const int n = config_.cells;
    CheckRange(violation, std::min({interior_smallest_difference, alpha_[0] - beta_[0],
                                    alpha_[n] - beta_[n]}));
  }
  return Status::Ok();
}

// --- General path: pressure-dependent wave speed and column separation -------------------------

namespace {

// W(p), its inverse and c(p): the tabulated mixture law when an extension adds compressibility,
// else the model's own (W = PipeLaw::PressureTerm, c constant).
class PressureFunction {
 public:
  PressureFunction(const PipeLaw& law, const MixtureLaw* mixture) : law_(law), mixture_(mixture) {}
  double W(double p) const { return mixture_ ? mixture_->W(p) : law_.PressureTerm(p); }
  double Pressure(double w, double guess_pa) const {
    return mixture_ ? mixture_->Pressure(w, guess_pa) : law_.PressureFromDifference(2.0 * w);
  }
  // dW/dp = 1 / (rho c).
  double DW(double p) const {
    return mixture_ ? mixture_->DW(p) : -1.0 / law_.DPressureDVelocityAtPressure(p);
  }
  double WAndWaveSpeed(double p, double* c) const {
    if (mixture_) return mixture_->WAndWaveSpeed(p, c);
    *c = law_.wave_speed_mps();
    return law_.PressureTerm(p);
  }

 private:
  const PipeLaw& law_;
  const MixtureLaw* mixture_;
};

// p(0) once beta(0) is known: W(p) = u - beta.
class GeneralInletRelation final : public SlopeFromPressure {
 public:
  GeneralInletRelation(const PressureFunction& w, double beta, double guess_pa)
      : w_(w), beta_(beta), guess_pa_(guess_pa) {}
  double PressurePa(double u) const override { return w_.Pressure(u - beta_, guess_pa_); }
  double PressureAndSlope(double u, double* slope) const override {
    const double p = PressurePa(u);
    *slope = 1.0 / w_.DW(p);
    return p;
  }

 private:
  const PressureFunction& w_;
  double beta_;
  double guess_pa_;
};

// p(L) once alpha(L) is known: W(p) = alpha - u.
class GeneralOutletRelation final : public SlopeFromPressure {
 public:
  GeneralOutletRelation(const PressureFunction& w, double alpha, double guess_pa)
      : w_(w), alpha_(alpha), guess_pa_(guess_pa) {}
  double PressurePa(double u) const override { return w_.Pressure(alpha_ - u, guess_pa_); }
  double PressureAndSlope(double u, double* slope) const override {
    const double p = PressurePa(u);
    *slope = -1.0 / w_.DW(p);
    return p;
  }

 private:
  const PressureFunction& w_;
  double alpha_;
  double guess_pa_;
};

// A vapour cavity at a boundary node: the boundary sees p_v whatever its velocity.
class CavityRelation final : public BoundaryRelation {
 public:
  explicit CavityRelation(double vapour_pressure_pa) : p_v_(vapour_pressure_pa) {}
  double PressurePa(double) const override { return p_v_; }
  double DPressureDVelocity(double) const override { return 0.0; }

 private:
  double p_v_;
};

// The pressure at a node with free gas (the DGCM, characteristics_solver.h): the root above p_v
// of G / (p - p_v) = q + kappa W(p), kappa > 0. W's tangent at the last iterate makes it the
// quadratic K y^2 + R y - G = 0 in y = p - p_v (K = kappa W' > 0), whose positive root is taken
// in the form without cancellation: exact at once when W is linear (the linear law without a
// mixture), Newton's passes on W otherwise.
double GasNodePressure(const PressureFunction& fn, bool w_linear, double g, double p_v, double q,
                       double kappa, double guess_pa) {
  double p = std::max(guess_pa, p_v + 1.0);
  for (int pass = 0; pass < 30; ++pass) {
    const double slope = fn.DW(p);
    const double k = kappa * slope;
    const double r = q + kappa * (fn.W(p) + slope * (p_v - p));
    const double root = std::sqrt(r * r + 4.0 * k * g);
    const double y = r >= 0.0 ? 2.0 * g / (r + root) : (root - r) / (2.0 * k);
    const double change = std::fabs(p_v + y - p);
    p = p_v + y;
    if (w_linear || change <= 1e-12 * p) break;
  }
  return p;
}

// p(u) at an end node with free gas: G / (p - p_v) = q + kappa_u u + kappa W(p), u the
// boundary's velocity (the choke's or the inlet's side of the node; the pipe's side, linear in
// W, is in q and kappa). dp/du from the implicit function: -kappa_u / (G / y^2 + kappa W').
class GasBoundaryRelation final : public BoundaryRelation {
 public:
  GasBoundaryRelation(const PressureFunction& fn, bool w_linear, double g, double p_v, double q,
                      double kappa_u, double kappa, double guess_pa)
      : fn_(fn),
        w_linear_(w_linear),
        g_(g),
        p_v_(p_v),
        q_(q),
        kappa_u_(kappa_u),
        kappa_(kappa),
        guess_pa_(guess_pa) {}
  double PressurePa(double u) const override {
    return GasNodePressure(fn_, w_linear_, g_, p_v_, q_ + kappa_u_ * u, kappa_, guess_pa_);
  }
  double DPressureDVelocity(double u) const override {
    double slope = 0.0;
    PressureAndSlope(u, &slope);
    return slope;
  }
  double PressureAndSlope(double u, double* slope) const override {
    const double p = PressurePa(u);
    const double y = p - p_v_;
    *slope = -kappa_u_ / (g_ / (y * y) + kappa_ * fn_.DW(p));
    return p;
  }

 private:
  const PressureFunction& fn_;
  bool w_linear_;
  double g_, p_v_, q_, kappa_u_, kappa_, guess_pa_;
};

// The steady orifice (5.3.2) against any pipe relation: as ChokeBoundary::SolveOutletVelocity,
// with the pipe side linearised around each iterate, p ~ p_k - b (s - s_k), s = q_c.
double SolveChokeVelocity(const BoundaryRelation& pipe, const ChokeBoundaryInputs& in,
                          double area_m2, double rho_l, double velocity_guess_mps) {
  const double q_b = in.pump_flow_m3ps;
  const double g = in.flow_coefficient_m2;
  if (g <= 0.0) return -q_b / area_m2;
  const double a = rho_l / (g * g);
  double s = q_b + area_m2 * velocity_guess_mps;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double u = (s - q_b) / area_m2;
    double slope = 0.0;
    const double p = pipe.PressureAndSlope(u, &slope);
    const double b = -slope / area_m2;
    const double d = p - in.outlet_pressure_pa + b * s;
    const double magnitude =
        d == 0.0 ? 0.0 : 2.0 * std::fabs(d) / (b + std::sqrt(b * b + 4.0 * a * std::fabs(d)));
    const double next = std::copysign(magnitude, d);
    const double change = std::fabs(next - s);
    s = next;
    if (change <= 1e-13 * (std::fabs(s) + 1e-12)) break;
  }
  return (s - q_b) / area_m2;
}

}  // namespace

void CharacteristicsSolver::OnExtensionsChanged() {
  mixture_.reset();
  if (!compressibility_extensions_.empty()) {
    const std::vector<const PipeExtension*> extensions = compressibility_extensions_;
    mixture_ = std::make_unique<MixtureLaw>(law_, config_.density_kgpm3, config_.k_pa,
                                            [extensions](double p) {
                                              double sum = 0.0;
                                              for (const PipeExtension* extension : extensions) {
                                                sum += extension->ExtraCompressibilityPerPa(p);
                                              }
                                              return sum;
                                            });
  }
  vapour_pressure_pa_ =
      vapour_pressure_extension_ != nullptr ? vapour_pressure_extension_->VapourPressurePa() : 0.0;
  general_ = mixture_ != nullptr || vapour_pressure_pa_ > 0.0;
  const std::size_t nodes = general_ ? config_.cells + 1 : 0;
  for (auto* scratch : {&pressure_, &w_, &speed_up_, &speed_down_, &alpha_left_, &alpha_right_,
                        &beta_left_, &beta_right_, &u_left_, &u_right_}) {
    scratch->assign(nodes, 0.0);
  }
  const std::size_t mixture_nodes = mixture_ != nullptr ? nodes : 0;
  log_pressure_.assign(mixture_nodes, 0.0);
  for (auto* known : {&known_alpha_, &known_beta_, &known_pressure_, &known_log_pressure_}) {
    known->assign(mixture_nodes, std::numeric_limits<double>::quiet_NaN());  // nothing known
  }
  cavity_volume_.assign(vapour_pressure_pa_ > 0.0 ? nodes : 0, 0.0);
  velocity_jump_.assign(cavity_volume_.size(), 0.0);
  const PipeExtension::FreeGas gas = vapour_pressure_extension_ != nullptr
                                         ? vapour_pressure_extension_->CavityFreeGas()
                                         : PipeExtension::FreeGas{};
  gas_void_fraction_ = gas.void_fraction;
  gas_reference_pa_ = gas.reference_pressure_pa;
  gas_weighting_ = gas.weighting;
  if (gas_void_fraction_ > 0.0) ResetGasVolumes();
}

void CharacteristicsSolver::OnStateReset() {
  std::fill(cavity_volume_.begin(), cavity_volume_.end(), 0.0);
  std::fill(velocity_jump_.begin(), velocity_jump_.end(), 0.0);
  if (gas_void_fraction_ > 0.0) ResetGasVolumes();
}

double CharacteristicsSolver::GasConstant(int i) const {
  const double share = i == 0 || i == config_.cells ? 0.5 : 1.0;
  return gas_void_fraction_ * config_.area_m2 * share * config_.dx_m() *
         (gas_reference_pa_ - vapour_pressure_pa_);
}

// The gas in equilibrium with the state: no jump, V = G / (p - p_v) (1 Pa above p_v at least).
void CharacteristicsSolver::ResetGasVolumes() {
  for (std::size_t i = 0; i < cavity_volume_.size(); ++i) {
    const double p = law_.Pressure(alpha_[i], beta_[i]);
    cavity_volume_[i] = GasConstant(static_cast<int>(i)) / std::max(p - vapour_pressure_pa_, 1.0);
    velocity_jump_[i] = 0.0;
  }
}

double CharacteristicsSolver::GasVolumeKnown(int i) const {
  return cavity_volume_[i] + dt_s_ * config_.area_m2 * (1.0 - gas_weighting_) * velocity_jump_[i];
}

double CharacteristicsSolver::CavityVolumeM3() const {
  if (gas_void_fraction_ > 0.0) {
    // DGCM: V advances by dt A (psi j + (1 - psi) j_old); V - dt A (psi - 1/2) j advances by the
    // trapezoidal dt A (j + j_old) / 2, as the liquid does. Includes the gas at the start.
    double sum = 0.0;
    for (std::size_t i = 0; i < cavity_volume_.size(); ++i) {
      sum +=
          cavity_volume_[i] - (gas_weighting_ - 0.5) * dt_s_ * config_.area_m2 * velocity_jump_[i];
    }
    return sum;
  }
  // The cavities are advanced by implicit Euler, half a step ahead of the time level: the
  // time-centred volume V - A dt (u_right - u_left)/2 is the one the liquid balances (exactly,
  // for the linear model without friction: the sum of alpha - beta over the nodes changes by the
  // boundary flows plus the trapezoidal sum of the jumps; with friction each side of a cavity
  // node takes its own share of the new point's friction, first order in dt).
  double sum = 0.0;
  for (std::size_t i = 0; i < cavity_volume_.size(); ++i) {
    sum += std::max(0.0, cavity_volume_[i] - 0.5 * dt_s_ * config_.area_m2 * velocity_jump_[i]);
  }
  return sum;
}

// What the parts of a general step share: the mixture's W(p) and c(p), the cavities' vapour
// pressure, the momentum sources of this step.
struct CharacteristicsSolver::GeneralStep {
  PressureFunction fn;
  double r;  // dt / dx [s/m]: 1 / c of the grid
  bool linear;
  bool cavitation;
  double p_v;                     // vapour pressure [Pa]; 0 without column separation
  double w_v;                     // W(p_v)
  const double* source_explicit;  // a_i [m/s^2] of S_i = a_i + b_i u_i; null: no sources
  const double* source_implicit;  // b_i [1/s]
  double SourceExplicit(int i) const {
    return source_explicit != nullptr ? source_explicit[i] : 0.0;
  }
  double SourceImplicit(int i) const {
    return source_implicit != nullptr ? source_implicit[i] : 0.0;
  }
};

Status CharacteristicsSolver::StepGeneral(const PipeStepInputs& inputs, RangeViolation* violation) {
  const bool cavitation = vapour_pressure_pa_ > 0.0;
  const PressureFunction fn(law_, mixture_.get());
  const bool has_sources = EvaluateMomentumSources();
  const GeneralStep step{fn,
                         dt_s_ / config_.dx_m(),
                         config_.model == PipeModel::kLinear,
                         cavitation,
                         vapour_pressure_pa_,
                         cavitation ? fn.W(vapour_pressure_pa_) : 0.0,
                         has_sources ? source_explicit_.data() : nullptr,
                         has_sources ? source_implicit_.data() : nullptr};
  LoadGeneralOldLevel(step);
  StepGeneralInterior(step);
  StepGeneralInlet(step, inputs);
  StepGeneralOutlet(step, inputs);
  return AdvanceToNewLevel(violation);
}

// The old level in the mixture's invariants, each side of a cavity node separately.
void CharacteristicsSolver::LoadGeneralOldLevel(const GeneralStep& step) {
  const int n = config_.cells;
  for (int i = 0; i <= n; ++i) {
    const double u = 0.5 * (alpha_[i] + beta_[i]);
    double c = 0.0;
    double p, w;
    if (mixture_ == nullptr) {
      // The law's own W: alpha - beta = 2 W(p) exactly (pipe_law.h), no logarithm needed.
      p = law_.Pressure(alpha_[i], beta_[i]);
      w = 0.5 * (alpha_[i] - beta_[i]);
      c = law_.wave_speed_mps();
    } else {
      // The mixture's W at ln p: known from the step that made this state (RememberPressure),
      // else from the state.
      const bool known = alpha_[i] == known_alpha_[i] && beta_[i] == known_beta_[i];
      p = known ? known_pressure_[i] : law_.Pressure(alpha_[i], beta_[i]);
      log_pressure_[i] = known ? known_log_pressure_[i] : std::log(std::max(p, 1e-300));
      w = mixture_->WAndWaveSpeedAtLog(p, log_pressure_[i], &c);
    }
    pressure_[i] = p;
    velocity_[i] = u;
    w_[i] = w;
    speed_up_[i] =
        step.linear ? c : u + c;  // the linear model's characteristics move at +-c (7.0.4)
    speed_down_[i] = step.linear ? c : c - u;
    // An interior cavity node stores the mean of its sides, a boundary node its outer side.
    const double jump = step.cavitation ? velocity_jump_[i] : 0.0;
    const double right_share = i == 0 ? 1.0 : (i == n ? 0.0 : 0.5);
    u_left_[i] = u - (1.0 - right_share) * jump;
    u_right_[i] = u + right_share * jump;
    alpha_left_[i] = w + u_left_[i];
    alpha_right_[i] = w + u_right_[i];
    beta_left_[i] = -w + u_left_[i];
    beta_right_[i] = -w + u_right_[i];
  }
}

// Foot of the C+ characteristic arriving at node i: at x_i - sigma dx with the speed interpolated
// there, sigma = s_i / (1 + s_i - s_(i-1)), s = speed dt / dx (<= 1 but for u > 0 at the full wave
// speed, where the foot lies beyond node i-1, as in AlphaFoot). Returns alpha there, *u_foot u.
inline double CharacteristicsSolver::GeneralAlphaFoot(const GeneralStep& step, int i,
                                                      double* u_foot) const {
  const double s_here = speed_up_[i] * step.r;
  const double s_near = speed_up_[i - 1] * step.r;
  // Next to the inlet the foot cannot lie beyond node 0: clamped to its pipe side (alpha_right_),
  // never the boundary's outer side, which a cavity there separates from the pipe.
  const double sigma =
      i == 1 ? std::min(s_here / (1.0 + s_here - s_near), 1.0) : s_here / (1.0 + s_here - s_near);
  if (sigma <= 1.0) {
    *u_foot = (1.0 - sigma) * u_left_[i] + sigma * u_right_[i - 1];
    return (1.0 - sigma) * alpha_left_[i] + sigma * alpha_right_[i - 1];
  }
  const int j = std::max(i - 2, 0);
  const double tau = std::min(sigma - 1.0, 1.0);
  *u_foot = (1.0 - tau) * u_left_[i - 1] + tau * u_right_[j];
  return (1.0 - tau) * alpha_left_[i - 1] + tau * alpha_right_[j];
}

// Foot of the C- characteristic arriving at node i, mirrored.
inline double CharacteristicsSolver::GeneralBetaFoot(const GeneralStep& step, int i,
                                                     double* u_foot) const {
  const int n = config_.cells;
  const double s_here = speed_down_[i] * step.r;
  const double s_near = speed_down_[i + 1] * step.r;
  // Next to the outlet: clamped to node N's pipe side (beta_left_), as at the inlet.
  const double sigma = i == n - 1 ? std::min(s_here / (1.0 + s_here - s_near), 1.0)
                                  : s_here / (1.0 + s_here - s_near);
  if (sigma <= 1.0) {
    *u_foot = (1.0 - sigma) * u_right_[i] + sigma * u_left_[i + 1];
    return (1.0 - sigma) * beta_right_[i] + sigma * beta_left_[i + 1];
  }
  const int j = std::min(i + 2, n);
  const double tau = std::min(sigma - 1.0, 1.0);
  *u_foot = (1.0 - tau) * u_right_[i + 1] + tau * u_left_[j];
  return (1.0 - tau) * beta_right_[i + 1] + tau * beta_left_[j];
}

bool CharacteristicsSolver::InCavity(const GeneralStep& step, int i,
                                     double liquid_pressure_pa) const {
  return liquid_pressure_pa < step.p_v || cavity_volume_[i] > 0.0;
}

// A cavity's volume after the step with the new jump u_right - u_left (implicit Euler, see the
// header). Below p_v the node is a cavity whatever the volume (a closure at an end need not make
// the jump positive); above it, while the cavity has volume: then true, and the node holds p_v.
// Otherwise the cavity collapses (V = 0) and the liquid solution stands.
bool CharacteristicsSolver::SettleCavity(const GeneralStep& step, int i, double liquid_pressure_pa,
                                         double jump) {
  const double volume = cavity_volume_[i] + dt_s_ * config_.area_m2 * jump;
  if (liquid_pressure_pa < step.p_v || volume > 0.0) {
    cavity_volume_[i] = std::max(volume, 0.0);
    return true;
  }
  cavity_volume_[i] = 0.0;
  return false;
}

// Interior nodes: the trapezoidal rule along both characteristics with the new point's friction
// linearised, as StepInterior, and the momentum sources semi-implicit.
// The DGCM's nodes in a loop of their own (kGas), so that the other paths' loop is the same
// code as without it.
void CharacteristicsSolver::StepGeneralInterior(const GeneralStep& step) {
  if (step.cavitation && gas_void_fraction_ > 0.0) {
    StepGeneralInteriorNodes<true>(step);
  } else {
    StepGeneralInteriorNodes<false>(step);
  }
}

template <bool kGas>
void CharacteristicsSolver::StepGeneralInteriorNodes(const GeneralStep& step) {
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  for (int i = 1; i < n; ++i) {
    double ua, ub;
    const double a_foot = GeneralAlphaFoot(step, i, &ua);
    const double b_foot = GeneralBetaFoot(step, i, &ub);
    const double fa = config_.Friction(ua);
    const double fb = config_.Friction(ub);
    const double lambda =
        config_.friction_f1_per_s + config_.friction_f2_per_m * std::fabs(velocity_[i]);
    const double sa = step.SourceExplicit(i);
    const double sb = step.SourceImplicit(i);
    double u_p = (a_foot + b_foot - 0.5 * h * (fa + fb) - 2.0 * h * gs - 2.0 * h * sa) /
                 (2.0 + h * lambda + 2.0 * h * sb);
    const double w_p = 0.5 * (a_foot - b_foot) - 0.25 * h * (fa - fb);
    double log_p = 0.0;
    double p_p = mixture_ != nullptr ? mixture_->PressureAndLog(w_p, log_pressure_[i], &log_p)
                                     : step.fn.Pressure(w_p, pressure_[i]);
    const double p_liquid = p_p;

    if constexpr (kGas) {
      // DGCM: both sides from their characteristics at the node's p, the gas law closes them.
      const double d = 1.0 + 0.5 * h * lambda + h * sb;
      const double a_r = a_foot - 0.5 * h * fa - h * gs - h * sa;
      const double b_r = b_foot - 0.5 * h * fb - h * gs - h * sa;
      const double k = dt_s_ * config_.area_m2 * gas_weighting_ / d;
      const double g = GasConstant(i);
      p_p = GasNodePressure(step.fn, mixture_ == nullptr && step.linear, g, step.p_v,
                            GasVolumeKnown(i) + k * (b_r - a_r), 2.0 * k, pressure_[i]);
      const double w = step.fn.W(p_p);
      const double u_l = (a_r - w) / d;
      const double u_r = (b_r + w) / d;
      cavity_volume_[i] = g / (p_p - step.p_v);
      velocity_jump_[i] = u_r - u_l;
      u_p = 0.5 * (u_l + u_r);
    } else if (step.cavitation) {
      double jump = 0.0;
      if (InCavity(step, i, p_p)) {
        // Each side at p_v: alpha_P = W(p_v) + u_left, beta_P = -W(p_v) + u_right.
        const double d = 1.0 + 0.5 * h * lambda + h * sb;
        const double u_l = (a_foot - 0.5 * h * fa - h * gs - h * sa - step.w_v) / d;
        const double u_r = (b_foot - 0.5 * h * fb - h * gs - h * sa + step.w_v) / d;
        if (SettleCavity(step, i, p_p, u_r - u_l)) {
          p_p = step.p_v;
          u_p = 0.5 * (u_l + u_r);
          jump = u_r - u_l;
        }
      }
      velocity_jump_[i] = jump;
    }

    // law_.Alpha and law_.Beta, one logarithm; none where the law is the liquid's own and no
    // cavity moved the pressure: its W is w_p itself.
    const double term = mixture_ == nullptr && p_p == p_liquid ? w_p : law_.PressureTerm(p_p);
    alpha_next_[i] = term + u_p;
    beta_next_[i] = -term + u_p;
    if (mixture_ != nullptr) RememberPressure(i, p_p, p_p == p_liquid ? log_p : std::log(p_p));
  }
}

// The new level's pressure at node i and its logarithm, for the next step's LoadGeneralOldLevel
// (what the mixture law needs is ln p: it saves an exp and a log per node and step). Keyed by
// alpha and beta: a state set otherwise is recomputed.
void CharacteristicsSolver::RememberPressure(int i, double pressure_pa, double log_pressure) {
  known_alpha_[i] = alpha_next_[i];
  known_beta_[i] = beta_next_[i];
  known_pressure_[i] = pressure_pa;
  known_log_pressure_[i] = log_pressure;
}

// Inlet, x = 0: the beta characteristic from the pipe; u(0) from the piston or a closure.
void CharacteristicsSolver::StepGeneralInlet(const GeneralStep& step,
                                             const PipeStepInputs& inputs) {
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  const double area = config_.area_m2;
  double ub;
  const double b_foot = GeneralBetaFoot(step, 0, &ub);
  const double fb = config_.Friction(ub);
  const auto beta_at = [&](double u) {
    return b_foot - 0.5 * h * (fb + config_.Friction(u)) - h * gs -
           h * (step.SourceExplicit(0) + step.SourceImplicit(0) * u);
  };
  const InletInputs inlet{inputs.end.inlet_velocity_mps * area, area, h};
  double u0 = inlet_closure_ != nullptr ? velocity_[0] : inputs.end.inlet_velocity_mps;
  double beta0 = 0.0;
  for (int pass = 0; pass < (inlet_closure_ != nullptr ? 2 : 1); ++pass) {
    beta0 = beta_at(u0);
    if (inlet_closure_ != nullptr) {
      u0 = inlet_closure_->SolveInletVelocity(GeneralInletRelation(step.fn, beta0, pressure_[0]),
                                              inlet);
    }
  }
  double p0 = step.fn.Pressure(u0 - beta0, pressure_[0]);
  if (step.cavitation && gas_void_fraction_ > 0.0) {
    // DGCM: the pipe side u_pipe = B + W(p) from C- (its friction at the last pass's velocity),
    // the inlet's side from the piston or the closure against the node's gas law.
    const double g = GasConstant(0);
    const double k = h * area * gas_weighting_;
    double u_pipe = u_right_[0];
    double u_side = velocity_[0];
    for (int pass = 0; pass < 2; ++pass) {
      const double b_fixed = beta_at(u_pipe);
      const GasBoundaryRelation relation(step.fn, mixture_ == nullptr && step.linear, g, step.p_v,
                                         GasVolumeKnown(0) + k * b_fixed, -k, k, pressure_[0]);
      u_side = inlet_closure_ != nullptr ? inlet_closure_->SolveInletVelocity(relation, inlet)
                                         : inputs.end.inlet_velocity_mps;
      p0 = relation.PressurePa(u_side);
      u_pipe = b_fixed + step.fn.W(p0);
    }
    cavity_volume_[0] = g / (p0 - step.p_v);
    velocity_jump_[0] = u_pipe - u_side;
    u0 = u_side;
  } else if (step.cavitation) {
    double jump = 0.0;
    if (InCavity(step, 0, p0)) {
      // Pipe side from C- at p_v (friction settled by fixed-point passes, h f' << 1); the
      // piston side is what the inlet delivers against p_v.
      double u_pipe = u0;
      for (int pass = 0; pass < 3; ++pass) u_pipe = beta_at(u_pipe) + step.w_v;
      const double u_side = inlet_closure_ != nullptr ? inlet_closure_->SolveInletVelocity(
                                                            CavityRelation(step.p_v), inlet)
                                                      : inputs.end.inlet_velocity_mps;
      if (SettleCavity(step, 0, p0, u_pipe - u_side)) {
        p0 = step.p_v;
        u0 = u_side;  // the node keeps the flow at x = 0, the pipe side leaves on alpha
        jump = u_pipe - u_side;
      }
    }
    velocity_jump_[0] = jump;
  }
  alpha_next_[0] = law_.Alpha(p0, u0);
  beta_next_[0] = law_.Beta(p0, u0);
}

// Outlet, x = L: the alpha characteristic from the pipe; u(L) from the choke or a closure.
void CharacteristicsSolver::StepGeneralOutlet(const GeneralStep& step,
                                              const PipeStepInputs& inputs) {
  const int n = config_.cells;
  const double h = dt_s_;
  const double gs = config_.gravity_slope_mps2;
  const double area = config_.area_m2;
  double ua;
  const double a_foot = GeneralAlphaFoot(step, n, &ua);
  const double fa = config_.Friction(ua);
  const auto alpha_at = [&](double u) {
    return a_foot - 0.5 * h * (fa + config_.Friction(u)) - h * gs -
           h * (step.SourceExplicit(n) + step.SourceImplicit(n) * u);
  };
  const auto solve = [&](const BoundaryRelation& relation, double guess) {
    return outlet_closure_ != nullptr
               ? outlet_closure_->SolveOutletVelocity(relation, inputs.end.choke, h, guess)
               : SolveChokeVelocity(relation, inputs.end.choke, area, config_.choke_density_kgpm3,
                                    guess);
  };
  double u_l = velocity_[n];
  double alpha_l = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    alpha_l = alpha_at(u_l);
    u_l = solve(GeneralOutletRelation(step.fn, alpha_l, pressure_[n]), u_l);
  }
  double p_l = step.fn.Pressure(alpha_l - u_l, pressure_[n]);
  if (step.cavitation && gas_void_fraction_ > 0.0) {
    // DGCM: the pipe side u_pipe = A - W(p) from C+, the choke's or the closure's side against
    // the node's gas law.
    const double g = GasConstant(n);
    const double k = h * area * gas_weighting_;
    double u_pipe = u_left_[n];
    double u_side = velocity_[n];
    for (int pass = 0; pass < 2; ++pass) {
      const double a_fixed = alpha_at(u_pipe);
      const GasBoundaryRelation relation(step.fn, mixture_ == nullptr && step.linear, g, step.p_v,
                                         GasVolumeKnown(n) - k * a_fixed, k, k, pressure_[n]);
      u_side = solve(relation, u_side);
      p_l = relation.PressurePa(u_side);
      u_pipe = a_fixed - step.fn.W(p_l);
    }
    cavity_volume_[n] = g / (p_l - step.p_v);
    velocity_jump_[n] = u_side - u_pipe;
    u_l = u_side;
  } else if (step.cavitation) {
    double jump = 0.0;
    if (InCavity(step, n, p_l)) {
      double u_pipe = u_l;
      for (int pass = 0; pass < 3; ++pass) u_pipe = alpha_at(u_pipe) - step.w_v;
      const double u_side = solve(CavityRelation(step.p_v), u_l);
      if (SettleCavity(step, n, p_l, u_side - u_pipe)) {
        p_l = step.p_v;
        u_l = u_side;  // the node keeps the flow through the choke, the pipe side leaves on beta
        jump = u_side - u_pipe;
      }
    }
    velocity_jump_[n] = jump;
  }
  alpha_next_[n] = law_.Alpha(p_l, u_l);
  beta_next_[n] = law_.Beta(p_l, u_l);
}

}  // namespace mpdrig
