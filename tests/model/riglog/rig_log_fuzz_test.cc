// Seeded mutation fuzzing of the rig-log reader (tests/support/mutator.h): thousands of mutated
// logs, each read to its end. What must hold for every input: no crash (and no sanitizer report
// in the ASan/UBSan build, docs/validation.md, "Fuzzing and the sanitizer build"), an error is
// `name:line:column: message`, and what the reader accepts keeps its promises: time strictly
// increasing by at least the minimum step and at most the maximum gap, every value finite or NaN. A
// failure prints the seed and the iteration; MPDRIG_FUZZ_SEED and MPDRIG_FUZZ_ITERATIONS rerun or
// extend it.
#include <cmath>
#include <cstdio>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/riglog/rig_log_reader.h"
#include "tests/support/mutator.h"
#include "tests/support/shell.h"

namespace mpdrig::riglog {
namespace {

// Valid logs to start from: the example, one with every channel and metadata, CRLF line ends.
std::vector<std::string> SeedLogs() {
  std::vector<std::string> seeds = {
      testing::ReadFile(MPDRIG_SOURCE_DIR "/tests/data/riglog/example.csv")};
  std::string full =
      "\xef\xbb\xbf# rig-log: 1\n# source: fuzz\n# atmospheric_pressure_pa: 101325\n"
      "time_s,piston_position_m,choke_position_deg,FT1_lpm,FT2_lpm,FT3_lpm,"
      "FT4_lpm,C1_barg,C2_barg,P1_barg,P2_barg,PT1_barg,PT2_bara,PT3_barg,PT10_barg\n";
  for (int i = 0; i < 12; ++i) {
    char row[400];
    std::snprintf(row, sizeof row,
                  "%.3f,%.4f,31.0,20.1,5.0,5.1,-0.2,0.02,3.9%d,4.5,4.4,4.2,5.2,4.1,3.9\n", 0.01 * i,
                  0.01 * std::sin(i), i % 10);
    full += row;
  }
  full += "# a comment after the header\n0.2,0,31,,nan,5,0,0,3,4,4,4,5,4,3\n\n";
  seeds.push_back(full);
  std::string crlf;
  for (char c : seeds.front()) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  seeds.push_back(crlf);
  return seeds;
}

// Reads `text` to its end; returns an empty string or the first broken promise.
std::string ReadAndCheck(const std::string& text) {
  static const std::regex kError(R"(^fuzz\.csv:[0-9]+:[0-9]+: .+)");
  const ReadOptions options;
  auto reader =
      RigLogReader::FromStream(std::make_unique<std::istringstream>(text), "fuzz.csv", options);
  if (!reader.ok()) {
    const std::string message = reader.status().message();
    return std::regex_search(message, kError) ? "" : "error without a position: " + message;
  }
  const std::size_t time = reader->time_index();
  std::vector<double> values;
  double previous = -INFINITY;
  for (long row = 0;; ++row) {
    auto next = reader->Next(&values);
    if (!next.ok()) {
      const std::string message = next.status().message();
      return std::regex_search(message, kError) ? "" : "error without a position: " + message;
    }
    if (!*next) return "";
    if (values.size() != reader->columns().size()) return "a row of the wrong width";
    const double t = values[time];
    if (!std::isfinite(t)) return "time not finite in row " + std::to_string(row);
    if (row > 0 && !(t - previous >= options.min_step_s * (1 - 1e-9) &&
                     t - previous <= options.max_gap_s * (1 + 1e-9))) {
      return "time step " + std::to_string(t - previous) + " s accepted";
    }
    previous = t;
    for (double v : values) {
      if (std::isinf(v)) return "an infinite value accepted in row " + std::to_string(row);
    }
  }
}

TEST(RigLogFuzz, MutatedLogsAreReadOrRefusedWithAPosition) {
  const std::uint64_t seed = testing::FuzzSeed(20261125);
  const long iterations = testing::FuzzIterations(50000);
  testing::Mutator mutator(SeedLogs(), seed);
  long refused = 0;
  for (long i = 0; i < iterations; ++i) {
    const std::string text = mutator.Next();
    const std::string broken = ReadAndCheck(text);
    ASSERT_EQ(broken, "") << "seed " << seed << ", iteration " << i << ", input:\n" << text;
    auto probe = RigLogReader::FromStream(std::make_unique<std::istringstream>(text), "fuzz.csv");
    if (!probe.ok()) ++refused;
  }
  // The mutations must reach past the header, or this tests little: most are refused somewhere,
  // but not all at the header.
  std::printf("%ld mutated logs (seed %llu): %ld refused at the header\n", iterations,
              static_cast<unsigned long long>(seed), refused);
  EXPECT_LT(refused, iterations * 9 / 10);
}

// Inputs that once broke the log tools (each is a regression test of its own): a time of 1e308
// (hung compare for minutes), steps of 1e-12 s (null metrics), a pressure of 1e308 (silently
// infinite) and a choke at -50 deg (replayed).
TEST(RigLogFuzz, FormerlyHarmfulLogsAreRefusedAtTheirPosition) {
  const std::string header = "time_s,choke_position_deg,PT1_barg\n";
  for (const std::string& rows :
       {std::string("0,31,4\n1e308,31,4\n"), std::string("0,31,4\n1e-12,31,4\n"),
        std::string("0,31,4\n0.01,31,1e308\n"), std::string("0,31,4\n0.01,-50,4\n")}) {
    const std::string text = header + rows;
    EXPECT_EQ(ReadAndCheck(text), "") << text;
    auto reader = RigLogReader::FromStream(std::make_unique<std::istringstream>(text), "fuzz.csv");
    ASSERT_TRUE(reader.ok());
    std::vector<double> values;
    ASSERT_TRUE(reader->Next(&values).ok());
    auto second = reader->Next(&values);
    ASSERT_FALSE(second.ok()) << text;
    EXPECT_EQ(second.status().message().rfind("fuzz.csv:3:", 0), 0u) << second.status().message();
  }
}

}  // namespace
}  // namespace mpdrig::riglog
