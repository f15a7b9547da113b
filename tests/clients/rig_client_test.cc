// The C++ client library (clients/client/rig_client.h) against a lockstep `mpdrig serve` process
// over loopback, in a domain of the test's own: what the Python module relies on, tested without
// Python (tests/clients/python tests the module on top).
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "clients/client/rig_client.h"
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

}  // namespace
}  // namespace mpdrig
