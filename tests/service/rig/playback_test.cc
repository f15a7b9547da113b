// A recorded log as the rig (`mpdrig serve --playback`), and the mystery rig's status: what a
// client receives over loopback DDS is the log, row by row; channels the log lacks arrive as NaN
// (not measured); commands are refused with the reason; a hidden effect is not named.
#include "service/dds/topics.h"
#include "service/rig/log_playback.h"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/effects/effect.h"
#include "model/riglog/rig_log.h"
#include "mpdrig.h"
#include "service/rig/rig_host.h"
#include "service/rig/rig_service.h"
#include "service/rig/wire.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig::service {
namespace {

constexpr int kRows = 300;
constexpr double kT0 = 5.0;  // a log need not start at 0

// A lab-like log: four decimals, no P1/P2/FT3/FT4/PT2..4/PT6..9 columns, and PT5 left empty on
// one row (not measured there).
std::string WriteLog(const std::string& name) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream out(path);
  out << "# rig-log: 1\n# atmospheric_pressure_pa: 100000\n"
      << "time_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,C2_barg,PT1_barg,"
         "PT5_barg,PT10_barg,FT1_lpm\n";
  char line[512];
  for (int i = 0; i < kRows; ++i) {
    const double t = kT0 + 0.01 * i;
    const double s = std::sin(2.0 * M_PI * 0.5 * t);
    std::snprintf(line, sizeof line, "%.2f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%s,%.4f,%.4f\n", t,
                  0.1 * s, 31.0 + 0.1 * s, 8.0, 0.0, 4.0 + 0.2 * s, 4.3 + 0.5 * s,
                  i == 10 ? "" : std::to_string(4.1 + 0.3 * s).c_str(), 4.0 + 0.21 * s,
                  8.0 + 2.0 * s);
    out << line;
  }
  return path;
}

// Relative agreement of a value that went log -> SI -> wire (lab units) and back: a few ulps of
// the conversion, far below the log's 4 decimals.
void ExpectSame(double logged, double received, const char* what, int row) {
  if (std::isnan(logged)) {
    EXPECT_TRUE(std::isnan(received))
        << what << " row " << row << ": not measured, got " << received;
  } else {
    EXPECT_NEAR(received, logged, 1e-12 * std::max(1.0, std::fabs(logged)))
        << what << " row " << row;
  }
}

TEST(LogPlayback, PlaysEveryRowInOrderAndMarksMissingChannelsNotMeasured) {
  const std::string path = WriteLog("mpdrig-playback-host.csv");
  auto log = riglog::ReadRigLog(path);
  ASSERT_TRUE(log.ok()) << log.status().message();
  auto playback = LogPlayback::Open(path, false);
  ASSERT_TRUE(playback.ok()) << playback.status().message();
  EXPECT_NEAR((*playback)->period_s(), 0.01, 1e-9);
  auto rig = RigHost::CreatePlayback("lab-1", RigParams(), SimulationOptions(), *playback);
  ASSERT_TRUE(rig.ok()) << rig.status().message();
  EXPECT_NEAR(rig->params().atmospheric_pressure_pa, 100000.0, 0.0);

  // A recording takes no commands: each is refused with the reason and counted.
  EXPECT_FALSE(rig->SetChokeDeg(40.0).ok());
  EXPECT_FALSE(rig->SetPumpLpm(5.0).ok());
  EXPECT_EQ(rig->counters().rejected_commands, 2u);
  EXPECT_NE(rig->counters().last_rejection.find("plays back a recording"), std::string::npos)
      << rig->counters().last_rejection;

  for (int i = 0; i < kRows; ++i) {
    EXPECT_FALSE(rig->finished()) << "row " << i;
    auto sample = rig->Tick();
    ASSERT_TRUE(sample.ok()) << sample.status().message();
    EXPECT_EQ(sample->time_s, log->time_s[i]);
    for (Channel channel :
         {Channel::kPistonPosition, Channel::kChokePosition, Channel::kFT2, Channel::kC2,
          Channel::kPT1, Channel::kPT5, Channel::kPT10, Channel::kFT1}) {
      ExpectSame((*log->Find(channel))[i], (*sample)[channel],
                 std::string(riglog::ChannelName(channel)).c_str(), i);
    }
    for (Channel absent :
         {Channel::kP1, Channel::kP2, Channel::kPT2, Channel::kFT3, Channel::kFT4}) {
      EXPECT_TRUE(std::isnan((*sample)[absent])) << riglog::ChannelName(absent);
    }
  }
  EXPECT_TRUE(rig->finished());
  EXPECT_FALSE(rig->Tick().ok());  // past the end: an error, not an invented row
}

TEST(LogPlayback, LoopKeepsTheClockRising) {
  const std::string path = WriteLog("mpdrig-playback-loop.csv");
  auto playback = LogPlayback::Open(path, true);
  ASSERT_TRUE(playback.ok());
  double previous = -1.0;
  for (int i = 0; i < 2 * kRows + 5; ++i) {
    auto sample = (*playback)->Next(0);
    ASSERT_TRUE(sample.ok()) << sample.status().message();
    if (i > 0) {
      EXPECT_NEAR(sample->time_s - previous, 0.01, 1e-9) << "row " << i;
    }
    previous = sample->time_s;
  }
  EXPECT_EQ((*playback)->passes(), 2u);
  EXPECT_FALSE((*playback)->finished());
}

// A log whose row `bad` (0-based, after the header line) is broken as `kind` says, the rows
// before it good at 100 Hz. Past LogPlayback::kPeriodRows, so Open reads it only later.
std::string WriteLogWithABadRow(const std::string& name, int rows, int bad,
                                const std::string& kind) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream out(path);
  out << "time_s,piston_position_m,choke_position_deg,PT1_barg\n";
  for (int i = 0; i < rows; ++i) {
    double t = 0.01 * i;
    if (i >= bad && kind == "gap") t += 15.0;  // 15 s without a sample
    if (i == bad && kind == "repeated time") t = 0.01 * (i - 1);
    if (i == bad && kind == "truncated") {
      out << t << ",0.0\n";  // a line cut short: two fields of four
      continue;
    }
    out << t << "," << 0.01 * std::sin(t) << ",31," << 4.0 + 0.1 * std::sin(t) << "\n";
  }
  return path;
}

// A bad row anywhere (past the rows Open reads to find the pace: a hang before) ends the
// playback with the row's file:line:column: every row before it goes out, none after it, and
// every later call gives the same error.
TEST(LogPlayback, ABadRowFurtherOnEndsThePlaybackWithItsLine) {
  constexpr int kBad = 1500;
  for (const std::string kind : {"gap", "repeated time", "truncated"}) {
    SCOPED_TRACE(kind);
    const std::string path = WriteLogWithABadRow("mpdrig-playback-late-bad.csv", 2000, kBad, kind);
    auto playback = LogPlayback::Open(path, false);
    ASSERT_TRUE(playback.ok()) << playback.status().message();
    for (int i = 0; i < kBad; ++i) {
      auto row = (*playback)->Next(0);
      ASSERT_TRUE(row.ok()) << "row " << i << ": " << row.status().message();
    }
    const std::string where = path + ":" + std::to_string(kBad + 2) + ":";  // 1-based, header
    for (int again = 0; again < 3; ++again) {
      auto row = (*playback)->Next(0);
      ASSERT_FALSE(row.ok()) << "a row after the bad one went out";
      EXPECT_NE(row.status().message().find(where), std::string::npos) << row.status().message();
    }
    EXPECT_FALSE((*playback)->failed().ok());
    EXPECT_FALSE((*playback)->finished());
  }
  // A longer gap limit admits the gap (serve --max-gap-s): every row plays.
  const std::string path = WriteLogWithABadRow("mpdrig-playback-gap.csv", 2000, kBad, "gap");
  riglog::ReadOptions read;
  read.max_gap_s = 20.0;
  auto playback = LogPlayback::Open(path, false, read);
  ASSERT_TRUE(playback.ok()) << playback.status().message();
  for (int i = 0; i < 2000; ++i) ASSERT_TRUE((*playback)->Next(0).ok()) << "row " << i;
  EXPECT_TRUE((*playback)->finished());
}

// The same as a process, as the issue met it: `mpdrig serve --playback` ticked on for ever
// without a word. Now it ends within a second of reaching the row, non-zero, naming it.
TEST(ServePlayback, ABadRowEndsTheServiceWithItsLine) {
  constexpr int kBad = 1500;
  const std::string path = WriteLogWithABadRow(
      "mpdrig-serve-bad-" + std::to_string(::getpid()) + ".csv", 2000, kBad, "repeated time");
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  testing::ChildProcess serve({MPDRIG_EXE, "serve", "--playback", path, "--rig", "lab-1", "--clock",
                               "fast", "--domain", std::to_string(domain)},
                              testing::ChildOptions::Stderr(testing::Output::Capture()));
  ASSERT_TRUE(serve.started()) << serve.error();
  const int code = serve.Wait(30.0);  // 1500 rows at the fast clock: well under a second
  EXPECT_NE(code, testing::ChildProcess::kNoExit) << "still running: the playback hangs";
  EXPECT_NE(code, 0);
  EXPECT_NE(serve.err().find(path + ":" + std::to_string(kBad + 2) + ":"), std::string::npos)
      << serve.err();

  // --max-gap-s admits a long gap: the whole log plays and the service ends normally.
  const std::string gap = WriteLogWithABadRow(
      "mpdrig-serve-gap-" + std::to_string(::getpid()) + ".csv", 2000, kBad, "gap");
  testing::ChildProcess admitted(
      {MPDRIG_EXE, "serve", "--playback", gap, "--rig", "lab-1", "--clock", "fast", "--domain",
       std::to_string(domain), "--max-gap-s", "20"},
      testing::ChildOptions::Stderr(testing::Output::Capture()));
  ASSERT_TRUE(admitted.started()) << admitted.error();
  EXPECT_EQ(admitted.Wait(30.0), 0) << admitted.err();
}

TEST(LogPlayback, RefusesABadLogWithItsLine) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "mpdrig-playback-bad.csv").string();
  std::ofstream(path) << "time_s,piston_position_m,choke_position_deg\n0,0,31\n0.01,abc,31\n";
  auto playback = LogPlayback::Open(path, false);
  ASSERT_FALSE(playback.ok());
  EXPECT_NE(playback.status().message().find(":3:"), std::string::npos)
      << playback.status().message();
}

// The service end to end: lockstep, so every row is published before the test reads them.
class PlaybackServiceTest : public ::testing::Test {
 protected:
  void Start(std::vector<RigHost> rigs, bool hide_effects) {
    ServeOptions options;
    options.clock = ClockMode::kLockstep;
    options.domain = static_cast<dds_domainid_t>(testing::ClaimTestDomain());
    ASSERT_GT(options.domain, 0);
    options.hide_effects = hide_effects;
    auto service = RigService::Create(std::move(rigs), options);
    ASSERT_TRUE(service.ok()) << service.status().message();
    service_ = std::move(service).value();
    thread_ = std::thread([this] { run_status_ = service_->Run(stop_); });
    auto participant = dds::CreateParticipant(options.domain);
    ASSERT_TRUE(participant.ok());
    participant_ = std::move(participant).value();
    const dds_entity_t p = participant_.handle();
    sensors_topic_ = *dds::CreateTopic(p, dds::topics::kSensors.type, dds::topics::kSensors.name);
    status_topic_ = *dds::CreateTopic(p, dds::topics::kStatus.type, dds::topics::kStatus.name);
    choke_topic_ =
        *dds::CreateTopic(p, dds::topics::kChokeCommand.type, dds::topics::kChokeCommand.name);
    step_topic_ =
        *dds::CreateTopic(p, dds::topics::kStepRequest.type, dds::topics::kStepRequest.name);
    sensors_.emplace(
        *dds::Reader<mpdrig_RigSensors>::Create(p, sensors_topic_.handle(), dds::SensorQos(true)));
    status_.emplace(
        *dds::Reader<mpdrig_RigStatus>::Create(p, status_topic_.handle(), dds::StatusQos()));
    choke_.emplace(
        *dds::Writer<mpdrig_ChokeCommand>::Create(p, choke_topic_.handle(), dds::CommandQos()));
    const dds::Qos step_qos = dds::RequestQos();  // as the service reads requests
    step_.emplace(*dds::Writer<mpdrig_StepRequest>::Create(p, step_topic_.handle(), step_qos));
    // The service's readers must have matched before a step request goes out.
    for (int i = 0; i < 100; ++i) {
      dds_publication_matched_status_t matched{};
      dds_get_publication_matched_status(step_->handle(), &matched);
      if (matched.current_count > 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  void TearDown() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    EXPECT_TRUE(run_status_.ok()) << run_status_.message();
  }
  // Steps and waits for the status that completes the request.
  std::optional<mpdrig_RigStatus> Step(const char* rig_id, std::uint32_t steps) {
    static std::uint64_t id = 0;
    ++id;
    mpdrig_StepRequest request{const_cast<char*>(rig_id), id, steps};
    EXPECT_TRUE(step_->Write(request).ok());
    for (int attempt = 0; attempt < 200; ++attempt) {
      auto ready = status_->Wait(DDS_MSECS(100));
      if (!ready.ok() || !*ready) continue;
      bool done = false;
      (void)status_->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
        if (s.last_completed_step_request != id) return;
        done = true;
        rejected_ = s.rejected_commands;
        last_rejection_ = s.last_rejection;
        effects_.clear();
        for (std::uint32_t i = 0; i < s.active_effects._length; ++i)
          effects_.push_back(s.active_effects._buffer[i]);
      });
      if (done) return mpdrig_RigStatus{};
    }
    ADD_FAILURE() << "step request " << id << " never completed";
    return std::nullopt;
  }

  std::unique_ptr<RigService> service_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  Status run_status_ = Status::Ok();
  dds::Entity participant_, sensors_topic_, status_topic_, choke_topic_, step_topic_;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors_;
  std::optional<dds::Reader<mpdrig_RigStatus>> status_;
  std::optional<dds::Writer<mpdrig_ChokeCommand>> choke_;
  std::optional<dds::Writer<mpdrig_StepRequest>> step_;
  std::uint64_t rejected_ = 0;
  std::string last_rejection_;
  std::vector<std::string> effects_;
};

TEST_F(PlaybackServiceTest, ReRecordedLogEqualsTheLogRowByRow) {
  const std::string path = WriteLog("mpdrig-playback-dds.csv");
  auto log = riglog::ReadRigLog(path);
  ASSERT_TRUE(log.ok());
  auto playback = LogPlayback::Open(path, false);
  ASSERT_TRUE(playback.ok());
  std::vector<RigHost> rigs;
  rigs.push_back(*RigHost::CreatePlayback("lab-1", RigParams(), SimulationOptions(), *playback));
  Start(std::move(rigs), false);

  char rig_id[] = "lab-1";
  mpdrig_ChokeCommand command{rig_id, 45.0};
  ASSERT_TRUE(choke_->Write(command).ok());
  ASSERT_EQ(dds_wait_for_acks(choke_->handle(), DDS_SECS(5)), DDS_RETCODE_OK);
  ASSERT_TRUE(Step("lab-1", kRows));
  EXPECT_EQ(rejected_, 1u);
  EXPECT_NE(last_rejection_.find("plays back a recording"), std::string::npos) << last_rejection_;

  // What a recorder (rig_echo) receives: every row, in order, the log's values in its units.
  std::vector<mpdrig_RigSensors> received;
  std::vector<std::string> ids;
  for (int attempt = 0; attempt < 50 && received.size() < kRows; ++attempt) {
    (void)sensors_->Wait(DDS_MSECS(100));
    (void)sensors_->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
      mpdrig_RigSensors copy = s;
      copy.rig_id = nullptr;  // the loan's string is not ours to keep
      received.push_back(copy);
    });
  }
  ASSERT_EQ(received.size(), static_cast<std::size_t>(kRows));
  const double atm = 100000.0;
  auto barg = [atm](const std::vector<double>* si, int i) {
    return units::PaAbsToBarg((*si)[i], atm);
  };
  for (int i = 0; i < kRows; ++i) {
    const mpdrig_RigSensors& s = received[i];
    EXPECT_EQ(s.sample_counter, static_cast<std::uint64_t>(i));
    EXPECT_EQ(s.sim_time_s, log->time_s[i]);
    ExpectSame((*log->Find(Channel::kPistonPosition))[i], s.piston_position_m, "piston", i);
    ExpectSame(units::ChokeFracToDeg((*log->Find(Channel::kChokePosition))[i]),
               s.choke_position_deg, "choke", i);
    ExpectSame(barg(log->Find(Channel::kC2), i), s.C2_barg, "C2", i);
    ExpectSame(barg(log->Find(Channel::kPT1), i), s.PT_barg[0], "PT1", i);
    ExpectSame(barg(log->Find(Channel::kPT5), i), s.PT_barg[4], "PT5", i);
    ExpectSame(barg(log->Find(Channel::kPT10), i), s.PT_barg[9], "PT10", i);
    ExpectSame(units::M3psToLpm((*log->Find(Channel::kFT1))[i]), s.FT1_lpm, "FT1", i);
    ExpectSame(units::M3psToLpm((*log->Find(Channel::kFT2))[i]), s.FT2_lpm, "FT2", i);
    EXPECT_TRUE(std::isnan(s.P1_barg) && std::isnan(s.P2_barg) && std::isnan(s.FT3_lpm) &&
                std::isnan(s.FT4_lpm) && std::isnan(s.PT_barg[1]))
        << "row " << i << ": a channel the log lacks must arrive as not measured";
  }
  EXPECT_TRUE(std::isnan(received[10].PT_barg[4]));  // the empty field

  // Steps asked past the end of a lockstep playback are refused on the status; the service runs
  // on (its run ends without error when stopped: TearDown checks Run's status).
  ASSERT_TRUE(Step("lab-1", 5));
  EXPECT_EQ(rejected_, 6u) << "the command, then each of the 5 steps past the end";
  EXPECT_NE(last_rejection_.find("has ended"), std::string::npos) << last_rejection_;
}

TEST_F(PlaybackServiceTest, HiddenEffectIsNotNamedOnStatus) {
  RigParams params;
  ASSERT_TRUE(ApplyEffectSpec(&params, "unsteady_friction").ok());
  std::vector<RigHost> rigs;
  rigs.push_back(*RigHost::Create("mystery", params, SimulationOptions(), 100.0));
  Start(std::move(rigs), true);
  ASSERT_TRUE(Step("mystery", 2));
  ASSERT_EQ(effects_.size(), 1u);
  EXPECT_EQ(effects_[0], "a hidden effect is active");
}

}  // namespace
}  // namespace mpdrig::service
