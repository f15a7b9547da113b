// Method of characteristics on the characteristic grid (the water-hammer standard; thesis B.1).
//
// Problem: alpha_t + (u + c) alpha_x = S(u),  beta_t + (u - c) beta_x = S(u),
//          S(u) = -g sin(gamma) - f(u),  u = (alpha + beta)/2     (6.1.16-17; linear: 7.0.10-11)
// Grid: N cells, dt = dx / c, so a characteristic of speed +-c leaves one node and lands exactly
// on the next one: transport is exact for the linear model (no numerical diffusion or
// dispersion, whatever N). For the quasi-linear model the foot of a characteristic moves by
// u dt (|u| / c ~ 3e-4 of a cell here) and is found by linear interpolation between nodes.
// Source terms are integrated with the trapezoidal rule along the characteristic; the friction
// at the new point is linearised as f(u_P) ~ (f1 + f2 |u_old|) u_P, which closes the two
// characteristic equations at each node in one explicit formula (second order in dt for the
// linear friction of the analytic model, 9.2).
#pragma once

#include <vector>

#include "model/pipe/pipe_solver.h"

namespace mpdrig {

class CharacteristicsSolver final : public PipeSolver {
 public:
  CharacteristicsSolver(const PipeConfig& config, double p_bar_pa);

  double time_step_s() const override { return dt_s_; }
  Status Step(const PipeStepInputs& inputs, RangeViolation* violation) override;

 protected:
  // Momentum sources are added explicitly along both characteristics; closures replace the
  // piston's or the choke's relation at the ends (pipe_extension.h).
  bool supports_momentum_sources() const override { return true; }
  bool supports_boundary_closures() const override { return true; }

 private:
  // Values at the foot of the characteristics that arrive at node i (the velocity is the
  // neighbouring node's, see StepInteriorQuasiLinear).
  struct Foot {
    double invariant;
    double velocity;
  };
  Foot AlphaFoot(int i) const;  // alpha characteristic arriving at node i (from the left)
  Foot BetaFoot(int i) const;   // beta characteristic arriving at node i (from the right)
  void StepInteriorLinear();
  void StepInteriorQuasiLinear();

  double dt_s_;
  std::vector<double> alpha_next_;
  std::vector<double> beta_next_;
  std::vector<double> velocity_;  // scratch: u at the nodes, old time level
};

}  // namespace mpdrig
