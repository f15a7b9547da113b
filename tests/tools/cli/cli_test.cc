// The mpdrig command line, run as a user runs it: the real binary, real files, exit codes and
// messages. Every run here simulates a few seconds at most (milliseconds of CPU).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/config/rig_config.h"
#include "model/params/rig_params.h"
#include "model/riglog/rig_log.h"
#include "tests/support/sanitizer.h"
#include "tests/support/statistics.h"
#include "tests/support/test_domain.h"
#include "tools/cli/program.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;  // standard output
  std::string err;  // standard error
};

std::string Quote(const std::string& text) { return "'" + text + "'"; }

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Each test runs in its own fresh directory under the build tree, removed when the test passes.
class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(MPDRIG_BINARY_DIR) / "tests" / "service" /
           ("cli_test." + std::to_string(::getpid()) + "." + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs `mpdrig <args>` (a shell command line) from the test directory.
  RunResult Run(const std::string& args) const {
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

  // The run of the brief: 0.2 Hz heave, choke 31 deg, 5 L/min, outlet at atmosphere, 5 s.
  // Without sensor noise: the tests that use it check the model's physics to better than the
  // lab's sensors read it (the noise has tests of its own below).
  std::string SimulateSine(const std::string& name,
                           const std::string& options = "--sensor-noise none") const {
    const std::string path = Path(name);
    const RunResult run =
        Run("simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 "
            "--outlet-barg 0 --duration 5 " +
            options + " --out " + Quote(path));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return path;
  }

  fs::path dir_;
};

riglog::RigLog ReadLog(const std::string& path) {
  Result<riglog::RigLog> log = riglog::ReadRigLog(path);
  EXPECT_TRUE(log.ok()) << log.status().message();
  return log.ok() ? std::move(log).value() : riglog::RigLog{};
}

const std::vector<double>& Column(const riglog::RigLog& log, const std::string& channel) {
  static const std::vector<double> kEmpty;
  const std::vector<double>* values = log.Find(channel);
  EXPECT_NE(values, nullptr) << "no column " << channel;
  return values != nullptr ? *values : kEmpty;
}

// --- help ----------------------------------------------------------------------------------

TEST_F(CliTest, TopLevelHelpListsTheCommands) {
  const RunResult run = Run("--help");
  EXPECT_EQ(run.exit_code, 0) << run.err;
  for (const char* command : {"demo", "simulate", "freqresp", "params"}) {
    EXPECT_TRUE(Contains(run.out, command)) << command << " not in\n" << run.out;
  }
}

TEST_F(CliTest, EachCommandHelpShowsItsKeyOptions) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> expected = {
      {"demo", {"--out", "--config", "--set"}},
      {"simulate",
       {"--inputs", "--piston", "--choke-deg", "--pump-lpm", "--outlet-barg", "--duration",
        "--rate-hz", "--out", "--allow-negative-pressure", "--model", "--cells", "--config",
        "--set", "sine:", "sweep:", "step:"}},
      {"freqresp",
       {"--analytic", "--simulated", "--choke", "--fmin", "--fmax", "--points", "--out"}},
      {"params", {"--format", "pbtxt", "--config", "--set"}},
  };
  for (const auto& [command, options] : expected) {
    const RunResult run = Run(command + " --help");
    EXPECT_EQ(run.exit_code, 0) << command << ": " << run.err;
    for (const std::string& option : options) {
      EXPECT_TRUE(Contains(run.out, option)) << command << " --help lacks " << option;
    }
  }
}

TEST_F(CliTest, NoOrUnknownCommandFails) {
  EXPECT_NE(Run("").exit_code, 0);
  EXPECT_NE(Run("bogus").exit_code, 0);
}

// --- the front and mpdrig-all (tools/CMakeLists.txt) ----------------------------------------

// What the front is for: a `simulate` that loads neither DDS nor the least-squares stack. Its
// shared libraries, as the dynamic loader resolves them (ldd), must not include any of them.
TEST_F(CliTest, TheFrontLoadsOnlyTheModelCore) {
  if (testing::kUnderAddressSanitizer)
    GTEST_SKIP() << "the sanitizer build links the front's libraries shared";
  FILE* pipe = ::popen(("ldd " + Quote(MPDRIG_EXE)).c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string libraries;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) libraries.append(buffer, read);
  ASSERT_EQ(::pclose(pipe), 0) << libraries;
  for (const char* heavy : {"libddsc", "libglog", "libcholmod", "liblapack", "libprotobuf",
                            "libsundials", "libfftw3", "libstdc++", "libcrypto"}) {
    EXPECT_FALSE(Contains(libraries, heavy)) << heavy << " in\n" << libraries;
  }
}

// Every other command line goes to mpdrig-all with the same arguments and comes back with its
// exit code; without mpdrig-all beside it, the front says what is missing and fails.
TEST_F(CliTest, TheFrontHandsOtherCommandsToMpdrigAll) {
  const RunResult fit_help = Run("fit --help");
  EXPECT_EQ(fit_help.exit_code, 0) << fit_help.err;
  EXPECT_TRUE(Contains(fit_help.out, "--params")) << fit_help.out;
  const RunResult bad = Run("compare no-such-log.csv");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Contains(bad.err, "no-such-log.csv")) << bad.err;

  const fs::path lone = dir_ / "lone";
  fs::create_directories(lone);
  fs::copy_file(MPDRIG_EXE, lone / "mpdrig");
  const std::string command = Quote((lone / "mpdrig").string()) + " serve --help 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, read);
  const int status = ::pclose(pipe);
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 127) << out;
  EXPECT_TRUE(Contains(out, "mpdrig-all")) << out;
  // The front's own commands do not need it: each one it names is registered in it.
  for (const std::string_view name : cli::kCoreCommands) {
    const std::string help =
        Quote((lone / "mpdrig").string()) + " " + std::string(name) + " --help >/dev/null 2>&1";
    EXPECT_EQ(std::system(help.c_str()), 0) << name;
  }
  const std::string simulate = Quote((lone / "mpdrig").string()) +
                               " simulate --piston sine:amp_m=0.1,freq_hz=0.2 --duration 1 --out " +
                               Quote(Path("lone.csv")) + " >/dev/null 2>&1";
  EXPECT_EQ(std::system(simulate.c_str()), 0);
  EXPECT_TRUE(fs::exists(Path("lone.csv")));
}

// --- params --------------------------------------------------------------------------------

TEST_F(CliTest, ParamsListsEveryKeyWithItsUnit) {
  const RunResult run = Run("params");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::vector<std::string> lines;
  std::istringstream in(run.out);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  for (const ParamInfo& info : ParamTable()) {
    // One line per key: "<key> <value> <unit> <meaning>", columns separated by spaces.
    const std::string key(info.key);
    const auto line = std::find_if(lines.begin(), lines.end(), [&](const std::string& l) {
      return l.rfind(key + " ", 0) == 0;
    });
    ASSERT_NE(line, lines.end()) << key << " not listed in\n" << run.out;
    std::istringstream fields(line->substr(key.size()));
    std::string value, rest;
    fields >> value;
    std::getline(fields, rest);
    rest.erase(0, rest.find_first_not_of(' '));
    EXPECT_EQ(rest.rfind(std::string(info.unit) + " ", 0), 0u)
        << key << " lacks its unit [" << info.unit << "]: " << *line;
  }
}

TEST_F(CliTest, ParamsPbtxtRoundTrip) {
  const RunResult pbtxt = Run("params --format pbtxt");
  ASSERT_EQ(pbtxt.exit_code, 0) << pbtxt.err;
  const std::string config = Path("rig.pbtxt");
  WriteFile(config, pbtxt.out);

  const RunResult table = Run("params");
  const RunResult loaded = Run("params --config " + Quote(config));
  ASSERT_EQ(loaded.exit_code, 0) << loaded.err;
  EXPECT_EQ(loaded.out, table.out);
  const RunResult again = Run("params --format pbtxt --config " + Quote(config));
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.out, pbtxt.out);

  Result<RigParams> params = LoadRigConfig(config);
  ASSERT_TRUE(params.ok()) << params.status().message();
  const RigParams defaults;
  for (const ParamInfo& info : ParamTable()) {
    EXPECT_EQ((*params).*info.member, defaults.*info.member) << info.key;
  }
}

TEST_F(CliTest, ParamsSetOverridesAndRejectsBadValues) {
  const RunResult set = Run("params --set wave_speed_mps=1100");
  ASSERT_EQ(set.exit_code, 0) << set.err;
  EXPECT_TRUE(std::regex_search(set.out, std::regex(R"((^|\n)wave_speed_mps +1100 )")));

  const RunResult bad = Run("params --set wave_speed_mps=abc");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Contains(bad.err, "wave_speed_mps")) << bad.err;
  EXPECT_TRUE(Contains(bad.err, "abc")) << bad.err;

  const RunResult unknown = Run("params --set wave_speed=1100");
  EXPECT_NE(unknown.exit_code, 0);
  EXPECT_TRUE(Contains(unknown.err, "wave_speed_mps")) << "valid keys listed: " << unknown.err;
}

// --- simulate ------------------------------------------------------------------------------

TEST_F(CliTest, SimulateWritesARigLogWithEveryChannel) {
  const riglog::RigLog log = ReadLog(SimulateSine("X.csv"));
  ASSERT_EQ(log.num_rows(), 501u);
  for (std::size_t i = 0; i < log.num_rows(); ++i) {
    ASSERT_NEAR(log.time_s[i], i / 100.0, 1e-9) << "row " << i;
  }
  std::vector<std::string> channels = {
      "P1", "P2", "C1", "C2", "FT1", "FT2", "FT3", "FT4", "piston_position", "choke_position"};
  for (int k = 1; k <= 10; ++k) channels.push_back("PT" + std::to_string(k));
  for (const std::string& channel : channels) {
    const std::vector<double>& values = Column(log, channel);
    ASSERT_EQ(values.size(), log.num_rows()) << channel;
    for (double v : values) ASSERT_TRUE(std::isfinite(v)) << channel;
  }
  // Inputs as commanded. Channels are interpolated linearly between solver steps (dt = 5.3 ms),
  // which bends the sine by up to A w^2 dt^2 / 8 = 5.5e-7 m.
  const std::vector<double>& piston = Column(log, "piston_position");
  EXPECT_NEAR(piston[125], 0.1, 1e-6);  // t = 1.25 s, the crest of the 0.2 Hz sine
  EXPECT_NEAR(Column(log, "choke_position")[0], 31.0 / 90.0, 1e-12);
  EXPECT_NEAR(Column(log, "FT2")[0], units::LpmToM3ps(5.0), 1e-12);
  EXPECT_NEAR(Column(log, "C1")[0], log.atmospheric_pressure_pa, 1e-6);
}

// Before the first pressure wave from the piston reaches the choke (L/c = 900/850 = 1.06 s), the
// choke sees the initial steady state: all pump flow through the orifice, thesis (5.3.2):
// C2 - C1 = rho_L (q/G)^2 with q = 5 L/min, G(31 deg) = 4.5e-6 m^2, rho_L = 998 kg/m^3.
TEST_F(CliTest, SimulateSteadyChokePressureIsTheOrificeLaw) {
  const riglog::RigLog log = ReadLog(SimulateSine("X.csv"));
  ASSERT_EQ(log.num_rows(), 501u);
  const double q = 5.0e-3 / 60.0;
  const double expected = 998.0 * (q / 4.5e-6) * (q / 4.5e-6);  // 3.42 bar
  const std::vector<double>& c1 = Column(log, "C1");
  const std::vector<double>& c2 = Column(log, "C2");
  int checked = 0;
  for (std::size_t i = 0; i < log.num_rows() && log.time_s[i] <= 1.0; ++i) {
    EXPECT_NEAR(c2[i] - c1[i], expected, 0.005 * expected) << "t = " << log.time_s[i];
    ++checked;
  }
  EXPECT_EQ(checked, 101);
}

// Replaying a log drives the model with the logged positions. What differs from the profile run:
// the piston velocity comes from the 100 Hz samples (smoothed, linearly interpolated) instead of
// the exact sine. Interpolation changes the velocity by up to A w^2 dt / 2 = 0.1 (2 pi 0.2)^2
// 0.01 / 2 = 8e-4 m/s, 0.6% of the peak 0.126 m/s; Joukowsky turns that into at most 0.4% of the
// pressure swing. The choke is constant, so using it as measured (no actuator) changes nothing.
// Tolerance: 0.5% of each channel's swing.
void ExpectReplayMatches(const riglog::RigLog& original, const riglog::RigLog& replay,
                         const std::string& channel, std::size_t first_row, std::size_t end_row) {
  const std::vector<double>& x = Column(original, channel);
  const std::vector<double>& y = Column(replay, channel);
  ASSERT_EQ(x.size(), y.size());
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  const double swing = *hi - *lo;
  ASSERT_GT(swing, 0.5e5) << channel << " hardly moves: the comparison would say nothing";
  for (std::size_t i = first_row; i < end_row; ++i) {
    EXPECT_NEAR(y[i], x[i], 0.005 * swing) << channel << " at t = " << original.time_s[i]
                                           << " s (row " << i << " of " << x.size() << ")";
  }
}

TEST_F(CliTest, ReplayReproducesTheRun) {
  const std::string original_path = SimulateSine("X.csv");
  const std::string replay_path = Path("Y.csv");
  const RunResult run = Run("simulate --inputs " + Quote(original_path) +
                            " --sensor-noise none --out " + Quote(replay_path));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const riglog::RigLog original = ReadLog(original_path);
  const riglog::RigLog replay = ReadLog(replay_path);
  ASSERT_EQ(replay.num_rows(), original.num_rows());
  EXPECT_EQ(replay.time_s, original.time_s);
  // Every row but the last (see ReplayLastSampleUsesOnlyLoggedInputs).
  const std::size_t n = original.num_rows();
  ExpectReplayMatches(original, replay, "PT1", 0, n - 1);
  ExpectReplayMatches(original, replay, "C2", 0, n - 1);
}

// The last sample of a replay must come from the logged inputs, like every other. Simulate()
// takes the piston velocity at the end of a step as the centred difference of the position over
// [t_b - dt/2, t_b + dt/2], and the last step ends after the log's last time stamp, where the
// replayed position is held constant: the velocity drops to zero there, and PT1 jumps by a
// Joukowsky step (about 0.28 bar here, a quarter of the swing) in the last row.
TEST_F(CliTest, ReplayLastSampleUsesOnlyLoggedInputs) {
  const std::string original_path = SimulateSine("X.csv");
  const std::string replay_path = Path("Y.csv");
  const RunResult run = Run("simulate --inputs " + Quote(original_path) +
                            " --sensor-noise none --out " + Quote(replay_path));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const riglog::RigLog original = ReadLog(original_path);
  const riglog::RigLog replay = ReadLog(replay_path);
  ASSERT_EQ(replay.num_rows(), original.num_rows());
  const std::size_t n = original.num_rows();
  ExpectReplayMatches(original, replay, "PT1", n - 1, n);
  ExpectReplayMatches(original, replay, "C2", n - 1, n);
}

// The default is the lab's sensors (thesis Table 4.1.1): the default run minus the run with
// --sensor-noise none is the noise alone, with the lab's standard deviation per channel kind
// (flows relative to their reading). The sample standard deviation of n normal draws spreads by
// 1 / sqrt(2 (n - 1)) of itself; the tolerance is 4 of those.
using teststats::SampleStdDev;
using teststats::StdDevTolerance;

TEST_F(CliTest, SimulateAddsTheLabSensorNoiseByDefault) {
  const riglog::RigLog clean =
      ReadLog(SimulateSine("clean.csv", "--sensor-noise none --pressure-at 450"));
  const riglog::RigLog noisy =
      ReadLog(SimulateSine("noisy.csv", "--sensor-noise lab --pressure-at 450"));
  const RunResult by_default = Run(
      "simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 --outlet-barg 0 "
      "--duration 5 --pressure-at 450 --out " +
      Quote(Path("default.csv")));
  ASSERT_EQ(by_default.exit_code, 0) << by_default.err;
  EXPECT_EQ(ReadFile(Path("default.csv")), ReadFile(Path("noisy.csv"))) << "default: lab, seed 1";
  ASSERT_EQ(noisy.columns, clean.columns);
  ASSERT_EQ(noisy.time_s, clean.time_s);
  auto metadata = [](const riglog::RigLog& log) {
    std::string found;
    for (const auto& [key, value] : log.metadata) {
      if (key == "sensor_noise") found = value;
    }
    return found;
  };
  EXPECT_EQ(metadata(noisy), "lab, seed 1");
  EXPECT_EQ(metadata(clean), "") << "--sensor-noise none writes what it wrote before the noise";

  std::vector<double> pressure, flow, piston, choke;
  for (std::size_t c = 0; c < noisy.columns.size(); ++c) {
    const std::string& channel = noisy.columns[c].channel;
    if (channel == "p_450m") {  // the model's, not a sensor
      EXPECT_EQ(noisy.values_si[c], clean.values_si[c]);
      continue;
    }
    for (std::size_t i = 0; i < noisy.num_rows(); ++i) {
      const double x = clean.values_si[c][i];
      const double e = noisy.values_si[c][i] - x;
      switch (noisy.columns[c].quantity()) {
        case riglog::Quantity::kPressure:
          pressure.push_back(e);
          break;
        case riglog::Quantity::kFlow:
          flow.push_back(e / (0.02 * std::fabs(x) + units::LpmToM3ps(0.05)));
          break;
        case riglog::Quantity::kPosition:
          piston.push_back(e);
          break;
        default:
          choke.push_back(e);
      }
    }
  }
  ASSERT_EQ(pressure.size(), 14u * 501u);
  ASSERT_EQ(flow.size(), 4u * 501u);
  EXPECT_NEAR(SampleStdDev(pressure), 2400.0, StdDevTolerance(pressure.size()) * 2400.0);
  EXPECT_NEAR(SampleStdDev(flow), 1.0, StdDevTolerance(flow.size()));
  EXPECT_NEAR(SampleStdDev(piston), 0.5e-3, StdDevTolerance(piston.size()) * 0.5e-3);
  EXPECT_NEAR(SampleStdDev(choke), 0.1 / 90.0, StdDevTolerance(choke.size()) * 0.1 / 90.0);

  // Another seed, other numbers.
  const RunResult other = Run(
      "simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 --outlet-barg 0 "
      "--duration 5 --pressure-at 450 --noise-seed 2 --out " +
      Quote(Path("other.csv")));
  ASSERT_EQ(other.exit_code, 0) << other.err;
  const riglog::RigLog other_log = ReadLog(Path("other.csv"));
  EXPECT_NE(Column(other_log, "PT1"), Column(noisy, "PT1"));
}

TEST_F(CliTest, SimulateNamesABadSensorNoise) {
  const RunResult run =
      Run("simulate --piston 0 --duration 1 --sensor-noise 'lab,pressure=-1bar' "
          "--out " +
          Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--sensor-noise") && Contains(run.err, "'pressure=-1bar'"))
      << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

// The model names what is wrong; the command line adds the flag that fixes it.
TEST_F(CliTest, AnEffectParameterOfAnEffectThatIsOffNamesTheFlagThatSwitchesItOn) {
  const RunResult run =
      Run("simulate --piston 0 --duration 1 --set unsteady_friction.k=0.02 --out " +
          Quote(Path("E.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err,
                       "effect 'unsteady_friction' is not switched on (add --effect "
                       "unsteady_friction)"))
      << run.err;
  EXPECT_FALSE(fs::exists(Path("E.csv")));
}

TEST_F(CliTest, SimulateRequiresOut) {
  const RunResult run = Run("simulate --piston sine:amp_m=0.1,freq_hz=0.2 --duration 1");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--out")) << run.err;
}

TEST_F(CliTest, SimulateRequiresADrive) {
  const RunResult run = Run("simulate --duration 1 --out " + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--inputs") && Contains(run.err, "--piston")) << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

// The reservoir - pipe - valve rig of docs/bergant-simpson.md, as the page runs it: its valve's
// pressure as p_37.23m_barg every 0.1 ms, with the linear law; the NTNU rig's inputs refused.
TEST_F(CliTest, SimulateRunsTheReservoirPipeValveRig) {
  const std::string config =
      Quote(std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999.pbtxt");
  const RunResult run = Run("simulate --config " + config +
                            " --duration 0.8 --pressure-at 37.23 --sensor-noise none --out " +
                            Quote(Path("valve.csv")));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto log = riglog::ReadRigLog(Path("valve.csv"));
  ASSERT_TRUE(log.ok()) << log.status().message();
  const std::string text = ReadFile(Path("valve.csv"));
  EXPECT_TRUE(Contains(text, "# model: linear, 200 cells")) << text.substr(0, 400);
  EXPECT_TRUE(Contains(text, "p_37.23m_barg")) << text.substr(0, 400);
  EXPECT_TRUE(Contains(text, "\n0.0001,")) << "rows every 0.1 ms";
  const RunResult piston =
      Run("simulate --config " + config + " --piston 0 --out " + Quote(Path("Z.csv")));
  EXPECT_EQ(piston.exit_code, 1);
  EXPECT_TRUE(Contains(piston.err, "--piston does not apply")) << piston.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

// The commands that replay a log through the NTNU rig's inputs, or use its analytic model,
// refuse a reservoir - pipe - valve configuration rather than ignore its valve and run the NTNU
// rig in its place.
TEST_F(CliTest, LogCommandsRefuseTheReservoirPipeValveRig) {
  const std::string config =
      Quote(std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999.pbtxt");
  const std::string log = SimulateSine("X.csv");
  for (const std::string& command : std::vector<std::string>{
           "compare " + Quote(log) + " --json " + Quote(Path("c.json")),
           "fit " + Quote(log) + " --params wave_speed_mps --json " + Quote(Path("f.json")),
           "diagnose " + Quote(log), "freqresp --analytic --out " + Quote(Path("r.csv")),
           "gains --disturbance-hz 0.2 --out " + Quote(Path("g.csv"))}) {
    const RunResult run = Run(command + " --config " + config);
    EXPECT_EQ(run.exit_code, 1) << command;
    EXPECT_TRUE(Contains(run.err, "works on the NTNU rig only") &&
                Contains(run.err, "bergant-simpson-1999.pbtxt") &&
                Contains(run.err, "mpdrig simulate --config"))
        << command << ": " << run.err;
  }
}

TEST_F(CliTest, SimulateRefusesBothInputsAndPiston) {
  const std::string original_path = SimulateSine("X.csv");
  const RunResult run = Run("simulate --inputs " + Quote(original_path) +
                            " --piston sine:amp_m=0.1,freq_hz=0.2 --out " + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--inputs") && Contains(run.err, "--piston")) << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

TEST_F(CliTest, SimulateNamesAMissingInputColumn) {
  const std::string inputs = Path("no_piston.csv");
  WriteFile(inputs,
            "# rig-log: 1\n"
            "time_s,choke_position_deg,PT1_barg\n"
            "0,31,3.6\n"
            "0.01,31,3.6\n"
            "0.02,31,3.6\n");
  const RunResult run =
      Run("simulate --inputs " + Quote(inputs) + " --out " + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, inputs)) << run.err;
  EXPECT_TRUE(Contains(run.err, "piston_position")) << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

TEST_F(CliTest, SimulateNamesFileLineAndColumnOfABadLog) {
  const std::string inputs = Path("bad_time.csv");
  WriteFile(inputs,
            "# rig-log: 1\n"
            "time_s,piston_position_m,choke_position_deg\n"
            "0,0,31\n"
            "0.01,0,31\n"
            "0.01,0,31\n");  // line 5: time does not increase
  const RunResult run =
      Run("simulate --inputs " + Quote(inputs) + " --out " + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, inputs + ":5:1:")) << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

TEST_F(CliTest, SimulateRejectsAnUnknownProfileKind) {
  const RunResult run =
      Run("simulate --piston wobble:amp_m=0.1,freq_hz=0.2 --out " + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--piston")) << run.err;
  EXPECT_TRUE(Contains(run.err, "wobble")) << run.err;
  EXPECT_TRUE(Contains(run.err, "sine")) << "valid kinds listed: " << run.err;
  const RunResult choke =
      Run("simulate --piston 0 --choke-deg sine:amp_m=1,freq_hz=1 --out " + Quote(Path("Z.csv")));
  EXPECT_NE(choke.exit_code, 0);
  EXPECT_TRUE(Contains(choke.err, "--choke-deg") && Contains(choke.err, "amp_deg")) << choke.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

// Absurd durations and rates, found by a bad-input probe: before, inf, 1e308 and 1e17 crashed (the
// output count's std::lround overflowed) and 1e9 allocated until std::bad_alloc. Now each is
// refused at once, naming the flag and its limit, and nothing is written.
TEST_F(CliTest, SimulateRefusesAbsurdDurationsAndRatesNamingTheFlagAndTheLimit) {
  struct Case {
    std::string flags;
    std::string named;
  };
  const std::vector<Case> cases = {
      {"--duration inf", "--duration inf s must be in (0, 86400] s"},
      {"--duration 1e308", "--duration 1e+308 s must be in (0, 86400] s"},
      {"--duration 1e17", "--duration 1e+17 s must be in (0, 86400] s"},
      {"--duration 1e9", "--duration 1e+09 s must be in (0, 86400] s"},
      {"--duration nan", "--duration nan s"},
      {"--duration -1", "--duration -1 s"},
      {"--duration 1 --rate-hz inf", "--rate-hz inf Hz must be in (0, 100000] Hz"},
      {"--duration 86400 --rate-hz 1000", "8.64e+07 samples, at most 1e+07"},
  };
  for (const Case& c : cases) {
    const RunResult run = Run("simulate --piston 0 " + c.flags + " --out " + Quote(Path("Z.csv")));
    EXPECT_EQ(run.exit_code, 1) << c.flags << ": refused with an error, not a crash\n" << run.err;
    EXPECT_TRUE(Contains(run.err, c.named)) << c.flags << ": " << run.err;
    EXPECT_FALSE(fs::exists(Path("Z.csv"))) << c.flags;
  }
}

// Found by a bad-input probe: simulate held its whole output in memory (135 MB for 600 s at 1 kHz,
// about 230 B a sample). It streams it now: 200 001 samples (45 MB held before) must not raise the
// process's peak memory by more than 15 MB over a run of 1 001 samples.
TEST_F(CliTest, SimulateStreamsItsOutputInBoundedMemory) {
  if (testing::kUnderAddressSanitizer) {
    GTEST_SKIP()
        << "RSS under AddressSanitizer measures its quarantine (tests/support/sanitizer.h)";
  }
  auto peak_rss_kb = [] {
    rusage usage{};
    ::getrusage(RUSAGE_CHILDREN, &usage);  // the largest child so far
    return usage.ru_maxrss;
  };
  const std::string run =
      "simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 --sensor-noise "
      "none ";
  ASSERT_EQ(Run(run + "--duration 0.5 --rate-hz 2000 --out " + Quote(Path("short.csv"))).exit_code,
            0);
  const long short_kb = peak_rss_kb();
  const RunResult long_run =
      Run(run + "--duration 100 --rate-hz 2000 --out " + Quote(Path("long.csv")));
  ASSERT_EQ(long_run.exit_code, 0) << long_run.err;
  const long long_kb = peak_rss_kb();
  EXPECT_LT(long_kb - short_kb, 15 * 1024)
      << "peak RSS " << short_kb << " kB for 1 001 samples, " << long_kb << " kB for 200 001";
  EXPECT_EQ(ReadLog(Path("long.csv")).num_rows(), 200001u);
  EXPECT_TRUE(Contains(long_run.out, "200001 samples")) << long_run.out;
}

// A steady rig log at 100 Hz for 2 s (lines 3-203), then `last_line` (line 204).
std::string SteadyLogWith(const std::string& last_line) {
  std::string text =
      "# rig-log: 1\ntime_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,C2_barg,"
      "PT1_barg,FT1_lpm\n";
  for (int i = 0; i <= 200; ++i) {
    char row[96];
    std::snprintf(row, sizeof row, "%.2f,0,31,5,0,3.9,4.2,5\n", i * 0.01);
    text += row;
  }
  return text + last_line + "\n";
}

// Found by a bad-input probe: one huge time value made compare, simulate --inputs and diagnose run
// for minutes, and a long gap passed silently. Each log tool now refuses a gap longer than
// --max-gap-s (default 10 s) with the file, line and column, and takes a wider limit.
TEST_F(CliTest, LogToolsRefuseAGapInTimeAtItsLineAndTakeAWiderLimit) {
  const std::string gap = Path("gap.csv");
  WriteFile(gap, SteadyLogWith("22,0,31,5,0,3.9,4.2,5"));
  const std::string huge = Path("huge.csv");
  WriteFile(huge, SteadyLogWith("1e308,0,31,5,0,3.9,4.2,5"));
  for (const std::string& command :
       {"simulate --inputs " + Quote(gap) + " --out " + Quote(Path("Z.csv")),
        "compare " + Quote(gap) + " --json " + Quote(Path("Z.json")),
        "diagnose " + Quote(gap) + " --json " + Quote(Path("Z.json")),
        "observe " + Quote(gap) + " --disturbance-hz 0.2 --out " + Quote(Path("Z.csv"))}) {
    const RunResult run = Run(command);
    EXPECT_EQ(run.exit_code, 1) << command << "\n" << run.err;
    EXPECT_TRUE(Contains(run.err, gap + ":204:1: time_s: 22 is 20 s after the previous sample's 2 "
                                        "(line 203), a gap longer than 10 s"))
        << command << "\n"
        << run.err;
    EXPECT_TRUE(Contains(run.err, "--max-gap-s")) << run.err;
  }
  for (const std::string& command :
       {"simulate --inputs " + Quote(huge) + " --out " + Quote(Path("Z.csv")),
        "compare " + Quote(huge) + " --json " + Quote(Path("Z.json")),
        "diagnose " + Quote(huge) + " --json " + Quote(Path("Z.json"))}) {
    const RunResult run = Run(command);
    EXPECT_EQ(run.exit_code, 1) << command << "\n" << run.err;
    EXPECT_TRUE(Contains(run.err, huge + ":204:1: time_s: 1e+308 is 1e+308 s after"))
        << command << "\n"
        << run.err;
  }
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
  EXPECT_FALSE(fs::exists(Path("Z.json")));

  const RunResult wider = Run("simulate --inputs " + Quote(gap) +
                              " --max-gap-s 30 --sensor-noise none --out " + Quote(Path("Z.csv")));
  EXPECT_EQ(wider.exit_code, 0) << wider.err;
  riglog::ReadOptions read;
  read.max_gap_s = 30.0;
  auto written = riglog::ReadRigLog(Path("Z.csv"), read);
  ASSERT_TRUE(written.ok()) << written.status().message();
  EXPECT_EQ(written->num_rows(), 202u);
  const RunResult bad =
      Run("simulate --inputs " + Quote(gap) + " --max-gap-s 0 --out " + Quote(Path("Y.csv")));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Contains(bad.err, "--max-gap-s")) << bad.err;
}

// Found by a bad-input probe: time steps of 1e-12 s gave null metrics with exit 0, and a choke
// opening of -50 deg was replayed. Both are errors at their file, line and column.
TEST_F(CliTest, LogToolsRefuseOutOfRangeValuesAndTinyTimeStepsAtTheirPosition) {
  const std::string tiny = Path("tiny.csv");
  WriteFile(tiny, SteadyLogWith("2.000000000001,0,31,5,0,3.9,4.2,5"));
  const RunResult compare = Run("compare " + Quote(tiny) + " --json " + Quote(Path("Z.json")));
  EXPECT_EQ(compare.exit_code, 1) << compare.err;
  EXPECT_TRUE(Contains(compare.err, tiny + ":204:1: time_s: 2.000000000001 is only "))
      << compare.err;
  EXPECT_FALSE(fs::exists(Path("Z.json")));

  const std::string choke = Path("choke.csv");
  WriteFile(choke, SteadyLogWith("2.01,0,-50,5,0,3.9,4.2,5"));
  const RunResult simulate =
      Run("simulate --inputs " + Quote(choke) + " --out " + Quote(Path("Z.csv")));
  EXPECT_EQ(simulate.exit_code, 1) << simulate.err;
  EXPECT_TRUE(Contains(simulate.err, choke + ":204:8: choke_position_deg: -50 is outside the "
                                             "physical range of a choke opening"))
      << simulate.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

TEST_F(CliTest, SimulateRejectsBadModelOptions) {
  const RunResult model =
      Run("simulate --piston 0 --duration 1 --model foo --out " + Quote(Path("Z.csv")));
  EXPECT_NE(model.exit_code, 0);
  EXPECT_TRUE(Contains(model.err, "--model") && Contains(model.err, "foo")) << model.err;
  const RunResult cells =
      Run("simulate --piston 0 --duration 1 --cells 1 --out " + Quote(Path("Z.csv")));
  EXPECT_NE(cells.exit_code, 0);
  EXPECT_TRUE(Contains(cells.err, "--cells")) << cells.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv")));
}

// 0.2 m at 0.5 Hz moves the piston at up to 0.63 m/s: the Joukowsky drop
// rho c v (A_d - A_d2)/A = 2.9 bar at the inlet, with no pump and the outlet at atmosphere, takes
// the absolute pressure below zero at once.
const char kCavitatingRun[] =
    "simulate --piston sine:amp_m=0.2,freq_hz=0.5 --choke-deg 31 --pump-lpm 0 --outlet-barg 0 "
    "--duration 2 --out ";

TEST_F(CliTest, SimulateStopsBelowZeroAbsolutePressure) {
  const RunResult run = Run(kCavitatingRun + Quote(Path("Z.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "absolute pressure")) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex(R"(t = [0-9.eE+-]+ s)"))) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex(R"(x = [0-9.eE+-]+ m)"))) << run.err;
  EXPECT_TRUE(Contains(run.err, "--allow-negative-pressure")) << run.err;
  EXPECT_FALSE(fs::exists(Path("Z.csv"))) << "no numbers from outside the model's range";
}

TEST_F(CliTest, SimulateAllowsNegativePressureWithAWarning) {
  const RunResult run = Run(kCavitatingRun + Quote(Path("Z.csv")) + " --allow-negative-pressure");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(Contains(run.err, "warning")) << run.err;
  EXPECT_TRUE(Contains(run.err, "absolute pressure")) << run.err;
  const riglog::RigLog log = ReadLog(Path("Z.csv"));
  EXPECT_EQ(log.num_rows(), 201u);
  bool warned_in_log = false;
  for (const auto& [key, value] : log.metadata) warned_in_log |= key == "warning";
  EXPECT_TRUE(warned_in_log) << "the log itself records that it left the model's range";
}

// --- freqresp and demo -----------------------------------------------------------------------

TEST_F(CliTest, FreqrespAnalyticWritesTheDefaultGrid) {
  const std::string out = Path("F.csv");
  const RunResult run = Run("freqresp --analytic --choke closed --out " + Quote(out));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  std::istringstream in(ReadFile(out));
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "freq_hz,magnitude_pa_per_m,phase_deg");
  std::vector<double> freqs;
  while (std::getline(in, line)) {
    double f = 0.0, magnitude = 0.0, phase = 0.0;
    char c1 = 0, c2 = 0;
    std::istringstream fields(line);
    ASSERT_TRUE(fields >> f >> c1 >> magnitude >> c2 >> phase) << line;
    EXPECT_EQ(c1, ',');
    EXPECT_EQ(c2, ',');
    EXPECT_TRUE(std::isfinite(magnitude) && magnitude > 0.0) << line;
    EXPECT_TRUE(std::isfinite(phase)) << line;
    freqs.push_back(f);
  }
  ASSERT_EQ(freqs.size(), 59u);
  EXPECT_NEAR(freqs.front(), 0.02, 1e-12);
  EXPECT_NEAR(freqs.back(), 0.6, 1e-12);
  EXPECT_TRUE(std::is_sorted(freqs.begin(), freqs.end()));
  EXPECT_TRUE(Contains(run.out, out)) << run.out;
}

TEST_F(CliTest, FreqrespNeedsAMethod) {
  const RunResult run = Run("freqresp --out " + Quote(Path("F.csv")));
  EXPECT_NE(run.exit_code, 0);
  EXPECT_TRUE(Contains(run.err, "--analytic")) << run.err;
}

TEST_F(CliTest, DemoWritesALogAndSummarises) {
  const std::string out = Path("D.csv");
  const RunResult run = Run("demo --out " + Quote(out));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(Contains(run.out, out)) << run.out;
  EXPECT_TRUE(Contains(run.out, "PT1")) << run.out;
  const riglog::RigLog log = ReadLog(out);
  EXPECT_EQ(log.num_rows(), 6001u);  // 60 s at 100 Hz
  EXPECT_NE(log.Find("PT1"), nullptr);
}

TEST_F(CliTest, ObserveEstimatesBottomHolePressureFromTopsideChannels) {
  // The observer sees only C2 and FT1 of a simulated log; after 3 periods (15 s at 0.2 Hz) its
  // BHP estimate follows PT1 to 2% of the oscillation amplitude (the observer's design bound; the
  // model tests measure 0.07-0.1% for this case with the quadratic friction included).
  const std::string log = Path("in.csv");
  const std::string est = Path("est.csv");
  // Noise-free channels: the observer at the lab's noise is the next test's.
  ASSERT_EQ(Run("simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 45 --pump-lpm 20 "
                "--outlet-barg 1 --duration 40 --sensor-noise none --out " +
                Quote(log))
                .exit_code,
            0);
  const RunResult run = Run("observe " + Quote(log) +
                            " --disturbance-hz 0.2 --quadratic-friction --out " + Quote(est));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const riglog::RigLog out = ReadLog(est);
  const std::vector<double>* measured = out.Find("PT1");
  const std::vector<double>* estimate = out.Find("BHP_est");
  ASSERT_NE(measured, nullptr);
  ASSERT_NE(estimate, nullptr);
  double lo = 1e300, hi = -1e300, worst = 0.0;
  for (std::size_t i = 0; i < out.num_rows(); ++i) {
    if (out.time_s[i] < 15.0) continue;
    lo = std::min(lo, (*measured)[i]);
    hi = std::max(hi, (*measured)[i]);
    worst = std::max(worst, std::fabs((*measured)[i] - (*estimate)[i]));
  }
  EXPECT_LT(worst, 0.02 * 0.5 * (hi - lo));

  const std::string no_c2 = Path("no_c2.csv");
  WriteFile(no_c2, "time_s,piston_position_m,choke_position_deg,FT1_lpm\n0,0,31,1\n0.01,0,31,1\n");
  const RunResult bad =
      Run("observe " + Quote(no_c2) + " --disturbance-hz 0.2 --out " + Quote(est));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_TRUE(Contains(bad.err, "C2")) << bad.err;
}

// `observe` at the lab's sensor noise (Table 4.1.1: C2 0.024 bar, FT1 2 % of
// reading + 0.05 L/min, white per 100 Hz sample), 0.2 Hz heave. With its defaults (noise
// estimated from the log, Kalman gain, zero-lag prefilter) the BHP fit against the noise-free
// PT1 after 20 s is >= 90 % (measured 97 %; the model tests cover 0.1-0.33 Hz, two chokes, three
// seeds); the thesis's poles (--pole -40 20, or --gains thesis) give about 42 %.
TEST_F(CliTest, ObserveDefaultsHoldAtLabNoise) {
  const std::string clean = Path("clean.csv");
  ASSERT_EQ(Run("simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 45 --pump-lpm 20 "
                "--outlet-barg 1 --duration 60 --out " +
                Quote(clean))
                .exit_code,
            0);
  riglog::RigLog log = ReadLog(clean);
  const std::vector<double> truth = *log.Find("PT1");
  const auto c2_column = log.FindColumn("C2");
  const auto ft1_column = log.FindColumn("FT1");
  ASSERT_TRUE(c2_column.has_value());
  ASSERT_TRUE(ft1_column.has_value());
  std::vector<double>* c2 = &log.values_si[*c2_column];
  std::vector<double>* ft1 = &log.values_si[*ft1_column];
  std::mt19937 rng(21);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (std::size_t i = 0; i < log.num_rows(); ++i) {
    (*c2)[i] += 2400.0 * n01(rng);
    (*ft1)[i] += (0.02 * std::fabs((*ft1)[i]) + units::LpmToM3ps(0.05)) * n01(rng);
  }
  const std::string noisy = Path("noisy.csv");
  ASSERT_TRUE(riglog::WriteRigLog(log, noisy).ok());
  auto fit = [&](const std::string& flags) {
    const std::string est = Path("est_noisy.csv");
    const RunResult run =
        Run("observe " + Quote(noisy) + " --disturbance-hz 0.2 " + flags + " --out " + Quote(est));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    const riglog::RigLog out = ReadLog(est);
    const std::vector<double>& y = truth;
    const std::vector<double>& yhat = *out.Find("BHP_est");
    double mean = 0.0, e2 = 0.0, d2 = 0.0;
    int n = 0;
    for (std::size_t i = 0; i < out.num_rows(); ++i) {
      if (out.time_s[i] > 20.0) mean += y[i], ++n;
    }
    mean /= n;
    for (std::size_t i = 0; i < out.num_rows(); ++i) {
      if (out.time_s[i] <= 20.0) continue;
      e2 += std::pow(y[i] - yhat[i], 2);
      d2 += std::pow(y[i] - mean, 2);
    }
    return std::make_pair(100.0 * (1.0 - std::sqrt(e2 / d2)), run.out);
  };
  const auto [by_noise, said] = fit("");
  const auto [thesis, said_thesis] = fit("--pole -40 20");
  const auto [thesis_named, unused] = fit("--gains thesis");
  const auto [told, said_told] = fit("--pressure-noise-bar 0.024 --flow-noise-lpm 0.07");
  std::printf(
      "observe at lab noise, 0.2 Hz: fit %.1f %% (told the noise: %.1f %%), thesis's poles "
      "%.1f %%\n%s",
      by_noise, told, thesis, said.c_str());
  EXPECT_GE(by_noise, 90.0);
  EXPECT_GE(told, 90.0);
  EXPECT_LT(thesis, 85.0);
  EXPECT_EQ(thesis, thesis_named);
  EXPECT_TRUE(Contains(said, "Kalman")) << said;
  EXPECT_TRUE(Contains(said_thesis, "(given)")) << said_thesis;
  const RunResult help = Run("observe --help");
  EXPECT_TRUE(Contains(help.out, "Kalman")) << help.out;
  EXPECT_TRUE(Contains(help.out, "--gains")) << help.out;
}

TEST_F(CliTest, GainsWritesTheInjectionGainsAlongThePipe) {
  const std::string gains = Path("gains.csv");
  const RunResult run = Run("gains --disturbance-hz 0.25 --out " + Quote(gains));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string text = ReadFile(gains);
  EXPECT_TRUE(Contains(text, "x_m,x,p1_per_s,p2_per_s")) << text.substr(0, 400);
  EXPECT_NE(Run("gains --disturbance-hz -1 --out " + Quote(gains)).exit_code, 0);
}

TEST_F(CliTest, ServeFastRunsForItsDurationAndReports) {
  // DDS stays on loopback by default; a domain no other test process uses.
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  const RunResult run =
      Run("serve --clock fast --duration 2 --rate-hz 100 --rig a --rig b --domain " + domain);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(Contains(run.err, "loopback only")) << run.err;
  EXPECT_TRUE(Contains(run.err, "sensor noise: lab, seed 1"))
      << "the lab's by default: " << run.err;
  EXPECT_TRUE(Contains(run.err, "a ran 2.000 s of rig time, 200 samples")) << run.err;
  EXPECT_TRUE(Contains(run.err, "b ran 2.000 s of rig time, 200 samples")) << run.err;
}

TEST_F(CliTest, ServeRefusesBadOptions) {
  EXPECT_NE(Run("serve --clock sundial").exit_code, 0);
  EXPECT_NE(Run("serve --rate-hz 0").exit_code, 0);
  const RunResult twice = Run("serve --clock fast --duration 1 --rig a --rig a --domain " +
                              std::to_string(testing::ClaimTestDomain()));
  EXPECT_NE(twice.exit_code, 0);
  EXPECT_TRUE(Contains(twice.err, "given twice")) << twice.err;
  const RunResult noise = Run("serve --clock fast --duration 1 --sensor-noise loud --domain " +
                              std::to_string(testing::ClaimTestDomain()));
  EXPECT_NE(noise.exit_code, 0);
  EXPECT_TRUE(Contains(noise.err, "--sensor-noise") && Contains(noise.err, "'loud'")) << noise.err;
}

// Bad serve options are refused with a reason before anything runs (no DDS traffic: the checks
// come before the domain is created; the domain is the test's own anyway).
TEST_F(CliTest, ServeRefusesBadObserverProfileAndHeaveOptions) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  const std::string serve = "serve --duration 1 --domain " + std::to_string(domain) + " ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--rate-hz 100 --estimate-hz 1000", "estimate rate 1000 Hz"},
      {"--rate-hz 50 --profile-hz 500", "profile rate 500 Hz"},
      {"--observer-pole 1 2", "negative real part"},
      {"--heave-amp-m 0.1 --heave-hz 3", "--heave-hz"},
      {"--heave-amp-m 0.7", "--heave-amp-m"},
      {"--profile-points 1", "--profile-points"},
  };
  for (const auto& [options, reason] : cases) {
    const RunResult run = Run(serve + options);
    EXPECT_NE(run.exit_code, 0) << options;
    EXPECT_TRUE(Contains(run.err, reason)) << options << ": " << run.err;
  }
}

// The mystery rig: reveal names the effect `serve --hidden-effect random --seed S` runs, the same
// one for the same seed, and different seeds draw different effects; bad options are refused.
TEST_F(CliTest, RevealIsDeterministicPerSeedAndServeRefusesBadMysteryAndPlaybackOptions) {
  const RunResult a = Run("reveal --seed 7");
  const RunResult b = Run("reveal --seed 7");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  EXPECT_TRUE(Contains(a.out, "seed 7: ")) << a.out;
  std::set<std::string> drawn;
  for (int seed = 1; seed <= 20; ++seed) {
    const std::string out = Run("reveal --seed " + std::to_string(seed)).out;
    const std::size_t name = out.find(": ") + 2;  // "seed S: NAME:key=value,...  (summary)"
    drawn.insert(out.substr(name, out.find(':', name) - name));
  }
  EXPECT_GE(drawn.size(), 3u) << "20 seeds should draw several of the catalogue's effects";

  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  const std::string serve = "serve --clock fast --duration 0.2 --domain " + std::to_string(domain);
  const RunResult mystery = Run(serve + " --hidden-effect random --seed 7");
  EXPECT_EQ(mystery.exit_code, 0) << mystery.err;
  EXPECT_TRUE(Contains(mystery.err, "a hidden effect is active")) << mystery.err;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --hidden-effect no_such_effect", "no_such_effect"},
      {" --loop", "--loop needs --playback"},
      {" --playback missing.csv", "missing.csv"},
      {" --playback missing.csv --rig a --rig b", "one --rig"},
  };
  for (const auto& [options, reason] : cases) {
    const RunResult run = Run(serve + options);
    EXPECT_NE(run.exit_code, 0) << options;
    EXPECT_TRUE(Contains(run.err, reason)) << options << ": " << run.err;
  }
}

}  // namespace
}  // namespace mpdrig
