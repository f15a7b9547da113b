#include "model/riglog/rig_log_writer.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/riglog/rig_log.h"
#include "model/riglog/rig_log_reader.h"

namespace mpdrig::riglog {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string TestPath(const std::string& suffix = "") {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return ::testing::TempDir() + "riglog_writer_" + info->name() + suffix + ".csv";
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

ColumnSpec Column(const char* name) {
  Result<ColumnSpec> column = ParseColumnName(name);
  MPDRIG_CHECK(column.ok());
  return std::move(column).value();
}

// Every unit kind, known and unknown channels.
std::vector<ColumnSpec> EveryUnitColumns() {
  return {Column("piston_position_m"),
          Column("choke_position_deg"),
          Column("choke_ref_frac"),
          Column("FT1_lpm"),
          Column("FT3_m3ps"),
          Column("PT1_barg"),
          Column("PT2_bara"),
          Column("C1_pag"),
          Column("C2_paa"),
          Column("ref_time_s")};
}

TEST(RigLogWriter, RoundTripsEveryUnitWithANonDefaultAtmosphere) {
  constexpr double kAtmospherePa = 98000.5;
  const std::vector<ColumnSpec> columns = EveryUnitColumns();
  // Plausible SI magnitudes per column, in the order of EveryUnitColumns.
  const std::vector<double> center = {0.0, 0.4, 0.5, 4e-4, -2e-4, 5e5, 4e5, 1.2e5, 3e5, 10.0};
  const std::vector<double> spread = {0.05, 0.3, 0.5, 2e-4, 3e-4, 2e5, 1e5, 1e4, 1e5, 10.0};

  const std::string path = TestPath();
  const Metadata metadata = {{"source", "writer test"}, {"atmospheric_pressure_pa", "98000.5"}};
  std::vector<double> times;
  std::vector<std::vector<double>> rows;
  {
    Result<RigLogWriter> writer = RigLogWriter::Open(path, metadata, columns);
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    EXPECT_EQ(writer->atmospheric_pressure_pa(), kAtmospherePa);
    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    double t = 0.0;
    for (int r = 0; r < 1000; ++r) {
      t += 0.001 * (1.0 + 0.5 * unit(random));  // non-uniform sampling
      std::vector<double> row(columns.size());
      for (std::size_t c = 0; c < columns.size(); ++c) {
        row[c] = (r + c) % 17 == 5 ? kNaN : center[c] + spread[c] * unit(random);
      }
      ASSERT_TRUE(writer->WriteRow(t, row).ok());
      times.push_back(t);
      rows.push_back(row);
    }
    ASSERT_TRUE(writer->Close().ok());
  }

  Result<RigLog> log = ReadRigLog(path);
  ASSERT_TRUE(log.ok()) << log.status().message();
  const Metadata expected_metadata = {
      {"rig-log", "1"}, {"source", "writer test"}, {"atmospheric_pressure_pa", "98000.5"}};
  EXPECT_EQ(log->metadata, expected_metadata);
  EXPECT_EQ(log->atmospheric_pressure_pa, kAtmospherePa);
  EXPECT_EQ(log->columns, columns);
  EXPECT_EQ(log->time_s, times) << "time is written in seconds, shortest round-trip text";
  ASSERT_EQ(log->num_rows(), rows.size());
  int nans = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const double expected = rows[r][c];
      const double actual = log->values_si[c][r];
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(actual));
        ++nans;
        continue;
      }
      // SI -> unit -> text (exact) -> unit -> SI: two roundings each way.
      const double tolerance =
          4 * std::numeric_limits<double>::epsilon() *
          (std::abs(expected) + (IsGauge(columns[c].unit) ? kAtmospherePa : 0));
      ASSERT_NEAR(actual, expected, tolerance) << columns[c].name << " row " << r;
    }
  }
  EXPECT_GT(nans, 0);
}

TEST(RigLogWriter, WritesLabUnitsAsShortestNumbers) {
  const std::vector<ColumnSpec> columns = {Column("PT1_barg"), Column("C1_pag"),
                                           Column("choke_position_deg"), Column("FT2_lpm"),
                                           Column("P2_bara")};
  std::ostringstream out;
  {
    Result<RigLogWriter> writer = RigLogWriter::ToStream(
        &out, "memory.csv", {{"source", "unit test"}, {"atmospheric_pressure_pa", "98000.5"}},
        columns);
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    ASSERT_TRUE(
        writer->WriteRow(0.0, std::vector<double>{2e5 + 98000.5, 98123.5, 0.5, 1e-3, 3e5}).ok());
    ASSERT_TRUE(writer->WriteRow(0.01, std::vector<double>{kNaN, kNaN, 1.0, kNaN, 0.0}).ok());
    ASSERT_TRUE(writer->Close().ok());
  }
  EXPECT_EQ(out.str(),
            "# rig-log: 1\n"
            "# source: unit test\n"
            "# atmospheric_pressure_pa: 98000.5\n"
            "time_s,PT1_barg,C1_pag,choke_position_deg,FT2_lpm,P2_bara\n"
            "0,2,123,45,60,3\n"
            "0.01,,,90,,0\n");
}

TEST(RigLogWriter, AddsTheAtmosphericPressureItUsedAndMovesTheVersionFirst) {
  std::ostringstream out;
  {
    Result<RigLogWriter> writer =
        RigLogWriter::ToStream(&out, "memory.csv", {{"note", ""}, {"rig-log", "1"}}, {});
    ASSERT_TRUE(writer.ok()) << writer.status().message();
    ASSERT_TRUE(writer->WriteRow(1.5, std::vector<double>{}).ok());
  }  // the destructor closes
  EXPECT_EQ(out.str(), "# rig-log: 1\n# note:\n# atmospheric_pressure_pa: 101325\ntime_s\n1.5\n");
}

TEST(RigLogWriter, DashWritesToStandardOutput) {
  ::testing::internal::CaptureStdout();
  Result<RigLogWriter> writer = RigLogWriter::Open("-", {}, {Column("FT1_m3ps")});
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE(writer->WriteRow(0.0, std::vector<double>{1e-4}).ok());
  ASSERT_TRUE(writer->Close().ok());
  EXPECT_EQ(::testing::internal::GetCapturedStdout(),
            "# rig-log: 1\n# atmospheric_pressure_pa: 101325\ntime_s,FT1_m3ps\n0,0.0001\n");
}

TEST(RigLogWriter, RefusesBadHeadsWithoutCreatingAFile) {
  struct Case {
    Metadata metadata;
    std::vector<ColumnSpec> columns;
    const char* message;
  };
  const std::vector<Case> cases = {
      {{{"rig-log", "2"}}, {}, ": metadata 'rig-log' is '2'; this writer writes version 1"},
      {{{"atmospheric_pressure_pa", "abc"}},
       {},
       ": metadata atmospheric_pressure_pa: 'abc' is not a number"},
      {{{"a key", "x"}},
       {},
       ": metadata key 'a key' is not a key (a letter, then letters, digits, '_', '-', '.')"},
      {{{"note", "two\nlines"}}, {}, ": metadata 'note': the value contains a line break"},
      {{{"note", " padded"}},
       {},
       ": metadata 'note': the value starts or ends with a blank, which a reader drops"},
      {{},
       {TimeColumn()},
       ": column 'time_s' must not be listed; time is WriteRow's time_s argument and always the "
       "first column"},
      {{},
       {Column("PT1_barg"), Column("PT1_paa")},
       ": duplicate channel 'PT1' (columns 'PT1_barg' and 'PT1_paa')"},
      {{},
       {ColumnSpec{"PT1_barg", "PT1", Unit::kBara}},
       ": column 'PT1_barg' does not match its channel 'PT1' and unit 'bara'"},
      {{},
       {ColumnSpec{"PT1_lpm", "PT1", Unit::kLpm}},
       ": column 'PT1_lpm': channel 'PT1' is a pressure, but unit 'lpm' is a flow; valid units: "
       "barg, bara, pag, paa"},
  };
  const std::string path = TestPath();
  for (const Case& c : cases) {
    std::filesystem::remove(path);
    Result<RigLogWriter> writer = RigLogWriter::Open(path, c.metadata, c.columns);
    ASSERT_FALSE(writer.ok()) << c.message;
    EXPECT_EQ(writer.status().message(), path + c.message);
    EXPECT_FALSE(std::filesystem::exists(path)) << c.message;
  }
}

TEST(RigLogWriter, RefusesBadRows) {
  const std::string path = TestPath();
  Result<RigLogWriter> writer =
      RigLogWriter::Open(path, {}, {Column("PT1_barg"), Column("FT1_lpm")});
  ASSERT_TRUE(writer.ok());
  // Lines 1-3 are the head; the first sample would be line 4.
  EXPECT_EQ(writer->WriteRow(0.0, std::vector<double>{1.0}).message(),
            path + ":4: row has 1 values for 2 columns");
  EXPECT_EQ(writer->WriteRow(kNaN, std::vector<double>{1.0, 1.0}).message(),
            path + ":4: time_s nan is not finite");
  EXPECT_EQ(writer->WriteRow(0.0, std::vector<double>{std::numeric_limits<double>::infinity(), 1.0})
                .message(),
            path + ":4: PT1_barg: value inf (SI) is not finite in barg");
  EXPECT_EQ(writer->WriteRow(0.0, std::vector<double>{1.0, 1e306}).message(),
            path + ":4: FT1_lpm: value 1e+306 (SI) is not finite in lpm");
  ASSERT_TRUE(writer->WriteRow(0.5, std::vector<double>{2e5, kNaN}).ok());
  EXPECT_EQ(
      writer->WriteRow(0.5, std::vector<double>{2e5, kNaN}).message(),
      path + ":5: time_s 0.5 is not after the previous 0.5; time must be strictly increasing");
  EXPECT_EQ(
      writer->WriteRow(0.25, std::vector<double>{2e5, kNaN}).message(),
      path + ":5: time_s 0.25 is not after the previous 0.5; time must be strictly increasing");
  ASSERT_TRUE(writer->Close().ok());
  EXPECT_FALSE(writer->WriteRow(1.0, std::vector<double>{2e5, kNaN}).ok());
  // What was accepted is a valid log.
  Result<RigLog> log = ReadRigLog(path);
  ASSERT_TRUE(log.ok()) << log.status().message();
  EXPECT_EQ(log->num_rows(), 1u);
}

TEST(RigLogWriter, WriteRigLogRoundTripsTheExample) {
  Result<RigLog> example =
      ReadRigLog(std::string(MPDRIG_SOURCE_DIR) + "/tests/data/riglog/example.csv");
  ASSERT_TRUE(example.ok()) << example.status().message();
  const std::string path = TestPath();
  ASSERT_TRUE(WriteRigLog(*example, path).ok());
  Result<RigLog> back = ReadRigLog(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->metadata, example->metadata);
  EXPECT_EQ(back->columns, example->columns);
  EXPECT_EQ(back->time_s, example->time_s);
  for (std::size_t c = 0; c < example->columns.size(); ++c) {
    for (std::size_t r = 0; r < example->num_rows(); ++r) {
      EXPECT_NEAR(back->values_si[c][r], example->values_si[c][r],
                  4e-16 * std::abs(example->values_si[c][r]) + 1e-300);
    }
  }
  // The lab's own numbers come back as written (shortest text of the same double).
  EXPECT_NE(ReadText(path).find("\n0.01,0.0006,31,28.2,0.02,3.96,4.23,3.95,28.3\n"),
            std::string::npos)
      << ReadText(path);
}

TEST(RigLogWriter, WriteRigLogChecksTheTable) {
  RigLog log;
  log.time_s = {0.0, 1.0};
  ASSERT_TRUE(log.AddColumn(Column("PT1_barg"), {2e5, 3e5}).ok());
  EXPECT_FALSE(log.AddColumn(Column("PT1_bara"), {2e5, 3e5}).ok()) << "duplicate channel";
  EXPECT_FALSE(log.AddColumn(Column("PT2_barg"), {2e5}).ok()) << "wrong length";
  EXPECT_FALSE(log.AddColumn(TimeColumn(), {0.0, 1.0}).ok());
  const std::string path = TestPath();

  log.atmospheric_pressure_pa = 100000.0;
  ASSERT_TRUE(WriteRigLog(log, path).ok());
  EXPECT_EQ(ReadText(path),
            "# rig-log: 1\n# atmospheric_pressure_pa: 100000\ntime_s,PT1_barg\n0,1\n1,2\n");

  log.metadata = {{"atmospheric_pressure_pa", "101325"}};
  EXPECT_EQ(WriteRigLog(log, path).message(),
            path +
                ": metadata atmospheric_pressure_pa '101325' disagrees with "
                "RigLog::atmospheric_pressure_pa 100000");
  log.metadata.clear();
  log.values_si[0].pop_back();
  EXPECT_EQ(WriteRigLog(log, path).message(),
            path + ": column 'PT1_barg' has 1 values for 2 times");
  log.values_si[0].push_back(3e5);
  log.time_s[1] = 0.0;
  EXPECT_EQ(WriteRigLog(log, path).message(),
            path + ":5: time_s 0 is not after the previous 0; time must be strictly increasing");
}

}  // namespace
}  // namespace mpdrig::riglog
