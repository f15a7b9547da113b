// Helpers shared by the physics tests: drive a RigSimulator step by step with time functions.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::testing {

// Every parameter of the thesis, with the quadratic friction removed when a test compares with
// the linear-friction closed forms of chapter 9.
inline RigParams LinearFrictionParams() {
  RigParams params;
  params.friction_f2_per_m = 0.0;
  return params;
}

struct Drive {
  std::function<double(double)> piston_position_m = [](double) { return 0.0; };
  std::function<RigInputs(double)> rig;
};

// Steps the simulator from t = 0 to `duration_s`; calls `observe` after every step (and once at
// t = 0). Piston velocity: centred difference of the position over the step, as Simulate() does.
inline RigSimulator RunSteps(const RigParams& params, const SimulationOptions& options,
                             const Drive& drive, double duration_s,
                             const std::function<void(const RigSimulator&)>& observe = {}) {
  auto created =
      RigSimulator::Create(params, options, drive.rig(0.0), drive.piston_position_m(0.0));
  EXPECT_TRUE(created.ok()) << created.status().message();
  RigSimulator sim = std::move(created).value();
  if (observe) observe(sim);
  const double dt = sim.time_step_s();
  const long steps = std::lround(duration_s / dt);
  for (long n = 1; n <= steps; ++n) {
    const double t = n * dt;
    StepInputs in;
    in.piston_velocity_mps =
        (drive.piston_position_m(t + 0.5 * dt) - drive.piston_position_m(t - 0.5 * dt)) / dt;
    in.piston_position_m = drive.piston_position_m(t);
    in.rig = drive.rig(t);
    const Status status = sim.Step(in);
    EXPECT_TRUE(status.ok()) << status.message();
    if (!status.ok()) break;
    if (observe) observe(sim);
  }
  return sim;
}

inline RigInputs Held(double choke_deg, double pump_lpm, double outlet_barg) {
  RigInputs in;
  in.choke_opening_frac = units::ChokeDegToFrac(choke_deg);
  in.pump_flow_m3ps = units::LpmToM3ps(pump_lpm);
  in.outlet_pressure_pa = units::BargToPaAbs(outlet_barg, units::kStandardAtmospherePa);
  return in;
}

// The four (model, scheme) combinations every physics property must hold for.
struct Variant {
  PipeModel model;
  PipeScheme scheme;
};
inline std::vector<Variant> AllVariants() {
  return {{PipeModel::kQuasiLinear, PipeScheme::kCharacteristics},
          {PipeModel::kLinear, PipeScheme::kCharacteristics},
          {PipeModel::kQuasiLinear, PipeScheme::kMethodOfLines},
          {PipeModel::kLinear, PipeScheme::kMethodOfLines}};
}
inline std::string VariantName(const ::testing::TestParamInfo<Variant>& info) {
  return std::string(info.param.model == PipeModel::kLinear ? "Linear" : "QuasiLinear") +
         (info.param.scheme == PipeScheme::kCharacteristics ? "Characteristics" : "MethodOfLines");
}

}  // namespace mpdrig::testing
