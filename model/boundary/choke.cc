#include "model/boundary/choke.h"

#include <algorithm>
#include <cmath>

namespace mpdrig {

ChokeCharacteristic::ChokeCharacteristic(const RigParams& params)
    : table_(params.choke_characteristic), leak_m2_(params.choke_leak_m2) {
  MPDRIG_CHECK(table_.size() >= 2);
}

double ChokeCharacteristic::FlowCoefficientM2(double opening_frac) const {
  const double u =
      std::clamp(opening_frac, table_.front().opening_frac, table_.back().opening_frac);
  auto upper =
      std::upper_bound(table_.begin(), table_.end(), u,
                       [](double value, const ChokePoint& p) { return value < p.opening_frac; });
  if (upper == table_.end()) upper = table_.end() - 1;
  if (upper == table_.begin()) upper = table_.begin() + 1;
  const ChokePoint& a = *(upper - 1);
  const ChokePoint& b = *upper;
  const double w = (u - a.opening_frac) / (b.opening_frac - a.opening_frac);
  const double g = a.g_m2 + w * (b.g_m2 - a.g_m2);
  return std::max(g, leak_m2_);
}

double ChokeActuator::Advance(double opening_frac, double reference_frac, double dt_s) const {
  // Exact solution of the lag over dt where the rate limit does not bind; where it binds, the
  // opening moves at the limit. Both clamp at the reference, so the step never overshoots.
  const double error = reference_frac - opening_frac;
  const double lag_step =
      time_constant_s_ > 0.0 ? error * (1.0 - std::exp(-dt_s / time_constant_s_)) : error;
  const double max_step = rate_limit_per_s_ * dt_s;
  return std::clamp(opening_frac + std::clamp(lag_step, -max_step, max_step), 0.0, 1.0);
}

double ChokeBoundary::SolveOutletVelocity(const PipeLaw& law, double alpha_l,
                                          const ChokeBoundaryInputs& in,
                                          double velocity_guess_mps) const {
  const double q_b = in.pump_flow_m3ps;
  const double g = in.flow_coefficient_m2;
  if (g <= 0.0) return -q_b / area_m2_;  // tight choke: all pump flow goes down the pipe

  // Work in the choke flow s = q_c = q_b + A u; the orifice term is a s|s| with a = rho_L / G^2.
  // Around the current iterate s_k the pipe side is p(s) ~ p_k - b (s - s_k), b = -(dp/du)/A > 0,
  // so F(s) ~ D - b s - a s|s| with D = p_k - p_0 + b s_k, whose root has the closed form below
  // (stable for either sign of D). For the linear model p is exactly linear in u: one solve is
  // the answer. The quasi-linear one converges quadratically, in one or two iterations from the
  // previous step's u(L).
  const double a = rho_l_ / (g * g);
  auto solve_piecewise_quadratic = [a](double d, double b) {
    const double magnitude = 2.0 * std::fabs(d) / (b + std::sqrt(b * b + 4.0 * a * std::fabs(d)));
    return std::copysign(magnitude, d);
  };

  double s = q_b + area_m2_ * velocity_guess_mps;
  for (int iteration = 0; iteration < 20; ++iteration) {
    const double p = law.PressureFromAlpha(alpha_l, (s - q_b) / area_m2_);
    const double b = -law.DPressureDVelocityAtPressure(p) / area_m2_;
    const double s_next = solve_piecewise_quadratic(p - in.outlet_pressure_pa + b * s, b);
    const double change = std::fabs(s_next - s);
    s = s_next;
    // The iteration converges quadratically: after a change of 1e-8 of s the next would be of
    // order 1e-16 of s (round-off), so it is not computed (one exp saved, most steps).
    if (law.model() == PipeModel::kLinear || change <= 1e-8 * (std::fabs(s) + 1e-12)) break;
  }
  return (s - q_b) / area_m2_;
}

}  // namespace mpdrig
