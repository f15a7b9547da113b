#include "model/params/rig_params.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

// Defaults are typed in as decimal literals: they must be bit-identical to the thesis values.
// Derived quantities are checked to a relative 1e-12 (a few ulps of rounding in pi r^2 etc.).
constexpr double kDerivedRelTol = 1e-12;

// G of the default characteristic at `deg`, or NaN if the table has no point there.
double DefaultGAtDeg(const RigParams& params, double deg) {
  for (const ChokePoint& point : params.choke_characteristic) {
    if (std::abs(point.opening_frac * 90.0 - deg) < 1e-9) return point.g_m2;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

TEST(RigParams, DefaultsAreTheThesisValues) {
  const RigParams params;
  EXPECT_EQ(params.wave_speed_mps, 850.0);                     // Table 9.4.1
  EXPECT_EQ(params.friction_f1_per_s, 0.15);                   // Table 9.4.1
  EXPECT_EQ(params.friction_f2_per_m, 0.63);                   // (8.6.8)
  EXPECT_EQ(params.choke_leak_m2, 6e-7);                       // Table 9.4.1
  EXPECT_EQ(params.pipe_length_m, 900.0);                      // Table 8.1.2
  EXPECT_EQ(params.pipe_inner_radius_m, 0.008);                // Table 8.1.2
  EXPECT_EQ(params.pipe_elevation_gain_m, 2.3);                // Table 8.1.2
  EXPECT_EQ(params.upper_rod_diameter_m, 0.025);               // Table 8.1.1
  EXPECT_EQ(params.lower_rod_diameter_m, 0.022);               // Table 8.1.1
  EXPECT_EQ(params.compartment_height_m, 1.7);                 // (5.4.2)
  EXPECT_EQ(params.piston_friction_fd1_pa_s_per_m, -43840.0);  // (8.2.1)
  EXPECT_EQ(params.piston_friction_fd2_pa_s2_per_m2, -410400.0);
  EXPECT_EQ(params.density_kgpm3, 998.0);
  EXPECT_EQ(params.choke_density_kgpm3, 998.0);
  EXPECT_EQ(params.atmospheric_pressure_pa, 101325.0);
  EXPECT_TRUE(params.Validate().ok()) << params.Validate().message();
}

TEST(RigParams, DefaultChokeCharacteristicIsTable841) {
  const RigParams params;
  ASSERT_EQ(params.choke_characteristic.size(), 12u);
  EXPECT_EQ(DefaultGAtDeg(params, 31.0), 4.5e-6);
  EXPECT_EQ(DefaultGAtDeg(params, 90.0), 1.03e-4);
  EXPECT_EQ(DefaultGAtDeg(params, 0.0), 0.0);  // the leak floors it at evaluation, not here
  EXPECT_EQ(DefaultGAtDeg(params, 15.0), 0.0);
  EXPECT_EQ(params.choke_characteristic.front().opening_frac, 0.0);
  EXPECT_EQ(params.choke_characteristic.back().opening_frac, 1.0);
  for (std::size_t i = 1; i < params.choke_characteristic.size(); ++i) {
    EXPECT_GT(params.choke_characteristic[i].opening_frac,
              params.choke_characteristic[i - 1].opening_frac);
    EXPECT_GE(params.choke_characteristic[i].g_m2, params.choke_characteristic[i - 1].g_m2)
        << "Table 8.4.1 is monotone in the opening";
  }
}

TEST(RigParams, DerivedAreas) {
  const RigParams params;
  const double displacement = std::numbers::pi / 4.0 * (0.025 * 0.025 - 0.022 * 0.022);
  EXPECT_NEAR(params.PistonDisplacementAreaM2(), displacement, kDerivedRelTol * displacement);
  const double pipe_area = std::numbers::pi * 0.008 * 0.008;
  EXPECT_NEAR(params.PipeAreaM2(), pipe_area, kDerivedRelTol * pipe_area);
  EXPECT_NEAR(params.SinInclination(), 2.3 / 900.0, kDerivedRelTol);
  const double k = 850.0 * 850.0 * 998.0 - 101325.0;
  EXPECT_NEAR(params.QuasiLinearK(), k, kDerivedRelTol * k);
}

// Thesis 8.6.1: the piston's top speed 0.41 m/s pushes about 4.5e-5 m^3/s into the pipe, about
// 0.22 m/s of mean flow velocity. The thesis prints two digits (truncated: 4.54e-5, 0.226), so the
// tolerances are one unit of the last printed digit.
TEST(RigParams, PistonAreaReproducesThesisSection861) {
  const RigParams params;
  const double piston_speed_mps = 0.41;
  const double flow_m3ps = piston_speed_mps * params.PistonDisplacementAreaM2();
  EXPECT_NEAR(flow_m3ps, 4.5e-5, 0.1e-5);
  EXPECT_NEAR(flow_m3ps / params.PipeAreaM2(), 0.22, 0.01);
}

TEST(RigParams, EveryDefaultIsWithinItsBounds) {
  const RigParams params;
  for (const ParamInfo& info : ParamTable()) {
    const double value = params.*info.member;
    EXPECT_GE(value, info.min_value) << info.key;
    EXPECT_LE(value, info.max_value) << info.key;
    EXPECT_FALSE(info.unit.empty()) << info.key;
    EXPECT_FALSE(info.description.empty()) << info.key;
  }
}

TEST(RigParams, TableKeysAndMembersAreUnique) {
  std::set<std::string_view> keys;
  std::vector<double RigParams::*> members;  // member pointers are not ordered: compare by ==
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_TRUE(keys.insert(info.key).second) << "duplicate key " << info.key;
    for (double RigParams::*member : members) {
      EXPECT_NE(member, info.member) << "two keys share the member of " << info.key;
    }
    members.push_back(info.member);
    EXPECT_EQ(FindParam(info.key), &info);
  }
  EXPECT_EQ(FindParam("no_such_key"), nullptr);
  EXPECT_EQ(FindParam(""), nullptr);
}

// Each key writes its own member and no other.
TEST(RigParams, SetParamWritesExactlyItsMember) {
  for (const ParamInfo& info : ParamTable()) {
    RigParams params;
    const RigParams defaults;
    const double target = info.max_value;  // inclusive bound, always different from the default
    ASSERT_NE(defaults.*info.member, target) << info.key;
    std::ostringstream text;
    text.precision(17);
    text << target;
    const Status status = SetParam(&params, info.key, text.str());
    ASSERT_TRUE(status.ok()) << info.key << ": " << status.message();
    for (const ParamInfo& other : ParamTable()) {
      EXPECT_EQ(params.*other.member, other.key == info.key ? target : defaults.*other.member)
          << "setting " << info.key << " changed " << other.key;
    }
  }
}

TEST(RigParams, SetParamAcceptsNumbers) {
  RigParams params;
  ASSERT_TRUE(SetParam(&params, "wave_speed_mps", "1100").ok());
  EXPECT_EQ(params.wave_speed_mps, 1100.0);
  ASSERT_TRUE(SetParam(&params, "wave_speed_mps", "1.173e3").ok());
  EXPECT_EQ(params.wave_speed_mps, 1173.0);
  ASSERT_TRUE(SetParam(&params, "piston_friction_fd1_pa_s_per_m", "-5e4").ok());
  EXPECT_EQ(params.piston_friction_fd1_pa_s_per_m, -5e4);
  // Bounds are inclusive.
  const ParamInfo* info = FindParam("wave_speed_mps");
  ASSERT_NE(info, nullptr);
  EXPECT_TRUE(SetParam(&params, "wave_speed_mps", "10").ok());
  EXPECT_TRUE(SetParam(&params, "wave_speed_mps", "5000").ok());
  EXPECT_EQ(info->min_value, 10.0);
  EXPECT_EQ(info->max_value, 5000.0);
}

TEST(RigParams, SetParamRejectsUnknownKeyAndListsValidKeys) {
  RigParams params;
  const Status status = SetParam(&params, "wave_speed", "1100");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("'wave_speed'"), std::string::npos) << status.message();
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_NE(status.message().find(std::string(info.key)), std::string::npos)
        << "message does not list " << info.key << ": " << status.message();
  }
}

TEST(RigParams, SetParamRejectsBadValuesAndLeavesParamsUnchanged) {
  const char* bad_values[] = {"nan",     "NaN",   "inf",   "-inf",  "infinity", "abc",  "",
                              "1100abc", " 1100", "1100 ", "1,100", "1e",       "0x10", "--1"};
  for (const char* value : bad_values) {
    RigParams params;
    const Status status = SetParam(&params, "wave_speed_mps", value);
    EXPECT_FALSE(status.ok()) << "accepted '" << value << "'";
    EXPECT_NE(status.message().find("wave_speed_mps"), std::string::npos) << status.message();
    EXPECT_EQ(params.wave_speed_mps, 850.0) << "changed by rejected '" << value << "'";
  }
}

TEST(RigParams, SetParamRejectsOutOfBoundsAndNamesTheKey) {
  const char* out_of_bounds[] = {"9.999", "5000.001", "-850", "0", "1e300"};
  for (const char* value : out_of_bounds) {
    RigParams params;
    const Status status = SetParam(&params, "wave_speed_mps", value);
    EXPECT_FALSE(status.ok()) << "accepted " << value;
    EXPECT_NE(status.message().find("wave_speed_mps"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("outside"), std::string::npos) << status.message();
    EXPECT_EQ(params.wave_speed_mps, 850.0);
  }
  RigParams params;
  // A radius in mm instead of m is the unit mistake the bounds exist for.
  EXPECT_FALSE(SetParam(&params, "pipe_inner_radius_m", "8").ok());
  EXPECT_FALSE(SetParam(&params, "atmospheric_pressure_pa", "1.01325").ok());  // bar, not Pa
}

TEST(RigParams, ApplyOverride) {
  RigParams params;
  ASSERT_TRUE(ApplyOverride(&params, "friction_f1_per_s=0.24").ok());
  EXPECT_EQ(params.friction_f1_per_s, 0.24);

  const Status no_equals = ApplyOverride(&params, "friction_f1_per_s");
  ASSERT_FALSE(no_equals.ok());
  EXPECT_NE(no_equals.message().find("key=value"), std::string::npos) << no_equals.message();
  EXPECT_NE(no_equals.message().find("friction_f1_per_s"), std::string::npos);

  EXPECT_FALSE(ApplyOverride(&params, "=0.3").ok());
  EXPECT_FALSE(ApplyOverride(&params, "friction_f1_per_s=").ok());
  EXPECT_FALSE(ApplyOverride(&params, "friction_f1_per_s=0.3=0.4").ok());
  EXPECT_FALSE(ApplyOverride(&params, "friction_f1_per_s =0.3").ok());
  EXPECT_EQ(params.friction_f1_per_s, 0.24);
}

// Found by a bad-input probe: an upper rod no thicker than the lower one (or 0) was accepted and
// reversed (or removed) the piston's effect.
TEST(RigParams, ValidateCatchesRodsThatReverseThePiston) {
  for (auto [upper, lower] :
       {std::pair{0.020, 0.022}, std::pair{0.0, 0.022}, std::pair{0.022, 0.022}}) {
    RigParams params;
    params.upper_rod_diameter_m = upper;
    params.lower_rod_diameter_m = lower;
    const Status status = params.Validate();
    ASSERT_FALSE(status.ok()) << upper << " " << lower;
    EXPECT_NE(status.message().find("upper_rod_diameter_m = "), std::string::npos)
        << status.message();
    EXPECT_NE(status.message().find("must exceed lower_rod_diameter_m"), std::string::npos)
        << status.message();
  }
  RigParams no_lower_rod;
  no_lower_rod.lower_rod_diameter_m = 0.0;
  EXPECT_TRUE(no_lower_rod.Validate().ok()) << no_lower_rod.Validate().message();
}

TEST(RigParams, ValidateCatchesABadChokeTable) {
  {
    RigParams params;
    std::swap(params.choke_characteristic[4], params.choke_characteristic[5]);
    const Status status = params.Validate();
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("strictly increasing"), std::string::npos) << status.message();
  }
  {
    RigParams params;  // a repeated opening is not increasing either
    params.choke_characteristic[5].opening_frac = params.choke_characteristic[4].opening_frac;
    EXPECT_FALSE(params.Validate().ok());
  }
  {
    RigParams params;
    params.choke_characteristic.back().opening_frac = 1.01;
    EXPECT_FALSE(params.Validate().ok());
  }
  {
    RigParams params;
    params.choke_characteristic[3].g_m2 = -1e-7;
    EXPECT_FALSE(params.Validate().ok());
  }
  {
    RigParams params;
    params.choke_characteristic[3].g_m2 = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(params.Validate().ok());
  }
  {
    RigParams params;
    params.choke_characteristic.resize(1);
    EXPECT_FALSE(params.Validate().ok());
  }
}

TEST(RigParams, ValidateCatchesBadScalars) {
  {
    RigParams params;
    params.wave_speed_mps = std::numeric_limits<double>::quiet_NaN();
    const Status status = params.Validate();
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("wave_speed_mps"), std::string::npos) << status.message();
  }
  {
    RigParams params;
    params.pipe_inner_radius_m = 8.0;
    const Status status = params.Validate();
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("pipe_inner_radius_m"), std::string::npos) << status.message();
  }
  {
    RigParams params;  // within its own bounds, but higher than the pipe is long
    params.pipe_elevation_gain_m = 901.0;
    EXPECT_FALSE(params.Validate().ok());
  }
}

// The tuning ranges `fit` searches live in the parameter table beside the bounds: each lies
// within its parameter's bounds and holds the thesis value it starts from.
TEST(RigParams, TuningRangesLieWithinTheBoundsAndHoldTheThesisValues) {
  const RigParams defaults;
  int ranges = 0;
  for (const ParamInfo& info : ParamTable()) {
    if (!(info.fit_min < info.fit_max)) continue;
    ++ranges;
    EXPECT_GE(info.fit_min, info.min_value) << info.key;
    EXPECT_LE(info.fit_max, info.max_value) << info.key;
    const double value = defaults.*(info.member);
    EXPECT_TRUE(value >= info.fit_min && value <= info.fit_max) << info.key << " = " << value;
  }
  EXPECT_GE(ranges, 3) << "wave speed, pipe friction and choke leak have tuning ranges";
}

TEST(RigParams, ParamInfoGetsAndSetsItsMemberWithinItsBounds) {
  auto info = LookUpParam("friction_f1_per_s");
  ASSERT_TRUE(info.ok()) << info.status().message();
  RigParams params;
  EXPECT_EQ((*info)->Get(params), 0.15);
  ASSERT_TRUE((*info)->Set(&params, 0.2).ok());
  EXPECT_EQ(params.friction_f1_per_s, 0.2);
  for (const double bad : {-0.1, 1.0e4, std::numeric_limits<double>::quiet_NaN()}) {
    const Status status = (*info)->Set(&params, bad);
    EXPECT_FALSE(status.ok()) << bad;
    EXPECT_NE(status.message().find("friction_f1_per_s"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("outside"), std::string::npos) << status.message();
    EXPECT_EQ(params.friction_f1_per_s, 0.2);
  }
}

TEST(RigParams, LookUpParamListsTheValidKeysAndWhatElseTheCallerTakes) {
  auto unknown = LookUpParam("wave_speed");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.status().message().rfind("unknown parameter 'wave_speed'; valid keys: ", 0), 0u)
      << unknown.status().message();
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_NE(unknown.status().message().find(std::string(info.key)), std::string::npos)
        << info.key;
  }
  // The same wording as SetParam's.
  RigParams params;
  EXPECT_EQ(unknown.status().message(), SetParam(&params, "wave_speed", "1").message());
  auto more = LookUpParam("wave_speed", "EFFECT.KEY");
  ASSERT_FALSE(more.ok());
  EXPECT_EQ(more.status().message(), unknown.status().message() + ", or EFFECT.KEY");
}

TEST(RigParams, FitRangeIsTheTuningRangeOrAFactorOfThreeWithinTheBounds) {
  for (const ParamInfo& info : ParamTable()) {
    const auto [lower, upper] = info.FitRange();
    EXPECT_LT(lower, upper) << info.key;
    EXPECT_GE(lower, info.min_value) << info.key;
    EXPECT_LE(upper, info.max_value) << info.key;
    if (info.fit_min < info.fit_max) {
      EXPECT_EQ(lower, info.fit_min) << info.key;
      EXPECT_EQ(upper, info.fit_max) << info.key;
    }
  }
  // No tuning range: a factor of 3 either way around the thesis value, 0.1 s here (5.3).
  const auto [lower, upper] = FindParam("choke_time_constant_s")->FitRange();
  EXPECT_DOUBLE_EQ(lower, 0.1 / 3.0);
  EXPECT_DOUBLE_EQ(upper, 0.1 * 3.0);
}

TEST(RigParams, EffectSettingSetReplacesOrAppends) {
  EffectSetting setting{"unsteady_friction", {}};
  setting.Set("k", 0.02);
  setting.Set("k", 0.04);
  ASSERT_EQ(setting.values.size(), 1u);
  EXPECT_EQ(*setting.Find("k"), 0.04);
}
}  // namespace
}  // namespace mpdrig
