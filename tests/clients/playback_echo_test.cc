// A rig log played back by `mpdrig serve --playback` and recorded by rig_echo is the same log:
// every row, in order, the same times, every value to far below the log's precision, and the
// channels the log lacks recorded as not measured. Three processes over loopback DDS; the test
// is the lockstep clock, so no row goes out before the recorder is there.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "model/riglog/rig_log.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

constexpr int kRows = 500;

TEST(PlaybackEcho, ReRecordedLogIsTheLog) {
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(::getpid());
  const std::string original = dir + "playback_original_" + tag + ".csv";
  const std::string recorded = dir + "playback_recorded_" + tag + ".csv";
  {
    // Lab-like: four decimals, 100 Hz from t = 12.5 s, no P1/P2/FT3/FT4 and only three PTs;
    // PT5 empty on one row.
    std::ofstream out(original);
    // A lab at altitude (an atmosphere of 950 hPa): the rig's gauge pressures are relative to it,
    // and the recording must say so to convert back to the same absolute pressures.
    out << "# rig-log: 1\n# source: playback_echo_test\n# atmospheric_pressure_pa: 95000\n"
        << "time_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,C2_barg,PT1_barg,"
           "PT5_barg,PT10_barg,FT1_lpm\n";
    char line[256];
    for (int i = 0; i < kRows; ++i) {
      const double t = 12.5 + 0.01 * i;
      const double s = std::sin(2.0 * M_PI * 0.3 * t);
      char pt5[32] = "";
      if (i != 123) std::snprintf(pt5, sizeof pt5, "%.4f", 4.1 + 0.3 * s);
      std::snprintf(line, sizeof line, "%.2f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%s,%.4f,%.4f\n", t,
                    0.1 * s, 31.0 + 0.05 * s, 8.0 + 0.01 * s, 0.01, 4.0 + 0.2 * s, 4.3 + 0.5 * s,
                    pt5, 4.0 + 0.21 * s, 8.0 + 2.0 * s);
      out << line;
    }
  }
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);

  testing::ChildProcess echo(
      {RIG_ECHO_EXE, "--rig", "lab-1", "--domain", domain, "--samples", std::to_string(kRows),
       "--timeout", "30", "--out", recorded},
      testing::ChildOptions::Stderr(testing::Output::File(dir + "playback_echo_" + tag + ".err")));
  ASSERT_TRUE(echo.started()) << echo.error();
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--playback", original, "--rig", "lab-1", "--clock", "lockstep",
       "--domain", domain},
      testing::ChildOptions::Stderr(testing::Output::File(dir + "playback_serve_" + tag + ".err")));
  ASSERT_TRUE(serve.started()) << serve.error();

  auto dds_domain = dds::Domain::Create(claimed, dds::LoopbackConfig());
  ASSERT_TRUE(dds_domain.ok()) << dds_domain.status().message();
  auto participant = dds::CreateParticipant(claimed);
  ASSERT_TRUE(participant.ok());
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kStepRequest);
  ASSERT_TRUE(topic.ok());
  const dds::Qos qos = dds::RequestQos();  // as the service reads requests
  auto steps = dds::Writer<mpdrig_StepRequest>::Create(participant->handle(), topic->handle(), qos);
  ASSERT_TRUE(steps.ok());
  bool matched = false;
  for (int i = 0; i < 200 && !matched; ++i) {
    dds_publication_matched_status_t status{};
    dds_get_publication_matched_status(steps->handle(), &status);
    matched = status.current_count > 0;
    if (!matched) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(matched) << "mpdrig serve never took step requests";
  // The service and the recorder find each other on loopback within milliseconds; a second is
  // plenty on a loaded machine.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  char rig_id[] = "lab-1";
  ASSERT_TRUE(steps->Write(mpdrig_StepRequest{rig_id, 1, kRows}).ok());
  ASSERT_EQ(echo.Wait(60.0), 0) << "rig_echo did not record " << kRows << " samples";
  serve.Signal(SIGTERM);
  EXPECT_EQ(serve.Wait(10.0), 0);

  auto a = riglog::ReadRigLog(original);
  auto b = riglog::ReadRigLog(recorded);
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok()) << b.status().message();
  ASSERT_EQ(b->num_rows(), a->num_rows());
  EXPECT_EQ(b->atmospheric_pressure_pa, 95000.0) << "the recording lost the rig's atmosphere";
  for (std::size_t i = 0; i < a->num_rows(); ++i) {
    ASSERT_EQ(b->time_s[i], a->time_s[i]) << "row " << i;
  }
  // Every channel of the recording: the original's values (SI both, to a few ulps of the
  // barg -> Pa -> barg round trip; the log has 4 decimals), or not measured where it has none.
  for (const riglog::ColumnSpec& column : b->columns) {
    const std::vector<double>* got = b->Find(column.channel);
    const std::vector<double>* want = a->Find(column.channel);
    for (std::size_t i = 0; i < a->num_rows(); ++i) {
      const double expected = want != nullptr ? (*want)[i] : std::nan("");
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan((*got)[i])) << column.channel << " row " << i;
      } else {
        EXPECT_NEAR((*got)[i], expected, 1e-9 * std::max(1.0, std::fabs(expected)))
            << column.channel << " row " << i;
      }
    }
  }
  std::filesystem::remove(original);
  std::filesystem::remove(recorded);
}

// In real time a playback's first rows went out before a recorder that was already waiting had
// matched the service's writer (1499 of 1500 rows recorded, t = 0 missing). With
// --wait-for-readers 1 the service waits for it: every row is recorded, from the first.
TEST(PlaybackEcho, AWaitingRecorderGetsEveryRowOfARealTimePlayback) {
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(::getpid());
  const std::string original = dir + "playback_rt_original_" + tag + ".csv";
  const std::string recorded = dir + "playback_rt_recorded_" + tag + ".csv";
  constexpr int kRealTimeRows = 1500;  // 3 s at 500 Hz
  {
    std::ofstream out(original);
    out << "# rig-log: 1\ntime_s,piston_position_m,choke_position_deg,C2_barg,PT1_barg\n";
    for (int i = 0; i < kRealTimeRows; ++i) {
      const double t = 0.002 * i;
      out << t << "," << 0.05 * std::sin(t) << ",31," << 3.9 + 0.1 * std::sin(t) << ","
          << 4.2 + 0.1 * std::sin(t) << "\n";
    }
  }
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  testing::ChildProcess echo({RIG_ECHO_EXE, "--rig", "lab-1", "--domain", domain, "--samples",
                              std::to_string(kRealTimeRows), "--timeout", "30", "--out", recorded},
                             testing::ChildOptions::Quiet());
  ASSERT_TRUE(echo.started()) << echo.error();
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--playback", original, "--rig", "lab-1", "--clock", "realtime",
       "--domain", domain, "--wait-for-readers", "1", "--no-observer"},
      testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  EXPECT_EQ(echo.Wait(60.0), 0) << "rig_echo did not record every row";
  EXPECT_EQ(serve.Wait(30.0), 0);
  auto b = riglog::ReadRigLog(recorded);
  ASSERT_TRUE(b.ok()) << b.status().message();
  ASSERT_EQ(b->num_rows(), static_cast<std::size_t>(kRealTimeRows));
  EXPECT_EQ(b->time_s.front(), 0.0) << "the first row was lost";
}

}  // namespace
}  // namespace mpdrig
