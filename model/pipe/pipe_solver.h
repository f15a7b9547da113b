// A pipe solver advances the Riemann invariants alpha, beta of the copper pipe (thesis 6.1, 7.0)
// on a uniform grid of N cells, nodes x_i = i L / N, i = 0..N (node 0 at the heave generator,
// node N at the choke), one fixed time step at a time. The boundaries close it:
//   x = 0: u(0) = u_0 given by the piston (5.4.1), alpha(0) = -beta(0) + 2 u_0        (6.7.1)
//   x = L: u(L) from the choke (ChokeBoundary), beta(L) = -alpha(L) + 2 u(L)          (6.6.1)
// Friction f(u) = f1 u + f2 u|u| (8.6.8) and gravity g sin(gamma) act as source terms.
//
// Two schemes implement this interface:
//   CharacteristicsSolver - method of characteristics on the characteristic grid (the water-
//     hammer standard); dt = dx / c, exact transport for the linear model. The default.
//   MolSolver - the method-of-lines form of the thesis (6.1.2), upwind in space, integrated in
//     time by SUNDIALS ARKODE.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model/boundary/choke.h"
#include "model/common/status.h"
#include "model/core/pipe_law.h"
#include "model/params/rig_params.h"
#include "model/pipe/pipe_extension.h"

namespace mpdrig {

enum class PipeScheme { kCharacteristics, kMethodOfLines };

// The boundary inputs at one instant.
struct PipeBoundaryValues {
  double inlet_velocity_mps = 0.0;  // u_0 = q_0 / A
  ChokeBoundaryInputs choke{};
};

// The boundary inputs at the start and at the end of a step. The characteristics scheme imposes
// the end values at the new time level (boundary values are point values there); the method of
// lines varies them linearly across the step.
struct PipeStepInputs {
  PipeBoundaryValues start;
  PipeBoundaryValues end;
};

// The part of the rig configuration a pipe solver needs, resolved once.
struct PipeConfig {
  PipeModel model = PipeModel::kQuasiLinear;
  int cells = 0;
  double length_m = 0.0;
  double area_m2 = 0.0;
  double wave_speed_mps = 0.0;
  double density_kgpm3 = 0.0;
  double k_pa = 0.0;  // quasi-linear k = c^2 rho_ref - p_ref
  double friction_f1_per_s = 0.0;
  double friction_f2_per_m = 0.0;
  double gravity_slope_mps2 = 0.0;  // g sin(gamma)
  double choke_density_kgpm3 = 0.0;

  static PipeConfig FromParams(const RigParams& params, PipeModel model, int cells);
  double dx_m() const { return length_m / cells; }
  double Friction(double u) const {  // f(u) (8.6.8)
    return friction_f1_per_s * u + friction_f2_per_m * u * (u < 0 ? -u : u);
  }
};

// Where and when the model left its range (absolute pressure at or below zero).
struct RangeViolation {
  bool occurred = false;
  double min_pressure_pa = 0.0;
  double position_m = 0.0;
};

class PipeSolver {
 public:
  virtual ~PipeSolver() = default;

  const PipeConfig& config() const { return config_; }
  const PipeLaw& law() const { return law_; }
  virtual double time_step_s() const = 0;

  // alpha_i, beta_i at the N + 1 nodes (boundary nodes included).
  const std::vector<double>& alpha() const { return alpha_; }
  const std::vector<double>& beta() const { return beta_; }

  // Sets the steady state with the pipe at rest and outlet pressure p_l (thesis 6.5): hydrostatic
  // profile (6.5.3) for the quasi-linear model, p_l + rho g sin(gamma) (L - x) for the linear one.
  void SetRestState(double outlet_pressure_pa);
  // Sets the state at the N + 1 nodes from a pressure [Pa abs] and a velocity [m/s] profile (a
  // state other than a steady one: a replay that starts from the measured pipe). Both have N + 1
  // values.
  void SetState(const std::vector<double>& pressure_pa, const std::vector<double>& velocity_mps);

  // Physics beyond the thesis's pipe (model/effects), consulted every step; not owned, must outlive
  // the solver. Refused when the scheme does not support a hook one of them uses, when two
  // close the same end, or when two set a vapour pressure.
  Status SetExtensions(std::vector<const PipeExtension*> extensions);

  // Total volume of the vapour cavities [m^3] (column separation; 0 without it).
  virtual double CavityVolumeM3() const { return 0.0; }

  // Advances one time step. A solver failure is an error; leaving the model's range is reported
  // in `violation` (the caller decides whether that stops the run).
  virtual Status Step(const PipeStepInputs& inputs, RangeViolation* violation) = 0;

  // Pressure [Pa abs] and velocity [m/s] at x in [0, L], linear in the invariants between nodes.
  double PressureAt(double x_m) const;
  double VelocityAt(double x_m) const;
  // The pipe's stored liquid volume change relative to p_ref: integral of (rho(p)/rho_ref - 1) A dx
  // with rho(p) from (5.2.1) (trapezoid over the nodes). Its rate is q_in - q_out (continuity).
  double StoredVolumeM3() const;

 protected:
  PipeSolver(const PipeConfig& config, double p_bar_pa);
  // Which hooks the scheme implements (SetExtensions refuses the others).
  virtual bool supports_momentum_sources() const { return false; }
  virtual bool supports_boundary_closures() const { return false; }
  virtual bool supports_compressibility() const { return false; }
  virtual bool supports_column_separation() const { return false; }
  // Called at the end of SetExtensions (e.g. to tabulate what the extensions change).
  virtual void OnExtensionsChanged() {}
  // Sum of the extensions' momentum sources at the current state into source_explicit_ and
  // source_implicit_.
  // Returns false when no extension adds one.
  bool EvaluateMomentumSources();

  // Called after alpha_/beta_ were overwritten from outside the scheme (SetRestState).
  virtual void OnStateReset() {}
  // Index and weight of the interval holding x.
  void Locate(double x_m, int* index, double* weight) const;
  // Smallest alpha - beta over the nodes, turned into a RangeViolation if at or below zero
  // pressure.
  void CheckRange(RangeViolation* violation) const;
  // The same when the scheme already knows that smallest alpha - beta over the nodes.
  void CheckRange(RangeViolation* violation, double smallest_difference) const;

  PipeConfig config_;
  PipeLaw law_;
  ChokeBoundary choke_;
  std::vector<double> alpha_;
  std::vector<double> beta_;
  // Extensions, by hook.
  std::vector<const PipeExtension*> source_extensions_;
  const PipeExtension* inlet_closure_ = nullptr;
  const PipeExtension* outlet_closure_ = nullptr;
  std::vector<const PipeExtension*> compressibility_extensions_;
  const PipeExtension* vapour_pressure_extension_ = nullptr;
  std::vector<double> source_explicit_;  // a_i [m/s^2] of S_i = a_i + b_i u_i(new), nodes 0..N
  std::vector<double> source_implicit_;  // b_i [1/s]
};

Result<std::unique_ptr<PipeSolver>> MakePipeSolver(PipeScheme scheme, const PipeConfig& config,
                                                   double p_bar_pa);

}  // namespace mpdrig
