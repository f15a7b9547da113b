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
                                          const ChokeBoundaryInputs& in) const {
  const double q_b = in.pump_flow_m3ps;
  const double g = in.flow_coefficient_m2;
  if (g <= 0.0) return -q_b / area_m2_;  // tight choke: all pump flow goes down the pipe

  // Work in the choke flow s = q_c = q_b + A u. Orifice term: a s|s| with a = rho_L / G^2.
  const double a = rho_l_ / (g * g);
  // Linear part of the pipe side at the current point: p(alpha, u) ~ p(alpha, u*) + Z (u - u*)
  // with Z = dp/du < 0. For the linear model this is exact, so one solve of the piecewise
  // quadratic is the answer; the quasi-linear model needs a few Newton corrections.
  auto residual = [&](double s) {
    const double u = (s - q_b) / area_m2_;
    return law.PressureFromAlpha(alpha_l, u) - in.outlet_pressure_pa - a * s * std::fabs(s);
  };
  // Closed form of  D - b (s - s0) - a s|s| = 0  with b = -Z/A > 0 (stable for either sign).
  auto solve_piecewise_quadratic = [a](double d, double b) {
    const double magnitude = 2.0 * std::fabs(d) / (b + std::sqrt(b * b + 4.0 * a * std::fabs(d)));
    return std::copysign(magnitude, d);
  };

  double s = q_b;  // start: the pipe at rest, u = 0
  for (int iteration = 0; iteration < 20; ++iteration) {
    const double u = (s - q_b) / area_m2_;
    const double b = -law.DPressureDVelocityAtAlpha(alpha_l, u) / area_m2_;
    // Residual at s, rewritten around s: F(s + ds) ~ F(s) - b ds - a[(s+ds)|s+ds| - s|s|].
    const double d = residual(s) + a * s * std::fabs(s) + b * s;  // D - b*0 form around origin
    const double s_next = solve_piecewise_quadratic(d, b);
    const double change = std::fabs(s_next - s);
    s = s_next;
    if (law.model() == PipeModel::kLinear || change <= 1e-14 * (std::fabs(s) + 1e-12)) break;
  }
  return (s - q_b) / area_m2_;
}

}  // namespace mpdrig
