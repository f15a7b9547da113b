// The frequency-domain commands run as a user runs them: `mpdrig freqresp --termination`,
// `mpdrig freqresp --from-log`, `mpdrig fit --resonances` (docs/rig-measurements.md).
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string Quote(const std::string& text) { return "'" + text + "'"; }

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

double JsonValue(const std::string& json, const std::string& key) {
  std::smatch match;
  const std::regex pattern("\"" + key + "\": *(-?[0-9.eE+-]+)");
  if (!std::regex_search(json, match, pattern)) return std::nan("");
  return std::stod(match[1].str());
}

class FreqCommandsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::path(MPDRIG_BINARY_DIR) / "tests" / "tools" /
           ("freq_commands_test." + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }
  static RunResult Run(const std::string& args) {
    const std::string err_path = Path("stderr.txt");
    const std::string command = "cd " + Quote(dir_.string()) + " && " + Quote(MPDRIG_EXE) + " " +
                                args + " 2>" + Quote(err_path);
    RunResult result;
    FILE* pipe = ::popen(command.c_str(), "r");
    if (pipe == nullptr) return result;
    char buffer[4096];
    std::size_t read = 0;
    while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.out.append(buffer, read);
    const int status = ::pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.err = ReadFile(err_path);
    return result;
  }
  static fs::path dir_;
};
fs::path FreqCommandsTest::dir_;

TEST_F(FreqCommandsTest, TerminationsGiveTheBarePipesResonances) {
  // c = 1173 m/s: c/2L = 0.6517 Hz with the valve, c/4L = 0.3258 Hz open (with f1: 0.6518, 0.3260).
  RunResult valve =
      Run("freqresp --analytic --termination closed-at-pipe-end --set "
          "wave_speed_mps=1173 --fmin 0.05 --fmax 1 --out valve.csv");
  ASSERT_EQ(valve.exit_code, 0) << valve.err;
  EXPECT_TRUE(Contains(valve.out, "termination closed-at-pipe-end")) << valve.out;
  EXPECT_TRUE(Contains(valve.out, "first resonance 0.6518 Hz")) << valve.out;
  RunResult open =
      Run("freqresp --analytic --termination choke-open --set wave_speed_mps=1173 "
          "--fmin 0.05 --fmax 1 --out open.csv");
  ASSERT_EQ(open.exit_code, 0) << open.err;
  EXPECT_TRUE(Contains(open.out, "first resonance 0.3260 Hz")) << open.out;

  RunResult unknown = Run("freqresp --analytic --termination valve --out x.csv");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_TRUE(Contains(unknown.err, "choke-closed, choke-open, closed-at-pipe-end")) << unknown.err;
  RunResult both = Run("freqresp --analytic --termination choke-open --choke closed --out x.csv");
  EXPECT_NE(both.exit_code, 0);
  RunResult pump = Run("freqresp --analytic --termination choke-open --pump-lpm 5 --out x.csv");
  EXPECT_NE(pump.exit_code, 0);
  EXPECT_TRUE(Contains(pump.err, "pump is off")) << pump.err;
}

TEST_F(FreqCommandsTest, FitResonancesWithTheWaveSpeedHeld) {
  const std::string csv = std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/thesis-resonances.csv";
  RunResult fit = Run("fit --resonances " + Quote(csv) +
                      " --set wave_speed_mps=1173 --hold wave_speed_mps --effect "
                      "topside_compliance --effect gas_entrainment --quiet --json fit.json");
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const std::string json = ReadFile(Path("fit.json"));
  for (const char* key :
       {"\"configuration\": \"choke-closed\"", "\"measured_hz\"", "\"base_model_hz\"",
        "\"model_hz\"", "\"response\": \"analytic\"", "\"closed-at-pipe-end\""}) {
    EXPECT_TRUE(Contains(json, key)) << key << "\n" << json;
  }
  EXPECT_FALSE(Contains(json, "\"wave_speed_mps\": {")) << "held, so not fitted";
  EXPECT_LT(JsonValue(json, "max_error_hz"), 0.005);
  EXPECT_TRUE(Contains(fit.out, "wave_speed_mps held at 1173")) << fit.out;

  std::ofstream(Path("bad.csv")) << "configuration,frequency_hz,uncertainty_hz\n"
                                 << "choke-closed,0.44,0.01\nchoke-open,0.25;0.01\n";
  RunResult bad = Run("fit --resonances bad.csv --json -");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Contains(bad.err, "bad.csv:3:")) << bad.err;
  RunResult both = Run("fit " + Quote(csv) + " --resonances " + Quote(csv) + " --json -");
  EXPECT_NE(both.exit_code, 0);
  RunResult hold = Run("fit --resonances " + Quote(csv) + " --hold wave_speed --quiet");
  EXPECT_NE(hold.exit_code, 0);
  EXPECT_TRUE(Contains(hold.err, "wave_speed")) << hold.err;
}

TEST_F(FreqCommandsTest, FromLogWritesJsonAndCsv) {
  RunResult synth = Run("synth --seed 1 --duration 60 --out s.csv");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  RunResult fr = Run("freqresp --from-log s.csv --segment-s 30 --json fr.json --csv fr.csv");
  ASSERT_EQ(fr.exit_code, 0) << fr.err;
  EXPECT_TRUE(Contains(fr.out, "PT1")) << fr.out;
  const std::string json = ReadFile(Path("fr.json"));
  for (const char* key : {"\"channels\"", "\"channel\": \"PT1\"", "\"peaks\"", "\"coherence\"",
                          "\"segments\": 3", "\"df_hz\""}) {
    EXPECT_TRUE(Contains(json, key)) << key;
  }
  const std::string csv = ReadFile(Path("fr.csv"));
  EXPECT_EQ(csv.rfind("channel,freq_hz,magnitude_pa_per_m,phase_deg,coherence\n", 0), 0u);
  RunResult mixed = Run("freqresp --from-log s.csv --analytic");
  EXPECT_NE(mixed.exit_code, 0);
}

TEST_F(FreqCommandsTest, FromLogAppendsItsResonanceToAListThatDiagnoseReads) {
  RunResult synth = Run("synth --seed 1 --duration 60 --out r.csv");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  fs::remove(Path("list.csv"));
  RunResult first =
      Run("freqresp --from-log r.csv --segment-s 30 --termination choke-open "
          "--resonance-list list.csv");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::string list = ReadFile(Path("list.csv"));
  EXPECT_EQ(list.rfind("configuration,frequency_hz,uncertainty_hz\nchoke-open,", 0), 0u) << list;
  // The same termination again is refused with the line, and the file is left as it was.
  RunResult again =
      Run("freqresp --from-log r.csv --segment-s 30 --termination choke-open "
          "--resonance-list list.csv");
  EXPECT_NE(again.exit_code, 0);
  EXPECT_TRUE(Contains(again.err, "list.csv:3:1")) << again.err;
  EXPECT_EQ(ReadFile(Path("list.csv")), list);
  RunResult unnamed = Run("freqresp --from-log r.csv --segment-s 30 --resonance-list list.csv");
  EXPECT_NE(unnamed.exit_code, 0);
  EXPECT_TRUE(Contains(unnamed.err, "--termination")) << unnamed.err;

  // diagnose --resonances on the thesis's three peaks, c held at the fronts' 1173 m/s.
  std::ofstream(Path("thesis.csv")) << "configuration,frequency_hz,uncertainty_hz\n"
                                    << "choke-closed,0.44,0.01\nchoke-open,0.25,0.01\n"
                                    << "closed-at-pipe-end,0.49,0.01\n";
  RunResult d =
      Run("diagnose --resonances thesis.csv --set wave_speed_mps=1173 --hold "
          "wave_speed_mps --response analytic --json d.json");
  ASSERT_EQ(d.exit_code, 0) << d.err;
  const std::string json = ReadFile(Path("d.json"));
  for (const char* key :
       {"\"resonances\"", "\"configuration\": \"choke-closed\"", "\"measured_hz\"",
        "\"base_model_hz\"", "\"model_hz\"", "\"selected\"", "\"uniform_wave_speed\"",
        "\"closed_open_ratio\"", "\"not_fitted\"", "\"selection_end\""}) {
    EXPECT_TRUE(Contains(json, key)) << key;
  }
  // The final model's largest error: the top-level key, after every candidate's.
  const std::size_t top = json.rfind("\n  \"max_error_hz\"");
  ASSERT_NE(top, std::string::npos) << json;
  EXPECT_LT(JsonValue(json.substr(top), "max_error_hz"), 0.015) << json;
  EXPECT_TRUE(Contains(d.out, "selected:")) << d.out;
  RunResult both = Run("diagnose r.csv --resonances thesis.csv");
  EXPECT_NE(both.exit_code, 0);
  RunResult neither = Run("diagnose --json -");
  EXPECT_NE(neither.exit_code, 0);
}

}  // namespace
}  // namespace mpdrig
