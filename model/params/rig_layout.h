// What sits at the two ends of the pipe: the rig's layout.
//
// The default is the NTNU rig of the thesis (chapter 5): the heave generator (piston, 5.4) at
// x = 0, the choke with its back-pressure pump (5.3) at x = L, the pipe starting at rest (6.5).
// The other layout is the classic water-hammer apparatus (reservoir - pipe - valve; Wylie &
// Streeter, Fluid Transients in Systems, 1993, ch. 3; Bergant & Simpson, J. Hydraul. Eng. 125(8),
// 1999):
//   x = 0: a reservoir at a constant head,       p(0) = p_atm + rho g H_R
//          (no entrance loss: the velocity head V0^2 / 2g is 0.1 m at 1.4 m/s),
//   x = L: a valve discharging into a downstream reservoir, an orifice with a closure law
//          q = tau(t) G_0 sqrt((p(L) - p_d) / rho),  p_d = p_atm + rho g H_d,
//          the same orifice equation as the choke (5.3.2) with G = tau(t) G_0 and no pump,
//   t = t0: steady flow V0 throughout: p(x) falls from p(0) with friction and gravity,
//          dp/dx = -rho (f(V0) + g sin(gamma)), and G_0 makes the valve pass V0 at p(L).
// The relative opening tau(t) in [0, 1] (1 open) is either tau = (1 - (t - t_s)/t_c)^m for
// t_s <= t <= t_s + t_c (Wylie & Streeter's closure law; m = 1 linear in the valve's effective
// area), 1 before and 0 after, or linear between given points (t_k, tau_k), held beyond them.
//
// Config example (rig_config.proto):
//   reservoir { head_m: 22 }
//   valve { closure_time_s: 0.009 }
//   steady_flow { velocity_mps: 1.4 }
#pragma once

#include <string>
#include <vector>

#include "model/common/status.h"

namespace mpdrig {

struct ValveOpeningPoint {
  double time_s = 0.0;
  double opening = 0.0;  // tau in [0, 1]
};

struct ValveClosure {
  double start_s = 0.0;                   // t_s
  double closure_time_s = 0.0;            // t_c > 0 (when no points are given)
  double exponent = 1.0;                  // m
  std::vector<ValveOpeningPoint> points;  // if any: tau linear between them, instead of t_c, m
  double downstream_head_m = 0.0;         // H_d, gauge, metres of the liquid

  // tau(t) in [0, 1].
  double RelativeOpening(double time_s) const;
  // The time tau first reaches 0 (infinity if it never does).
  double ClosedAtS() const;
  Status Validate() const;
};

struct RigLayout {
  enum class Inlet { kHeaveGenerator, kReservoir };
  enum class Outlet { kChoke, kValve };

  Inlet inlet = Inlet::kHeaveGenerator;
  Outlet outlet = Outlet::kChoke;
  double reservoir_head_m = 0.0;  // H_R: gauge pressure head at the pipe inlet, m of the liquid
  ValveClosure valve;
  double steady_velocity_mps = 0.0;  // V0, the flow the run starts from (reservoir and valve)

  bool is_ntnu_rig() const { return inlet == Inlet::kHeaveGenerator && outlet == Outlet::kChoke; }
  // The layouts the simulator assembles: the NTNU rig, or reservoir - pipe - valve.
  Status Validate() const;
  // "heave generator - pipe - choke" or "reservoir 22 m - pipe - valve (closes in 0.009 s), V0 =
  // 1.4 m/s".
  std::string Describe() const;
};

}  // namespace mpdrig
