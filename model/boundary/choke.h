// The choke at the pipe outlet x = L: characteristic, actuator, and the boundary condition.
//
// Steady orifice equation (5.3.2), both flow directions (6.6.1-6.6.2):
//   q_c = q_b + A u(L)   (5.3.1),    p_c - p_0 = rho_L q_c |q_c| / G(u_c)^2,
// with p_c = p(L) the choke inlet pressure (C2) and p_0 the choke outlet pressure (C1).
// G(u_c): linear interpolation of Table 8.4.1, floored at the tuned leak of Table 9.4.1
// (design.md convention), G = max(G_table(u_c), leak) [m^2].
// Actuator (5.3, 8.4): first-order lag with time constant T and a rate limit,
//   du_c/dt = clamp((u_ref - u_c)/T, -r, r).
#pragma once

#include <vector>

#include "model/core/pipe_law.h"
#include "model/params/rig_params.h"

namespace mpdrig {

class ChokeCharacteristic {
 public:
  explicit ChokeCharacteristic(const RigParams& params);
  // G(u_c) [m^2] for an opening in [0, 1] (clamped to the table's range).
  double FlowCoefficientM2(double opening_frac) const;

 private:
  std::vector<ChokePoint> table_;
  double leak_m2_;
};

class ChokeActuator {
 public:
  explicit ChokeActuator(const RigParams& params)
      : time_constant_s_(params.choke_time_constant_s),
        rate_limit_per_s_(params.choke_rate_limit_frac_per_s) {}
  // The opening after dt_s, starting from `opening_frac`, driven towards `reference_frac`.
  double Advance(double opening_frac, double reference_frac, double dt_s) const;

 private:
  double time_constant_s_;
  double rate_limit_per_s_;
};

// Inputs of the outlet boundary, held over one step.
struct ChokeBoundaryInputs {
  double flow_coefficient_m2;  // G(u_c); 0 means a tight (leak-free) closed choke
  double pump_flow_m3ps;       // q_b, back-pressure pump, positive into the choke node
  double outlet_pressure_pa;   // p_0 (C1), absolute
};

// Solves the outlet boundary for u(L) given the arriving invariant alpha(L): the unique root of
//   F(u) = p(alpha, u) - p_0 - rho_L q_c|q_c|/G^2,  q_c = q_b + A u,
// which is strictly decreasing in u (p falls with u along an alpha characteristic, the orifice
// term rises). This replaces the bisection of (6.6.3)-(6.6.9)/(7.2.4)-(7.2.13): the linear model
// has the closed form below, the quasi-linear one is finished by a safeguarded Newton iteration.
class ChokeBoundary {
 public:
  ChokeBoundary(double pipe_area_m2, double choke_density_kgpm3)
      : area_m2_(pipe_area_m2), rho_l_(choke_density_kgpm3) {}
  // Returns u(L) [m/s]. `velocity_guess_mps` (e.g. the previous step's u(L)) only speeds up
  // the quasi-linear iteration; the answer does not depend on it.
  double SolveOutletVelocity(const PipeLaw& law, double alpha_l, const ChokeBoundaryInputs& in,
                             double velocity_guess_mps = 0.0) const;

 private:
  double area_m2_;
  double rho_l_;
};

}  // namespace mpdrig
