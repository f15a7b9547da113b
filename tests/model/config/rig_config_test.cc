#include "model/config/rig_config.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <google/protobuf/descriptor.h>
#include <gtest/gtest.h>

#include "model/config/rig_config.pb.h"
#include "model/params/rig_params.h"

namespace mpdrig {
namespace {

const std::string kSource = "rig.pbtxt";

// Expects every scalar of `actual` to equal `expected` exactly (each key is parsed, not computed).
void ExpectScalarsEqual(const RigParams& actual, const RigParams& expected) {
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_EQ(actual.*info.member, expected.*info.member) << info.key;
  }
}

void ExpectChokeTablesEqual(const std::vector<ChokePoint>& actual,
                            const std::vector<ChokePoint>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].opening_frac, expected[i].opening_frac) << "point " << i;
    EXPECT_EQ(actual[i].g_m2, expected[i].g_m2) << "point " << i;
  }
}

std::string ErrorOf(const std::string& text) {
  Result<RigParams> parsed = ParseRigConfig(text, kSource);
  EXPECT_FALSE(parsed.ok()) << "accepted:\n" << text;
  return parsed.ok() ? std::string() : parsed.status().message();
}

TEST(RigConfig, SetsGivenValuesAndKeepsDefaults) {
  const std::string text =
      "# tuned by hand\n"
      "wave_speed_mps: 1100\n"
      "friction_f1_per_s: 0.24   # after 9.4\n"
      "piston_friction_fd1_pa_s_per_m: -5e4\n";
  Result<RigParams> parsed = ParseRigConfig(text, kSource);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  RigParams expected;
  expected.wave_speed_mps = 1100.0;
  expected.friction_f1_per_s = 0.24;
  expected.piston_friction_fd1_pa_s_per_m = -5e4;
  ExpectScalarsEqual(*parsed, expected);
  ExpectChokeTablesEqual(parsed->choke_characteristic, RigParams().choke_characteristic);
}

TEST(RigConfig, EmptyTextGivesTheDefaults) {
  Result<RigParams> parsed = ParseRigConfig("", kSource);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  ExpectScalarsEqual(*parsed, RigParams());
}

TEST(RigConfig, AppliesOnTopOfTheGivenDefaults) {
  RigParams base;
  base.gravity_mps2 = 9.82;
  Result<RigParams> parsed = ParseRigConfig("wave_speed_mps: 900", kSource, base);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  EXPECT_EQ(parsed->gravity_mps2, 9.82);
  EXPECT_EQ(parsed->wave_speed_mps, 900.0);
}

TEST(RigConfig, ChokePointsReplaceTheTableInDegrees) {
  const std::string text =
      "choke_point { opening_deg: 0  g_m2: 0 }\n"
      "choke_point { opening_deg: 45 g_m2: 5e-5 }\n"
      "choke_point { opening_deg: 90 g_m2: 1.03e-4 }\n";
  Result<RigParams> parsed = ParseRigConfig(text, kSource);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  ExpectChokeTablesEqual(parsed->choke_characteristic, {{0.0, 0.0}, {0.5, 5e-5}, {1.0, 1.03e-4}});
  ExpectScalarsEqual(*parsed, RigParams());
}

TEST(RigConfig, UnknownFieldNamesSourceLineAndColumn) {
  // Line 2; the unknown name starts at column 3 (1-based). Columns point at the start of the
  // offending token, as in the rig-log reader and in the syntax-error case below.
  const std::string message = ErrorOf("wave_speed_mps: 1100\n  wave_speed: 3\n");
  EXPECT_EQ(message.rfind(kSource + ":2:3: ", 0), 0u) << message;
  EXPECT_NE(message.find("wave_speed"), std::string::npos) << message;
}

TEST(RigConfig, SyntaxErrorNamesSourceLineAndColumn) {
  // Missing ':' on line 3; the offending token `1100` starts at column 16.
  const std::string message = ErrorOf("# comment\nfriction_f1_per_s: 0.2\nwave_speed_mps 1100\n");
  EXPECT_EQ(message.rfind(kSource + ":3:16: ", 0), 0u) << message;
}

TEST(RigConfig, NonNumberNamesSourceLineAndColumn) {
  const std::string message = ErrorOf("wave_speed_mps: fast\n");
  EXPECT_EQ(message.rfind(kSource + ":1:17: ", 0), 0u) << message;
}

TEST(RigConfig, RepeatedScalarIsAnError) {
  const std::string message = ErrorOf("wave_speed_mps: 1100\nwave_speed_mps: 1200\n");
  EXPECT_EQ(message.rfind(kSource + ":2:", 0), 0u) << message;
  EXPECT_NE(message.find("wave_speed_mps"), std::string::npos) << message;
}

TEST(RigConfig, OutOfBoundsValueNamesTheKeyAndItsPosition) {
  const std::string message =
      ErrorOf("wave_speed_mps: 1100\n  pipe_inner_radius_m: 8\n");  // mm, not m
  EXPECT_EQ(message.rfind(kSource + ":2:3: ", 0), 0u) << message;
  EXPECT_NE(message.find("pipe_inner_radius_m"), std::string::npos) << message;
  EXPECT_NE(message.find("outside"), std::string::npos) << message;
}

TEST(RigConfig, NonFiniteValuesAreErrors) {
  for (const char* value : {"nan", "inf", "-inf"}) {
    const std::string message = ErrorOf(std::string("wave_speed_mps: ") + value + "\n");
    EXPECT_NE(message.find("wave_speed_mps"), std::string::npos) << value << ": " << message;
  }
}

TEST(RigConfig, BadChokeTableIsAnError) {
  const std::string message = ErrorOf(
      "choke_point { opening_deg: 40 g_m2: 1e-5 }\n"
      "choke_point { opening_deg: 30 g_m2: 2e-5 }\n");
  // A bad characteristic is found in the file: the error names the point's line and column.
  EXPECT_EQ(message.rfind(kSource + ":2:1: ", 0), 0u) << message;
  EXPECT_NE(message.find("increasing"), std::string::npos) << message;
  const std::string range = ErrorOf(
      "choke_point { opening_deg: 0 g_m2: 0 }\n"
      "wave_speed_mps: 1000\n"
      "  choke_point { opening_deg: 45 g_m2: -1 }\n");
  EXPECT_EQ(range.rfind(kSource + ":3:3: ", 0), 0u) << range;
  EXPECT_NE(range.find("G >= 0"), std::string::npos) << range;
  EXPECT_FALSE(ParseRigConfig("choke_point { opening_deg: 91 g_m2: 1e-5 }\n"
                              "choke_point { opening_deg: 0 g_m2: 0 }\n",
                              kSource)
                   .ok());
}

// An effect's bad parameter is an error at the line and column of that parameter (and an unknown
// effect at the effect's), so a long config points at the line to fix.
TEST(RigConfig, BadEffectParameterNamesItsLineAndColumn) {
  const std::string bounds = ErrorOf(
      "wave_speed_mps: 1000\n"
      "effect {\n"
      "  name: \"sensor_lag\"\n"
      "  param { key: \"time_constant_s\" value: 5 }\n"
      "}\n");
  EXPECT_EQ(bounds.rfind(kSource + ":4:3: ", 0), 0u) << bounds;
  EXPECT_NE(bounds.find("time_constant_s"), std::string::npos) << bounds;
  const std::string key = ErrorOf(
      "effect { name: \"sensor_lag\"\n"
      "         param { key: \"time_constant_s\" value: 0.1 }\n"
      "         param { key: \"tau\" value: 0.1 } }\n");
  EXPECT_EQ(key.rfind(kSource + ":3:10: ", 0), 0u) << key;
  EXPECT_NE(key.find("no parameter 'tau'"), std::string::npos) << key;
  const std::string twice = ErrorOf(
      "effect { name: \"sensor_lag\"\n"
      "  param { key: \"time_constant_s\" value: 0.1 }\n"
      "  param { key: \"time_constant_s\" value: 0.2 } }\n");
  EXPECT_EQ(twice.rfind(kSource + ":3:3: ", 0), 0u) << twice;
  const std::string name = ErrorOf("wave_speed_mps: 1000\n  effect { name: \"gremlins\" }\n");
  EXPECT_EQ(name.rfind(kSource + ":2:3: ", 0), 0u) << name;
  EXPECT_NE(name.find("unknown effect 'gremlins'"), std::string::npos) << name;
  // A rule between parameters (free gas given at a pressure above the vapour pressure) is an error
  // at the effect's line, whatever order the parameters come in; each one alone is within bounds.
  const std::string gas_below_vapour = ErrorOf(
      "wave_speed_mps: 1000\n"
      "effect { name: \"column_separation\"\n"
      "  param { key: \"gas_reference_pressure_pa\" value: 2000 }\n"
      "  param { key: \"gas_void_fraction\" value: 1e-7 } }\n");
  EXPECT_EQ(gas_below_vapour.rfind(kSource + ":2:1: ", 0), 0u) << gas_below_vapour;
  EXPECT_NE(gas_below_vapour.find("gas_reference_pressure_pa = 2000 Pa must be above "
                                  "vapour_pressure_pa = 2300 Pa"),
            std::string::npos)
      << gas_below_vapour;
  auto gas_above_vapour = ParseRigConfig(
      "effect { name: \"column_separation\"\n"
      "  param { key: \"gas_void_fraction\" value: 1e-7 }\n"
      "  param { key: \"vapour_pressure_pa\" value: 1000 }\n"
      "  param { key: \"gas_reference_pressure_pa\" value: 2000 } }\n",
      kSource);
  EXPECT_TRUE(gas_above_vapour.ok()) << gas_above_vapour.status().message();
  // Without free gas the reference pressure is not used, and not checked against p_v.
  EXPECT_TRUE(ParseRigConfig("effect { name: \"column_separation\"\n"
                             "  param { key: \"gas_reference_pressure_pa\" value: 2000 } }\n",
                             kSource)
                  .ok());
  // A good one still parses, with its value.
  auto good = ParseRigConfig(
      "effect { name: \"sensor_lag\" param { key: \"time_constant_s\" value: 0.2 } }\n", kSource);
  ASSERT_TRUE(good.ok()) << good.status().message();
  ASSERT_EQ(good->effects.size(), 1u);
  EXPECT_EQ(*good->effects[0].Find("time_constant_s"), 0.2);
}

TEST(RigConfig, FormattedDefaultsParseBackIdentically) {
  const RigParams defaults;
  const std::string text = FormatRigConfig(defaults);
  for (const ParamInfo& info : ParamTable()) {
    std::string line_start = "\n";  // (built stepwise: GCC 12 warns falsely on "\n" + string)
    line_start.append(info.key).append(": ");
    EXPECT_NE(text.find(line_start), std::string::npos) << info.key << " missing from\n" << text;
  }
  // Parse on top of different defaults, so a key the text lost cannot pass unnoticed.
  RigParams other;
  for (const ParamInfo& info : ParamTable()) other.*info.member = info.max_value;
  other.pipe_elevation_gain_m = 0.0;
  other.choke_characteristic = {{0.0, 1e-6}, {1.0, 2e-6}};
  Result<RigParams> parsed = ParseRigConfig(text, kSource, other);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message() << "\n" << text;
  ExpectScalarsEqual(*parsed, defaults);
  ExpectChokeTablesEqual(parsed->choke_characteristic, defaults.choke_characteristic);
}

TEST(RigConfig, FormattedChangedParamsParseBack) {
  RigParams params;
  params.wave_speed_mps = 1173.0;
  params.friction_f1_per_s = 0.24;
  params.choke_leak_m2 = 2.5e-7;
  params.choke_characteristic = {{0.0, 0.0}, {0.25, 1e-6}, {1.0, 1.1e-4}};
  Result<RigParams> parsed = ParseRigConfig(FormatRigConfig(params), kSource);
  ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  ExpectScalarsEqual(*parsed, params);
  ExpectChokeTablesEqual(parsed->choke_characteristic, params.choke_characteristic);
}

TEST(RigConfig, LoadFromFile) {
  const std::string path = ::testing::TempDir() + "rig_config_test_load.pbtxt";
  {
    std::ofstream out(path, std::ios::trunc);
    out << "wave_speed_mps: 1000\nbad_key: 1\n";
  }
  Result<RigParams> loaded = LoadRigConfig(path);
  ASSERT_FALSE(loaded.ok());
  // The exact column is UnknownFieldNamesSourceLineAndColumn's business.
  EXPECT_EQ(loaded.status().message().rfind(path + ":2:", 0), 0u) << loaded.status().message();
  EXPECT_NE(loaded.status().message().find("bad_key"), std::string::npos);
  {
    std::ofstream out(path, std::ios::trunc);
    out << "wave_speed_mps: 1000\n";
  }
  loaded = LoadRigConfig(path);
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  EXPECT_EQ(loaded->wave_speed_mps, 1000.0);
  std::filesystem::remove(path);

  Result<RigParams> missing = LoadRigConfig(path + ".does-not-exist");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find(path + ".does-not-exist"), std::string::npos);
}

// The config file and the table describe the same scalars: every table key is an optional double
// field of mpdrig.config.RigConfig, and every optional double field is a table key.
TEST(RigConfig, ProtoAndParameterTableAreInSync) {
  namespace pb = google::protobuf;
  const pb::Descriptor* descriptor = config::RigConfig::descriptor();
  ASSERT_NE(descriptor, nullptr);
  for (const ParamInfo& info : ParamTable()) {
    const pb::FieldDescriptor* field = descriptor->FindFieldByName(std::string(info.key));
    ASSERT_NE(field, nullptr) << info.key << " has no field in rig_config.proto";
    EXPECT_EQ(field->type(), pb::FieldDescriptor::TYPE_DOUBLE) << info.key;
    EXPECT_FALSE(field->is_repeated()) << info.key;
    EXPECT_TRUE(field->has_presence()) << info.key << " must be `optional` so unset keeps default";
  }
  int scalar_fields = 0;
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const pb::FieldDescriptor* field = descriptor->field(i);
    if (field->is_repeated()) {
      EXPECT_TRUE(field->name() == "choke_point" || field->name() == "effect")
          << "unexpected repeated field " << field->name();
      continue;
    }
    if (field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE) {
      // The layout's blocks (model/params/rig_layout.h), not scalars of the table.
      EXPECT_TRUE(field->name() == "reservoir" || field->name() == "valve" ||
                  field->name() == "steady_flow")
          << "unexpected block " << field->name();
      continue;
    }
    ++scalar_fields;
    EXPECT_EQ(field->type(), pb::FieldDescriptor::TYPE_DOUBLE) << field->name();
    EXPECT_NE(FindParam(field->name()), nullptr)
        << "rig_config.proto field " << field->name() << " is not a key of ParamTable()";
  }
  EXPECT_EQ(scalar_fields, static_cast<int>(ParamTable().size()));
}
}  // namespace
}  // namespace mpdrig
