// hose_compliance: the elastic rubber hose between the heave generator and the copper pipe
// (thesis 11.3: "the rubber hose going from the piston compartment and into the copper pipe ...
// may add a time delay"; 8.3 for wall elasticity). A lumped capacitance at the pipe inlet:
//   C dp_0/dt = q_0 - A u(0),      p_0 = p(0) = P2,      C = V_h / K_eff   [m^3/Pa],
// with q_0 = -v_d (A_d - A_d2) the displaced flow of (5.4.1), which no longer enters the pipe
// directly. The hose holds no flow resistance or inertia, so the pressure in it is the pipe inlet
// pressure. The pipe's inlet flow FT4 = A u(0) lags the piston: with the pipe's input impedance
// Z_in(w) = P2/FT4, FT4/q_0 = 1 / (1 + i w C Z_in), and the added compliance lowers the
// resonance frequencies. C = 0 is the rigid inlet (5.4.1).
//
// Unlike piston_compressibility (the compartment's own two volumes and the BHA gap flow,
// (5.4.3)-(5.4.5)), this adds one state at one place: it changes how FT4 and the pipe follow the
// piston, but leaves the relation between P1 and P2 the thesis's algebraic (5.4.2) in v_d. A
// compliant compartment instead makes P1 - P2 answer the pressure (the gap flow must fill the
// volume below the BHA), e.g. P1 - P2 moves during a choke step with the piston at rest.
//
// Boundary closure (pipe_extension.h), implicit Euler over the step: with p(u) the pressure the
// pipe imposes for the new inlet velocity u,
//   g(u) = q_0 - A u - C (p(u) - p_0,prev) / dt = 0,
// strictly decreasing in u (dp/du = rho c > 0 at the inlet): stable at any step.
// State: p_0 at the last time level [Pa abs], set from the pipe after every step.
//
// Defaults: 2 m of 16 mm bore hose (V_h = 4.0e-4 m^3) at an effective bulk modulus of 1e8 Pa
// (reinforced rubber; water alone is 2.2e9 Pa) gives C = 4e-12 m^3/Pa, about 2 % of the pipe's
// own compliance V / (rho c^2) = 2.5e-10 m^3/Pa.
//
// Config example:  effect { name: "hose_compliance" value { key: "compliance_m3_per_pa" value:
// 2e-11 } }
#include <cmath>

#include "model/common/root_finding.h"
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class HoseCompliance final : public Effect {
 public:
  explicit HoseCompliance(double compliance_m3_per_pa) : compliance_(compliance_m3_per_pa) {}

  void Initialize(const PipeSolver& pipe, const ChannelValues&) override {
    pressure_pa_ = pipe.PressureAt(0.0);
    velocity_mps_ = pipe.VelocityAt(0.0);
  }
  bool closes_inlet() const override { return true; }
  double SolveInletVelocity(const BoundaryRelation& pipe, const InletInputs& in) const override {
    const double q_0 = in.displaced_flow_m3ps;
    const double area = in.area_m2;
    const double k = compliance_ / in.dt_s;
    const auto g = [&](double u) {
      return q_0 - area * u - k * (pipe.PressurePa(u) - pressure_pa_);
    };
    const auto dg = [&](double u) { return -area - k * pipe.DPressureDVelocity(u); };
    return SolveDecreasing(velocity_mps_, 0.01, g, dg);
  }
  void AfterStep(const PipeSolver& pipe, const StepRecord&) override {
    pressure_pa_ = pipe.PressureAt(0.0);
    velocity_mps_ = pipe.VelocityAt(0.0);
  }

 private:
  double compliance_;          // C [m^3/Pa]
  double pressure_pa_ = 0.0;   // p_0 at the last time level
  double velocity_mps_ = 0.0;  // u(0) at the last time level: the Newton start
};

}  // namespace

const EffectInfo& HoseComplianceEffect() {
  static const EffectInfo info{
      "hose_compliance",
      "elastic hose at the pipe inlet: C dp(0)/dt = q_0 - A u(0), C = V_h / K_eff",
      "11.3 (rubber hose, suspected time delay), 8.3 (wall elasticity); replaces the rigid "
      "(5.4.1)",
      "removes a lag and an amplitude loss of the inlet flow FT4 and of the pressures behind the "
      "piston's motion, and lowers resonance frequencies that the model puts too high",
      {{"compliance_m3_per_pa", "m^3/Pa", "hose compliance C = V_h / K_eff", 4.0e-12, 0.0, 1.0e-9,
        true}},
      [](const EffectContext& context) {
        return std::make_unique<HoseCompliance>(context.Get("compliance_m3_per_pa"));
      }};
  return info;
}

}  // namespace mpdrig
