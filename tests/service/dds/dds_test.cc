// The DDS layer over loopback: a sample makes the round trip, a late joiner gets the current
// command (transient-local), bad names are errors. Every test runs in its own DDS domain with
// the loopback configuration, so tests never collide or leak onto a network.
#include "service/dds/dds.h"
#include "service/dds/topics.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mpdrig.h"
#include "tests/support/test_domain.h"

namespace mpdrig::dds {
namespace {

// A domain no other test process uses (tests/support/test_domain.h).
dds_domainid_t TestDomain() {
  const int id = testing::ClaimTestDomain();
  EXPECT_GT(id, 0) << "no free DDS domain id for the test";
  return static_cast<dds_domainid_t>(id);
}

struct Fixture {
  Domain domain;
  Entity participant;
};

Fixture Open() {
  auto domain = Domain::Create(TestDomain(), LoopbackConfig());
  EXPECT_TRUE(domain.ok()) << domain.status().message();
  auto participant = CreateParticipant(domain->id());
  EXPECT_TRUE(participant.ok()) << participant.status().message();
  return {std::move(domain).value(), std::move(participant).value()};
}

TEST(Dds, SensorSampleRoundTripOverLoopback) {
  Fixture f = Open();
  auto topic = CreateTopic(f.participant.handle(), dds::topics::kSensors);
  ASSERT_TRUE(topic.ok()) << topic.status().message();
  auto reader =
      Reader<mpdrig_RigSensors>::Create(f.participant.handle(), topic->handle(), SensorQos());
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  auto writer =
      Writer<mpdrig_RigSensors>::Create(f.participant.handle(), topic->handle(), SensorQos());
  ASSERT_TRUE(writer.ok()) << writer.status().message();

  mpdrig_RigSensors sample{};
  char rig_id[] = "rig-1";
  sample.rig_id = rig_id;
  sample.sample_counter = 42;
  sample.sim_time_s = 1.5;
  sample.PT_barg[0] = 4.25;
  sample.C2_barg = 3.9;
  sample.FT3_lpm = 5.0;
  ASSERT_TRUE(writer->Write(sample).ok());

  auto ready = reader->Wait(DDS_SECS(5));
  ASSERT_TRUE(ready.ok()) << ready.status().message();
  ASSERT_TRUE(*ready) << "no sample within 5 s";
  int seen = 0;
  auto taken = reader->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
    EXPECT_STREQ(s.rig_id, "rig-1");
    EXPECT_EQ(s.sample_counter, 42u);
    EXPECT_DOUBLE_EQ(s.PT_barg[0], 4.25);
    EXPECT_DOUBLE_EQ(s.C2_barg, 3.9);
    EXPECT_DOUBLE_EQ(s.FT3_lpm, 5.0);
    ++seen;
  });
  ASSERT_TRUE(taken.ok()) << taken.status().message();
  EXPECT_EQ(seen, 1);
}

TEST(Dds, LateJoinerGetsTheCurrentCommand) {
  Fixture f = Open();
  auto topic = CreateTopic(f.participant.handle(), dds::topics::kChokeCommand);
  ASSERT_TRUE(topic.ok());
  auto writer =
      Writer<mpdrig_ChokeCommand>::Create(f.participant.handle(), topic->handle(), CommandQos());
  ASSERT_TRUE(writer.ok());
  char rig_id[] = "rig-1";
  for (double deg : {20.0, 31.0}) {  // only the last one is current
    mpdrig_ChokeCommand command{rig_id, deg};
    ASSERT_TRUE(writer->Write(command).ok());
  }
  // The reader joins after both writes.
  auto reader =
      Reader<mpdrig_ChokeCommand>::Create(f.participant.handle(), topic->handle(), CommandQos());
  ASSERT_TRUE(reader.ok());
  auto ready = reader->Wait(DDS_SECS(5));
  ASSERT_TRUE(ready.ok() && *ready) << "late joiner got nothing within 5 s";
  std::vector<double> received;
  ASSERT_TRUE(reader
                  ->TakeEach([&](const mpdrig_ChokeCommand& c, const dds_sample_info_t&) {
                    received.push_back(c.opening_deg);
                  })
                  .ok());
  ASSERT_EQ(received.size(), 1u);
  EXPECT_DOUBLE_EQ(received[0], 31.0);
}

// Requests (RequestQos: volatile) are lost if written before the reader matched: AwaitReader
// returns false at its deadline without one, and true once one has matched; a request written
// then arrives, every one of them (keep all). A deadline beyond what DDS can express waits
// forever rather than overflowing.
TEST(Dds, AwaitReaderWaitsForAMatchAndRequestsAreKeptAll) {
  Fixture f = Open();
  auto topic = CreateTopic(f.participant.handle(), dds::topics::kStepRequest);
  ASSERT_TRUE(topic.ok());
  auto writer =
      Writer<mpdrig_StepRequest>::Create(f.participant.handle(), topic->handle(), RequestQos());
  ASSERT_TRUE(writer.ok());
  const auto alone = AwaitReader(writer->handle(), DeadlineAfter(0.2));
  ASSERT_TRUE(alone.ok()) << alone.status().message();
  EXPECT_FALSE(*alone) << "no reader yet: the deadline passes";

  auto reader =
      Reader<mpdrig_StepRequest>::Create(f.participant.handle(), topic->handle(), RequestQos());
  ASSERT_TRUE(reader.ok());
  const auto matched = AwaitReader(writer->handle(), DeadlineAfter(5.0));
  ASSERT_TRUE(matched.ok()) << matched.status().message();
  EXPECT_TRUE(*matched);
  char rig_id[] = "rig-1";
  for (std::uint64_t id = 1; id <= 20; ++id) {
    mpdrig_StepRequest request{rig_id, id, 1};
    ASSERT_TRUE(writer->Write(request).ok());
  }
  ASSERT_EQ(dds_wait_for_acks(writer->handle(), DDS_SECS(5)), DDS_RETCODE_OK);
  std::vector<std::uint64_t> received;
  ASSERT_TRUE(reader
                  ->TakeEach([&](const mpdrig_StepRequest& r, const dds_sample_info_t&) {
                    received.push_back(r.request_id);
                  })
                  .ok());
  ASSERT_EQ(received.size(), 20u) << "keep all: no request of the same rig replaces another";
  EXPECT_EQ(DeadlineAfter(std::numeric_limits<double>::infinity()), DDS_NEVER);
  EXPECT_EQ(DeadlineAfter(1e12), DDS_NEVER);    // 31 700 years: past DDS's int64 nanoseconds
  const dds_time_t past = DeadlineAfter(-1.0);  // now: a negative wait is none
  EXPECT_LE(past, dds_time());
  EXPECT_EQ(received.front(), 1u);
  EXPECT_EQ(received.back(), 20u);
}

TEST(Dds, LoopbackConfigSelectsOnlyTheLoopbackInterface) {
  // Cyclone's own trace names the interfaces it selected; the machine may have others (eth0).
  const std::string trace = ::testing::TempDir() + "mpdrig_dds_trace_" + std::to_string(getpid());
  {
    auto domain = Domain::Create(TestDomain(), LoopbackConfig() +
                                                   "<Tracing><Verbosity>config</Verbosity>"
                                                   "<OutputFile>" +
                                                   trace + "</OutputFile></Tracing>");
    ASSERT_TRUE(domain.ok()) << domain.status().message();
    auto participant = CreateParticipant(domain->id());
    ASSERT_TRUE(participant.ok());
  }
  std::FILE* file = std::fopen(trace.c_str(), "r");
  ASSERT_NE(file, nullptr);
  std::string selected;
  char line[1024];
  while (std::fgets(line, sizeof(line), file) != nullptr) {
    const char* at = std::strstr(line, "selected interfaces:");
    if (at != nullptr) selected = at;
  }
  std::fclose(file);
  std::remove(trace.c_str());
  ASSERT_FALSE(selected.empty()) << "no 'selected interfaces' line in the trace";
  EXPECT_NE(selected.find(" lo "), std::string::npos) << selected;
  EXPECT_EQ(selected.find(','), std::string::npos) << "more than one interface: " << selected;
}

TEST(Dds, InvalidTopicNameIsAnErrorWithTheReason) {
  Fixture f = Open();
  auto topic = CreateTopic(f.participant.handle(), &mpdrig_RigSensors_desc, "bad name!");
  ASSERT_FALSE(topic.ok());
  EXPECT_NE(topic.status().message().find("dds_create_topic bad name!"), std::string::npos)
      << topic.status().message();
}

}  // namespace
}  // namespace mpdrig::dds
