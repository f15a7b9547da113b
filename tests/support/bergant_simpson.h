// The Bergant & Simpson (1999) reservoir - pipe - valve rig as the repository's examples describe
// it (docs/examples/bergant-simpson-1999*.pbtxt, docs/bergant-simpson.md), for the tests that run
// it. Header-only; the including test target defines MPDRIG_SOURCE_DIR.
#pragma once

#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "model/config/rig_config.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::testing {

// The severe case (1.4 m/s) and the moderate one (0.3 m/s).
inline const std::string kBergantSimpsonSevere =
    std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999.pbtxt";
inline const std::string kBergantSimpsonModerate =
    std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999-moderate.pbtxt";

// The rig of an example config (a failure is the test's, with the loader's message).
inline RigParams LoadExampleRig(const std::string& path) {
  auto params = LoadRigConfig(path);
  EXPECT_TRUE(params.ok()) << params.status().message();
  return params.ok() ? *params : RigParams();
}

// The example with the discrete vapour cavity model in place of the examples' discrete gas cavity
// model (column_separation's gas_void_fraction 0): for the tests of the DVCM's closed forms and of
// what does not involve cavities, whose results then do not depend on the examples' choice.
inline RigParams LoadExampleRigWithVapourCavities(const std::string& path) {
  RigParams params = LoadExampleRig(path);
  EffectSetting* cavities = params.FindEffect("column_separation");
  EXPECT_NE(cavities, nullptr) << path;
  if (cavities != nullptr) cavities->Set("gas_void_fraction", 0.0);
  return params;
}

// Runs the rig from its steady start for `duration_s` at its own boundaries (no step inputs: the
// reservoir and the valve's closure law drive it), calling `record` at the start and after every
// grid step. Returns the time step (0 where the rig cannot be built; a failed step ends the run;
// both are the test's failures).
inline double StepValveRig(const RigParams& params, const SimulationOptions& options,
                           double duration_s,
                           const std::function<void(const RigSimulator&)>& record) {
  auto created = RigSimulator::Create(params, options, RigInputs{});
  EXPECT_TRUE(created.ok()) << created.status().message();
  if (!created.ok()) return 0.0;
  RigSimulator sim = std::move(created).value();
  record(sim);
  while (sim.time_s() < duration_s) {
    const Status status = sim.Step(StepInputs{});
    EXPECT_TRUE(status.ok()) << status.message();
    if (!status.ok()) break;
    record(sim);
  }
  return sim.time_step_s();
}

}  // namespace mpdrig::testing
