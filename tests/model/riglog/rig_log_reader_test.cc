#include "model/riglog/rig_log_reader.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/riglog/rig_log.h"

namespace mpdrig::riglog {
namespace {

constexpr double kStandardAtmospherePa = 101325.0;

// A file named after the running test, holding `content` byte for byte.
std::string WriteTestFile(const std::string& content, const std::string& suffix = "") {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string path = ::testing::TempDir() + "riglog_reader_" + info->name() + suffix + ".csv";
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
  out.close();
  EXPECT_TRUE(out.good()) << path;
  return path;
}

// Reads `content` as a file and expects exactly `path + location_and_message`.
void ExpectError(const std::string& content, const std::string& location_and_message,
                 const std::string& suffix = "") {
  const std::string path = WriteTestFile(content, suffix);
  Result<RigLog> log = ReadRigLog(path);
  ASSERT_FALSE(log.ok()) << "accepted:\n" << content;
  EXPECT_EQ(log.status().message(), path + location_and_message);
}

RigLog ReadOk(const std::string& content) {
  const std::string path = WriteTestFile(content);
  Result<RigLog> log = ReadRigLog(path);
  EXPECT_TRUE(log.ok()) << log.status().message();
  return log.ok() ? std::move(log).value() : RigLog{};
}

TEST(RigLogReader, ExampleFromTheFormatSpecification) {
  Result<RigLog> log =
      ReadRigLog(std::string(MPDRIG_SOURCE_DIR) + "/tests/data/riglog/example.csv");
  ASSERT_TRUE(log.ok()) << log.status().message();
  const Metadata expected_metadata = {{"rig-log", "1"},
                                      {"source", "lab, sine 0.2 Hz, choke 31 deg"},
                                      {"atmospheric_pressure_pa", "101325"}};
  EXPECT_EQ(log->metadata, expected_metadata);
  EXPECT_EQ(log->atmospheric_pressure_pa, kStandardAtmospherePa);
  ASSERT_EQ(log->num_rows(), 2u);
  EXPECT_EQ(log->time_s, (std::vector<double>{0.0, 0.01}));
  ASSERT_EQ(log->columns.size(), 8u);
  EXPECT_EQ(log->columns[0], (ColumnSpec{"piston_position_m", "piston_position", Unit::kM}));
  EXPECT_EQ(log->columns[7], (ColumnSpec{"FT3_lpm", "FT3", Unit::kLpm}));

  EXPECT_EQ(*log->Find(Channel::kPistonPosition), (std::vector<double>{0.0, 0.0006}));
  EXPECT_EQ((*log->Find("choke_position"))[0], 31.0 / 90.0);
  EXPECT_DOUBLE_EQ((*log->Find("FT2"))[1], 28.2e-3 / 60.0);
  EXPECT_DOUBLE_EQ((*log->Find("FT3"))[1], 28.3e-3 / 60.0);
  EXPECT_DOUBLE_EQ((*log->Find("C1"))[0], 0.02e5 + 101325.0);
  EXPECT_DOUBLE_EQ((*log->Find("C2"))[0], 3.95e5 + 101325.0);
  EXPECT_DOUBLE_EQ((*log->Find("PT1"))[1], 4.23e5 + 101325.0);
  EXPECT_DOUBLE_EQ((*log->Find("PT10"))[0], 3.96e5 + 101325.0);
  EXPECT_EQ(log->Find("PT5"), nullptr);
  EXPECT_EQ(log->Find("time"), &log->time_s);
}

TEST(RigLogReader, StreamingApiShowsColumnsInFileOrder) {
  const std::string path =
      WriteTestFile("# rig-log: 1\nPT1_barg,time_s,FT4_m3ps\n1,0,2e-4\n2,0.5,\n");
  Result<RigLogReader> reader = RigLogReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  ASSERT_EQ(reader->columns().size(), 3u);
  EXPECT_EQ(reader->columns()[1], TimeColumn());
  EXPECT_EQ(reader->time_index(), 1u);
  EXPECT_EQ(reader->FindColumn("FT4"), 2u);
  EXPECT_EQ(reader->FindColumn("time"), 1u);
  EXPECT_EQ(reader->FindColumn("FT1"), std::nullopt);
  EXPECT_EQ(reader->line_number(), 2);

  std::vector<double> values;
  Result<bool> more = reader->Next(&values);
  ASSERT_TRUE(more.ok() && *more);
  EXPECT_EQ(values, (std::vector<double>{1e5 + kStandardAtmospherePa, 0.0, 2e-4}));
  more = reader->Next(&values);
  ASSERT_TRUE(more.ok() && *more);
  EXPECT_EQ(values[1], 0.5);
  EXPECT_TRUE(std::isnan(values[2]));
  EXPECT_EQ(reader->line_number(), 4);
  more = reader->Next(&values);
  ASSERT_TRUE(more.ok());
  EXPECT_FALSE(*more);
  EXPECT_EQ(reader->samples_read(), 2);
  more = reader->Next(&values);
  ASSERT_TRUE(more.ok());
  EXPECT_FALSE(*more);
}

TEST(RigLogReader, FromStreamUsesTheGivenName) {
  auto in = std::make_unique<std::istringstream>("time_s\n0\nx\n");
  Result<RigLogReader> reader = RigLogReader::FromStream(std::move(in), "memory.csv");
  ASSERT_TRUE(reader.ok());
  std::vector<double> values;
  ASSERT_TRUE(*reader->Next(&values));
  Result<bool> bad = reader->Next(&values);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message(), "memory.csv:3:1: time_s: 'x' is not a number");
  // The reader stays failed.
  Result<bool> again = reader->Next(&values);
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.status().message(), bad.status().message());
}

TEST(RigLogReader, CrLfLineEnds) {
  RigLog log = ReadOk(
      "# rig-log: 1\r\n# atmospheric_pressure_pa: 100000\r\ntime_s,PT1_barg,FT1_lpm\r\n"
      "0,1,60\r\n0.5,2,\r\n1,3,nan");  // last line without a line end
  EXPECT_EQ(log.metadata[1].second, "100000");
  EXPECT_EQ(log.atmospheric_pressure_pa, 100000.0);
  EXPECT_EQ(log.columns.back().name, "FT1_lpm");
  EXPECT_EQ(log.time_s, (std::vector<double>{0.0, 0.5, 1.0}));
  EXPECT_EQ(*log.Find("PT1"), (std::vector<double>{2e5, 3e5, 4e5}));
  const std::vector<double>& ft1 = *log.Find("FT1");
  EXPECT_DOUBLE_EQ(ft1[0], 1e-3);
  EXPECT_TRUE(std::isnan(ft1[1]));
  EXPECT_TRUE(std::isnan(ft1[2]));

  ExpectError("time_s,PT1_barg\r\n0,abc\r\n", ":2:3: PT1_barg: 'abc' is not a number", "_error");
}

TEST(RigLogReader, EmptyFieldsAndNanAreNotMeasured) {
  RigLog log = ReadOk("time_s,PT1_barg,PT2_barg,FT1_lpm\n0,,nan,NaN\n1,1,NAN,\n");
  ASSERT_EQ(log.num_rows(), 2u);
  EXPECT_TRUE(std::isnan((*log.Find("PT1"))[0]));
  EXPECT_EQ((*log.Find("PT1"))[1], 1e5 + kStandardAtmospherePa);
  for (const char* channel : {"PT2", "FT1"}) {
    EXPECT_TRUE(std::isnan((*log.Find(channel))[0])) << channel;
    EXPECT_TRUE(std::isnan((*log.Find(channel))[1])) << channel;
  }
}

TEST(RigLogReader, UnknownColumnsAreKeptWithTheQuantityOfTheirUnit) {
  RigLog log = ReadOk(
      "time_s,BHP_est_barg,piston_ref_m,pump_setting_lpm,ref_time_s,valve_frac\n"
      "0,2,0.01,30,0.5,0.25\n");
  ASSERT_EQ(log.columns.size(), 5u);
  EXPECT_EQ(log.columns[0], (ColumnSpec{"BHP_est_barg", "BHP_est", Unit::kBarg}));
  EXPECT_EQ(log.columns[1].quantity(), Quantity::kPosition);
  EXPECT_EQ(log.columns[3].quantity(), Quantity::kTime);
  EXPECT_EQ((*log.Find("BHP_est"))[0], 2e5 + kStandardAtmospherePa);
  EXPECT_EQ((*log.Find("piston_ref"))[0], 0.01);
  EXPECT_DOUBLE_EQ((*log.Find("pump_setting"))[0], 0.5e-3);
  EXPECT_EQ((*log.Find("ref_time"))[0], 0.5);
  EXPECT_EQ((*log.Find("valve"))[0], 0.25);
}

TEST(RigLogReader, CommentsBetweenSamplesAreIgnored) {
  RigLog log = ReadOk(
      "# rig-log: 1\n# a free comment, not metadata\n#source:bench\ntime_s,PT1_barg\n0,1\n"
      "# pump restarted\n# note: after the header is a plain comment\n0.1,2\n#\n0.2,3\n");
  const Metadata expected = {{"rig-log", "1"}, {"source", "bench"}};
  EXPECT_EQ(log.metadata, expected);
  EXPECT_EQ(log.time_s, (std::vector<double>{0.0, 0.1, 0.2}));
}

TEST(RigLogReader, TrailingEmptyLinesBomAndHeaderOnly) {
  EXPECT_EQ(ReadOk("time_s\n0\n1\n\n\n").num_rows(), 2u);
  EXPECT_EQ(ReadOk("time_s\r\n0\r\n\r\n\r\n# end of run\r\n").num_rows(), 1u);
  RigLog bom = ReadOk("\xEF\xBB\xBF# rig-log: 1\ntime_s\n0\n");
  EXPECT_EQ(bom.metadata.front().first, "rig-log");
  RigLog header_only = ReadOk("# rig-log: 1\ntime_s,PT1_barg\n");
  EXPECT_EQ(header_only.num_rows(), 0u);
  EXPECT_EQ(header_only.columns.size(), 1u);
  EXPECT_EQ(header_only.values_si.size(), 1u);
  RigLog no_version = ReadOk("time_s\n0\n");
  EXPECT_TRUE(no_version.metadata.empty());
}

TEST(RigLogReader, GaugePressuresUseTheLogsAtmosphericPressure) {
  RigLog log = ReadOk(
      "# atmospheric_pressure_pa:  95000.5 \ntime_s,PT1_barg,P1_pag,P2_bara,C2_paa,C1_barg\n"
      "0,2,500,3,250000,-0.5\n");
  EXPECT_EQ(log.atmospheric_pressure_pa, 95000.5);
  EXPECT_EQ(log.metadata[0].second, "95000.5");
  EXPECT_EQ((*log.Find("PT1"))[0], 2e5 + 95000.5);
  EXPECT_EQ((*log.Find("P1"))[0], 500 + 95000.5);
  EXPECT_EQ((*log.Find("P2"))[0], 3e5);
  EXPECT_EQ((*log.Find("C2"))[0], 250000.0);
  EXPECT_EQ((*log.Find("C1"))[0], -0.5e5 + 95000.5);
}

// ---- Every error class, with the exact file:line:column ----------------------------------

constexpr char kKnownUnits[] = "known units: s, m, deg, frac, lpm, m3ps, barg, bara, pag, paa";

TEST(RigLogReaderErrors, UnknownUnitSuffix) {
  ExpectError(
      "# rig-log: 1\n# source: test\ntime_s,piston_position_m,tank_level_mm\n0,0,1\n",
      std::string(":3:26: unknown unit suffix 'mm' in column 'tank_level_mm'; ") + kKnownUnits);
  ExpectError("time_s,PT1\n",
              std::string(":1:8: column 'PT1' has no unit suffix; a column is "
                          "named <channel>_<unit>, ") +
                  kKnownUnits,
              "_no_suffix");
  ExpectError("time_s,\n", ":1:8: empty column name", "_empty");
}

TEST(RigLogReaderErrors, KnownChannelInAUnitOfAnotherQuantity) {
  ExpectError("time_s,PT1_lpm\n0,1\n",
              ":1:8: column 'PT1_lpm': channel 'PT1' is a pressure, but unit 'lpm' is a flow; "
              "valid units: barg, bara, pag, paa");
  ExpectError("time_s,PT1_barg,choke_position_barg\n",
              ":1:17: column 'choke_position_barg': channel 'choke_position' is a choke opening, "
              "but unit 'barg' is a pressure; valid units: deg, frac",
              "_choke");
  ExpectError("time_m,PT1_barg\n",
              ":1:1: column 'time_m': channel 'time' is a time, but unit 'm' is a position; valid "
              "units: s",
              "_time");
}

TEST(RigLogReaderErrors, DuplicateColumn) {
  ExpectError("time_s,PT1_barg,PT2_barg,PT1_barg\n",
              ":1:26: duplicate column 'PT1_barg' (also at column 8)");
  ExpectError("time_s,PT1_barg,PT1_bara\n",
              ":1:17: duplicate channel 'PT1': column 'PT1_bara' and column 'PT1_barg' at column 8",
              "_channel");
  ExpectError("time_s,time_s\n", ":1:8: duplicate column 'time_s' (also at column 1)", "_time");
}

TEST(RigLogReaderErrors, NonNumericField) {
  // 55 good samples, then line 57 with 'abc' at character 23.
  std::string content = "time_s,piston_position_m,PT1_barg\n";
  char row[64];
  for (int i = 0; i < 55; ++i) {
    std::snprintf(row, sizeof(row), "%.2f,0.001,4.2\n", 0.01 * i);
    content += row;
  }
  content += "0.5500000,0.001234567,abc\n";
  ExpectError(content, ":57:23: PT1_barg: 'abc' is not a number");
  ExpectError("time_s,PT1_barg\n0, 1\n", ":2:3: PT1_barg: ' 1' is not a number", "_space");
  ExpectError("time_s,PT1_barg\n0,\"1\"\n", ":2:3: PT1_barg: '\"1\"' is not a number", "_quoted");
  ExpectError("time_s,PT1_barg\n0,1e400\n",
              ":2:3: PT1_barg: '1e400' is out of the range of a double", "_range");
}

TEST(RigLogReaderErrors, InfiniteField) {
  const std::string hint =
      " is not a finite number (write an empty field or 'nan' if not measured)";
  ExpectError("time_s,PT1_barg\n0,1\n0.1,inf\n", ":3:5: PT1_barg: 'inf'" + hint);
  ExpectError("time_s,FT1_lpm,PT1_barg\n0,1,-Infinity\n", ":2:5: PT1_barg: '-Infinity'" + hint,
              "_negative");
  ExpectError("time_s,PT1_barg\n0,-nan\n", ":2:3: PT1_barg: '-nan'" + hint, "_minus_nan");
}

TEST(RigLogReaderErrors, WrongFieldCount) {
  ExpectError("time_s,PT1_barg,PT2_barg\n0,1,2\n0.1,1\n",
              ":3:6: expected 3 fields as in the header, found 2");
  ExpectError("time_s,PT1_barg,PT2_barg\n0,1,2,3\n",
              ":2:7: expected 3 fields as in the header, found 4", "_too_many");
  ExpectError("time_s,PT1_barg,PT2_barg\n0,1,2,\n",
              ":2:7: expected 3 fields as in the header, found 4", "_trailing_comma");
}

TEST(RigLogReaderErrors, MissingTimeColumn) {
  ExpectError("# rig-log: 1\npiston_position_m,PT1_barg\n0,1\n",
              ":2:1: missing required column 'time_s' (sample time in seconds)");
}

TEST(RigLogReaderErrors, EmptyOrNanTime) {
  ExpectError("time_s,PT1_barg\n0,1\n,2\n", ":3:1: time_s: empty; every sample needs a time");
  ExpectError("PT1_barg,time_s\n1,0\n2,nan\n",
              ":3:3: time_s: 'nan' is not a time; every sample needs a time", "_nan");
}

TEST(RigLogReaderErrors, TimeNotStrictlyIncreasing) {
  ExpectError("time_s,PT1_barg\n0,1\n0.01,1\n# comment\n0.01,2\n",
              ":5:1: time_s: 0.01 is not after the previous sample's 0.01 (line 3); time must be "
              "strictly increasing");
  ExpectError("PT1_barg,time_s\n1,0.5\n1,0.25\n",
              ":3:3: time_s: 0.25 is not after the previous sample's 0.5 (line 2); time must be "
              "strictly increasing",
              "_decreasing");
}

// Found by a bad-input probe: one wild time value made every tool replay the model over it for
// minutes. A gap longer than ReadOptions::max_gap_s (default 10 s) is an error at the later sample.
TEST(RigLogReaderErrors, GapInTimeLongerThanTheLimit) {
  const std::string path = WriteTestFile("time_s,PT1_barg\n0,1\n0.01,1\n100000.01,1\n");
  Result<RigLog> log = ReadRigLog(path);
  ASSERT_FALSE(log.ok());
  EXPECT_EQ(log.status().message(),
            path +
                ":4:1: time_s: 100000.01 is 100000 s after the previous sample's 0.01 (line 3), "
                "a gap longer than 10 s (an interrupted recording or a wrong time; a longer gap "
                "limit admits it if it is real)");
  ReadOptions wider;
  wider.max_gap_s = 2.0e5;
  Result<RigLog> accepted = ReadRigLog(path, wider);
  ASSERT_TRUE(accepted.ok()) << accepted.status().message();
  EXPECT_EQ(accepted->num_rows(), 3u);

  const std::string huge = WriteTestFile("time_s,PT1_barg\n0,1\n0.01,1\n1e308,1\n", "_1e308");
  Result<RigLog> refused = ReadRigLog(huge);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().message().rfind(huge + ":4:1: time_s: 1e+308 is 1e+308 s after", 0),
            0u)
      << refused.status().message();
  // A gap of exactly the limit is fine.
  ReadOk("time_s,PT1_barg\n0,1\n10,1\n");
}

// Found by a bad-input probe: time steps of 1e-12 s gave null metrics and exit 0.
TEST(RigLogReaderErrors, TimeStepShorterThanTheLimit) {
  ExpectError("time_s,PT1_barg\n0,1\n1e-12,1\n",
              ":3:1: time_s: 1e-12 is only 1e-12 s after the previous sample's 0 (line 2); time "
              "steps must be at least 1e-06 s");
}

TEST(RigLogReaderErrors, BadTimeLimitsAreRefused) {
  const std::string path = WriteTestFile("time_s\n0\n");
  for (auto [gap, step] : {std::pair{std::nan(""), 1e-6}, std::pair{10.0, 0.0},
                           std::pair{1e-7, 1e-6}, std::pair{10.0, std::nan("")}}) {
    ReadOptions options;
    options.max_gap_s = gap;
    options.min_step_s = step;
    Result<RigLog> log = ReadRigLog(path, options);
    ASSERT_FALSE(log.ok()) << gap << " " << step;
    EXPECT_NE(log.status().message().find("time limits of a rig log"), std::string::npos)
        << log.status().message();
  }
}

// Found by a bad-input probe: values outside their quantity's physical range used to pass: 1e308
// barg became infinity ("not measured"), choke openings of -50 deg and 31 (as a fraction) were
// replayed.
TEST(RigLogReaderErrors, ValuesOutsideTheirPhysicalRange) {
  struct Case {
    std::string content;
    std::string message;  // after the path
  };
  const std::vector<Case> cases = {
      {"time_s,PT1_barg\n0,1\n0.01,1e308\n",
       ":3:6: PT1_barg: 1e+308 is outside the physical range of a pressure, "},
      {"time_s,C1_barg\n0,1e308\n", ":2:3: C1_barg: 1e+308 is outside the physical range of a "},
      {"time_s,PT1_bara\n0,-2000\n",
       ":2:3: PT1_bara: -2000 is outside the physical range of a pressure, -1000 .. 1000 bara"},
      {"time_s,piston_position_m,choke_position_deg\n0,0,-50\n",
       ":2:5: choke_position_deg: -50 is outside the physical range of a choke opening, -4.5 .. "
       "94.5 deg"},
      {"time_s,choke_position_frac\n0,31\n",
       ":2:3: choke_position_frac: 31 is outside the physical range of a choke opening, -0.05 .. "
       "1.05 frac"},
      {"time_s,FT2_lpm\n0,1e7\n",
       ":2:3: FT2_lpm: 10000000 is outside the physical range of a flow"},
      {"time_s,piston_position_m\n0,1e3\n",
       ":2:3: piston_position_m: 1000 is outside the physical range of a position, -10 .. 10 m"},
      {"time_s,BHP_est_barg\n0,1e308\n", ":2:3: BHP_est_barg: 1e+308 is outside"},
  };
  int index = 0;
  for (const Case& c : cases) {
    const std::string path = WriteTestFile(c.content, "_" + std::to_string(index++));
    Result<RigLog> log = ReadRigLog(path);
    ASSERT_FALSE(log.ok()) << "accepted:\n" << c.content;
    EXPECT_EQ(log.status().message().rfind(path + c.message, 0), 0u) << log.status().message();
  }
  // The edges of the ranges, and not measured, pass.
  const RigLog edges = ReadOk(
      "time_s,piston_position_m,choke_position_deg,FT2_lpm,PT1_bara,PT2_barg\n"
      "0,-10,-4.4,-5999,-1000,998\n0.01,10,94.4,5999,1000,\n");
  EXPECT_EQ(edges.num_rows(), 2u);
}

TEST(RigLogReaderErrors, UnsupportedVersion) {
  ExpectError("# rig-log: 2\ntime_s\n0\n",
              ":1:12: unsupported rig-log version '2'; this reader reads version 1");
  ExpectError("# rig-log: 1\n# rig-log: 1\ntime_s\n",
              ":2:1: duplicate metadata key 'rig-log' (first on line 1)", "_twice");
}

TEST(RigLogReaderErrors, BadAtmosphericPressure) {
  ExpectError("# rig-log: 1\n# atmospheric_pressure_pa: abc\ntime_s\n0\n",
              ":2:28: atmospheric_pressure_pa: 'abc' is not a number");
  ExpectError("# atmospheric_pressure_pa: 1.01325\ntime_s\n",
              ":1:28: atmospheric_pressure_pa: '1.01325' is not an atmospheric pressure in Pa "
              "(expected 10000 .. 1000000 Pa)",
              "_bar");
  ExpectError("# atmospheric_pressure_pa:\ntime_s\n", ":1:27: atmospheric_pressure_pa: empty value",
              "_empty");
}

TEST(RigLogReaderErrors, EmptyLines) {
  ExpectError("time_s\n0\n\n1\n",
              ":3:1: empty line inside the data (followed by a sample on line 4); empty lines are "
              "allowed only at the end of the file");
  ExpectError("# rig-log: 1\n\ntime_s\n",
              ":2:1: empty line before the header; the first line that is not a comment must be "
              "the header",
              "_before_header");
}

TEST(RigLogReaderErrors, NoHeader) {
  const std::string message =
      "no header line: expected column names such as 'time_s,piston_position_m'";
  ExpectError("", ":1:1: " + message);
  ExpectError("# rig-log: 1\n# source: x\n", ":3:1: " + message, "_comments_only");
}

TEST(RigLogReaderErrors, ColumnsCountCharactersNotBytes) {
  // 'ø' is two bytes in UTF-8 but one character.
  ExpectError("time_s,ø_m,PT1_lpm\n",
              ":1:12: column 'PT1_lpm': channel 'PT1' is a pressure, but unit 'lpm' is a flow; "
              "valid units: barg, bara, pag, paa");
}

TEST(RigLogReaderErrors, MissingFile) {
  const std::string path = ::testing::TempDir() + "riglog_reader_does_not_exist.csv";
  Result<RigLog> log = ReadRigLog(path);
  ASSERT_FALSE(log.ok());
  EXPECT_EQ(log.status().message(), path + ": cannot open for reading: No such file or directory");
  Result<RigLog> directory = ReadRigLog(::testing::TempDir());
  ASSERT_FALSE(directory.ok());
  EXPECT_NE(directory.status().message().find("is a directory"), std::string::npos);
}

TEST(RigLogReaderErrors, MutatedFilesAreReadOrRejectedWithAPosition) {
  const std::string original =
      "# rig-log: 1\n# atmospheric_pressure_pa: 101325\n"
      "time_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,PT1_barg\n"
      "0.00,0.0000,31.0,28.1,0.02,4.21\n0.01,0.0006,31.0,28.2,0.02,4.23\n"
      "0.02,0.0011,31.0,28.2,,4.25\n";
  const std::string alphabet = "0123456789.,-+eE#:_ \r\nnaifPTsmx\xC3\xB8\xFF";
  std::mt19937 random(5);
  const std::regex located(".*:[0-9]+:[0-9]+: .+");
  int rejected = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::string content = original;
    const int edits = 1 + static_cast<int>(random() % 3);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = random() % content.size();
      const char c = alphabet[random() % alphabet.size()];
      switch (random() % 3) {
        case 0:
          content[at] = c;
          break;
        case 1:
          content.insert(content.begin() + static_cast<std::ptrdiff_t>(at), c);
          break;
        default:
          content.erase(at, 1);
      }
    }
    auto in = std::make_unique<std::istringstream>(content);
    Result<RigLogReader> reader = RigLogReader::FromStream(std::move(in), "fuzz.csv");
    Status status = reader.status();
    if (reader.ok()) {
      std::vector<double> values;
      for (;;) {
        Result<bool> more = reader->Next(&values);
        if (!more.ok()) {
          status = more.status();
          break;
        }
        if (!*more) break;
      }
    }
    if (!status.ok()) {
      ++rejected;
      EXPECT_TRUE(std::regex_match(status.message(), located)) << status.message();
      EXPECT_EQ(status.message().rfind("fuzz.csv:", 0), 0u) << status.message();
    }
  }
  EXPECT_GT(rejected, 100);
}

// ---- Long logs -----------------------------------------------------------------------------

bool SameOrBothNan(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

TEST(RigLogReader, StreamingALongLogMatchesReadRigLog) {
  constexpr int kRows = 200000;
  std::string content =
      "# rig-log: 1\n# atmospheric_pressure_pa: 100500\n"
      "time_s,piston_position_m,choke_position_deg,FT2_lpm,PT1_barg,PT10_bara\n";
  content.reserve(content.size() + 48u * kRows);
  char row[128];
  for (int i = 0; i < kRows; ++i) {
    if (i % 50000 == 1) content += "# checkpoint\n";
    const double t = 0.001 * i;
    if (i % 7 == 3) {  // an unmeasured pressure now and then
      std::snprintf(row, sizeof(row), "%.3f,%.6f,%.2f,%.3f,,%.4f\n", t, 0.01 * std::sin(t), 31.0,
                    28.0, 5.0);
    } else {
      std::snprintf(row, sizeof(row), "%.3f,%.6f,%.2f,%.3f,%.4f,%.4f\n", t, 0.01 * std::sin(t),
                    31.0, 28.0, 4.0 + 0.1 * std::cos(t), 5.0);
    }
    content += row;
  }
  const std::string path = WriteTestFile(content);

  Result<RigLog> table = ReadRigLog(path);
  ASSERT_TRUE(table.ok()) << table.status().message();
  ASSERT_EQ(table->num_rows(), static_cast<std::size_t>(kRows));

  Result<RigLogReader> reader = RigLogReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  ASSERT_EQ(reader->columns().size(), 6u);
  std::vector<double> sample;
  std::size_t row_index = 0;
  bool all_equal = true;
  for (;;) {
    Result<bool> more = reader->Next(&sample);
    ASSERT_TRUE(more.ok()) << more.status().message();
    if (!*more) break;
    ASSERT_LT(row_index, table->num_rows());
    all_equal = all_equal && sample[0] == table->time_s[row_index];
    for (std::size_t c = 0; c < table->columns.size(); ++c) {
      all_equal = all_equal && SameOrBothNan(sample[c + 1], table->values_si[c][row_index]);
    }
    ++row_index;
  }
  EXPECT_TRUE(all_equal);
  EXPECT_EQ(row_index, static_cast<std::size_t>(kRows));
  EXPECT_EQ(reader->samples_read(), kRows);

  EXPECT_EQ(table->time_s.back(), 199.999);
  EXPECT_TRUE(std::isnan((*table->Find("PT1"))[3]));
  EXPECT_DOUBLE_EQ((*table->Find("PT1"))[0], 4.1e5 + 100500.0);
  EXPECT_EQ((*table->Find("PT10"))[kRows - 1], 5.0e5);
  EXPECT_DOUBLE_EQ((*table->Find("FT2"))[kRows - 1], 28.0e-3 / 60.0);
}

}  // namespace
}  // namespace mpdrig::riglog
