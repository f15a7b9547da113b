// `mpdrig traveltime`, run as a user runs it: a log from `mpdrig synth` (the lab's noise) gives the
// wave speed the log was made with, within 2 %, and the JSON has the documented fields; bad input
// is refused, naming what is wrong.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/shell.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;

const std::string kExe = MPDRIG_EXE;

fs::path TempDir() { return testing::TestTempDir("mpdrig_traveltime_command_test_"); }

int RunShell(const std::string& command, std::string* output) {
  return testing::RunShell(command, TempDir() / "command_output.txt", output);
}

// The number after "key": in a JSON text (NaN if absent).
double JsonNumber(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) return NAN;
  return std::stod(match[1].str());
}

TEST(TravelTimeCommandTest, SynthLogGivesItsWaveSpeedAndTheJsonFields) {
  const fs::path dir = TempDir();
  const fs::path log = dir / "lab.csv", json = dir / "tt.json";
  std::string output;
  ASSERT_EQ(RunShell(kExe + " synth --seed 2 --duration 60 --out " + log.string(), &output), 0)
      << output;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(output, match, std::regex("wave speed ([0-9.]+) m/s"))) << output;
  const double truth = std::stod(match[1].str());
  ASSERT_EQ(RunShell(kExe + " traveltime " + log.string() + " --json " + json.string(), &output), 0)
      << output;
  EXPECT_NE(output.find("correlating 45 pairs"), std::string::npos) << output;  // progress
  EXPECT_NE(output.find("PT1   PT10"), std::string::npos) << output;            // the table
  const std::string text = testing::ReadFile(json);
  const double c = JsonNumber(text, "wave_speed_mps");
  EXPECT_NEAR(c, truth, 0.02 * truth) << text;
  EXPECT_GT(JsonNumber(text, "wave_speed_uncertainty_mps"), 0.0);
  for (const char* field : {"\"pairs\": [", "\"from\": \"PT1\"", "\"to\": \"PT10\"", "\"delay_s\"",
                            "\"delay_up_s\"", "\"delay_down_s\"", "\"distance_m\": 900",
                            "\"pairs_used\"", "\"sample_rate_hz\": 100", "\"used\": true"}) {
    EXPECT_NE(text.find(field), std::string::npos) << field << " not in\n" << text;
  }
}

TEST(TravelTimeCommandTest, PerMoveTimesEachChokeMoveOrSaysWhyNot) {
  // synth's choke steps are small and slow (a few degrees over 0.5 s): each is found, and each is
  // timed or named as too weak on its own; the JSON lists them.
  const fs::path dir = TempDir();
  const fs::path log = dir / "lab.csv", json = dir / "tt.json";
  std::string output;
  ASSERT_EQ(RunShell(kExe + " synth --seed 1 --out " + log.string(), &output), 0) << output;
  ASSERT_EQ(RunShell(kExe + " traveltime " + log.string() + " --per-move --json " + json.string(),
                     &output),
            0)
      << output;
  EXPECT_NE(output.find("choke moves of 2 deg or more"), std::string::npos) << output;
  EXPECT_NE(output.find("moves timed"), std::string::npos) << output;
  const std::string text = testing::ReadFile(json);
  EXPECT_NE(text.find("\"moves\": ["), std::string::npos) << text;
  EXPECT_NE(text.find("\"end_to_end_delay_s\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"error\": \"fewer than three pairs"), std::string::npos) << text;
}

TEST(TravelTimeCommandTest, RefusesBadInputNamingIt) {
  const fs::path dir = TempDir();
  std::string output;
  const fs::path few = dir / "few.csv";
  {
    std::ofstream out(few);
    out << "time_s,PT1_barg,PT2_barg\n";
    for (int i = 0; i < 100; ++i) out << i * 0.01 << ",1,1\n";
  }
  EXPECT_EQ(RunShell(kExe + " traveltime " + few.string(), &output), 1) << output;
  EXPECT_NE(output.find("at least three of PT1..PT10"), std::string::npos) << output;
  EXPECT_EQ(RunShell(kExe + " traveltime " + few.string() + " --window-s 5:1", &output), 1);
  EXPECT_NE(output.find("T0 must be before T1"), std::string::npos) << output;
  EXPECT_EQ(RunShell(kExe + " traveltime " + few.string() + " --min-speed-mps 0", &output), 1);
  EXPECT_NE(output.find("0 < min < max"), std::string::npos) << output;
}

}  // namespace
}  // namespace mpdrig
