// "Fit now" for the shadow: a shadow started with a wrong wave speed, a wrong friction or an
// effect at a wrong strength, fed a rig's samples at the lab's sensor noise (thesis Table 4.1.1
// on every channel, the inputs too), fits c, f1 and the active effects' strengths on the rows it
// holds (FitShadowParameters, as `mpdrig fit`); the estimates land near the rig's truth and the
// shadow's error over its window falls once they are applied.
#include "model/identification/shadow_fit.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/shadow_model.h"
#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

constexpr double kRateHz = 100.0;
constexpr int kCells = 50;  // rig and shadow on the same grid; a finer one only costs time

using Excitation = testing::SineHeave;

// A heaving rig (sine on the piston, choke and pump held) read through the lab's noise.
std::vector<RigSample> NoisyRig(const RigParams& params, double duration_s, const Excitation& e,
                                std::uint64_t seed) {
  SimulationOptions grid;
  grid.cells = kCells;
  return testing::LabNoise(testing::HeavingRig(params, grid, kRateHz, duration_s, e), seed);
}

struct Case {
  const char* name;
  const char* truth_effect;  // "" : none
  const char* start_set;     // the shadow's wrong start: KEY=VALUE
  const char* key;           // the parameter that must come back
  double tolerance;          // relative
  Excitation excitation = {0.1, 0.25, 31.0, 10.0};
};

class ShadowFit : public ::testing::TestWithParam<Case> {};

TEST_P(ShadowFit, FitNowBringsTheWrongParameterBackAndTheErrorDown) {
  const Case& c = GetParam();
  for (const std::uint64_t seed : {7u, 8u}) {
    const Excitation& excitation = c.excitation;
    RigParams truth;
    if (*c.truth_effect != '\0') {
      ASSERT_TRUE(ApplyEffectSpec(&truth, c.truth_effect).ok());
    }
    RigParams start = truth;
    ASSERT_TRUE(ApplyOverride(&start, c.start_set).ok()) << c.start_set;
    const auto true_value = GetParamValue(truth, c.key);
    ASSERT_TRUE(true_value.ok());

    ShadowOptions options;
    options.simulation.cells = kCells;
    options.window_s = 10.0;
    options.warmup_s = 20.0;
    options.history_s = 60.0;
    auto shadow = ShadowModel::Create(start, options);
    ASSERT_TRUE(shadow.ok());
    for (const RigSample& s : NoisyRig(truth, 60.0, excitation, seed)) {
      ASSERT_TRUE((*shadow)->Push(s).ok());
    }
    const double before = (*shadow)->error();
    auto log = (*shadow)->HeldLog(60.0);
    ASSERT_TRUE(log.ok()) << log.status().message();
    auto fit = FitShadowParameters(std::move(log).value(), start, options.simulation);
    ASSERT_TRUE(fit.ok()) << fit.status().message();
    const auto estimate = GetParamValue(fit->params, c.key);
    ASSERT_TRUE(estimate.ok());
    ASSERT_TRUE((*shadow)->SetParams(fit->params).ok());
    const double after = (*shadow)->error();
    std::printf("  %s: %s, truth %g; shadow error %.4f -> %.4f\n", c.name, fit->summary.c_str(),
                *true_value, before, after);
    EXPECT_NEAR(*estimate, *true_value, c.tolerance * std::abs(*true_value)) << fit->summary;
    EXPECT_LT(after, 0.7 * before) << fit->summary;
  }
}

// Tolerances: at this noise and excitation `mpdrig fit` recovers c within a percent or two and f1
// and an effect's strength within some ten percent (their standard errors are of that order).
INSTANTIATE_TEST_SUITE_P(
    WrongStarts, ShadowFit,
    ::testing::Values(Case{"wave_speed", "", "wave_speed_mps=1100", "wave_speed_mps", 0.03},
                      Case{"friction", "", "friction_f1_per_s=0.6", "friction_f1_per_s", 0.25},
                      // A faster heave, where the transmitters' lag shows above the noise.
                      Case{"effect_strength",
                           "sensor_lag",
                           "sensor_lag.time_constant_s=0.01",
                           "sensor_lag.time_constant_s",
                           0.3,
                           {0.08, 0.4, 40.0, 15.0}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(ShadowFitParameters, BaseKeysThenTheActiveEffectsStrengths) {
  RigParams params;
  ASSERT_TRUE(ApplyEffectSpec(&params, "sensor_lag").ok());
  auto parameters = ShadowFitParameters(params);
  ASSERT_TRUE(parameters.ok());
  ASSERT_GE(parameters->size(), 3u);
  EXPECT_EQ((*parameters)[0].key, "wave_speed_mps");
  EXPECT_EQ((*parameters)[1].key, "friction_f1_per_s");
  EXPECT_EQ((*parameters)[2].key.rfind("sensor_lag.", 0), 0u);
}

}  // namespace
}  // namespace mpdrig
