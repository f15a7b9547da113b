// helical_friction: the extra friction of the coiled pipe, from Hasson's correlation (thesis
// 8.6.6-8.6.7). For laminar flow in a helix the Fanning factor is
//   f = 16/Re (0.556 + 0.0969 sqrt(Dn)),  Dn = Re sqrt(lambda)                     (8.6.6, 8.6.5)
//   lambda = (r_c/r_p) / ((r_c/r_p)^2 + (H/(2 pi r_p))^2)                            (8.6.4)
// whose momentum loss is (8 mu u / (rho r_p^2)) (0.556 + 0.0969 sqrt(Dn))                (8.6.7)
// The first part is a straight pipe's laminar friction, linear in u (what f1 u carries). The
// curvature's secondary flow adds the Dean-number part, growing as |u|^(1/2) u:
//   S = scale (8 mu / (rho r_p^2)) 0.0969 sqrt(Dn) u,    Re = rho |u| 2 r_p / mu.
// `scale` = 1 is Hasson's correlation; the fit may move it (the thesis found the coiled/straight
// ratio uncertain, 8.6 and [29]). It makes the damping grow with the flow amplitude: a larger
// heave is damped relatively more.
#include <cmath>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class HelicalFriction final : public Effect {
 public:
  HelicalFriction(const RigParams& rig, double scale, double coil_radius_m, double pitch_m,
                  double viscosity_pa_s) {
    const double r_p = rig.pipe_inner_radius_m;
    const double ratio = coil_radius_m / r_p;
    const double pitch_term = pitch_m / (2.0 * M_PI * r_p);
    const double lambda = ratio / (ratio * ratio + pitch_term * pitch_term);  // (8.6.4)
    const double rho = rig.density_kgpm3;
    // S = gain |u|^(1/2) u with sqrt(Dn) = (rho 2 r_p / mu)^(1/2) lambda^(1/4) |u|^(1/2).
    gain_ = scale * 8.0 * viscosity_pa_s / (rho * r_p * r_p) * 0.0969 *
            std::sqrt(rho * 2.0 * r_p / viscosity_pa_s) * std::pow(lambda, 0.25);
  }

  bool adds_momentum_source() const override { return gain_ > 0.0; }
  // Linearised like the base friction's quadratic term (characteristics_solver.h):
  // S = gain |u|^(1/2) u ~ (gain |u_old|^(1/2)) u_new, implicit in u_new.
  void AddMomentumSource(const PipeSnapshot& state, std::span<double>,
                         std::span<double> implicit_per_s) const override {
    for (std::size_t i = 0; i < implicit_per_s.size(); ++i) {
      const double u = 0.5 * (state.alpha[i] + state.beta[i]);
      implicit_per_s[i] += gain_ * std::sqrt(std::fabs(u));
    }
  }

 private:
  double gain_ = 0.0;  // [m^-1/2 s^-1/2]
};

}  // namespace

const EffectInfo& HelicalFrictionEffect() {
  static const EffectInfo info{
      "helical_friction",
      "Dean-number friction of the coiled pipe, S = scale 8 mu/(rho r^2) 0.0969 sqrt(Dn) u",
      "8.6.2, (8.6.4)-(8.6.7), Hasson 1955; coil data Table 8.1.2",
      "adds friction that grows faster than linearly with the flow: removes the model's too-"
      "large response to large heave amplitudes",
      {{"scale", "-", "multiplier on Hasson's curvature term (1 = the correlation)", 1.0, 0.0,
        5.0, true},
       {"coil_radius_m", "m", "coil radius r_c (Table 8.1.2)", 1.07, 0.05, 100.0, false},
       {"pitch_m", "m", "coil pitch H (Table 8.1.2)", 0.017, 0.0, 10.0, false},
       {"viscosity_pa_s", "Pa s", "water viscosity mu (Table 8.1.2)", 1.0e-3, 1.0e-4, 1.0e-1,
        false}},
      [](const EffectContext& context) {
        return std::make_unique<HelicalFriction>(
            context.rig, context.Get("scale"), context.Get("coil_radius_m"),
            context.Get("pitch_m"), context.Get("viscosity_pa_s"));
      }};
  return info;
}

}  // namespace mpdrig
