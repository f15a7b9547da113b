// Single commands from short-lived processes, each its own writer of strength 0, one after the
// other faster than the 1 s liveliness lease: every one must take effect. Two ways lose them
// (measured with tests/clients/one_shot_command, 20 commands 0.7 s apart): a process that exits
// right after writing loses the sample whenever the service has not yet matched its writer (16 of
// 20 lost), and one that exits without deleting its writer leaves a stale owner of the instance
// until its lease ends, which wins over the next writer of equal strength whenever its GUID sorts
// first (6-7 of 20 lost). dds::SendOnce waits for the match and the acknowledgement and deletes
// its writer (unregister), and so does the client library when a Rig leaves; this test holds
// both to every command applied. Processes over loopback.
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"
#include "service/rig/wire.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

// A program with `args`, its stderr discarded.
testing::ChildProcess Spawn(std::vector<std::string> args) {
  return testing::ChildProcess(std::move(args),
                               testing::ChildOptions::Stderr(testing::Output::Discard()));
}

// `mode` of tests/clients/one_shot_command: "reliable" (dds::SendOnce) or "library".
class OneShotCommands : public ::testing::TestWithParam<const char*> {};

TEST_P(OneShotCommands, EveryCommandFromAShortLivedWriterTakesEffect) {
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  testing::ChildProcess serve =
      Spawn({MPDRIG_EXE, "serve", "--clock", "realtime", "--rate-hz", "100", "--rig", "rig-1",
             "--domain", domain, "--sensor-noise", "none", "--no-observer", "--pump-lpm", "0"});
  ASSERT_TRUE(serve.started()) << serve.error();

  auto dds_domain = dds::Domain::Create(claimed, dds::LoopbackConfig());
  ASSERT_TRUE(dds_domain.ok());
  auto participant = dds::CreateParticipant(claimed);
  ASSERT_TRUE(participant.ok());
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kSensors.type,
                                dds::topics::kSensors.name);
  ASSERT_TRUE(topic.ok());
  auto sensors = dds::Reader<mpdrig_RigSensors>::Create(participant->handle(), topic->handle(),
                                                        dds::SensorQos());
  ASSERT_TRUE(sensors.ok());
  // Waits up to `timeout_s` for a sample whose FT2 (the pump flow, noise-free) is `flow_lpm`.
  auto shows = [&](double flow_lpm, double timeout_s) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    bool seen = false;
    while (!seen && std::chrono::steady_clock::now() < until) {
      auto ready = sensors->Wait(DDS_MSECS(50));
      if (!ready.ok() || !*ready) continue;
      (void)sensors->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
        seen = seen || std::fabs(s.FT2_lpm - flow_lpm) < 1e-9;
      });
    }
    return seen;
  };
  ASSERT_TRUE(shows(0.0, 20.0)) << "the rig never came up";

  constexpr int kCommands = 12;
  int applied = 0;
  std::string missed;
  for (int i = 0; i < kCommands; ++i) {
    const double flow_lpm = 1.5 + i;  // each distinct from the one before
    testing::ChildProcess sender =
        Spawn({ONE_SHOT_COMMAND_EXE, domain, "rig-1", std::to_string(flow_lpm), GetParam()});
    ASSERT_TRUE(sender.started()) << sender.error();
    EXPECT_EQ(sender.Wait(), 0) << "command " << i << " not sent";
    // The command was acknowledged before the sender exited: the next tick (10 ms) applies it.
    // One second covers a loaded machine; the next sender starts right after, well within the
    // previous writer's 1 s lease, where a stale owner would win.
    if (shows(flow_lpm, 1.0)) {
      ++applied;
    } else {
      missed += " " + std::to_string(flow_lpm);
    }
  }
  EXPECT_EQ(applied, kCommands) << "not applied:" << missed;
}

INSTANTIATE_TEST_SUITE_P(SendOnceAndClientLibrary, OneShotCommands,
                         ::testing::Values("reliable", "library"));

}  // namespace
}  // namespace mpdrig
