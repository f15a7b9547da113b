// Hooks through which physics beyond the thesis's pipe model reaches a pipe solver.
//
// A PipeExtension is what a pipe solver sees of a physical effect (model/effects/effect.h): an
// extra momentum source along the pipe, or its own closure of an end of the pipe. Every hook has
// a neutral default, so an extension overrides only what it changes. A solver that does not
// support a hook an extension uses refuses it at creation (PipeSolver::SetExtensions), so an
// effect is never silently ignored.
//
// The pipe layer knows nothing of effects: model/effects depends on this header, not the reverse.
#pragma once

#include <span>

#include "model/boundary/choke.h"
#include "model/core/pipe_law.h"

namespace mpdrig {

struct PipeConfig;

// What a momentum source may read: the state at the current time level, before the step.
struct PipeSnapshot {
  const PipeConfig& config;
  const PipeLaw& law;
  std::span<const double> alpha;  // nodes 0..N
  std::span<const double> beta;
  double dt_s;
};

// The pressure at a boundary node as a function of that node's velocity, once the invariant
// arriving from inside the pipe is known: at x = 0 the beta characteristic,
// p = P(alpha - beta) with alpha = 2u - beta; at x = L the alpha characteristic. Strictly
// monotonic in u (the pipe's impedance), so closures can solve for u with a safeguarded Newton
// (SolveDecreasing, model/common/root_finding.h).
class BoundaryRelation {
 public:
  virtual ~BoundaryRelation() = default;
  virtual double PressurePa(double velocity_mps) const = 0;
  virtual double DPressureDVelocity(double velocity_mps) const = 0;
  // Both at once: p(u), and dp/du in *slope. The solver's relations get the slope from the
  // pressure, so this evaluates the pressure law (an exp, or a mixture law's inversion) once
  // where the two calls above evaluate it twice; a closure's Newton iteration needs both.
  virtual double PressureAndSlope(double velocity_mps, double* slope) const {
    *slope = DPressureDVelocity(velocity_mps);
    return PressurePa(velocity_mps);
  }
};

// The inlet's inputs at the end of a step.
struct InletInputs {
  double displaced_flow_m3ps = 0.0;  // q_0 of (5.4.1): what a rigid heave generator would push
  double area_m2 = 0.0;              // pipe cross-section A
  double dt_s = 0.0;
};

class PipeExtension {
 public:
  virtual ~PipeExtension() = default;

  // --- A momentum source S [m/s^2] along the pipe -----------------------------------------------
  // Acts like friction: d(alpha)/dt = d(beta)/dt = -g sin(gamma) - f(u) - S along both
  // characteristics (6.1.16-6.1.17). Semi-implicit: S_i = a_i + b_i u_i(new), with a_i and
  // b_i >= 0 evaluated from the state before the step. The b part is treated implicitly (as the
  // base friction's f1 is), so a stiff damping term stays stable at any step; the a part is
  // explicit, first order in time.
  virtual bool adds_momentum_source() const { return false; }
  // Adds to explicit_mps2[i] (a_i) and implicit_per_s[i] (b_i) for every node i = 0..N.
  virtual void AddMomentumSource(const PipeSnapshot& /*state*/, std::span<double> /*explicit_mps2*/,
                                 std::span<double> /*implicit_per_s*/) const {}

  // --- The inlet x = 0 --------------------------------------------------------------------------
  // By default u(0) = q_0 / A (5.4.1, 6.7.1). An extension that closes the inlet returns u(0)
  // from the relation the pipe imposes; it may hold states (advanced by its owner after the step).
  virtual bool closes_inlet() const { return false; }
  virtual double SolveInletVelocity(const BoundaryRelation& /*pipe*/,
                                    const InletInputs& inputs) const {
    return inputs.displaced_flow_m3ps / inputs.area_m2;
  }

  // --- Extra compressibility of the pipe's contents (e.g. entrained gas) ------------------------
  // Adds C_x(p) >= 0 [1/Pa] to the liquid's compressibility 1/(rho c^2) at absolute pressure p, so
  // the local wave speed falls to c(p) = 1 / sqrt(rho (1/(rho c^2) + C_x(p))) <= c (thesis 8.3.5,
  // 8.3.6; the density stays the liquid's: small fractions). Must be >= 0: the grid is built for
  // the rig's wave speed c, which is the upper bound. A function of p only, called when the
  // solver tabulates the invariants (once per run).
  virtual bool changes_compressibility() const { return false; }
  virtual double ExtraCompressibilityPerPa(double /*pressure_pa*/) const { return 0.0; }

  // --- Column separation at the vapour pressure -------------------------------------------------
  // Where the pressure would fall below p_v [Pa abs], the liquid column separates: the pressure
  // is held at p_v and a vapour cavity opens (the discrete vapour cavity model, see
  // characteristics_solver.h). The cavity volumes are the solver's state.
  virtual bool has_vapour_pressure() const { return false; }
  virtual double VapourPressurePa() const { return 0.0; }
  // Free gas with the cavities: the discrete gas cavity model (DGCM, Wylie 1984) instead of the
  // vapour cavities. A void fraction alpha_0 of free gas at the reference pressure p_0 [Pa abs]
  // lumped at every node; its volume follows the isothermal law of its partial pressure,
  // V_g (p - p_v) = alpha_0 A dx (p_0 - p_v). void_fraction 0: the DVCM (the default).
  // weighting: psi of the gas volume's continuity, V = V_old + dt A (psi jump + (1 - psi)
  // jump_old), in [0.5, 1] (characteristics_solver.h).
  struct FreeGas {
    double void_fraction = 0.0;
    double reference_pressure_pa = 0.0;
    double weighting = 1.0;
  };
  virtual FreeGas CavityFreeGas() const { return {}; }

  // --- The outlet x = L -------------------------------------------------------------------------
  // By default the steady orifice equation (5.3.2) through ChokeBoundary.
  virtual bool closes_outlet() const { return false; }
  virtual double SolveOutletVelocity(const BoundaryRelation& /*pipe*/,
                                     const ChokeBoundaryInputs& /*choke*/, double /*dt_s*/,
                                     double velocity_guess_mps) const {
    return velocity_guess_mps;
  }
};

}  // namespace mpdrig
