// The shadow model beside a rig: fed a rig's measured samples, its error over the window is small
// when it is the rig's model, and when the rig has a physical effect the shadow lacks, switching
// that effect on (SetParams replays the held rows) cuts the error, a wrong one does not.
#include "model/analysis/shadow_model.h"

#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

constexpr double kRateHz = 100.0;
constexpr int kCells = 50;  // the same grid for rig and shadow (a finer one only costs time)

SimulationOptions Grid() {
  SimulationOptions options;
  options.cells = kCells;
  return options;
}

// A heaving rig as the service runs it (RigHost::Tick): a 0.1 m, 0.25 Hz sine on the piston,
// choke commanded at 31 deg through its actuator, 10 L/min of pump; noise-free channels.
std::vector<RigSample> RigRun(const RigParams& params, double duration_s) {
  RigInputs inputs;
  inputs.choke_opening_frac = units::ChokeDegToFrac(31.0);
  inputs.pump_flow_m3ps = units::LpmToM3ps(10.0);
  inputs.outlet_pressure_pa = params.atmospheric_pressure_pa;
  auto simulator = RigSimulator::Create(params, Grid(), inputs);
  EXPECT_TRUE(simulator.ok()) << simulator.status().message();
  RigSampler sampler(std::move(simulator).value());
  auto x = [](double t) { return 0.1 * std::sin(2.0 * std::numbers::pi * 0.25 * t); };
  std::vector<RigSample> out;
  for (int i = 1; i <= static_cast<int>(duration_s * kRateHz); ++i) {
    auto sample = sampler.SampleAt(i / kRateHz, [&](double t_b, double dt) {
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

ShadowOptions Options() {
  ShadowOptions options;
  options.simulation = Grid();
  options.window_s = 10.0;
  options.warmup_s = 20.0;
  return options;
}

TEST(ShadowModel, NoErrorUntilWarmedUpThenSmallForTheRigsOwnModel) {
  const std::vector<RigSample> rig = RigRun(RigParams(), 40.0);
  auto shadow = ShadowModel::Create(RigParams(), Options());
  ASSERT_TRUE(shadow.ok());
  for (std::size_t i = 0; i < rig.size(); ++i) {
    ASSERT_TRUE((*shadow)->Push(rig[i]).ok());
    if (rig[i].time_s < 19.0) {
      EXPECT_TRUE(std::isnan((*shadow)->error())) << rig[i].time_s;
    }
  }
  // The same model, fed the rig's own inputs: only the piston velocity differs (a smoothed
  // difference of the sampled position instead of the sine's derivative) and the choke (the
  // actuator's output replayed as measured). A few percent of each channel's swing.
  const double error = (*shadow)->error();
  std::printf("  own model: error %.5f over %zu samples\n", error, (*shadow)->window_samples());
  EXPECT_LT(error, 0.05);
  EXPECT_GT((*shadow)->window_samples(), 900u);  // most of the 10 s window at 100 Hz
  EXPECT_FALSE((*shadow)->TakeOutput().empty());
}

TEST(ShadowModel, RightEffectHalvesTheErrorWrongOneDoesNot) {
  RigParams truth;
  ASSERT_TRUE(ApplyEffectSpec(&truth, "unsteady_friction").ok());
  const std::vector<RigSample> rig = RigRun(truth, 40.0);

  auto shadow = ShadowModel::Create(RigParams(), Options());
  ASSERT_TRUE(shadow.ok());
  for (const RigSample& s : rig) ASSERT_TRUE((*shadow)->Push(s).ok());
  const double without = (*shadow)->error();
  ASSERT_TRUE(std::isfinite(without));

  for (const EffectInfo* info : EffectCatalogue()) {
    RigParams candidate;
    ASSERT_TRUE(ApplyEffectSpec(&candidate, std::string(info->name)).ok());
    ASSERT_TRUE((*shadow)->SetParams(candidate).ok());
    const double with = (*shadow)->error();
    std::printf("  %-24s error %.4f (without %.4f)\n", std::string(info->name).c_str(), with,
                without);
    if (info->name == "unsteady_friction") {
      EXPECT_LE(with, 0.5 * without);
    } else {
      EXPECT_GT(with, 0.5 * without) << info->name << " is not what the rig has";
    }
  }
}

TEST(ShadowModel, RefusesABadParameterAndKeepsItsModel) {
  auto shadow = ShadowModel::Create(RigParams(), Options());
  ASSERT_TRUE(shadow.ok());
  RigParams bad;
  bad.wave_speed_mps = std::nan("");
  EXPECT_FALSE((*shadow)->SetParams(bad).ok());
  EXPECT_EQ((*shadow)->params().wave_speed_mps, RigParams().wave_speed_mps);
  // A sample without its inputs is skipped, not a crash.
  RigSample gap;
  gap.time_s = 1.0;
  gap.values.fill(std::nan(""));
  EXPECT_TRUE((*shadow)->Push(gap).ok());
  EXPECT_EQ((*shadow)->skipped_samples(), 1);
}

}  // namespace
}  // namespace mpdrig
