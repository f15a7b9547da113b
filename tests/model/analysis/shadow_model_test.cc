// The shadow model beside a rig: fed a rig's measured samples, its error over the window is small
// when it is the rig's model, and when the rig has a physical effect the shadow lacks, switching
// that effect on (SetParams replays the held rows) cuts the error, a wrong one does not.
#include "model/analysis/shadow_model.h"

#include <cmath>
#include <cstdlib>
#include <string>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/effects/effect.h"
#include "model/sim/sensor_noise.h"

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
struct Excitation {
  double amplitude_m = 0.1, frequency_hz = 0.25, choke_deg = 31.0, pump_lpm = 10.0;
};

std::vector<RigSample> RigRun(const RigParams& params, double duration_s,
                              const Excitation& e = {}) {
  RigInputs inputs;
  inputs.choke_opening_frac = units::ChokeDegToFrac(e.choke_deg);
  inputs.pump_flow_m3ps = units::LpmToM3ps(e.pump_lpm);
  inputs.outlet_pressure_pa = params.atmospheric_pressure_pa;
  auto simulator = RigSimulator::Create(params, Grid(), inputs);
  EXPECT_TRUE(simulator.ok()) << simulator.status().message();
  RigSampler sampler(std::move(simulator).value());
  auto x = [&e](double t) {
    return e.amplitude_m * std::sin(2.0 * std::numbers::pi * e.frequency_hz * t);
  };
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

// The rig's samples as the lab reads them: thesis Table 4.1.1 on every channel (inputs too), or
// on the outputs only (the inputs as they truly were: what a perfect reconstruction would feed).
std::vector<RigSample> LabNoise(std::vector<RigSample> rig, std::uint64_t seed,
                                bool inputs_too = true) {
  SensorNoiseApplier noise(SensorNoise::Lab(), seed);
  for (RigSample& s : rig) {
    const RigSample truth = s;
    noise.MeasureSample(&s);
    if (!inputs_too) {
      for (Channel c : {Channel::kPistonPosition, Channel::kChokePosition, Channel::kFT2,
                        Channel::kC1})
        s.values[Index(c)] = truth.values[Index(c)];
    }
  }
  return rig;
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

// The shadow's error over its window after every row of `rig`, with `params`, then with each of
// `candidates` (SetParams replays the held rows).
struct Scores {
  double without = NAN;
  std::vector<double> with;
};
Scores Score(const std::vector<RigSample>& rig, const ShadowOptions& options,
             const std::vector<RigParams>& candidates) {
  Scores scores;
  auto shadow = ShadowModel::Create(RigParams(), options);
  EXPECT_TRUE(shadow.ok());
  for (const RigSample& s : rig) EXPECT_TRUE((*shadow)->Push(s).ok());
  scores.without = (*shadow)->error();
  for (const RigParams& candidate : candidates) {
    EXPECT_TRUE((*shadow)->SetParams(candidate).ok());
    scores.with.push_back((*shadow)->error());
  }
  return scores;
}

// At the lab's noise (Table 4.1.1 on every channel, the inputs too): the right effect halves the
// error, a wrong one does not. Effects the lab's noise hides are reported, with the noise floor.
TEST(ShadowModel, AtLabNoiseTheRightEffectHalvesTheError) {
  const char* list = std::getenv("MPDRIG_SHADOW_EFFECTS");
  std::vector<std::string> effects = {"unsteady_friction", "choke_inertia", "sensor_lag"};
  if (list != nullptr) {
    effects.clear();
    std::string text = list;
    for (std::size_t a = 0; a <= text.size();) {
      const std::size_t b = std::min(text.find(',', a), text.size());
      if (b > a) effects.push_back(text.substr(a, b - a));
      a = b + 1;
    }
  }
  const bool raw = std::getenv("MPDRIG_SHADOW_RAW") != nullptr;
  for (std::uint64_t seed : {1u, 2u}) {
    const Excitation excitation =
        seed == 1 ? Excitation{} : Excitation{0.08, 0.4, 40.0, 15.0};
    for (const std::string& effect : effects) {
      RigParams truth;
      ASSERT_TRUE(ApplyEffectSpec(&truth, effect).ok());
      const std::vector<RigSample> clean = RigRun(truth, 50.0, excitation);
      ShadowOptions options = Options();
      options.reconstruct_inputs = !raw;
      std::vector<RigParams> candidates = {truth};
      std::vector<std::string> names = {effect};
      for (const char* wrong : {"helical_friction", "piston_compressibility", "unsteady_friction"}) {
        if (effect == wrong) continue;
        RigParams candidate;
        ASSERT_TRUE(ApplyEffectSpec(&candidate, wrong).ok());
        candidates.push_back(candidate);
        names.emplace_back(wrong);
      }
      const Scores scores = Score(LabNoise(clean, seed), options, candidates);
      // The floor: the true model fed the true inputs, scored against the noisy outputs.
      ShadowOptions exact = Options();
      exact.reconstruct_inputs = false;
      exact.smoothing_s = 0.0;
      const Scores floor = Score(LabNoise(clean, seed, false), exact, {truth});
      std::printf("  seed %llu %-20s without %.4f  right %.4f  floor %.4f  ratio %.2f |",
                  static_cast<unsigned long long>(seed), effect.c_str(), scores.without,
                  scores.with[0], floor.with[0], scores.with[0] / scores.without);
      for (std::size_t k = 1; k < names.size(); ++k)
        std::printf(" %s %.3f", names[k].c_str(), scores.with[k]);
      std::printf("\n");
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
