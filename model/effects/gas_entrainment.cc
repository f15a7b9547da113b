// gas_entrainment: free air entrained in the water makes the pipe's contents more compressible,
// the more so the lower the pressure, so the wave speed depends on the local pressure
// (thesis 8.3.2-8.3.6: the measured c = 1173 m/s against 1353 m/s of the pipe-wall formula 8.3.1).
//
// A free-gas volume fraction eps0 at the reference pressure p_ref, compressed polytropically
// (p V^n = const; n = 1 isothermal, the small bubbles exchange heat with the water):
//   eps(p) = eps0 (p_ref / p)^(1/n)                                         [-]
// Mixture bulk modulus (8.3.5) with beta_air = n p, as a compressibility:
//   1/(rho c(p)^2) = (1 - eps)/K + eps/(n p),    K = rho c^2               (8.3.5, 8.3.6)
// with c the rig's wave_speed_mps (the liquid and wall, what the thesis tuned) and rho the
// liquid's density (small fractions: eps << 1, the air's mass and (8.3.3)'s density change are
// neglected). The pipe solver gets the extra compressibility
//   C_x(p) = eps(p)/(n p) - eps(p)/K >= 0                                   [1/Pa]
// (pipe_extension.h), so eps0 = 0 is the base model exactly. For eps0 = 1e-4 at 1 atm the wave
// speed is 650 m/s at 1 bar(a) and 840 m/s at 6 bar(a): the resonances and the PT1 -> PT10 travel
// time move with the mean pressure (choke setting, pump flow, C1), and the low-pressure part of a
// wave travels slower than its high-pressure part.
//
// Config example:  effect { name: "gas_entrainment" param { key: "void_fraction" value: 1e-4 } }
#include <algorithm>
#include <cmath>

#include "model/common/units.h"
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class GasEntrainment final : public Effect {
 public:
  GasEntrainment(double void_fraction, double reference_pressure_pa, double polytropic_index,
                 double liquid_bulk_modulus_pa)
      : eps0_(void_fraction),
        p_ref_(reference_pressure_pa),
        n_(polytropic_index),
        bulk_modulus_pa_(liquid_bulk_modulus_pa) {}

  bool changes_compressibility() const override { return eps0_ > 0.0; }
  double ExtraCompressibilityPerPa(double pressure_pa) const override {
    const double p = std::max(pressure_pa, 1e-300);
    const double eps = eps0_ * std::pow(p_ref_ / p, 1.0 / n_);
    // Above p = K/n (700 MPa) the gas would be stiffer than the water: nothing to add there.
    return std::max(0.0, eps / (n_ * p) - eps / bulk_modulus_pa_);
  }

 private:
  double eps0_;
  double p_ref_;
  double n_;
  double bulk_modulus_pa_;
};

}  // namespace

const EffectInfo& GasEntrainmentEffect() {
  static const EffectInfo info{
      "gas_entrainment",
      "entrained free air: 1/(rho c(p)^2) = (1 - eps)/(rho c^2) + eps/(n p), "
      "eps = eps0 (p_ref/p)^(1/n)",
      "8.3.2, (8.3.2)-(8.3.6): wave speed of a water-air mixture",
      "removes a resonance shift and a change of the PT1 -> PT10 travel time that depend on the "
      "mean pressure (choke setting, pump flow, outlet pressure): waves are slower where the "
      "pressure is low",
      {{"void_fraction", "-", "free gas volume fraction eps0 at the reference pressure", 1.0e-4,
        0.0, 0.02, true,
        // up to the thesis's own gap: its tuned c = 1173 m/s against the 1353 m/s of (8.3.1) is
        // eps/p = 1.8e-10 1/Pa, eps0 = 4.5e-4 at 1 atm for the rig's ~5 bar (8.3.5)
        5.0e-5, 1.0e-3},
       {"reference_pressure_pa", "Pa", "absolute pressure at which the fraction is eps0",
        units::kStandardAtmospherePa, 1.0e4, 1.0e7, false},
       {"polytropic_index", "-", "n of p V^n = const (1 isothermal, 1.4 adiabatic)", 1.0, 1.0, 1.4,
        false}},
      [](const EffectContext& context) {
        const double c = context.pipe.wave_speed_mps;
        return std::make_unique<GasEntrainment>(
            context.Get("void_fraction"), context.Get("reference_pressure_pa"),
            context.Get("polytropic_index"), context.pipe.density_kgpm3 * c * c);
      }};
  return info;
}

}  // namespace mpdrig
