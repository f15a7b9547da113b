// Method of lines (thesis 6.1.2, Table 6.3.1): the invariants at the grid nodes are ODE states,
//   y = [alpha_1 .. alpha_N, beta_0 .. beta_{N-1}]   (2N states; alpha_0 and beta_N are set by
//   the piston (6.7.1) and choke (6.6.1) boundaries at every right-hand-side evaluation),
//   alpha_i' = -(c + u_i) D-alpha_i - g sin(gamma) - f(u_i)    (6.1.16; linear: c instead of c+u)
//   beta_i'  =  (c - u_i) D+beta_i  - g sin(gamma) - f(u_i)    (6.1.17)
// D-, D+: upwind differences. The thesis used first order; that scheme's numerical damping
// (c dx k^2 / 2) is about a tenth of the physical one at 0.5 Hz even at N = 1000, so the
// resonance peaks come out too low. Second-order one-sided upwind differences
// (3 y_i - 4 y_{i-1} + y_{i-2}) / (2 dx) are used instead, first order next to the boundaries.
// Time integration: SUNDIALS ARKODE ERKStep (explicit adaptive Runge-Kutta, default 4th-order
// table), relative tolerance 1e-5, absolute 1e-8 m/s, stopping exactly at each outer step.
// Initial values: whatever SetRestState or the previous step left. Interval: one step at a time.
#pragma once

#include <memory>

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include "model/pipe/pipe_solver.h"

namespace mpdrig {

class MolSolver final : public PipeSolver {
 public:
  static Result<std::unique_ptr<MolSolver>> Create(const PipeConfig& config, double p_bar_pa);
  ~MolSolver() override;
  MolSolver(const MolSolver&) = delete;
  MolSolver& operator=(const MolSolver&) = delete;

  double time_step_s() const override { return dt_s_; }
  Status Step(const PipeStepInputs& inputs, RangeViolation* violation) override;

 private:
  MolSolver(const PipeConfig& config, double p_bar_pa);
  void OnStateReset() override { state_loaded_ = false; }
  Status Initialize();
  static int RightHandSide(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data);
  // The boundary inputs at time t within the current step (linear from start to end).
  PipeBoundaryValues BoundaryAt(double t) const;
  // Fills alpha_/beta_ (all nodes) from the ODE state y and the boundary conditions.
  void ExpandState(const double* y, const PipeBoundaryValues& boundary);
  Status LoadStateIntoSolver();

  double dt_s_;
  double t_s_ = 0.0;
  bool state_loaded_ = false;
  PipeStepInputs inputs_{};
  SUNContext context_ = nullptr;
  N_Vector y_ = nullptr;
  void* arkode_ = nullptr;
};

}  // namespace mpdrig
