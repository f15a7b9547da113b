// The heave generator at the pipe inlet x = 0 (thesis 5.4).
//
// The BHA (piston) moves with velocity v_d (positive up) in a closed compartment; the upper rod
// (area A_d) leaves and the lower rod (area A_d2) enters it, so the displaced flow into the pipe is
//   q_0 = -v_d (A_d - A_d2)                                  (5.4.1)
// and the pressure below the BHA (P1, floor level) is above the pipe inlet pressure (P2 = p(0)) by
//   p_b - p_p = f_d1 v_d + f_d2 v_d |v_d| + rho g h          (5.4.2)
// with the empirical friction of (8.2.1) and the compartment height h.
#pragma once

#include "model/params/rig_params.h"

namespace mpdrig {

class PistonBoundary {
 public:
  explicit PistonBoundary(const RigParams& params)
      : displacement_area_m2_(params.PistonDisplacementAreaM2()),
        pipe_area_m2_(params.PipeAreaM2()),
        fd1_(params.piston_friction_fd1_pa_s_per_m),
        fd2_(params.piston_friction_fd2_pa_s2_per_m2),
        rho_g_h_(params.density_kgpm3 * params.gravity_mps2 * params.compartment_height_m) {}

  double InletFlowM3ps(double piston_velocity_mps) const {  // (5.4.1)
    return -piston_velocity_mps * displacement_area_m2_;
  }
  double InletVelocityMps(double piston_velocity_mps) const {  // u(0) = q_0 / A, (9.2.5)
    return InletFlowM3ps(piston_velocity_mps) / pipe_area_m2_;
  }
  double BelowPistonPressurePa(double inlet_pressure_pa, double piston_velocity_mps) const {
    const double v = piston_velocity_mps;
    return inlet_pressure_pa + fd1_ * v + fd2_ * v * (v < 0 ? -v : v) + rho_g_h_;  // (5.4.2)
  }

 private:
  double displacement_area_m2_;
  double pipe_area_m2_;
  double fd1_;
  double fd2_;
  double rho_g_h_;
};

}  // namespace mpdrig
