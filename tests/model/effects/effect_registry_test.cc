#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/config/rig_config.h"
#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

using ::testing::HasSubstr;

TEST(EffectRegistry, EveryEffectIsDescribedAndDefaultsAreWithinBounds) {
  ASSERT_FALSE(EffectCatalogue().empty());
  for (const EffectInfo* info : EffectCatalogue()) {
    SCOPED_TRACE(info->name);
    EXPECT_EQ(FindEffectInfo(info->name), info);
    EXPECT_FALSE(info->summary.empty());
    EXPECT_FALSE(info->thesis.empty());
    EXPECT_FALSE(info->explains.empty());
    EXPECT_TRUE(info->create != nullptr);
    bool any_fitted = false;
    for (const EffectParamInfo& param : info->params) {
      EXPECT_LE(param.min_value, param.default_value) << param.key;
      EXPECT_LE(param.default_value, param.max_value) << param.key;
      EXPECT_FALSE(param.unit.empty()) << param.key;
      any_fitted |= param.fitted;
    }
    // diagnose needs at least one parameter to fit; an effect that is not a candidate has none
    // (it would be switched on and never told apart from the base model).
    EXPECT_EQ(any_fitted, info->diagnose_candidate) << "diagnose fits a candidate's parameters";
  }
}

TEST(EffectRegistry, UnknownEffectListsTheValidOnes) {
  RigParams params;
  const Status status = ApplyEffectSpec(&params, "gremlins");
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("unknown effect 'gremlins'"));
  EXPECT_THAT(status.message(), HasSubstr("unsteady_friction"));
  EXPECT_TRUE(params.effects.empty());
}

TEST(EffectRegistry, SpecSetsParametersAndChecksKeysNumbersAndBounds) {
  RigParams params;
  ASSERT_TRUE(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=0.2").ok());
  ASSERT_EQ(params.effects.size(), 1u);
  EXPECT_EQ(*params.effects[0].Find("time_constant_s"), 0.2);
  // Switching it on again merges.
  ASSERT_TRUE(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=0.1").ok());
  ASSERT_EQ(params.effects.size(), 1u);
  EXPECT_EQ(*params.effects[0].Find("time_constant_s"), 0.1);

  EXPECT_THAT(ApplyEffectSpec(&params, "sensor_lag:tau=1").message(),
              HasSubstr("has no parameter 'tau'"));
  EXPECT_THAT(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=abc").message(),
              HasSubstr("is not a number"));
  EXPECT_THAT(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=nan").message(),
              HasSubstr("finite"));
  EXPECT_THAT(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=50").message(),
              HasSubstr("outside"));
  EXPECT_THAT(ApplyEffectSpec(&params, "sensor_lag:time_constant_s").message(),
              HasSubstr("key=value"));
}

TEST(EffectRegistry, SetReachesAnEffectParameterOnlyWhenTheEffectIsOn) {
  RigParams params;
  EXPECT_THAT(ApplyOverride(&params, "unsteady_friction.k=0.05").message(),
              HasSubstr("not switched on"));
  ASSERT_TRUE(ApplyEffectSpec(&params, "unsteady_friction").ok());
  ASSERT_TRUE(ApplyOverride(&params, "unsteady_friction.k=0.05").ok());
  EXPECT_EQ(*params.FindEffect("unsteady_friction")->Find("k"), 0.05);
  ASSERT_TRUE(ApplyOverride(&params, "unsteady_friction.k=5").ok());  // bounds: the registry's
  EXPECT_THAT(ValidateEffects(params).message(), HasSubstr("outside"));
}

TEST(EffectRegistry, ConfigFileRoundTripsEffects) {
  RigParams params;
  ASSERT_TRUE(ApplyEffectSpec(&params, "unsteady_friction:k=0.07").ok());
  ASSERT_TRUE(ApplyEffectSpec(&params, "sensor_lag").ok());
  auto parsed = ParseRigConfig(FormatRigConfig(params), "round_trip.pbtxt");
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  ASSERT_EQ(parsed->effects.size(), 2u);
  EXPECT_EQ(parsed->effects[0].name, "unsteady_friction");
  EXPECT_EQ(*parsed->effects[0].Find("k"), 0.07);
  EXPECT_EQ(parsed->effects[1].name, "sensor_lag");
  EXPECT_TRUE(parsed->effects[1].values.empty());

  auto twice = ParseRigConfig("effect { name: \"sensor_lag\" }\neffect { name: \"sensor_lag\" }\n",
                              "twice.pbtxt");
  ASSERT_FALSE(twice.ok());
  EXPECT_THAT(twice.status().message(), HasSubstr("twice.pbtxt:2:1"));
}

TEST(EffectRegistry, SimulatorRefusesUnknownEffectsAndUnsupportedSchemes) {
  RigParams params;
  params.effects.push_back({"gremlins", {}});
  const RigInputs in = testing::Held(31, 5, 0);
  auto created = RigSimulator::Create(params, {}, in);
  ASSERT_FALSE(created.ok());
  EXPECT_THAT(created.status().message(), HasSubstr("unknown effect"));

  RigParams with_source;
  ASSERT_TRUE(ApplyEffectSpec(&with_source, "unsteady_friction").ok());
  SimulationOptions mol;
  mol.scheme = PipeScheme::kMethodOfLines;
  auto refused = RigSimulator::Create(with_source, mol, in);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), HasSubstr("unsteady_friction"));
  EXPECT_THAT(refused.status().message(), HasSubstr("characteristics"));
}

}  // namespace
}  // namespace mpdrig
