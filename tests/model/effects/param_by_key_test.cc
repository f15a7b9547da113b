// The accessor of a parameter by key, base or effect (model/effects/param_by_key.h): values read
// and set through both tables, their ranges, and an error that says why for every bad key or
// value, with the params left as they were.
#include "model/effects/param_by_key.h"

#include <limits>
#include <string>
#include <utility>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace mpdrig {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

RigParams WithSensorLag() {
  RigParams params;
  params.effects.push_back({"sensor_lag", {}});
  return params;
}

TEST(ParamByKey, ABaseKeyIsItsFieldOfRigParams) {
  RigParams params;
  auto value = GetParamValue(params, "wave_speed_mps");
  ASSERT_TRUE(value.ok()) << value.status().message();
  EXPECT_EQ(*value, 850.0);  // Table 9.4.1
  ASSERT_TRUE(SetParamValue(&params, "wave_speed_mps", 1173.0).ok());
  EXPECT_EQ(params.wave_speed_mps, 1173.0);
  // Bounds are inclusive (ParamTable(): 10..5000 m/s).
  EXPECT_TRUE(SetParamValue(&params, "wave_speed_mps", 10.0).ok());
  EXPECT_TRUE(SetParamValue(&params, "wave_speed_mps", 5000.0).ok());

  auto found = FindParamByKey("wave_speed_mps");
  ASSERT_TRUE(found.ok());
  EXPECT_EQ(found->base, FindParam("wave_speed_mps"));
  EXPECT_EQ(found->effect, nullptr);
  EXPECT_EQ(found->unit, "m/s");
  EXPECT_EQ(found->min_value, 10.0);
  EXPECT_EQ(found->max_value, 5000.0);
  // The thesis's tuning range (ParamInfo::fit_min, fit_max).
  EXPECT_EQ(found->FitRange(), std::make_pair(300.0, 1500.0));
  // No tuning range given: a factor of 3 either way around the thesis value, 0.1 s (5.3).
  auto lag = FindParamByKey("choke_time_constant_s");
  ASSERT_TRUE(lag.ok());
  EXPECT_DOUBLE_EQ(lag->FitRange().first, 0.1 / 3.0);
  EXPECT_DOUBLE_EQ(lag->FitRange().second, 0.1 * 3.0);
}

TEST(ParamByKey, AnEffectKeyIsItsSettingWithTheCataloguesDefault) {
  RigParams params = WithSensorLag();
  auto value = GetParamValue(params, "sensor_lag.time_constant_s");
  ASSERT_TRUE(value.ok()) << value.status().message();
  EXPECT_EQ(*value, 0.05);  // the catalogue's default, nothing set yet
  ASSERT_TRUE(SetParamValue(&params, "sensor_lag.time_constant_s", 0.2).ok());
  ASSERT_EQ(params.effects.size(), 1u);
  ASSERT_NE(params.effects[0].Find("time_constant_s"), nullptr);
  EXPECT_EQ(*params.effects[0].Find("time_constant_s"), 0.2);
  // Set again: replaced, not appended.
  ASSERT_TRUE(SetParamValue(&params, "sensor_lag.time_constant_s", 0.3).ok());
  EXPECT_EQ(params.effects[0].values.size(), 1u);
  EXPECT_EQ(*GetParamValue(params, "sensor_lag.time_constant_s"), 0.3);

  auto found = FindParamByKey("sensor_lag.time_constant_s");
  ASSERT_TRUE(found.ok());
  EXPECT_EQ(found->base, nullptr);
  EXPECT_EQ(found->effect, FindEffectInfo("sensor_lag"));
  ASSERT_NE(found->effect_param, nullptr);
  EXPECT_EQ(found->effect_param->key, "time_constant_s");
  EXPECT_EQ(found->unit, "s");
  // An effect's fit range is its bounds.
  EXPECT_EQ(found->min_value, 0.0);
  EXPECT_EQ(found->max_value, 1.0);
  EXPECT_EQ(found->FitRange(), std::make_pair(0.0, 1.0));
}

TEST(ParamByKey, AnEffectThatIsNotSwitchedOnIsAnError) {
  RigParams params;
  auto value = GetParamValue(params, "sensor_lag.time_constant_s");
  ASSERT_FALSE(value.ok());
  EXPECT_EQ(value.status().message(),
            "sensor_lag.time_constant_s: effect 'sensor_lag' is not switched on");
  const Status set = SetParamValue(&params, "sensor_lag.time_constant_s", 0.2);
  ASSERT_FALSE(set.ok());
  EXPECT_THAT(set.message(), HasSubstr("not switched on"));
  EXPECT_TRUE(params.effects.empty());  // not switched on by the setter either
}

TEST(ParamByKey, AnUnknownKeyListsTheValidOnes) {
  RigParams params = WithSensorLag();
  // A base key: every key of the table, and the effects' form.
  auto base = GetParamValue(params, "wave_speed");
  ASSERT_FALSE(base.ok());
  const std::string message = base.status().message();
  EXPECT_THAT(message, HasSubstr("unknown parameter 'wave_speed'; valid keys: "));
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_THAT(message, HasSubstr(std::string(info.key)));
  }
  EXPECT_THAT(message, HasSubstr(", or EFFECT.KEY of an effect (`mpdrig effects`)"));
  // An unknown effect: the effects.
  const Status effect = SetParamValue(&params, "no_such_effect.k", 1.0);
  ASSERT_FALSE(effect.ok());
  EXPECT_THAT(effect.message(),
              HasSubstr("no_such_effect.k: unknown effect 'no_such_effect'; valid effects: "));
  for (const EffectInfo* info : EffectCatalogue()) {
    EXPECT_THAT(effect.message(), HasSubstr(std::string(info->name)));
  }
  // An unknown key of a known effect: that effect's keys.
  auto key = FindParamByKey("sensor_lag.tau");
  ASSERT_FALSE(key.ok());
  EXPECT_EQ(key.status().message(),
            "unknown parameter 'sensor_lag.tau'; valid keys: sensor_lag.time_constant_s");
}

TEST(ParamByKey, AValueOutsideTheBoundsIsRefusedAndChangesNothing) {
  RigParams params = WithSensorLag();
  const Status base = SetParamValue(&params, "wave_speed_mps", 1.0);
  ASSERT_FALSE(base.ok());
  EXPECT_EQ(base.message(), "wave_speed_mps = 1 m/s is outside [10, 5000]");  // CheckInRange
  EXPECT_EQ(params.wave_speed_mps, 850.0);
  const Status effect = SetParamValue(&params, "sensor_lag.time_constant_s", 2.0);
  ASSERT_FALSE(effect.ok());
  EXPECT_EQ(effect.message(), "sensor_lag.time_constant_s = 2 s is outside [0, 1]");
  EXPECT_TRUE(params.effects[0].values.empty());
}

TEST(ParamByKey, NaNAndInfinitiesAreRefusedAndChangeNothing) {
  for (const double bad :
       {kNaN, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
    RigParams params = WithSensorLag();
    const Status base = SetParamValue(&params, "wave_speed_mps", bad);
    ASSERT_FALSE(base.ok()) << bad;
    EXPECT_EQ(base.message(), "wave_speed_mps: value must be finite");
    EXPECT_EQ(params.wave_speed_mps, 850.0);
    const Status effect = SetParamValue(&params, "sensor_lag.time_constant_s", bad);
    ASSERT_FALSE(effect.ok()) << bad;
    EXPECT_EQ(effect.message(), "sensor_lag.time_constant_s: value must be finite");
    EXPECT_TRUE(params.effects[0].values.empty());
  }
}

}  // namespace
}  // namespace mpdrig
