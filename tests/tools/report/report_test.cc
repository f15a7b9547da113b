// The comparison's presentation (tools/report/): the JSON has the documented fields, the HTML
// report is self-contained (no http(s) reference) and renders in headless Chromium; and the
// `mpdrig compare` command refuses bad input with a position and a non-zero exit code.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/shell.h"

#include "model/analysis/compare.h"
#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/common/units.h"
#include "model/riglog/rig_log.h"
#include "model/sim/log_inputs.h"
#include "tools/report/comparison_json.h"
#include "tools/report/html_report.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;
using riglog::Channel;

fs::path TempDir() { return mpdrig::testing::TestTempDir("mpdrig_report_test_"); }

using mpdrig::testing::ReadFile;

// Runs a shell command; returns its exit code and (in *output) stdout and stderr.
int RunShell(const std::string& command, std::string* output) {
  return mpdrig::testing::RunShell(command, TempDir() / "command_output.txt", output);
}

// A "measured" log: a 0.2 Hz piston sine through the model with c = 1000 m/s, PT1..PT10, C2, FT3,
// so the default model (c = 850 m/s) has something to get wrong.
std::string WriteLabLog() {
  riglog::RigLog log;
  for (long i = 0; i <= 3000; ++i) log.time_s.push_back(i * 0.01);
  std::vector<double> piston, choke, pump;
  for (double t : log.time_s) {
    piston.push_back(0.05 * std::sin(2.0 * std::numbers::pi * 0.2 * t));
    choke.push_back(units::ChokeDegToFrac(31.0));
    pump.push_back(units::LpmToM3ps(20.0));
  }
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kPistonPosition), piston).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kChokePosition), choke).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kFT2), pump).ok());
  auto signals = SignalsFromLog(log, "lab", ReplayOptions{});
  EXPECT_TRUE(signals.ok());
  SimulationOptions options;
  options.choke_input = ChokeInput::kMeasured;
  RigParams rig;
  rig.wave_speed_mps = 1000.0;
  auto run = Simulate(rig, options, *signals, log.time_s);
  EXPECT_TRUE(run.ok()) << run.status().message();
  std::vector<Channel> measured = {Channel::kC2, Channel::kFT3};
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    measured.push_back(static_cast<Channel>(static_cast<int>(Channel::kPT1) + k));
  }
  for (Channel channel : measured) {
    std::vector<double> values;
    for (const RigSample& sample : run->samples) values.push_back(sample[channel]);
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(channel), values).ok());
  }
  const std::string path = (TempDir() / "lab.csv").string();
  EXPECT_TRUE(riglog::WriteRigLog(log, path).ok());
  return path;
}

struct Rendered {
  Comparison comparison;
  std::string json;
  std::string html;
};

Rendered CompareLab() {
  const std::string path = WriteLabLog();
  auto comparison = CompareLog(path, RigParams{}, SimulationOptions{});
  EXPECT_TRUE(comparison.ok()) << comparison.status().message();
  report::ReportContext context;
  context.log_path = path;
  context.model_description = "default";
  return {*comparison, report::ComparisonJson(*comparison, context),
          report::ComparisonHtml(*comparison, context)};
}

TEST(ReportTest, JsonHasTheDocumentedFieldsInLabUnits) {
  const Rendered rendered = CompareLab();
  const std::string& json = rendered.json;
  for (const char* field : {"\"error\":",
                            "\"channels\":{",
                            "\"PT1\":{",
                            "\"C2\":{",
                            "\"FT3\":{",
                            "\"fit_percent\":",
                            "\"nrmse\":",
                            "\"rms\":",
                            "\"bias\":",
                            "\"lag_s\":",
                            "\"bands\":[",
                            "\"magnitude_ratio\":",
                            "\"phase_diff_deg\":",
                            "\"profile\":[",
                            "\"x_m\":",
                            "\"residual\":{",
                            "\"white\":",
                            "\"independent_of_inputs\":",
                            "\"transfer_functions\":{",
                            "\"unit\":\"barg\""}) {
    EXPECT_NE(json.find(field), std::string::npos) << field;
  }
  // Balanced: every '{' and '[' closed (no string in this JSON holds a bracket).
  EXPECT_EQ(std::count(json.begin(), json.end(), '{'), std::count(json.begin(), json.end(), '}'));
  EXPECT_EQ(std::count(json.begin(), json.end(), '['), std::count(json.begin(), json.end(), ']'));
  // Undefined numbers are null, never the non-JSON nan/inf.
  for (const char* bad : {":nan", ":-nan", ":inf", ":-inf", ",nan", ",inf", "[nan", "[inf"}) {
    EXPECT_EQ(json.find(bad), std::string::npos) << bad;
  }
  // rms in bar: the PT1 RMS error in Pa / 1e5 appears verbatim (shortest round-trip digits).
  const ChannelMetrics* pt1 = rendered.comparison.Find(Channel::kPT1);
  ASSERT_NE(pt1, nullptr);
  EXPECT_NE(json.find("\"rms\":" + riglog::FormatNumber(pt1->rms_si / 1e5)), std::string::npos);
}

TEST(ReportTest, HtmlIsSelfContainedAndRendersInHeadlessChromium) {
  const Rendered rendered = CompareLab();
  const std::string& html = rendered.html;
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_NE(html.find("<h2>Summary</h2>"), std::string::npos);
  EXPECT_NE(html.find("Error along the pipe"), std::string::npos);
  // The inputs as measured and as replayed: four plots, and how they were reconstructed.
  EXPECT_NE(html.find("<h2>Inputs: as measured and as replayed</h2>"), std::string::npos);
  EXPECT_NE(html.find("reconstructed under their noise"), std::string::npos);
  EXPECT_NE(html.find("choke_position [deg]"), std::string::npos);
  EXPECT_NE(html.find("FT2 [L/min]"), std::string::npos);
  EXPECT_NE(html.find("piston_position &rarr; PT1"), std::string::npos);
  EXPECT_NE(html.find("piston_position &rarr; C2"), std::string::npos);
  // One trace section per channel: 10 PT + C2 + FT3.
  std::size_t sections = 0;
  for (std::size_t at = html.find("<section"); at != std::string::npos;
       at = html.find("<section", at + 1))
    ++sections;
  EXPECT_EQ(sections, 12u);

  std::string found;
  if (RunShell("command -v chromium", &found) != 0) {
    GTEST_SKIP() << "chromium is not installed (deploy/install-deps.sh installs it)";
  }
  const fs::path dir = TempDir();
  const fs::path report = dir / "report.html";
  const fs::path blank = dir / "blank.html";
  std::ofstream(report, std::ios::binary) << html;
  std::ofstream(blank) << "<!DOCTYPE html><html><body></body></html>\n";
  auto screenshot = [&](const fs::path& page, const fs::path& png) {
    const fs::path profile = dir / ("profile_" + png.stem().string());
    fs::remove_all(profile);
    std::string output;
    const int code = RunShell(
        "chromium --headless --no-sandbox --disable-gpu --disable-background-networking "
        "--disable-component-update --disable-sync --no-first-run --user-data-dir=" +
            profile.string() + " --window-size=1280,2000 --screenshot=" + png.string() +
            " file://" + page.string(),
        &output);
    EXPECT_EQ(code, 0) << output;
    return fs::exists(png) ? fs::file_size(png) : 0u;
  };
  const auto blank_bytes = screenshot(blank, dir / "blank.png");
  const auto report_bytes = screenshot(report, dir / "report.png");
  ASSERT_GT(blank_bytes, 0u);
  // PNG compresses a uniform page to almost nothing; tables, text and plots do not compress like
  // that. A blank 1280x2000 page is a few kB; the report's first screen is hundreds of kB.
  EXPECT_GT(report_bytes, 10 * blank_bytes)
      << "report " << report_bytes << " bytes, blank page " << blank_bytes << " bytes";
}

// `mpdrig compare` streams the file (CompareLog); the in-memory steps give the same report, byte
// for byte, with one periodogram and with Welch segments (3001 samples: 10 segments of 512
// every 256, and one ending at the last sample).
TEST(ReportTest, StreamedAndInMemoryComparisonsRenderTheSame) {
  const std::string path = WriteLabLog();
  report::ReportContext context;
  context.log_path = path;
  context.model_description = "default";
  for (int segment : {1 << 17, 512}) {
    SCOPED_TRACE(segment);
    CompareOptions options;
    options.welch_segment_samples = segment;
    auto streamed = CompareLog(path, RigParams{}, SimulationOptions{}, options);
    ASSERT_TRUE(streamed.ok()) << streamed.status().message();
    auto log = LoadMeasuredLog(path);
    ASSERT_TRUE(log.ok()) << log.status().message();
    // As CompareLog: the start (steady, warmed up or measured) chosen from the measured
    // pressures.
    ReplayOptions replay;
    const Status start = ChooseReplayStart(*log, RigParams{}, SimulationOptions{}, &replay);
    ASSERT_TRUE(start.ok()) << start.message();
    auto model = ReplayModel(*log, RigParams{}, SimulationOptions{}, replay);
    ASSERT_TRUE(model.ok()) << model.status().message();
    auto in_memory = CompareTraces(*log, *model, options);
    ASSERT_TRUE(in_memory.ok()) << in_memory.status().message();
    const std::string json = report::ComparisonJson(*streamed, context);
    EXPECT_EQ(json, report::ComparisonJson(*in_memory, context));
    EXPECT_EQ(report::ComparisonHtml(*streamed, context),
              report::ComparisonHtml(*in_memory, context));
    EXPECT_NE(json.find(segment == 512 ? "\"spectrum_segments\":11" : "\"spectrum_segments\":1,"),
              std::string::npos);
  }
}

TEST(CompareCommandTest, RefusesBadInputWithPositionAndNonZeroExit) {
  const fs::path dir = TempDir();
  const fs::path log = dir / "bad_time.csv";
  std::ofstream(log) << "time_s,piston_position_m,choke_position_deg,PT1_barg\n"
                        "0,0,31,1\n0.02,0,31,1\n0.01,0,31,1\n";
  std::string output;
  const std::string exe = MPDRIG_EXE;
  EXPECT_NE(RunShell(exe + " compare " + log.string() + " --json " + (dir / "out.json").string(),
                     &output),
            0);
  EXPECT_NE(output.find(log.string() + ":4:1:"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir / "out.json"));

  const fs::path no_inputs = dir / "no_inputs.csv";
  std::ofstream(no_inputs) << "time_s,PT1_barg\n0,1\n0.01,1\n";
  EXPECT_NE(RunShell(exe + " compare " + no_inputs.string() + " --json -", &output), 0);
  EXPECT_NE(output.find(no_inputs.string() + ":1:1: required input column 'piston_position"),
            std::string::npos)
      << output;

  const fs::path unit = dir / "unit.csv";
  std::ofstream(unit) << "time_s,piston_position_m,choke_position_deg,PT1_psi\n0,0,31,1\n";
  EXPECT_NE(RunShell(exe + " compare " + unit.string() + " --json -", &output), 0);
  EXPECT_NE(output.find(unit.string() + ":1:"), std::string::npos) << output;

  EXPECT_NE(RunShell(exe + " compare " + log.string() + " --effect orifice --json -", &output), 0);
  EXPECT_NE(output.find("unknown effect 'orifice'; valid effects:"), std::string::npos) << output;
}

TEST(CompareCommandTest, WritesJsonAndReportForAGoodLog) {
  const std::string log = WriteLabLog();
  const fs::path dir = TempDir();
  std::string output;
  const std::string exe = MPDRIG_EXE;
  ASSERT_EQ(RunShell(exe + " compare " + log + " --json " + (dir / "out.json").string() +
                         " --report " + (dir / "out.html").string(),
                     &output),
            0)
      << output;
  // Progress: pass 1 counts the samples read, pass 2 (replay and metrics) gives percentages.
  EXPECT_NE(output.find("mpdrig compare: read"), std::string::npos) << output;
  EXPECT_NE(output.find("mpdrig compare: replay 100%"), std::string::npos) << output;
  EXPECT_NE(ReadFile(dir / "out.json").find("\"channels\":{\"PT1\":{"), std::string::npos);
  EXPECT_NE(ReadFile(dir / "out.html").find("<h2>Summary</h2>"), std::string::npos);
}

// A noise-free log whose pump stays at 5 L/min: the replayed FT2 is 5 and, here and there, the
// next double up. Its plot's tick loop once stepped below that resolution, never ended, and
// `mpdrig compare --report` aborted out of memory.
TEST(CompareCommandTest, ReportsOnANoiseFreeLogWithAConstantInput) {
  const fs::path dir = TempDir();
  const std::string exe = MPDRIG_EXE;
  const std::string log = (dir / "constant_pump.csv").string();
  std::string output;
  ASSERT_EQ(
      RunShell(exe + " simulate --piston 0 --choke-deg sine:amp_deg=3,freq_hz=0.1,mean_deg=31" +
                   " --pump-lpm 5 --duration 10 --sensor-noise none --out " + log,
               &output),
      0)
      << output;
  const std::string report = (dir / "constant_pump.html").string();
  // Bounded memory, so a relapse fails here rather than filling the machine (not under
  // AddressSanitizer, whose shadow memory alone exceeds any such bound).
#if defined(__SANITIZE_ADDRESS__)
  const std::string bound;
#else
  const std::string bound = "ulimit -v 4000000; ";
#endif
  ASSERT_EQ(RunShell(bound + exe + " compare " + log + " --report " + report, &output), 0)
      << output;
  const std::string html = ReadFile(report);
  EXPECT_NE(html.find("<h2>Summary</h2>"), std::string::npos);
  EXPECT_NE(html.find("</html>"), std::string::npos);
}

// A still rig, noise-free: every channel constant but for rounding (1e-12 bar), which the model
// matches. There is nothing to explain: each channel is left out as constant, not divided by its
// rounding. Before: "worst PT10 (fit 47.2 %)"; on identical rows "error 2.066e+10".
TEST(CompareCommandTest, ConstantChannelsAreLeftOutNotDividedByTheirRounding) {
  const fs::path dir = TempDir();
  const std::string exe = MPDRIG_EXE;
  const std::string log = (dir / "still_rig.csv").string();
  std::string output;
  ASSERT_EQ(RunShell(exe + " simulate --piston 0 --choke-deg 31 --pump-lpm 5 --duration 20" +
                         " --sensor-noise none --out " + log,
                     &output),
            0)
      << output;
  ASSERT_EQ(RunShell(exe + " compare " + log + " --json " + log + ".json 2>/dev/null", &output), 0)
      << output;
  EXPECT_EQ(output.find("worst"), std::string::npos) << output;
  EXPECT_NE(output.find("channels constant (within rounding"), std::string::npos) << output;
  const std::string json = ReadFile(log + ".json");
  EXPECT_NE(json.find("\"nrmse\":null"), std::string::npos) << "constant channels: null";
  // P1's lag was 10 s (the window's edge) with a correlation of 1.38: rounding, not a lag.
  EXPECT_EQ(json.find("\"lag_s\":10,"), std::string::npos) << "a lag found in rounding";

  // Identical rows, written by hand: one varying channel (PT5) is compared, the rest are not.
  const std::string rows = (dir / "identical_rows.csv").string();
  {
    std::ofstream out(rows);
    out << "time_s,piston_position_m,choke_position_deg,FT2_lpm,C2_barg,PT1_barg,PT5_barg\n";
    for (int i = 0; i < 20000; ++i) {
      out << 0.01 * i << ",0,31,5,3.9521,4.2138," << 4.1 + 0.01 * std::sin(0.05 * i) << "\n";
    }
  }
  ASSERT_EQ(RunShell(exe + " compare " + rows + " --json " + rows + ".json 2>/dev/null", &output),
            0)
      << output;
  EXPECT_NE(output.find("worst PT5"), std::string::npos) << output;
  EXPECT_NE(output.find("2 channels constant"), std::string::npos) << output;
  double error = 0.0;
  const std::size_t at = output.find("error (mean NRMSE) ");
  ASSERT_NE(at, std::string::npos) << output;
  ASSERT_EQ(std::sscanf(output.c_str() + at, "error (mean NRMSE) %lf", &error), 1) << output;
  EXPECT_LT(error, 1e4) << "the error of the one varying channel, not of rounding (2e10): "
                        << output;
}

}  // namespace
}  // namespace mpdrig
