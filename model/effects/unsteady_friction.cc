// unsteady_friction: instantaneous-acceleration unsteady friction (thesis 8.6.12, Brunone et al.
// 1991; review in Bergant, Simpson and Vitkovsky 2001, thesis ref. [5]):
//   f_u = k (du/dt + sgn(u) c |du/dx|)          [m/s^2], added to f(u) of (8.6.8).
// k is the Brunone coefficient (dimensionless, 0.01-0.1 in the literature for laminar and
// smooth-pipe flow). Steady flow is untouched. Why it damps, and more so at higher frequency:
// in a standing wave u = U cos(kx) sin(wt) the convective part is
// sgn(u) c |u_x| = c k U |sin(kx)| sgn(cos(kx)) sin(wt), in phase with u everywhere, so it
// always removes energy, at a rate proportional to c k = w. The du/dt part adds inertia (1 + k).
// (The variant c sgn(u u_x) |u_x| has no component at the drive frequency in this pipe's
// zero-mean-flow oscillation, and would not damp it at all.)
//
// convective_form = 1 switches to that variant, asked for as "Vitkovsky's sgn(u u_x) form" for
// valve closures with a mean flow (the reservoir - pipe - valve rig, docs/bergant-simpson.md):
//   f_u = k (du/dt + c sgn(u u_x) |u_x|) = k (du/dt + sgn(u) c u_x).
// The two convective terms agree where u_x > 0 and are opposite where u_x < 0. The thesis gives
// the default (8.6.12) as Brunone et al. 1991's; TSNet's documentation gives the same form,
// sign(V) |dV/dx|, as the instantaneous-acceleration-based model of Vitkovsky, Bergant, Simpson
// and Lambert 2006 (docs/bergant-simpson.md). The default stays 0.
// k from the flow: Vardy & Brown's shear decay coefficient C* (0.00476 laminar;
// 7.41 / Re^(log10(14.3 / Re^0.05)) turbulent) gives the theoretical k* = sqrt(C*) / 2.
//
// Discretisation (the standard one for the method of characteristics): with
// s = sgn(u u_x) = sgn(u) sgn(u_x), sgn(u) c |u_x| = s c u_x, so the bracket is a total
// derivative along a characteristic: du/dt + c u_x along C+ (s > 0), du/dt - c u_x along C-
// (s < 0). Over one step it is (u_P - u_F) / dt with F the node the characteristic comes from
// (i - 1 for C+, i + 1 for C-; the node itself where s = 0 or at the ends). The variant's
// bracket is du/dt + sgn(u) c u_x: s = sgn(u), the same discretisation. That is linear in
// the new velocity u_P: a semi-implicit source S = a + b u_P with b = k / dt, a = -k u_F / dt
// (pipe_extension.h), stable at any k.
#include <cmath>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

class UnsteadyFriction final : public Effect {
 public:
  UnsteadyFriction(double k, bool variant) : k_(k), variant_(variant) {}

  bool adds_momentum_source() const override { return k_ > 0.0; }
  void AddMomentumSource(const PipeSnapshot& state, std::span<double> explicit_mps2,
                         std::span<double> implicit_per_s) const override {
    const int n = state.config.cells;
    const double inv_dt = 1.0 / state.dt_s;
    const auto u = [&](int i) { return 0.5 * (state.alpha[i] + state.beta[i]); };
    for (int i = 0; i <= n; ++i) {
      int from = i;
      if (i > 0 && i < n) {
        const double s = variant_ ? u(i) : u(i) * (u(i + 1) - u(i - 1));
        from = s > 0.0 ? i - 1 : (s < 0.0 ? i + 1 : i);
      }
      explicit_mps2[i] -= k_ * u(from) * inv_dt;
      implicit_per_s[i] += k_ * inv_dt;
    }
  }

 private:
  double k_;
  bool variant_;
};

}  // namespace

const EffectInfo& UnsteadyFrictionEffect() {
  static const EffectInfo info{
      "unsteady_friction",
      "instantaneous-acceleration unsteady friction f_u = k (du/dt + sgn(u) c |u_x|)",
      "8.6.4, (8.6.12); Brunone 1991, Vitkovsky 2000 (ref. [5])",
      "adds damping that grows with frequency: removes the model's too-high resonance peaks and "
      "higher harmonics while leaving steady pressures alone",
      {{"k", "-", "Brunone coefficient k", 0.03, 0.0, 0.3, true},
       {"convective_form", "-",
        "0: the convective term c sgn(u) |u_x| (thesis 8.6.12); 1: c sgn(u u_x) |u_x| (a variant "
        "for valve closures with a mean flow); values round to the nearer",
        0.0, 0.0, 1.0, false}},
      [](const EffectContext& context) {
        return std::make_unique<UnsteadyFriction>(context.Get("k"),
                                                  context.Get("convective_form") >= 0.5);
      }};
  return info;
}

}  // namespace mpdrig
