// pump_curve: the back-pressure pump's delivered flow falls as the choke pressure rises
// (thesis 8.5, Fig. 8.5.1). The thesis fitted, for the pump at 100 % with the accumulator removed,
//   q_b = a exp(-b p_c) + c                                              (8.5.1)
// with a = -2.4050e-6 m^3/s, b = -2.5070e-6 1/Pa, c = 4.7967e-4 m^3/s and p_c the choke pressure
// C2 in Pa gauge. The model's pump command is a flow, so the curve is normalised: the command is
// the flow delivered at a reference pressure p_ref, and other pump settings scale in proportion:
//   q_b = q_cmd max(0, 1 + s (a / c) (exp(-b p_c) - exp(-b p_ref))),     p_c, p_ref gauge,
// where s scales the pressure-dependent term (s = 0: the thesis's constant q_b, s = 1: the slope
// of (8.5.1) relative to its level c). The linear form has no denominator that could vanish;
// the floor at zero is the pump, which does not run backwards. The relative slope is
//   d(q_b/q_cmd)/dp_c = s (a/c) (-b) exp(-b p_c)   [1/Pa],
// for s = 1: -0.13 %/bar at 0 barg, -0.44 %/bar at 5 barg, -1.5 %/bar at 10 barg.
//
// The pump reads the last step's choke pressure (RigSimulator: the pump is slow against one
// step); the initial steady state is the fixed point q_b = q_b(p_c(q_b)) (RigSimulator::Create).
// Use it where the pump command drives the model (a log without FT2, whose pump flow is then the
// command; the service's pump command): the model's FT2 is the delivered q_b. A log's measured
// FT2 already is the delivered flow, so replaying it with this effect would count the curve twice.
//
// Config example:  effect { name: "pump_curve" value { key: "scale" value: 3 } }
#include <algorithm>
#include <cmath>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class PumpCurve final : public Effect {
 public:
  PumpCurve(double scale, double a_m3ps, double b_per_pa, double c_m3ps, double reference_pa,
            double atmospheric_pa)
      : slope_(scale * a_m3ps / c_m3ps),
        b_per_pa_(b_per_pa),
        reference_term_(std::exp(-b_per_pa * reference_pa)),
        atmospheric_pa_(atmospheric_pa) {}

  bool changes_pump_flow() const override { return true; }
  double PumpFlowM3ps(double commanded_m3ps, double choke_pressure_pa) const override {
    const double gauge_pa = choke_pressure_pa - atmospheric_pa_;
    const double factor = 1.0 + slope_ * (std::exp(-b_per_pa_ * gauge_pa) - reference_term_);
    return commanded_m3ps * std::max(0.0, factor);
  }

 private:
  double slope_;  // s a / c
  double b_per_pa_;
  double reference_term_;  // exp(-b p_ref)
  double atmospheric_pa_;
};

}  // namespace

const EffectInfo& PumpCurveEffect() {
  static const EffectInfo info{
      "pump_curve",
      "pump flow falling with the choke pressure: q_b = q_cmd (1 + s (a/c)(exp(-b p_c) - "
      "exp(-b p_ref))), (8.5.1) normalised to the command at p_ref",
      "8.5, (8.5.1), Fig. 8.5.1; 11.4",
      "removes the pressure-dependent drop of the pump flow that makes C2 respond too strongly "
      "to choke steps (the pump gives way as the choke pressure rises)",
      {{"scale", "1", "strength s of the pressure-dependent term (1 = thesis fit of (8.5.1))", 1.0,
        0.0, 10.0, true},
       {"reference_pressure_pa", "Pa gauge",
        "choke pressure at which the pump delivers its command", 0.0, 0.0, 3.0e6, false},
       {"a_m3ps", "m^3/s", "a of (8.5.1)", -2.4050e-6, -1.0e-4, 0.0, false},
       {"b_per_pa", "1/Pa", "b of (8.5.1)", -2.5070e-6, -1.0e-5, 0.0, false},
       {"c_m3ps", "m^3/s", "c of (8.5.1): the curve's level", 4.7967e-4, 1.0e-5, 1.0e-2, false}},
      [](const EffectContext& context) {
        return std::make_unique<PumpCurve>(context.Get("scale"), context.Get("a_m3ps"),
                                           context.Get("b_per_pa"), context.Get("c_m3ps"),
                                           context.Get("reference_pressure_pa"),
                                           context.rig.atmospheric_pressure_pa);
      }};
  return info;
}

}  // namespace mpdrig
