// The streamed replay of a log file (model/analysis/log_file_replay.h, `mpdrig simulate --inputs`)
// against the replay of the whole log in memory it replaces (PrepareLogReplay, SignalsFromColumns,
// SimulateEach: what simulate --inputs ran before): the same doubles in every channel of every
// row, no tolerance, so that the command's output stays byte for byte what it was.
#include "model/analysis/log_file_replay.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/riglog/rig_log.h"
#include "model/sim/log_inputs.h"
#include "tests/support/lab_scenario.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;
using riglog::Channel;
using testing::LabNoise;
using testing::Scenario;
using testing::Sine;

std::string WriteLog(const riglog::RigLog& log, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "mpdrig_log_file_replay_test";
  fs::create_directories(dir);
  const std::string path = (dir / name).string();
  const Status written = riglog::WriteRigLog(log, path);
  EXPECT_TRUE(written.ok()) << written.message();
  return path;
}

// What simulate --inputs did before it streamed: the whole file in memory, the start and levels
// decided on it where it is a measured log, then Simulate on its time functions.
struct Reference {
  std::vector<RigSample> samples;
  InputReplayOptions replay;
};
Reference WholeLogReplay(const std::string& path, const SimulationOptions& options,
                         InputReplayOptions replay) {
  Reference reference;
  auto log = riglog::ReadRigLog(path);
  EXPECT_TRUE(log.ok()) << log.status().message();
  if (!log.ok()) return reference;
  std::optional<InputReconstruction> plan;
  if (auto measured = MeasuredLogFromRigLog(*log, path); measured.ok()) {
    const Status prepared = PrepareLogReplay(&*measured, RigParams{}, options, &replay);
    EXPECT_TRUE(prepared.ok()) << prepared.message();
    plan = measured->reconstruction;
  }
  auto columns = InputColumnsFromLog(*log, path);
  EXPECT_TRUE(columns.ok()) << columns.status().message();
  auto signals = SignalsFromColumns(*columns, path, replay, plan ? &*plan : nullptr);
  EXPECT_TRUE(signals.ok()) << signals.status().message();
  auto run = SimulateEach(RigParams{}, options, *signals, log->time_s,
                          [&](const RigSample& sample) { reference.samples.push_back(sample); });
  EXPECT_TRUE(run.ok()) << run.status().message();
  reference.replay = replay;
  return reference;
}

std::vector<RigSample> StreamedReplay(const std::string& path, const SimulationOptions& options,
                                      const InputReplayOptions& replay,
                                      InputReplayOptions* used = nullptr) {
  std::vector<RigSample> samples;
  auto prepared = LogFileReplay::Prepare(path, RigParams{}, options, replay);
  EXPECT_TRUE(prepared.ok()) << prepared.status().message();
  if (!prepared.ok()) return samples;
  if (used != nullptr) *used = prepared->replay();
  auto run = prepared->Run([&](const RigSample& sample) { samples.push_back(sample); });
  EXPECT_TRUE(run.ok()) << run.status().message();
  return samples;
}

void ExpectSameSamples(const std::vector<RigSample>& streamed,
                       const std::vector<RigSample>& reference) {
  ASSERT_EQ(streamed.size(), reference.size());
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const RigSample& a = streamed[i];
    const RigSample& b = reference[i];
    ASSERT_EQ(a.time_s, b.time_s) << "row " << i;
    for (std::size_t c = 0; c < a.values.size(); ++c) {
      // Bit for bit: both NaN (a channel the model has not) or the same double.
      if (std::isnan(b.values[c])) {
        ASSERT_TRUE(std::isnan(a.values[c])) << "row " << i << " channel " << c;
      } else {
        ASSERT_EQ(a.values[c], b.values[c]) << "row " << i << " channel " << c;
      }
    }
    ASSERT_EQ(a.pressure_at_positions_pa, b.pressure_at_positions_pa) << "row " << i;
  }
}

SimulationOptions WithPressuresAlongThePipe() {
  SimulationOptions options = testing::ScenarioReplayOptions();
  options.pressure_positions_m = {50.0, 450.0, 850.0};
  return options;
}

// A log at the lab's noise that starts mid-heave: the reconstruction, the warm-up and the level
// estimate all run, and each must come out as on the whole log.
TEST(LogFileReplay, GivesWhatTheWholeLogReplayGivesAtLabNoiseMidHeave) {
  const Scenario scenario{"mid_heave",
                          60.0,
                          20.37,
                          [](double t) { return Sine(t, 0.05, 0.2); },
                          [](double) { return 31.0; },
                          [](double) { return 5.0; }};
  const std::string path = WriteLog(LabNoise(testing::TruthLog(scenario), 1), "mid_heave.csv");
  const SimulationOptions options = WithPressuresAlongThePipe();
  const Reference reference = WholeLogReplay(path, options, InputReplayOptions{});
  // The test wants a start decided from the log: the periodic warm-up or the measured state
  // (ChooseReplayStart), and the streamed replay deciding the same.
  ASSERT_TRUE(reference.replay.warmup.has_value() || reference.replay.profile.has_value())
      << "the test wants a mid-heave start";
  InputReplayOptions used;
  ExpectSameSamples(StreamedReplay(path, options, InputReplayOptions{}, &used), reference.samples);
  EXPECT_EQ(used.warmup.has_value(), reference.replay.warmup.has_value());
  EXPECT_EQ(used.profile.has_value(), reference.replay.profile.has_value());
  if (used.warmup && reference.replay.warmup) {
    EXPECT_EQ(used.warmup->period_s, reference.replay.warmup->period_s);
  }

  // As measured (--raw-inputs): the pipeline's own piston smoothing instead.
  InputReplayOptions raw;
  raw.reconstruct_inputs = false;
  ExpectSameSamples(StreamedReplay(path, options, raw), WholeLogReplay(path, options, raw).samples);
}

// Longer than the head the start and the levels are decided on (kReconstructionPlanSamples
// rows): the streamed reconstruction must still join the head's decisions to the rest. At the
// lab's 100 Hz (11 min): the piston's smoothing window is a time, so its cost per row grows with
// the rate, and at 1 kHz this test took 9 s (up to 210 s under the sanitizers) where 100 Hz
// crosses the head just as well.
TEST(LogFileReplay, GivesWhatTheWholeLogReplayGivesBeyondThePlansHead) {
  const double rate_hz = 100.0;
  const Scenario scenario{"long",
                          static_cast<double>(kReconstructionPlanSamples) / rate_hz + 5.0,
                          0.0,
                          [](double t) { return Sine(t, 0.05, 0.2); },
                          [](double) { return 31.0; },
                          [](double) { return 5.0; }};
  const std::string path =
      WriteLog(LabNoise(testing::TruthLog(scenario, RigParams{}, rate_hz), 2), "long.csv");
  const SimulationOptions options = testing::ScenarioReplayOptions();
  const Reference reference = WholeLogReplay(path, options, InputReplayOptions{});
  ASSERT_GT(reference.samples.size(), kReconstructionPlanSamples);
  ExpectSameSamples(StreamedReplay(path, options, InputReplayOptions{}), reference.samples);
}

// A log of inputs alone (nothing to compare): no start or levels from pressures, the
// reconstruction planned on its head, as before.
TEST(LogFileReplay, ReplaysALogOfInputsAlone) {
  riglog::RigLog log =
      LabNoise(testing::TruthLog({"inputs", 20.0, 0.0, [](double t) { return Sine(t, 0.05, 0.2); },
                                  [](double) { return 31.0; }, [](double) { return 5.0; }}),
               3);
  riglog::RigLog inputs;
  inputs.time_s = log.time_s;
  for (Channel channel :
       {Channel::kPistonPosition, Channel::kChokePosition, Channel::kFT2, Channel::kC1}) {
    const auto column = log.FindColumn(riglog::ChannelName(channel));
    ASSERT_TRUE(column.has_value());
    ASSERT_TRUE(inputs.AddColumn(log.columns[*column], log.values_si[*column]).ok());
  }
  const std::string path = WriteLog(inputs, "inputs_only.csv");
  const SimulationOptions options = testing::ScenarioReplayOptions();
  auto prepared = LogFileReplay::Prepare(path, RigParams{}, options, InputReplayOptions{});
  ASSERT_TRUE(prepared.ok()) << prepared.status().message();
  EXPECT_FALSE(prepared->prepared_from_measurements());
  ExpectSameSamples(StreamedReplay(path, options, InputReplayOptions{}),
                    WholeLogReplay(path, options, InputReplayOptions{}).samples);
}

TEST(LogFileReplay, RefusesABadLineBeforeAnySampleWithItsPosition) {
  const std::string path =
      WriteLog(testing::TruthLog({"short", 2.0, 0.0, [](double t) { return Sine(t, 0.05, 0.2); },
                                  [](double) { return 31.0; }, [](double) { return 5.0; }}),
               "bad.csv");
  {
    std::ofstream append(path, std::ios::app);
    append << "1.5,0,31\n";  // time goes back, and too few columns
  }
  auto prepared = LogFileReplay::Prepare(path, RigParams{}, testing::ScenarioReplayOptions(), {});
  ASSERT_FALSE(prepared.ok());
  EXPECT_NE(prepared.status().message().find(path + ":"), std::string::npos)
      << prepared.status().message();
}

}  // namespace
}  // namespace mpdrig
