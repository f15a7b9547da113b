// A reservoir at the pipe inlet x = 0: a constant pressure, whatever flows (the classic upstream
// boundary of water hammer; Wylie & Streeter, Fluid Transients in Systems, 1993, ch. 3):
//   p(0, t) = p_R = p_atm + rho g H_R,
// the entrance loss neglected. It takes the place of the heave generator (5.4) in the reservoir -
// pipe - valve layout (model/params/rig_layout.h) through the pipe's inlet hook
// (PipeExtension::SolveInletVelocity): the solver hands it p(0) as a function of u(0) along the
// beta characteristic arriving from the pipe, and it returns the u(0) at which that is p_R.
//
// Parameter: p_R [Pa abs]. No state.
#pragma once

#include "model/pipe/pipe_extension.h"

namespace mpdrig {

class ReservoirInlet final : public PipeExtension {
 public:
  explicit ReservoirInlet(double pressure_pa) : pressure_pa_(pressure_pa) {}

  double pressure_pa() const { return pressure_pa_; }

  bool closes_inlet() const override { return true; }
  // The root of p(u) = p_R: p(u) rises with u at the inlet (BoundaryRelation), one Newton step
  // for the linear model, a few for the quasi-linear one.
  double SolveInletVelocity(const BoundaryRelation& pipe, const InletInputs& inputs) const override;

 private:
  double pressure_pa_;
};

}  // namespace mpdrig
