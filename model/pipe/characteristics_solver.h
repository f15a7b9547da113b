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
//
// General path (only when an extension changes the compressibility or sets a vapour pressure;
// the default path above does not change with it):
// - Pressure-dependent wave speed c(p) <= c (MixtureLaw): the grid keeps dt = dx / c, the
//   invariants are alpha = W(p) + u, beta = -W(p) + u with the tabulated W; the feet of the
//   characteristics (speeds u +- c(p), Courant number <= 1) are found with the speed linearly
//   interpolated between the nodes, and the invariants are interpolated there (the interpolated
//   method of characteristics, Wylie & Streeter; it damps where c(p) < c, as interpolation does).
//   alpha_, beta_ keep the model's own variables (PipeLaw), so pressures read the same everywhere.
// - Column separation by the discrete vapour cavity model (Wylie & Streeter 1993; Bergant &
//   Simpson 1999): where a node's pressure would fall below p_v, it is held at p_v and each
//   characteristic gives its own side's velocity, u_left from C+ and u_right from C-; the cavity
//   at the node grows as dV/dt = A (u_right - u_left), by implicit Euler (the DVCM weighting
//   psi = 1: a node whose liquid solution falls below p_v has u_right > u_left, so its cavity
//   grows and p >= p_v always holds). While V > 0 the node stays at p_v; when V would fall below 0
//   the cavity collapses (V = 0) and the node takes the liquid solution: the colliding columns
//   give the Joukowsky jump rho c du. The liquid balances with the time-centred cavity volume
//   (CavityVolumeM3) up to what each collapse leaves, at most A dt |u_right - u_left|.
//   An interior cavity node stores the mean of its two velocities and the jump u_right - u_left;
//   a boundary node stores the velocity of the boundary (piston, choke: FT4 and FT1 stay the
//   flows at the ends). Characteristics leaving a cavity node carry the velocity of their side.
// - Discrete gas cavity model (DGCM; Wylie 1984; Wylie & Streeter 1993 ch. 8), when the column
//   separation's extension gives free gas (PipeExtension::FreeGas): every node, always, has the
//   two sides of a cavity node above, with a gas volume V = G / (p - p_v), G = alpha_0 A dx_i
//   (p_0 - p_v) (dx_i = dx, dx/2 at the ends: the node's share of the pipe), and its continuity
//   V = V_old + dt A (psi (u_right - u_left) + (1 - psi) (u_right - u_left)_old). With each side's
//   velocity linear in W(p) (u_left = (A' - W)/d, u_right = (B' + W)/d) that is
//   G / (p - p_v) = q + kappa W(p), a quadratic in p for the linear law (the literature's form in
//   the head), solved in its stable form; Newton on W's tangent otherwise. Its root is unique
//   and above p_v (the left side falls from infinity, the right rises). At an end the boundary's
//   velocity enters as p(u) of the node (GasBoundaryRelation), which the choke or a closure
//   solves. psi = 1 (the default) is the DVCM's implicit Euler: as alpha_0 -> 0 the DGCM's
//   cavity is the DVCM's; Wylie's 0.5 < psi < 1 is centred but lets the cavities ring.
#pragma once

#include <limits>
#include <memory>
#include <vector>

#include "model/pipe/mixture_law.h"
#include "model/pipe/pipe_solver.h"

namespace mpdrig {

class CharacteristicsSolver final : public PipeSolver {
 public:
  CharacteristicsSolver(const PipeConfig& config, double p_bar_pa);

  double time_step_s() const override { return dt_s_; }
  Status Step(const PipeStepInputs& inputs, RangeViolation* violation) override;
  double CavityVolumeM3() const override;
  // Cavity volume at each node [m^3] (empty without column separation).
  const std::vector<double>& cavity_volumes_m3() const { return cavity_volume_; }
  // u_right - u_left at each node [m/s] (non-zero at cavities).
  const std::vector<double>& velocity_jumps_mps() const { return velocity_jump_; }

 protected:
  // Momentum sources are added explicitly along both characteristics; closures replace the
  // piston's or the choke's relation at the ends (pipe_extension.h).
  bool supports_momentum_sources() const override { return true; }
  bool supports_boundary_closures() const override { return true; }
  bool supports_compressibility() const override { return true; }
  bool supports_column_separation() const override { return true; }
  void OnExtensionsChanged() override;
  void OnStateReset() override;

 private:
  // Values at the foot of the characteristics that arrive at node i (the velocity is the
  // neighbouring node's, see StepInterior).
  struct Foot {
    double invariant;
    double velocity;
  };
  Foot AlphaFoot(int i) const;  // alpha characteristic arriving at node i (from the left)
  Foot BetaFoot(int i) const;   // beta characteristic arriving at node i (from the right)
  // Nodes 1..N-1 of the default path, both models (the cell loops of characteristics_solver.cc);
  // returns their smallest alpha - beta at the new level.
  double StepInterior();
  // The fast path's other parts (Step), in their order.
  double SourceAt(bool has_sources, int i, double u) const;
  void AddSourcesToInterior();
  void StepInletNode(const PipeStepInputs& inputs, bool has_sources);
  void StepOutletNode(const PipeStepInputs& inputs, bool has_sources);
  // The step's last part, on either path: alpha_next_, beta_next_ become the state.
  // NaN: the range check looks at every node itself.
  Status AdvanceToNewLevel(RangeViolation* violation, double interior_smallest_difference =
                                                          std::numeric_limits<double>::quiet_NaN());
  // The general path (see the header comment), in its steps; GeneralStep holds what they share.
  struct GeneralStep;
  Status StepGeneral(const PipeStepInputs& inputs, RangeViolation* violation);
  void LoadGeneralOldLevel(const GeneralStep& step);
  void StepGeneralInterior(const GeneralStep& step);
  template <bool kGas>
  void StepGeneralInteriorNodes(const GeneralStep& step);
  void StepGeneralInlet(const GeneralStep& step, const PipeStepInputs& inputs);
  void StepGeneralOutlet(const GeneralStep& step, const PipeStepInputs& inputs);
  // Feet of the characteristics arriving at node i in the general path: the invariant there,
  // and the velocity in *u_foot.
  double GeneralAlphaFoot(const GeneralStep& step, int i, double* u_foot) const;
  double GeneralBetaFoot(const GeneralStep& step, int i, double* u_foot) const;
  // Node i has a cavity, or its liquid solution's pressure falls below p_v.
  bool InCavity(const GeneralStep& step, int i, double liquid_pressure_pa) const;
  // Advances node i's cavity with the new jump u_right - u_left: true while it stays open.
  bool SettleCavity(const GeneralStep& step, int i, double liquid_pressure_pa, double jump);
  // DGCM: node i's gas constant G_i = alpha_0 A dx_i (p_0 - p_v), and its gas volume at the state.
  double GasConstant(int i) const;
  void ResetGasVolumes();
  // DGCM: V_old + dt A (1 - psi) jump_old, the part of node i's new gas volume known before the
  // step.
  double GasVolumeKnown(int i) const;
  void RememberPressure(int i, double pressure_pa, double log_pressure);

  double dt_s_;
  std::vector<double> alpha_next_;
  std::vector<double> beta_next_;
  std::vector<double> velocity_;  // scratch: u at the nodes, old time level
  // Scratch of the default path, per node j, old time level (StepInterior): what the alpha and
  // the beta characteristic leaving node j carry to its neighbour before the neighbour's own
  // friction, and that friction's share K_j = (h lambda_j / 2) / (2 + h lambda_j).
  std::vector<double> leaving_alpha_, leaving_beta_, friction_share_;

  // General path.
  bool general_ = false;
  std::unique_ptr<MixtureLaw> mixture_;  // null: W is the model's PressureTerm
  double vapour_pressure_pa_ = 0.0;      // 0: no column separation
  std::vector<double> cavity_volume_;    // V_i [m^3]
  std::vector<double> velocity_jump_;    // u_right - u_left at cavity nodes [m/s]
  // DGCM (free gas at every node; 0: the DVCM): alpha_0, p_0 [Pa abs], psi. cavity_volume_ then
  // holds each node's gas volume.
  double gas_void_fraction_ = 0.0;
  double gas_reference_pa_ = 0.0;
  double gas_weighting_ = 1.0;
  // Scratch, old time level: pressure, W, speeds, and the side values of the invariants and u.
  std::vector<double> pressure_, w_, speed_up_, speed_down_;
  std::vector<double> alpha_left_, alpha_right_, beta_left_, beta_right_, u_left_, u_right_;
  // With a mixture law: ln p of the old level, and the new level's alpha, beta, p and ln p as the
  // interior computed them (RememberPressure), the next step's old level if nothing changed it.
  std::vector<double> log_pressure_;
  std::vector<double> known_alpha_, known_beta_, known_pressure_, known_log_pressure_;
};

}  // namespace mpdrig
