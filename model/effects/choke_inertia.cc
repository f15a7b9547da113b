// choke_inertia: the dynamic orifice equation (thesis 5.3.3) in place of the steady one (5.3.2):
//   b1 dq_c/dt + b2 q_c |q_c| = (p_c - p_0) / rho_L,     b2 = 1 / G(u_c)^2,
// so the choke flow q_c = q_b + A u(L) lags the pressure difference: the liquid in the choke's
// flow path (length l, area a) must be accelerated, b1 = l / a [1/m]. Steady flow is the same as
// (5.3.2). Linearised about q_c the flow answers a pressure change with the time constant
// tau = b1 G^2 / (2 |q_c|): FT3 lags C2 by a phase that grows with frequency.
//
// Boundary closure (pipe_extension.h), implicit Euler in q_c over the step: with s = q_c,
//   F(s) = p(u(s)) - p_0 - rho_L s|s| / G^2 - rho_L b1 (s - s_prev) / dt = 0,  u = (s - q_b) / A,
// strictly decreasing in s. As in ChokeBoundary: around the iterate the pipe side is linear,
// p ~ p_k - b (s - s_k), and the root of the piecewise quadratic has a closed form.
#include <cmath>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class ChokeInertia final : public Effect {
 public:
  ChokeInertia(double b1_per_m, double area_m2, double rho_l)
      : b1_per_m_(b1_per_m), area_m2_(area_m2), rho_l_(rho_l) {}

  void Initialize(const PipeSolver&, const ChannelValues& channels) override {
    choke_flow_m3ps_ = channels[Index(Channel::kFT3)];
  }
  bool closes_outlet() const override { return true; }
  double SolveOutletVelocity(const BoundaryRelation& pipe, const ChokeBoundaryInputs& in,
                             double dt_s, double velocity_guess_mps) const override {
    const double q_b = in.pump_flow_m3ps;
    const double g = in.flow_coefficient_m2;
    if (g <= 0.0) return -q_b / area_m2_;  // tight choke: no flow to accelerate
    const double a = rho_l_ / (g * g);
    const double m = rho_l_ * b1_per_m_ / dt_s;
    double s = q_b + area_m2_ * velocity_guess_mps;
    for (int iteration = 0; iteration < 30; ++iteration) {
      const double u = (s - q_b) / area_m2_;
      double slope = 0.0;
      const double p = pipe.PressureAndSlope(u, &slope);
      const double b = -slope / area_m2_ + m;
      const double d = p - in.outlet_pressure_pa + (b - m) * s + m * choke_flow_m3ps_;
      // Root of d - b s - a s|s| = 0.
      const double magnitude = 2.0 * std::fabs(d) / (b + std::sqrt(b * b + 4.0 * a * std::fabs(d)));
      const double next = std::copysign(magnitude, d);
      const double change = std::fabs(next - s);
      s = next;
      if (change <= 1e-13 * (std::fabs(s) + 1e-12)) break;
    }
    return (s - q_b) / area_m2_;
  }
  void AfterStep(const PipeSolver& pipe, const StepRecord& step) override {
    choke_flow_m3ps_ =
        step.boundary.choke.pump_flow_m3ps + area_m2_ * pipe.VelocityAt(pipe.config().length_m);
  }

 private:
  double b1_per_m_;
  double area_m2_;
  double rho_l_;
  double choke_flow_m3ps_ = 0.0;  // q_c at the last time level
};

}  // namespace

const EffectInfo& ChokeInertiaEffect() {
  static const EffectInfo info{
      "choke_inertia",
      "dynamic orifice equation b1 dq_c/dt + q_c|q_c|/G^2 = (p_c - p_0)/rho_L",
      "5.3, (5.3.3); the thesis kept the steady (5.3.2)",
      "removes a phase lag of the choke flow FT3 (and of C2's response to it) that grows with "
      "frequency",
      {{"b1_per_m", "1/m", "inertance of the choke flow path b1 = length / area", 5.0e5, 0.0, 2.0e7,
        true}},
      [](const EffectContext& context) {
        return std::make_unique<ChokeInertia>(context.Get("b1_per_m"), context.pipe.area_m2,
                                              context.rig.choke_density_kgpm3);
      }};
  return info;
}

}  // namespace mpdrig
