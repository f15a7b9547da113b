// `mpdrig synth` with the lab's sensor noise (thesis Table 4.1.1) and the noise-free truth from the
// same seed (--truth-out): the real binary, real files.
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/riglog/rig_log.h"
#include "tests/support/shell.h"
#include "tests/support/statistics.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;

const std::string kExe = MPDRIG_EXE;

fs::path TempDir() { return testing::TestTempDir("mpdrig_synth_command_test_"); }

int RunShell(const std::string& command, std::string* output) {
  return testing::RunShell(command, TempDir() / "command_output.txt", output);
}

riglog::RigLog ReadLog(const fs::path& path) {
  auto log = riglog::ReadRigLog(path.string());
  EXPECT_TRUE(log.ok()) << log.status().message();
  return log.ok() ? std::move(log).value() : riglog::RigLog{};
}

std::string Metadata(const riglog::RigLog& log, const std::string& key) {
  for (const auto& [k, v] : log.metadata) {
    if (k == key) return v;
  }
  return "";
}

using teststats::SampleStdDev;
using teststats::StdDevTolerance;

// 30 s at 50 Hz: 1501 samples a channel.
const char kRun[] = " synth --seed 5 --duration 30 --rate-hz 50";

// Several hidden effects at once (the logs diagnose's forward selection is tried on): --effect
// repeated, each NAME[:KEY=VALUE,...]; a strength given is kept, the others drawn; the first
// effect's draw is the same as alone on the same seed. A name twice or an unknown key is refused.
TEST(SynthCommandTest, HidesSeveralEffectsAtGivenOrDrawnStrengths) {
  const fs::path dir = TempDir();
  const std::string two = (dir / "two.csv").string(), one = (dir / "one.csv").string();
  std::string output;
  ASSERT_EQ(RunShell(kExe + kRun +
                         " --effect unsteady_friction --effect sensor_lag:time_constant_s=0.1 "
                         "--out " +
                         two,
                     &output),
            0)
      << output;
  ASSERT_EQ(RunShell(kExe + kRun + " --effect unsteady_friction --out " + one, &output), 0)
      << output;
  const std::string hidden = Metadata(ReadLog(two), "hidden");
  const std::string alone = Metadata(ReadLog(one), "hidden");
  EXPECT_NE(hidden.find(" + sensor_lag time_constant_s=0.1;"), std::string::npos) << hidden;
  // "unsteady_friction k=...": the same draw as alone.
  const std::string first = alone.substr(0, alone.find(';'));
  EXPECT_EQ(hidden.rfind(first + " + ", 0), 0u) << hidden << " against " << alone;
  EXPECT_NE(
      RunShell(kExe + kRun + " --effect sensor_lag --effect sensor_lag --out " + two, &output), 0);
  EXPECT_NE(output.find("'sensor_lag' given twice"), std::string::npos) << output;
  EXPECT_NE(RunShell(kExe + kRun + " --effect sensor_lag:tau_s=1 --out " + two, &output), 0);
  EXPECT_NE(output.find("tau_s"), std::string::npos) << output;
}

// Absurd lengths and rates, found by a bad-input probe: before, --duration 1e9 allocated until
// std::bad_alloc aborted the process. Now they are refused at once, naming the flag and the limit.
TEST(SynthCommandTest, RefusesAbsurdDurationsAndRatesNamingTheFlagAndTheLimit) {
  const fs::path dir = TempDir();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--duration 1e9", "--duration 1e+09 s must be in [10, 86400] s"},
      {"--duration inf", "--duration inf s must be in [10, 86400] s"},
      {"--duration 30 --rate-hz inf", "--rate-hz inf Hz must be in [10, 10000] Hz"},
      {"--duration 86400 --rate-hz 1000", "8.64e+07 samples, at most 1e+07"},
  };
  for (const auto& [flags, named] : cases) {
    std::string output;
    EXPECT_EQ(
        RunShell(kExe + " synth --seed 1 " + flags + " --out " + (dir / "x.csv").string(), &output),
        1)
        << flags << ": refused with an error, not a crash\n"
        << output;
    EXPECT_NE(output.find(named), std::string::npos) << flags << ": " << output;
    EXPECT_FALSE(fs::exists(dir / "x.csv")) << flags;
  }
}

TEST(SynthCommandTest, TruthOutMinusTheLogHasTheLabStatistics) {
  const fs::path dir = TempDir();
  std::string output;
  ASSERT_EQ(RunShell(kExe + kRun + " --out " + (dir / "noisy.csv").string() + " --truth-out " +
                         (dir / "truth.csv").string(),
                     &output),
            0)
      << output;
  const riglog::RigLog noisy = ReadLog(dir / "noisy.csv");
  const riglog::RigLog truth = ReadLog(dir / "truth.csv");
  ASSERT_EQ(noisy.time_s, truth.time_s);
  ASSERT_EQ(noisy.columns, truth.columns);
  ASSERT_EQ(noisy.num_rows(), 1501u);
  EXPECT_EQ(Metadata(noisy, "sensor_noise"), "lab, seed 5");
  EXPECT_EQ(Metadata(noisy, "hidden"), Metadata(truth, "hidden")) << "same parameters";
  EXPECT_NE(Metadata(truth, "sensor_noise").find("none"), std::string::npos);

  // Pooled over the channels of each kind. Flow errors are divided by their sigma at the true
  // reading (2 % of it + 0.05 L/min): unit variance only if the noise scales with the reading
  // (the pump's 6-10 L/min give 0.17-0.25 L/min, 3-5 times the floor alone).
  std::vector<double> pressure, flow, piston, choke;
  for (std::size_t c = 0; c < noisy.columns.size(); ++c) {
    const riglog::Quantity quantity = noisy.columns[c].quantity();
    for (std::size_t i = 0; i < noisy.num_rows(); ++i) {
      const double x = truth.values_si[c][i];
      const double e = noisy.values_si[c][i] - x;
      switch (quantity) {
        case riglog::Quantity::kPressure:
          pressure.push_back(e);
          break;
        case riglog::Quantity::kFlow:
          flow.push_back(e / (0.02 * std::abs(x) + units::LpmToM3ps(0.05)));
          break;
        case riglog::Quantity::kPosition:
          piston.push_back(e);
          break;
        case riglog::Quantity::kChokeOpening:
          choke.push_back(e);
          break;
        case riglog::Quantity::kTime:
          break;
      }
    }
  }
  ASSERT_EQ(pressure.size(), 14u * 1501u);  // P1 P2 PT1..PT10 C1 C2
  ASSERT_EQ(flow.size(), 4u * 1501u);       // FT1..FT4
  EXPECT_NEAR(SampleStdDev(pressure), 2400.0, StdDevTolerance(pressure.size()) * 2400.0);
  EXPECT_NEAR(SampleStdDev(flow), 1.0, StdDevTolerance(flow.size()));
  EXPECT_NEAR(SampleStdDev(piston), 0.5e-3, StdDevTolerance(piston.size()) * 0.5e-3);
  EXPECT_NEAR(SampleStdDev(choke), 0.1 / 90.0, StdDevTolerance(choke.size()) * 0.1 / 90.0);
}

TEST(SynthCommandTest, SameSeedSameLogAndNoneIsTheTruth) {
  const fs::path dir = TempDir();
  std::string output;
  const std::string short_run = kExe + " synth --seed 9 --duration 12 --rate-hz 20";
  ASSERT_EQ(RunShell(short_run + " --out " + (dir / "a.csv").string(), &output), 0) << output;
  ASSERT_EQ(RunShell(short_run + " --out " + (dir / "b.csv").string(), &output), 0) << output;
  EXPECT_EQ(testing::ReadFile(dir / "a.csv"), testing::ReadFile(dir / "b.csv"));
  ASSERT_EQ(RunShell(short_run + " --sensor-noise none --out " + (dir / "none.csv").string() +
                         " --truth-out " + (dir / "truth.csv").string(),
                     &output),
            0)
      << output;
  const riglog::RigLog none = ReadLog(dir / "none.csv");
  const riglog::RigLog truth = ReadLog(dir / "truth.csv");
  EXPECT_EQ(none.values_si, truth.values_si);
  EXPECT_EQ(Metadata(none, "sensor_noise"), "none, seed 9");
  // ...and the lab log of that seed has the same truth.
  ASSERT_EQ(RunShell(short_run + " --out " + (dir / "lab.csv").string() + " --truth-out " +
                         (dir / "lab_truth.csv").string(),
                     &output),
            0)
      << output;
  EXPECT_EQ(ReadLog(dir / "lab_truth.csv").values_si, truth.values_si);
  EXPECT_NE(ReadLog(dir / "lab.csv").values_si, truth.values_si);
}

TEST(SynthCommandTest, OldFlagsOverrideOnePartAndBadSpecsAreNamed) {
  const fs::path dir = TempDir();
  std::string output;
  const std::string short_run = kExe + " synth --seed 9 --duration 12 --rate-hz 20";
  // Pressure noise off, the rest lab: pressures equal the truth, flows do not.
  ASSERT_EQ(RunShell(short_run + " --pressure-noise-pa 0 --out " + (dir / "a.csv").string() +
                         " --truth-out " + (dir / "t.csv").string(),
                     &output),
            0)
      << output;
  const riglog::RigLog a = ReadLog(dir / "a.csv");
  const riglog::RigLog t = ReadLog(dir / "t.csv");
  EXPECT_EQ(*a.Find("PT5"), *t.Find("PT5"));
  EXPECT_NE(*a.Find("FT1"), *t.Find("FT1"));
  EXPECT_NE(Metadata(a, "sensor_noise").find("pressure=0bar"), std::string::npos)
      << Metadata(a, "sensor_noise");

  EXPECT_NE(
      RunShell(short_run + " --sensor-noise 'lab,choke=0.1rad' --out " + (dir / "x.csv").string(),
               &output),
      0);
  EXPECT_NE(output.find("--sensor-noise"), std::string::npos) << output;
  EXPECT_NE(output.find("'choke=0.1rad'"), std::string::npos) << output;
  EXPECT_NE(output.find("deg"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
}

}  // namespace
}  // namespace mpdrig
