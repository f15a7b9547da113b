#include "model/riglog/channels.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

namespace mpdrig::riglog {
namespace {

constexpr char kKnownUnits[] = "s, m, deg, frac, lpm, m3ps, barg, bara, pag, paa";

TEST(RigLogChannels, EveryUnitSuffixParsesBackToItsUnit) {
  ASSERT_EQ(AllUnits().size(), 10u);
  for (Unit unit : AllUnits()) {
    Result<Unit> parsed = ParseUnit(UnitSuffix(unit));
    ASSERT_TRUE(parsed.ok()) << UnitSuffix(unit);
    EXPECT_EQ(*parsed, unit);
  }
  EXPECT_EQ(KnownUnitsList(), kKnownUnits);
}

TEST(RigLogChannels, UnknownUnitIsAnErrorListingTheKnownUnits) {
  Result<Unit> unit = ParseUnit("mm");
  ASSERT_FALSE(unit.ok());
  EXPECT_EQ(unit.status().message(),
            std::string("unknown unit suffix 'mm'; known units: ") + kKnownUnits);
  EXPECT_FALSE(ParseUnit("BARG").ok()) << "suffixes are case-sensitive";
  EXPECT_FALSE(ParseUnit("").ok());
}

TEST(RigLogChannels, UnitQuantitiesAndLabUnits) {
  EXPECT_EQ(QuantityOf(Unit::kS), Quantity::kTime);
  EXPECT_EQ(QuantityOf(Unit::kM), Quantity::kPosition);
  EXPECT_EQ(QuantityOf(Unit::kDeg), Quantity::kChokeOpening);
  EXPECT_EQ(QuantityOf(Unit::kFrac), Quantity::kChokeOpening);
  EXPECT_EQ(QuantityOf(Unit::kLpm), Quantity::kFlow);
  EXPECT_EQ(QuantityOf(Unit::kM3ps), Quantity::kFlow);
  for (Unit unit : {Unit::kBarg, Unit::kBara, Unit::kPag, Unit::kPaa}) {
    EXPECT_EQ(QuantityOf(unit), Quantity::kPressure);
  }
  EXPECT_TRUE(IsGauge(Unit::kBarg));
  EXPECT_TRUE(IsGauge(Unit::kPag));
  EXPECT_FALSE(IsGauge(Unit::kBara));
  EXPECT_FALSE(IsGauge(Unit::kPaa));

  EXPECT_EQ(LabUnitFor(Quantity::kTime), Unit::kS);
  EXPECT_EQ(LabUnitFor(Quantity::kPosition), Unit::kM);
  EXPECT_EQ(LabUnitFor(Quantity::kChokeOpening), Unit::kDeg);
  EXPECT_EQ(LabUnitFor(Quantity::kFlow), Unit::kLpm);
  EXPECT_EQ(LabUnitFor(Quantity::kPressure), Unit::kBarg);
  EXPECT_EQ(SiUnitFor(Quantity::kChokeOpening), Unit::kFrac);
  EXPECT_EQ(SiUnitFor(Quantity::kFlow), Unit::kM3ps);
  EXPECT_EQ(SiUnitFor(Quantity::kPressure), Unit::kPaa);
}

TEST(RigLogChannels, KnownChannelTable) {
  EXPECT_EQ(KnownChannels().size(), 21u);
  for (const ChannelInfo& info : KnownChannels()) {
    EXPECT_EQ(ChannelName(info.channel), info.name);
    EXPECT_EQ(FindChannel(info.name), info.channel);
    EXPECT_EQ(QuantityOf(info.channel), info.quantity);
  }
  EXPECT_EQ(FindChannel("time"), Channel::kTime);
  EXPECT_EQ(QuantityOf(Channel::kPistonPosition), Quantity::kPosition);
  EXPECT_EQ(QuantityOf(Channel::kChokePosition), Quantity::kChokeOpening);
  EXPECT_EQ(QuantityOf(Channel::kFT4), Quantity::kFlow);
  EXPECT_EQ(QuantityOf(Channel::kPT10), Quantity::kPressure);
  EXPECT_EQ(QuantityOf(Channel::kC1), Quantity::kPressure);
  EXPECT_EQ(FindChannel("PT11"), std::nullopt);
  EXPECT_EQ(FindChannel("pt1"), std::nullopt);
  EXPECT_EQ(LabColumn(Channel::kPT3).name, "PT3_barg");
  EXPECT_EQ(LabColumn(Channel::kFT2).name, "FT2_lpm");
  EXPECT_EQ(LabColumn(Channel::kChokePosition).name, "choke_position_deg");
  EXPECT_EQ(LabColumn(Channel::kPistonPosition).name, "piston_position_m");
}

TEST(RigLogChannels, ColumnNameSplitsAtTheLastUnderscore) {
  struct Case {
    const char* name;
    const char* channel;
    Unit unit;
  };
  for (const Case& c :
       {Case{"time_s", "time", Unit::kS}, Case{"piston_position_m", "piston_position", Unit::kM},
        Case{"choke_position_frac", "choke_position", Unit::kFrac},
        Case{"PT10_paa", "PT10", Unit::kPaa}, Case{"BHP_est_barg", "BHP_est", Unit::kBarg},
        Case{"piston_ref_m", "piston_ref", Unit::kM},
        Case{"pump_setting_lpm", "pump_setting", Unit::kLpm}}) {
    Result<ColumnSpec> column = ParseColumnName(c.name);
    ASSERT_TRUE(column.ok()) << column.status().message();
    EXPECT_EQ(column->name, c.name);
    EXPECT_EQ(column->channel, c.channel);
    EXPECT_EQ(column->unit, c.unit);
    Result<ColumnSpec> made = MakeColumn(c.channel, c.unit);
    ASSERT_TRUE(made.ok());
    EXPECT_EQ(*made, *column);
  }
  EXPECT_EQ(ParseColumnName("BHP_est_barg")->quantity(), Quantity::kPressure);
}

TEST(RigLogChannels, BadColumnNamesAreErrors) {
  EXPECT_EQ(ParseColumnName("tank_level_mm").status().message(),
            std::string("unknown unit suffix 'mm' in column 'tank_level_mm'; known units: ") +
                kKnownUnits);
  EXPECT_EQ(ParseColumnName("PT1_lpm").status().message(),
            "column 'PT1_lpm': channel 'PT1' is a pressure, but unit 'lpm' is a flow; valid "
            "units: barg, bara, pag, paa");
  EXPECT_EQ(ParseColumnName("choke_position_barg").status().message(),
            "column 'choke_position_barg': channel 'choke_position' is a choke opening, but unit "
            "'barg' is a pressure; valid units: deg, frac");
  EXPECT_FALSE(ParseColumnName("time_m").ok());
  EXPECT_FALSE(ParseColumnName("FT1_m").ok());
  EXPECT_FALSE(ParseColumnName("piston_position_deg").ok());
  EXPECT_EQ(ParseColumnName("pt1_barg").status().message(),
            "column 'pt1_barg': channel 'pt1' differs from the known channel 'PT1' only in case; "
            "channel names are case-sensitive");
  EXPECT_FALSE(ParseColumnName("PT1").ok());
  EXPECT_FALSE(ParseColumnName("_barg").ok());
  EXPECT_FALSE(ParseColumnName("").ok());
  EXPECT_FALSE(ParseColumnName(" PT1_barg").ok());
  EXPECT_FALSE(ParseColumnName("PT1_barg ").ok()) << "'barg ' is not a unit";
  EXPECT_FALSE(ParseColumnName("tank level_m").ok());
  EXPECT_FALSE(ParseColumnName("\"PT1_barg\"").ok());
  EXPECT_FALSE(MakeColumn("PT1", Unit::kLpm).ok());
}

TEST(RigLogChannels, ConversionsToSiAbsolute) {
  const double atm = 98765.0;
  EXPECT_EQ(ToSi(Unit::kBarg, 3.95, atm), 3.95 * 1e5 + atm);
  EXPECT_EQ(ToSi(Unit::kBara, 3.95, atm), 3.95 * 1e5);
  EXPECT_EQ(ToSi(Unit::kPag, 1200.0, atm), 1200.0 + atm);
  EXPECT_EQ(ToSi(Unit::kPaa, 1200.0, atm), 1200.0);
  EXPECT_EQ(ToSi(Unit::kDeg, 45.0, atm), 0.5);
  EXPECT_EQ(ToSi(Unit::kDeg, 90.0, atm), 1.0);
  EXPECT_EQ(ToSi(Unit::kFrac, 0.25, atm), 0.25);
  EXPECT_DOUBLE_EQ(ToSi(Unit::kLpm, 60.0, atm), 1e-3);
  EXPECT_EQ(ToSi(Unit::kM3ps, 1e-3, atm), 1e-3);
  EXPECT_EQ(ToSi(Unit::kS, 2.5, atm), 2.5);
  EXPECT_EQ(ToSi(Unit::kM, -0.1, atm), -0.1);
  EXPECT_TRUE(std::isnan(ToSi(Unit::kBarg, std::nan(""), atm)));

  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> lab(-50.0, 50.0);
  for (Unit unit : AllUnits()) {
    for (int i = 0; i < 100; ++i) {
      const double value = lab(random);
      const double value_si = ToSi(unit, value, atm);
      const double back = FromSi(unit, value_si, atm);
      // Round-off of the SI value, seen through the unit's scale (gauge units carry the
      // atmospheric offset in value_si).
      const double scale = ToSi(unit, 1.0, 0.0) - ToSi(unit, 0.0, 0.0);
      const double tolerance =
          4 * std::numeric_limits<double>::epsilon() * std::abs(value_si) / scale;
      EXPECT_NEAR(back, value, tolerance) << UnitSuffix(unit);
    }
  }
}

TEST(RigLogChannels, SampleFieldsAreCLocaleNumbers) {
  struct Case {
    const char* text;
    double value;
  };
  for (const Case& c :
       {Case{"0", 0.0}, Case{"3.95", 3.95}, Case{"-0.5", -0.5}, Case{"+2", 2.0}, Case{".5", 0.5},
        Case{"5.", 5.0}, Case{"1e3", 1000.0}, Case{"1.5E-3", 1.5e-3}, Case{"-2e+2", -200.0}}) {
    Result<double> value = ParseSampleField(c.text);
    ASSERT_TRUE(value.ok()) << c.text << ": " << value.status().message();
    EXPECT_EQ(*value, c.value) << c.text;
  }
  for (const char* text : {"", "nan", "NaN", "NAN"}) {
    Result<double> value = ParseSampleField(text);
    ASSERT_TRUE(value.ok()) << text;
    EXPECT_TRUE(std::isnan(*value)) << text;
  }
}

TEST(RigLogChannels, BadSampleFieldsAreErrors) {
  for (const char* text : {"abc", " 1", "1 ", "1,5", "0x10", "1e", "1.2.3", "++1", "+-1", "+", "-",
                           "1e400", "inf", "-inf", "Infinity", "-nan", "nan(1)", "\"1\"", "1\r"}) {
    EXPECT_FALSE(ParseSampleField(text).ok()) << text;
  }
  EXPECT_EQ(ParseSampleField("abc").status().message(), "'abc' is not a number");
  EXPECT_EQ(ParseSampleField("inf").status().message(),
            "'inf' is not a finite number (write an empty field or 'nan' if not measured)");
  EXPECT_EQ(ParseSampleField("1e400").status().message(),
            "'1e400' is out of the range of a double");
}

TEST(RigLogChannels, FormatNumberIsShortestAndRoundTrips) {
  EXPECT_EQ(FormatNumber(0.1), "0.1");
  EXPECT_EQ(FormatNumber(101325.0), "101325");
  EXPECT_EQ(FormatNumber(1e5), "100000");
  EXPECT_EQ(FormatNumber(2e-4), "0.0002");
  EXPECT_EQ(FormatNumber(-3.95), "-3.95");
  EXPECT_EQ(FormatNumber(1e-10), "1e-10");
  EXPECT_EQ(FormatNumber(1.5e20), "1.5e+20");
  EXPECT_EQ(FormatNumber(1e300), "1e+300");
  EXPECT_EQ(FormatNumber(std::nan("")), "");
  std::mt19937_64 random(11);
  for (int i = 0; i < 10000; ++i) {
    double value;
    const std::uint64_t bits = random();
    std::memcpy(&value, &bits, sizeof(value));
    if (!std::isfinite(value)) continue;
    Result<double> back = ParseSampleField(FormatNumber(value));
    ASSERT_TRUE(back.ok()) << FormatNumber(value);
    EXPECT_EQ(*back, value);
  }
}

// The rule FormatNumber states, by two std::to_chars conversions (the shortest text, and the
// shortest fixed text): the writer derives the fixed form from one conversion and must give these
// bytes for every value.
std::string ByTwoConversions(double value) {
  char shortest[64];
  const auto shortest_end = std::to_chars(shortest, shortest + sizeof(shortest), value).ptr;
  char fixed[400];
  const auto [fixed_end, fixed_ec] =
      std::to_chars(fixed, fixed + sizeof(fixed), value, std::chars_format::fixed);
  if (fixed_ec == std::errc() && (fixed_end - fixed) <= (shortest_end - shortest) + 3) {
    return std::string(fixed, fixed_end);
  }
  return std::string(shortest, shortest_end);
}

TEST(RigLogChannels, FormatNumberIsWhatTwoConversionsGive) {
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> decade(-30, 25);
  std::uniform_int_distribution<int> digits(1, 17);
  std::uniform_int_distribution<std::int64_t> integer(-(std::int64_t{1} << 54),
                                                      std::int64_t{1} << 54);
  const auto check = [](double value) {
    ASSERT_EQ(FormatNumber(value), ByTwoConversions(value)) << std::hexfloat << value;
  };
  // Where the forms change over and the fast path ends.
  for (double value : {0.0,
                       -0.0,
                       1.0,
                       9.5,
                       10.0,
                       99999.0,
                       1e5,
                       1e6,
                       1e7,
                       123456789.0,
                       0.001,
                       1e-4,
                       1e-5,
                       1.25e-6,
                       0x1p53,
                       -0x1p53,
                       0x1p53 - 1.0,
                       0x1p53 + 2.0,
                       1e15,
                       1e16,
                       1e17,
                       9007199254740991.0,
                       4503599627370495.5,
                       1e22,
                       1e23,
                       std::numeric_limits<double>::min(),
                       std::numeric_limits<double>::max(),
                       std::numeric_limits<double>::denorm_min()}) {
    check(value);
    check(-value);
  }
  for (int i = 0; i < 200000; ++i) {
    // A sensor's reading (few digits at any decade), any double in a decade, and integers near
    // 2^53.
    const double scale = std::pow(10.0, decade(random));
    const double rounded_to = std::pow(10.0, digits(random));
    check(std::round(unit(random) * rounded_to) / rounded_to * scale);
    check(-unit(random) * scale);
    check(static_cast<double>(integer(random)));
    check(static_cast<double>(integer(random)) * 0.5);
  }
}

TEST(RigLogChannels, AtmosphericPressureMustBePascals) {
  EXPECT_EQ(*ParseAtmosphericPressure("101325"), 101325.0);
  EXPECT_EQ(*ParseAtmosphericPressure("9.81e4"), 98100.0);
  EXPECT_FALSE(ParseAtmosphericPressure("").ok());
  EXPECT_FALSE(ParseAtmosphericPressure("nan").ok());
  EXPECT_FALSE(ParseAtmosphericPressure("abc").ok());
  EXPECT_FALSE(ParseAtmosphericPressure("-101325").ok());
  EXPECT_EQ(ParseAtmosphericPressure("1.01325").status().message(),
            "atmospheric_pressure_pa: '1.01325' is not an atmospheric pressure in Pa (expected "
            "10000 .. 1000000 Pa)");
}

TEST(RigLogChannels, MetadataKeys) {
  EXPECT_TRUE(IsMetadataKey("rig-log"));
  EXPECT_TRUE(IsMetadataKey("atmospheric_pressure_pa"));
  EXPECT_TRUE(IsMetadataKey("source.v2"));
  EXPECT_FALSE(IsMetadataKey(""));
  EXPECT_FALSE(IsMetadataKey("12"));
  EXPECT_FALSE(IsMetadataKey("a free comment"));
}

}  // namespace
}  // namespace mpdrig::riglog
