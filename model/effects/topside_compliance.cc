// topside_compliance: the elastic "topside" tubes between the copper pipe's outlet and the choke
// (thesis 8.3.2: about 4 m of rubber hose and 2.5 m of PVC pipe after the copper pipe; 11.1: with
// them cut off by a valve right after the copper pipe the closed-system resonance rises from
// 0.44 to 0.49 Hz, section 9.1). A lumped capacitance at the pipe outlet, before the choke:
//   C dp_L/dt = A u(L) + q_b - q_c,      p_L = p(L) = C2,      C = V_t / K_eff   [m^3/Pa],
// with q_c the choke flow of the steady orifice (5.3.2), p_L - p_0 = rho_L q_c |q_c| / G(u_c)^2,
// and q_b the back-pressure pump's flow, which joins at the choke node (5.3.1). The tubes hold no
// flow resistance or inertia, so the pressure in them is the pipe outlet pressure. C = 0 is the
// thesis's outlet: q_c = q_b + A u(L) (5.3.1). The model's FT3 is the choke flow q_c, which now
// differs from q_b + FT1 by what fills the tubes.
//
// What it does to the closed system: with a tight choke (G = 0) the pipe ends in the capacitance,
// A U(L) = i w C P(L). For the lossless pipe driven at x = 0 by the piston (velocity source) the
// input impedance P(0)/U(0) = Z (Z sinh(kL) + k cosh(kL)) / (Z cosh(kL) + k sinh(kL)) of (9.2.13)
// with the outlet impedance k = A / (i w C) has its poles where, theta = w L / c,
//   cos(theta) + (A / (w C rho c)) sin(theta) = 0   <=>   tan(theta) = -r theta,
//   r = C / C_pipe,   C_pipe = A L / (rho c^2) (the copper pipe's own compliance),
// whose first root lies in (pi/2, pi): the c/2L resonance of (9.3.4) (theta = pi, r = 0) moves
// down towards the open end's c/4L (theta = pi/2, r -> infinity). With an open choke the tubes
// sit beside an outlet held at p_0 and change little.
//
// Parameter, from the thesis's hose numbers (8.3.2) and the compliance of a thin-walled elastic
// tube per unit volume, dV/(V dp) = 1/K + D/(E e) (Wylie & Streeter, Fluid Transients, ch. 2;
// the same wall term as the thesis's (8.3.1) with kappa = 1, 2d/(d_0 - d) = D/e):
//   bore D = 19 mm, cross-section a = pi D^2/4 = 2.835e-4 m^2, water K = 2.2e9 Pa
//   rubber 19x29 mm (e = 5 mm, D/e = 3.8), 4 m:  V_r = 1.134e-3 m^3
//     E = 0.055 GPa (the thesis's mean of 0.01-0.1): 3.8/E + 1/K = 6.955e-8 1/Pa
//       (c_rubber = 1/sqrt(rho 6.955e-8) = 120 m/s, the thesis's value)   C_r = 7.89e-11 m^3/Pa
//     E = 0.1 GPa:  C_r = 4.36e-11;   E = 0.01 GPa:  C_r = 4.31e-10
//   PVC 19x25 mm (e = 3 mm), E = 1.5 GPa, 2.5 m:  V_p = 7.09e-4 m^3,
//     0.019/(1.5e9 0.003) + 1/K = 4.677e-9 1/Pa (c_PVC = 462 m/s, the thesis's)  C_p = 3.3e-12
//   C = C_r + C_p: default 8.2e-11 m^3/Pa (mean E); 4.7e-11 (E = 0.1 GPa) to 4.35e-10
//   (E = 0.01 GPa) over the thesis's range of rubber. Against the copper pipe's own
//   C_pipe = 2.5e-10 at c = 850 m/s (1.3e-10 at 1173 m/s): r = 0.33 at the default. Bounds 0 to
//   2e-9 (a hose four times softer than the softest rubber).
// Plausible on the rig (where `mpdrig synth` draws a hidden one, and diagnose scans): 2.5e-11 to
//   1.0e-10, from the rig's own resonances (thesis 9.1; docs/rig-measurements.md): cutting the
//   tubes off raised the closed resonance from 0.44 to 0.49 Hz, which at the copper pipe's
//   c = 882 m/s (2L 0.49 Hz) asks r = 0.118, C = 2.7e-11 (a reinforced hose: rubber at
//   E = 0.18 GPa); the most the tubes can be is all of the closed resonance's drop from the
//   fronts' c/2L = 0.65 Hz (c = 1173 m/s) to 0.44 Hz: r = 0.77, C = 1.0e-10. Softer (the bare
//   rubber's E = 0.01 GPa) would put the closed-choke resonance below what the rig shows.
//
// Boundary closure (pipe_extension.h), implicit Euler over the step: with P(u) the pressure the
// pipe imposes for the new outlet velocity u (falling in u along the alpha characteristic),
//   g(u) = A u + q_b - q_c(P(u)) - C (P(u) - p_L,prev) / dt = 0,
// strictly increasing in u: stable at any step. Around the iterate u_k the pipe side is linear,
// P ~ p_k + d (u - u_k), d < 0, and in the choke flow s the step's balance is
//   D - s - (m + C/dt) a s|s| = 0,  m = -A/d,  a = rho_L / G^2,
//   D = A u_k + q_b + m (p_k - p_0) + (C/dt) (p_L,prev - p_0),
// a piecewise quadratic with a closed-form root (as in ChokeBoundary); exact in one step for the
// linear pipe, quadratically convergent for the quasi-linear one.
// States: p_L at the last time level [Pa abs]; q_c of the last step (FT3).
//
// Config example:  effect { name: "topside_compliance" value { key: "compliance_m3_per_pa"
// value: 8.2e-11 } }
#include <cmath>
#include <limits>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class TopsideCompliance final : public Effect {
 public:
  TopsideCompliance(double compliance_m3_per_pa, double area_m2, double rho_l)
      : compliance_(compliance_m3_per_pa), area_m2_(area_m2), rho_l_(rho_l) {}

  void Initialize(const PipeSolver& pipe, const ChannelValues& channels) override {
    pressure_pa_ = pipe.PressureAt(pipe.config().length_m);
    choke_flow_m3ps_ = channels[Index(Channel::kFT3)];
  }

  bool closes_outlet() const override { return true; }
  double SolveOutletVelocity(const BoundaryRelation& pipe, const ChokeBoundaryInputs& in,
                             double dt_s, double velocity_guess_mps) const override {
    const double q_b = in.pump_flow_m3ps;
    const double g = in.flow_coefficient_m2;
    const double p_0 = in.outlet_pressure_pa;
    const double k = compliance_ / dt_s;
    double u = velocity_guess_mps;
    double previous_change = std::numeric_limits<double>::infinity();
    for (int iteration = 0; iteration < 30; ++iteration) {
      double d = 0.0;  // dp/du < 0 at the outlet
      const double p_k = pipe.PressureAndSlope(u, &d);
      const double m = -area_m2_ / d;
      double p = 0.0;
      if (g <= 0.0) {
        // Tight choke: q_c = 0, the balance is linear in p.
        p = (area_m2_ * u + q_b + m * p_k + k * pressure_pa_) / (m + k);
      } else {
        const double a = rho_l_ / (g * g);
        const double big_d = area_m2_ * u + q_b + m * (p_k - p_0) + k * (pressure_pa_ - p_0);
        const double b = (m + k) * a;
        const double s = std::copysign(
            2.0 * std::fabs(big_d) / (1.0 + std::sqrt(1.0 + 4.0 * b * std::fabs(big_d))), big_d);
        p = p_0 + a * s * std::fabs(s);
      }
      const double next = u + (p - p_k) / d;
      const double change = std::fabs(next - u);
      u = next;
      // Converged; or stalled at what rounding resolves. big_d carries C/dt (p - p_0), often far
      // larger than the A du a step changes it by, so u is resolved only to about eps |big_d| / A
      // (measured on the NTNU rig with C = 4e-11 m^3/Pa, dt = 21 ms: about 1e-15 m/s, the 1e-13
      // relative tolerance itself), and there the steps stop shrinking quadratically and wander.
      // Such a step, within 1e-10 of the velocity's scale and not half the one before, ends the
      // iteration (without this rule half the solves ran to the cap of 30 iterations).
      const double scale = std::fabs(u) + 1e-3;
      if (change <= 1e-13 * scale || (change <= 1e-10 * scale && change > 0.5 * previous_change)) {
        break;
      }
      previous_change = change;
    }
    return u;
  }

  void AfterStep(const PipeSolver& pipe, const StepRecord& step) override {
    const double length = pipe.config().length_m;
    const double p = pipe.PressureAt(length);
    // The node's balance over the step: what left through the choke.
    choke_flow_m3ps_ = area_m2_ * pipe.VelocityAt(length) + step.boundary.choke.pump_flow_m3ps -
                       compliance_ * (p - pressure_pa_) / step.dt_s;
    pressure_pa_ = p;
  }

  // FT3 is the choke flow, not q_b + A u(L).
  bool filters_sensors() const override { return true; }
  void FilterSensors(ChannelValues* values, double) override {
    (*values)[Index(Channel::kFT3)] = choke_flow_m3ps_;
  }

 private:
  double compliance_;             // C [m^3/Pa]
  double area_m2_;                // pipe cross-section A
  double rho_l_;                  // rho_L of (5.3.2)
  double pressure_pa_ = 0.0;      // p_L at the last time level
  double choke_flow_m3ps_ = 0.0;  // q_c over the last step
};

}  // namespace

const EffectInfo& TopsideComplianceEffect() {
  static const EffectInfo info{
      "topside_compliance",
      "elastic tubes between pipe outlet and choke: C dp(L)/dt = A u(L) + q_b - q_c, C = V_t / "
      "K_eff",
      "8.3.2 (4 m rubber, 2.5 m PVC after the copper pipe), 9.1 and 11.1 (resonance 0.44 Hz, "
      "0.49 Hz with the tubes cut off); replaces (5.3.1)",
      "lowers the closed-choke resonance towards the open one's (tan(wL/c) = -(C/C_pipe) wL/c) "
      "and makes the choke flow FT3 lag the pipe's outlet flow FT1",
      {{"compliance_m3_per_pa", "m^3/Pa", "topside tube compliance C = V_t / K_eff", 8.2e-11, 0.0,
        2.0e-9, true, 2.5e-11, 1.0e-10}},
      [](const EffectContext& context) {
        return std::make_unique<TopsideCompliance>(context.Get("compliance_m3_per_pa"),
                                                   context.pipe.area_m2,
                                                   context.rig.choke_density_kgpm3);
      }};
  return info;
}

}  // namespace mpdrig
