// column_separation: where the pressure would fall below the vapour pressure, the liquid column
// separates and a vapour cavity opens; the thesis's model instead goes on to negative absolute
// pressures (thesis 11.5), which the simulator reports as leaving the model's range.
//
// Discrete vapour cavity model (DVCM; Wylie & Streeter, Fluid Transients in Systems, 1993, ch. 8;
// Bergant & Simpson 1999), at the nodes of the characteristics grid (characteristics_solver.h):
//   p_i = p_v while V_i > 0,
//   dV_i/dt = A (u_right,i - u_left,i)      [m^3/s],  u_left from C+, u_right from C- at p = p_v,
//   V_i -> 0: the cavity collapses and the node takes the liquid solution again.
// At the ends the piston or the choke supplies the outer side's velocity against p_v. The
// collapse is a water hammer: the two columns meet with the velocity difference du, and the
// pressure jumps by rho c du (Joukowsky). The liquid is conserved: the pipe's stored volume plus
// the cavities changes by the inflow minus the outflow.
//
// With the effect on, pressures stay >= p_v > 0, so a run that the base model would stop with a
// negative absolute pressure (stop_on_range_violation) continues.
//
// p_v is fitted: the column breaks at the vapour pressure (2.3 kPa at 20 degC) or, with
// dissolved gas coming out of solution, at a higher "gaseous cavitation" pressure.
// The method-of-characteristics scheme supports it; `--scheme mol` refuses it.
//
// Config example:  effect { name: "column_separation" param { key: "vapour_pressure_pa" value: 2300
// } }
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class ColumnSeparation final : public Effect {
 public:
  explicit ColumnSeparation(double vapour_pressure_pa) : vapour_pressure_pa_(vapour_pressure_pa) {}

  bool has_vapour_pressure() const override { return true; }
  double VapourPressurePa() const override { return vapour_pressure_pa_; }

 private:
  double vapour_pressure_pa_;
};

}  // namespace

const EffectInfo& ColumnSeparationEffect() {
  static const EffectInfo info{
      "column_separation",
      "vapour cavities (DVCM): p held at p_v, cavity dV/dt = A (u_right - u_left) until it "
      "collapses",
      "11.5 (negative absolute pressures); beyond the thesis: Wylie & Streeter, Bergant & Simpson",
      "removes pressures that the model drives below zero absolute (the trace is flat at the "
      "vapour pressure instead) and adds the pressure spike when the cavity collapses",
      {{"vapour_pressure_pa", "Pa",
        "absolute pressure at which the column separates (vapour pressure, or higher with gas "
        "release)",
        2.3e3, 500.0, 9.0e4, true}},
      [](const EffectContext& context) {
        return std::make_unique<ColumnSeparation>(context.Get("vapour_pressure_pa"));
      }};
  return info;
}

}  // namespace mpdrig
