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
// Discrete gas cavity model (DGCM; Wylie, J. Fluids Eng. 106, 1984; Wylie & Streeter 1993 ch. 8;
// Bergant & Simpson 1999): with gas_void_fraction alpha_0 > 0, every node holds a little free gas
// at all times instead of switching between liquid and vapour cavity:
//   V_g (p - p_v) = alpha_0 A dx (p_0 - p_v)     (isothermal, the gas's partial pressure),
//   V_g = V_g,old + dt A (psi (u_right - u_left) + (1 - psi) (u_right - u_left)_old),
// p_0 = gas_reference_pressure_pa, psi = gas_weighting. In the liquid the gas lowers the wave speed
// (Wood: 1/(rho c_m^2) = 1/(rho c^2) + alpha/(p - p_v)); below a few kPa the gas swells into a
// cavity that the DVCM's would be, with p just above p_v. The literature's usual alpha_0 = 1e-7 at
// the reservoir pressure (3.2 bar abs on Bergant & Simpson's rig) lowers the wave speed by
// 0.03 % there, but by a quarter at 0.1 bar abs: the low-pressure zones between the cavities, where
// the DVCM's many small cavities and their collapses make its later pulses depend on the grid,
// are compliant instead. gas_void_fraction = 0 is the DVCM
// (the default). The three gas parameters are not fitted by diagnose: the choice of model is
// the user's; a fit of alpha_0 would trade it against the wave speed.
//
// Config example:  effect { name: "column_separation" param { key: "vapour_pressure_pa" value: 2300
// } }
//                  DGCM: add  param { key: "gas_void_fraction" value: 1e-7 }
//                             param { key: "gas_reference_pressure_pa" value: 316950 }
#include <sstream>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class ColumnSeparation final : public Effect {
 public:
  ColumnSeparation(double vapour_pressure_pa, const FreeGas& gas)
      : vapour_pressure_pa_(vapour_pressure_pa), gas_(gas) {}

  bool has_vapour_pressure() const override { return true; }
  double VapourPressurePa() const override { return vapour_pressure_pa_; }
  FreeGas CavityFreeGas() const override { return gas_; }

 private:
  double vapour_pressure_pa_;
  FreeGas gas_;
};

}  // namespace

const EffectInfo& ColumnSeparationEffect() {
  static const EffectInfo info{
      "column_separation",
      "vapour cavities (DVCM): p held at p_v, cavity dV/dt = A (u_right - u_left) until it "
      "collapses; or free gas at every node (DGCM, gas_void_fraction > 0)",
      "11.5 (negative absolute pressures); beyond the thesis: Wylie & Streeter, Bergant & Simpson",
      "removes pressures that the model drives below zero absolute (the trace is flat at the "
      "vapour pressure instead) and adds the pressure spike when the cavity collapses",
      {{"vapour_pressure_pa", "Pa",
        "absolute pressure at which the column separates (vapour pressure, or higher with gas "
        "release)",
        2.3e3, 500.0, 9.0e4, true},
       {"gas_void_fraction", "-",
        "free-gas void fraction alpha_0 at gas_reference_pressure_pa: > 0 switches to the discrete "
        "gas cavity model (DGCM; 1e-7 is the literature's usual value), 0 the vapour cavities "
        "(DVCM)",
        0.0, 0.0, 1.0e-2, false},
       {"gas_reference_pressure_pa", "Pa", "absolute pressure at which the void fraction is given",
        101325.0, 1.0e3, 1.0e8, false},
       {"gas_weighting", "-",
        "weighting psi of the gas volume's continuity in time (1: implicit, as the vapour "
        "cavities; 0.5: centred, lets the gas ring)",
        1.0, 0.5, 1.0, false}},
      [](const EffectContext& context) {
        return std::make_unique<ColumnSeparation>(
            context.Get("vapour_pressure_pa"),
            PipeExtension::FreeGas{context.Get("gas_void_fraction"),
                                   context.Get("gas_reference_pressure_pa"),
                                   context.Get("gas_weighting")});
      },
      /*diagnose_candidate=*/true,
      // The gas's void fraction is given at a pressure where there is liquid: at or below p_v the
      // DGCM's gas law (alpha_0 p_0 / (p - p_v)) has no meaning. The pipe checks it again.
      [](const EffectValues& values) {
        if (values.Get("gas_void_fraction") > 0.0 &&
            !(values.Get("gas_reference_pressure_pa") > values.Get("vapour_pressure_pa"))) {
          std::ostringstream out;
          out << "column_separation: gas_reference_pressure_pa = "
              << values.Get("gas_reference_pressure_pa")
              << " Pa must be above vapour_pressure_pa = " << values.Get("vapour_pressure_pa")
              << " Pa when gas_void_fraction > 0 (the void fraction is given where there is "
                 "liquid)";
          return Status::Error(out.str());
        }
        return Status::Ok();
      }};
  return info;
}

}  // namespace mpdrig
