// Helpers shared by the physics tests: drive a RigSimulator step by step with time functions, or
// sample a heaving rig as the service runs it and read it through the lab's sensor noise.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"

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

// A heave as the service runs it (RigHost::Tick): a sine on the piston, the choke commanded at
// choke_deg through its actuator, the pump held.
struct SineHeave {
  double amplitude_m = 0.1, frequency_hz = 0.25, choke_deg = 31.0, pump_lpm = 10.0;
};

// The rig's samples at `rate_hz` from 1/rate_hz to `duration_s` under `heave`, noise-free.
inline std::vector<RigSample> HeavingRig(const RigParams& params, const SimulationOptions& grid,
                                         double rate_hz, double duration_s,
                                         const SineHeave& heave = {}) {
  RigInputs inputs;
  inputs.choke_opening_frac = units::ChokeDegToFrac(heave.choke_deg);
  inputs.pump_flow_m3ps = units::LpmToM3ps(heave.pump_lpm);
  inputs.outlet_pressure_pa = params.atmospheric_pressure_pa;
  auto simulator = RigSimulator::Create(params, grid, inputs);
  EXPECT_TRUE(simulator.ok()) << simulator.status().message();
  RigSampler sampler(std::move(simulator).value());
  auto x = [&heave](double t) {
    return heave.amplitude_m * std::sin(2.0 * std::numbers::pi * heave.frequency_hz * t);
  };
  std::vector<RigSample> out;
  for (int i = 1; i <= static_cast<int>(duration_s * rate_hz); ++i) {
    auto sample = sampler.SampleAt(i / rate_hz, [&](double t_b, double dt) {
      StepInputs step;
      step.piston_velocity_mps = (x(t_b + 0.5 * dt) - x(t_b - 0.5 * dt)) / dt;
      step.piston_position_m = x(t_b);
      step.rig = inputs;
      return step;
    });
    EXPECT_TRUE(sample.ok());
    if (!sample.ok()) break;
    out.push_back(std::move(sample).value());
  }
  return out;
}

// The rig's samples as the lab reads them: thesis Table 4.1.1 on every channel (inputs too), or
// on the outputs only (the inputs as they truly were: what a perfect reconstruction would feed).
inline std::vector<RigSample> LabNoise(std::vector<RigSample> rig, std::uint64_t seed,
                                       bool inputs_too = true) {
  SensorNoiseApplier noise(SensorNoise::Lab(), seed);
  for (RigSample& s : rig) {
    const RigSample truth = s;
    noise.MeasureSample(&s);
    if (!inputs_too) {
      for (Channel c :
           {Channel::kPistonPosition, Channel::kChokePosition, Channel::kFT2, Channel::kC1})
        s.values[Index(c)] = truth.values[Index(c)];
    }
  }
  return rig;
}

}  // namespace mpdrig::testing
