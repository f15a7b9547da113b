// `mpdrig synth` and `mpdrig diagnose` as a user runs them: the JSON names outside checks read,
// the self-contained HTML report (rendered by headless Chromium), errors for bad input.

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/shell.h"

namespace {

namespace fs = std::filesystem;

fs::path TempDir() { return mpdrig::testing::TestTempDir("mpdrig_diagnose_test_"); }

using mpdrig::testing::ReadFile;

// Runs a shell command; returns its exit code and (in *output) stdout and stderr.
int RunShell(const std::string& command, std::string* output) {
  return mpdrig::testing::RunShell(command, TempDir() / "command_output.txt", output);
}

const std::string kExe = MPDRIG_EXE;

TEST(DiagnoseCommandTest, FindsAHiddenSensorLagAndWritesJsonAndReport) {
  const fs::path dir = TempDir();
  const std::string log = (dir / "lag.csv").string();
  std::string output;
  ASSERT_EQ(
      RunShell(kExe + " synth --effect sensor_lag --seed 3 --duration 30 --rate-hz 50 --out " + log,
               &output),
      0)
      << output;
  EXPECT_NE(ReadFile(log).find("# hidden: sensor_lag"), std::string::npos);
  const std::string json = (dir / "d.json").string();
  const std::string html = (dir / "d.html").string();
  // Two candidates keep the test short; the full catalogue is diagnose_test's.
  ASSERT_EQ(RunShell(kExe + " diagnose " + log + " --candidates choke_inertia,sensor_lag --json " +
                         json + " --report " + html,
                     &output),
            0)
      << output;
  EXPECT_NE(output.find("verdict: sensor_lag"), std::string::npos) << output;
  EXPECT_NE(output.find("selected: sensor_lag ("), std::string::npos) << output;
  EXPECT_NE(output.find("effects added one after the other"), std::string::npos) << output;
  EXPECT_NE(output.find("diagnose: 100% done"), std::string::npos) << "progress on stderr";
  const std::string text = ReadFile(json);
  for (const char* field :
       {"\"baseline\":{\"error\":", "\"params\":{\"wave_speed_mps\"",
        "\"candidates\":[{\"effect\":", "\"significant\":true", "\"verdict\":\"sensor_lag\"",
        "\"equivalent\":[", "\"held\":", "\"noise_floor\":",
        // Forward selection: the verdict first, then what ended it.
        "\"selected\":[{\"effect\":\"sensor_lag\"",
        "\"selection_end\":", "\"next\":", "\"failed\":[", "\"round\":1",
        // Round 2 (choke_inertia against the model with the lag), which ended the selection.
        "\"later_rounds\":[{\"round\":2,\"reference\":\"sensor_lag\"",
        "\"reference_error\":", "\"candidates\":[{\"effect\":\"choke_inertia\",\"round\":2",
        // What the best model leaves, against the noise floor; the regimes and the split.
        "\"residual\":{\"model\":\"base model + sensor_lag\"",
        "\"misses\":", "\"noise_floor_method\":", "\"findings\":[", "\"bands\":[",
        "\"split\":{\"fit_end_s\":", "\"regimes\":["}) {
    EXPECT_NE(text.find(field), std::string::npos) << field << " in " << text.substr(0, 400);
  }
  // Ranked best first: the first candidate is the verdict.
  EXPECT_LT(text.find("\"effect\":\"sensor_lag\""), text.find("\"effect\":\"choke_inertia\""));

  const std::string page = ReadFile(html);
  EXPECT_EQ(page.find("http://"), std::string::npos);
  EXPECT_EQ(page.find("https://"), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos);
  EXPECT_NE(page.find("Missing effect: <b>sensor_lag</b>"), std::string::npos);
  EXPECT_NE(page.find("before and after adding sensor_lag"), std::string::npos);
  EXPECT_NE(page.find("Effects added one after the other"), std::string::npos);
  EXPECT_NE(page.find("Selection ended: "), std::string::npos);
  EXPECT_NE(page.find("What is left"), std::string::npos);
  EXPECT_NE(page.find("Regimes of the log and the split"), std::string::npos);
  EXPECT_NE(output.find("what is left: "), std::string::npos) << output;
  EXPECT_NE(output.find("regimes: none"), std::string::npos) << output;

  std::string found;
  if (RunShell("command -v chromium", &found) != 0) {
    GTEST_SKIP() << "chromium is not installed (deploy/install-deps.sh installs it)";
  }
  const fs::path png = dir / "d.png";
  ASSERT_EQ(RunShell("chromium --headless --no-sandbox --disable-gpu "
                     "--disable-background-networking --disable-component-update --disable-sync "
                     "--no-first-run --user-data-dir=" +
                         (dir / "profile").string() + " --window-size=1280,1600 --screenshot=" +
                         png.string() + " file://" + html,
                     &output),
            0)
      << output;
  // A rendered page of plots and tables does not compress to a few kB as a blank one does.
  EXPECT_GT(fs::file_size(png), 30000u);
}

TEST(DiagnoseCommandTest, RefusesBadInput) {
  std::string output;
  EXPECT_NE(RunShell(kExe + " diagnose /nonexistent.csv --json -", &output), 0);
  const fs::path dir = TempDir();
  const std::string log = (dir / "x.csv").string();
  ASSERT_EQ(RunShell(kExe + " synth --seed 1 --duration 12 --rate-hz 20 --out " + log, &output), 0)
      << output;
  EXPECT_NE(RunShell(kExe + " diagnose " + log + " --candidates gremlins --json -", &output), 0);
  EXPECT_NE(output.find("unknown effect 'gremlins'; valid effects:"), std::string::npos) << output;
  EXPECT_NE(RunShell(kExe + " synth --pressure-noise-pa -1 --out " + log, &output), 0);
  EXPECT_NE(output.find("--pressure-noise-pa"), std::string::npos) << output;
  EXPECT_NE(RunShell(kExe + " synth --pump-stop 5 --out " + log, &output), 0);
  EXPECT_NE(output.find("--pump-stop '5': expected START:DURATION"), std::string::npos) << output;
  EXPECT_NE(RunShell(kExe + " synth --duration 12 --choke-close 10:8 --out " + log, &output), 0);
  EXPECT_NE(output.find("choke closure at 10 s for 8 s must lie inside the log"), std::string::npos)
      << output;
  EXPECT_NE(RunShell(kExe + " synth --effect gremlins --out " + log, &output), 0);
  EXPECT_NE(output.find("valid effects"), std::string::npos) << output;
  {
    std::ofstream bad(dir / "bad.csv");
    bad << "# rig-log: 1\ntime_s,piston_position_m,choke_position_deg,PT1_barg\n0,0,31,1\n"
           "0.01,0,31,abc\n";
  }
  EXPECT_NE(RunShell(kExe + " diagnose " + (dir / "bad.csv").string() + " --json -", &output), 0);
  EXPECT_NE(output.find("bad.csv:4:"), std::string::npos) << output;
}

}  // namespace
