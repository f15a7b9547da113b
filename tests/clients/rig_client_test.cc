// The C++ client library (clients/client/rig_client.h) against a lockstep `mpdrig serve` process
// over loopback, in a domain of the test's own: what the Python module relies on, tested without
// Python (tests/clients/python tests the module on top).
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "clients/client/participant.h"
#include "clients/client/rig_client.h"
#include "clients/client/rig_streams.h"
#include "clients/client/shadow_client.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

TEST(RigClient, StepsReadsCommandsAndReportsRefusalsOfALockstepRig) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100", "--rig", "r1", "--domain",
       std::to_string(domain), "--sensor-noise", "none", "--pump-lpm", "5", "--choke-deg", "31"},
      testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();

  client::RigOptions options;
  options.rig_id = "r1";
  options.domain = domain;
  options.timeout_s = 20.0;
  auto rig = client::Rig::Connect(options);
  ASSERT_TRUE(rig.ok()) << rig.status().message();
  client::Rig& r = **rig;
  EXPECT_TRUE(r.lockstep());

  auto first = r.Step(10);
  ASSERT_TRUE(first.ok()) << first.status().message();
  auto arrived = r.TakeArrived();
  ASSERT_TRUE(arrived.ok());
  ASSERT_EQ(arrived->size(), 10u);  // every sample of the steps, in order
  for (std::size_t i = 1; i < arrived->size(); ++i) {
    EXPECT_EQ((*arrived)[i].sample_counter, (*arrived)[i - 1].sample_counter + 1);
  }
  EXPECT_EQ(arrived->back().sample_counter, first->sample_counter);

  // A command applies from the next step: the choke (0.1 s actuator lag) is there within 3 s.
  ASSERT_TRUE(r.Choke(45.0).ok());
  auto opened = r.Step(300);
  ASSERT_TRUE(opened.ok()) << opened.status().message();
  EXPECT_NEAR(opened->choke_position_deg, 45.0, 0.5);

  // NaN is refused by the rig, reported once, and the rig keeps the last valid command.
  ASSERT_TRUE(r.Choke(std::nan("")).ok());
  auto held = r.Step(100);
  ASSERT_TRUE(held.ok());
  EXPECT_NEAR(held->choke_position_deg, 45.0, 0.5);
  auto rejections = r.NewRejections();
  ASSERT_TRUE(rejections.ok());
  EXPECT_EQ(rejections->first, 1u);
  EXPECT_NE(rejections->second.find("choke"), std::string::npos) << rejections->second;
  rejections = r.NewRejections();
  ASSERT_TRUE(rejections.ok());
  EXPECT_EQ(rejections->first, 0u);

  // The observer's estimate of the last sample is there, paired by counter.
  auto estimate = r.EstimateFor(held->sample_counter);
  ASSERT_TRUE(estimate.ok()) << estimate.status().message();
  EXPECT_EQ(estimate->sample_counter, held->sample_counter);

  // Bad input is a value, never a crash.
  EXPECT_FALSE(r.Step(0).ok());
  // More than an hour of rig time in one request: refused by the service, and the call says so
  // at once instead of waiting out its timeout for a completion that never comes.
  const auto asked = std::chrono::steady_clock::now();
  auto too_long = r.Step(4000000000u);
  ASSERT_FALSE(too_long.ok());
  EXPECT_NE(too_long.status().message().find("more than 3600 s of rig time"), std::string::npos)
      << too_long.status().message();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count(), 10.0);
  EXPECT_TRUE(r.Step(1).ok()) << "the rig steps on after the refusal";
  client::RigOptions missing = options;
  missing.rig_id = "nope";
  missing.timeout_s = 0.5;
  auto none = client::Rig::Connect(missing);
  EXPECT_FALSE(none.ok());
  missing.timeout_s = std::nan("");
  EXPECT_FALSE(client::Rig::Connect(missing).ok());
  missing.timeout_s = 1.0;
  missing.domain = 999;
  EXPECT_FALSE(client::Rig::Connect(missing).ok());

  // The service stops: the rig is lost (its sensor writer left), and every call says so.
  serve.Signal(SIGTERM);
  serve.Wait();
  auto after = r.Step(1);
  ASSERT_FALSE(after.ok());
  EXPECT_EQ(r.last_failure(), client::Failure::kLost) << after.status().message();
  EXPECT_TRUE(r.lost().has_value());
  r.Close();
  EXPECT_FALSE(r.Choke(30.0).ok());
}

// A lab's configuration file (a file URI, as `--dds-config file:///lab.xml` passes it) works for
// a lockstep client: the fast acknowledgements are layered over it as one more element of
// Cyclone's list (appended to the URI they made an invalid configuration). And a recorder's
// options: every sample kept, no estimate or profile reader, no timeout.
TEST(RigClient, ConfigurationFileAndRecorderOptions) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100", "--rig", "r1", "--domain",
       std::to_string(domain), "--sensor-noise", "none"},
      testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  const std::filesystem::path file = std::filesystem::temp_directory_path() /
                                     ("rig_client_test_" + std::to_string(::getpid()) + ".xml");
  {
    std::ofstream out(file);
    out << "<CycloneDDS><Domain id=\"any\"><General><Interfaces>"
           "<NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
           "<AllowMulticast>false</AllowMulticast></General><Discovery>"
           "<ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"127.0.0.1\"/>"
           "</Peers></Discovery></Domain></CycloneDDS>\n";
  }
  client::RigOptions options;
  options.rig_id = "r1";
  options.domain = domain;
  options.dds_config = "file://" + file.string();
  options.timeout_s = 0.0;  // wait for ever: the rig is there
  options.keep_every_sample = true;
  options.read_estimates = false;
  options.read_profiles = false;
  auto rig = client::Rig::Connect(options);
  std::filesystem::remove(file);
  ASSERT_TRUE(rig.ok()) << rig.status().message();
  client::Rig& r = **rig;
  auto last = r.Step(50);
  ASSERT_TRUE(last.ok()) << last.status().message();
  auto arrived = r.TakeArrived();
  ASSERT_TRUE(arrived.ok());
  ASSERT_EQ(arrived->size(), 50u);
  EXPECT_EQ(arrived->back().sample_counter, last->sample_counter);
  // Publication and arrival times of each sample, in order (rig_echo --timing uses them).
  for (std::size_t i = 1; i < arrived->size(); ++i) {
    EXPECT_GE((*arrived)[i].published_s, (*arrived)[i - 1].published_s);
    EXPECT_GE((*arrived)[i].received_s, (*arrived)[i - 1].received_s);
  }
  EXPECT_GT(arrived->front().published_s, 1.6e9) << "seconds since 1970";
  EXPECT_FALSE(r.NewestEstimate().has_value());
  auto estimate = r.EstimateFor(std::nullopt);
  ASSERT_FALSE(estimate.ok());
  EXPECT_NE(estimate.status().message().find("does not read estimates"), std::string::npos);
  client::RigOptions negative = options;
  negative.timeout_s = -1.0;
  EXPECT_FALSE(client::Rig::Connect(negative).ok());
}

// One client must never stop a class's shared lockstep rig. A recorder (rig_echo) of rig r1 is
// stopped (SIGSTOP, as a debugger holds a process) and later another one is killed (SIGKILL: its
// participant lingers until its 10 s lease ends, as after a controller killed and restarted):
// neither acknowledges again, and a keep-all sensor writer would fill and then fail the
// service's writes (the service died after 100-300 steps). A controller steps r1 2000 periods
// past each, another steps r2 beside it, the status names the stopped reader, and the service
// runs on.
TEST(RigClient, AStoppedOrKilledReaderDoesNotHoldUpALockstepRig) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  const std::string d = std::to_string(domain);
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100", "--rig", "r1", "--rig", "r2",
       "--domain", d, "--pump-lpm", "5", "--choke-deg", "31"},
      testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  client::RigOptions options;
  options.domain = domain;
  options.timeout_s = 20.0;
  options.rig_id = "r1";
  auto r1 = client::Rig::Connect(options);
  ASSERT_TRUE(r1.ok()) << r1.status().message();
  options.rig_id = "r2";
  auto r2 = client::Rig::Connect(options);
  ASSERT_TRUE(r2.ok()) << r2.status().message();

  const std::string out = ::testing::TempDir() + "stopped_reader_" + std::to_string(::getpid());
  auto start_echo = [&](const std::string& name) {
    auto echo = std::make_unique<testing::ChildProcess>(
        std::vector<std::string>{RIG_ECHO_EXE, "--rig", "r1", "--domain", d, "--samples", "100000",
                                 "--timeout", "60", "--out", out + name + ".csv"},
        testing::ChildOptions::Quiet());
    EXPECT_TRUE(echo->started()) << echo->error();
    return echo;
  };
  // Steps r1 `steps` periods in requests of 100, and r2 100 periods beside them.
  auto step_both = [&](int steps) {
    for (int done = 0; done < steps; done += 100) {
      auto s = (*r1)->Step(100);
      if (!s.ok())
        return ::testing::AssertionFailure()
               << "r1 after " << done << " steps: " << s.status().message();
    }
    auto s = (*r2)->Step(100);
    if (!s.ok()) return ::testing::AssertionFailure() << "r2: " << s.status().message();
    return ::testing::AssertionSuccess();
  };
  auto stopped_reader_reported = [&] {
    for (int i = 0; i < 60; ++i) {  // up to 6 s: well inside the stopped reader's 10 s lease
      auto status = (*r1)->LatestStatus();
      if (status.ok()) {
        for (const std::string& w : status->warnings) {
          if (w.find("acknowledged nothing") != std::string::npos) return true;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  };

  // A recorder that reads, then stops acknowledging.
  auto stopped = start_echo("a");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // it matches the rig
  ASSERT_TRUE(step_both(100));
  ASSERT_TRUE(stopped->Signal(SIGSTOP));
  EXPECT_TRUE(step_both(2000));
  EXPECT_TRUE(stopped_reader_reported()) << "the status never named the stopped reader";
  EXPECT_EQ(serve.Wait(0.0), testing::ChildProcess::kNoExit) << "the service ended";

  // A recorder killed without a goodbye: its reader lives on in the other participants until its
  // lease ends.
  auto killed = start_echo("b");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_TRUE(step_both(100));
  killed->Kill();
  EXPECT_TRUE(step_both(2000));
  EXPECT_EQ(serve.Wait(0.0), testing::ChildProcess::kNoExit) << "the service ended";
  stopped->Kill();
}

// One participant holds several rigs (the dashboard shows many through one; a controller may
// command two): two lockstep rigs of one service, each stepped and commanded through its own
// Rig on the one participant, a command reaching only its rig; a read-only RigStreams on the
// same participant sees both rigs' statuses and samples; closing one Rig leaves the other
// working.
TEST(ClientParticipant, OneParticipantHoldsSeveralRigs) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  testing::ChildProcess serve({MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100",
                               "--rig", "r1", "--rig", "r2", "--domain", std::to_string(domain),
                               "--sensor-noise", "lab", "--pump-lpm", "5", "--choke-deg", "31"},
                              testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  client::ParticipantOptions joining;
  joining.domain = domain;
  auto participant = client::Participant::Join(joining);
  ASSERT_TRUE(participant.ok()) << participant.status().message();
  auto streams = client::RigStreams::Open(*participant, {});
  ASSERT_TRUE(streams.ok()) << streams.status().message();
  client::RigOptions options;
  options.domain = domain;
  options.timeout_s = 20.0;
  options.rig_id = "r1";
  auto r1 = client::Rig::Connect(*participant, options);
  ASSERT_TRUE(r1.ok()) << r1.status().message();
  options.rig_id = "r2";
  auto r2 = client::Rig::Connect(*participant, options);
  ASSERT_TRUE(r2.ok()) << r2.status().message();

  // The choke's actuator lag is 0.1 s: after 3 s its position is the command's, within the
  // lab's 0.1 deg sensor noise (5 sigma: 0.5 deg).
  ASSERT_TRUE((*r1)->Choke(45.0).ok());
  auto a = (*r1)->Step(300);
  auto b = (*r2)->Step(300);
  ASSERT_TRUE(a.ok()) << a.status().message();
  ASSERT_TRUE(b.ok()) << b.status().message();
  EXPECT_NEAR(a->choke_position_deg, 45.0, 0.5);
  EXPECT_NEAR(b->choke_position_deg, 31.0, 0.5) << "r1's command reached r2";

  std::map<std::string, std::uint64_t> samples;
  std::map<std::string, std::string> clocks;
  client::RigStreams::Visitor visit;
  visit.sensors = [&](const std::string& id, const client::Sensors&) { ++samples[id]; };
  visit.status = [&](const std::string& id, const client::RigStatus& s) { clocks[id] = s.clock; };
  for (int i = 0; i < 100 && (clocks.size() < 2 || samples.size() < 2); ++i) {
    const client::RigStreams::Taken taken = (*streams)->Take(visit);
    EXPECT_TRUE(taken.error.empty()) << taken.error;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(clocks["r1"], "lockstep");
  EXPECT_EQ(clocks["r2"], "lockstep");
  EXPECT_GT(samples["r1"], 0u);
  EXPECT_GT(samples["r2"], 0u);

  (*r1)->Close();
  auto again = (*r2)->Step(10);
  ASSERT_TRUE(again.ok()) << again.status().message();
  EXPECT_EQ(again->sample_counter, b->sample_counter + 10);
  joining.domain = 300;
  EXPECT_FALSE(client::Participant::Join(joining).ok()) << "no such DDS domain id";
}

TEST(ClientShadow, ActionsAreNamedAndAnUnknownOneListsThem) {
  auto on = client::ShadowActionNamed("effect_on");
  ASSERT_TRUE(on.ok());
  EXPECT_EQ(*on, client::ShadowAction::kEffectOn);
  EXPECT_TRUE(client::ShadowActionNeedsArgument(*on));
  auto cancel = client::ShadowActionNamed("fit_cancel");
  ASSERT_TRUE(cancel.ok());
  EXPECT_FALSE(client::ShadowActionNeedsArgument(*cancel));
  auto bad = client::ShadowActionNamed("explode");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().message(),
            "unknown action 'explode' (effect_on, effect_off, set, reset, fit_now, fit_cancel)");
}

}  // namespace
}  // namespace mpdrig
