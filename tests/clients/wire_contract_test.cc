// The documented wire contract is enough (docs/python.md, "From MATLAB, ROS 2 or another DDS
// client"): a participant built from only what that section and the QoS table say - the service's
// domain, the loopback settings, the topic names verbatim, the types of idl/mpdrig.idl compiled
// afresh by idlc for this test (not the project's build of them), the QoS of the table, the
// lockstep rule (each command acknowledged before the step request) - reads, commands and steps a
// real `mpdrig serve`. Nothing of service/dds or clients/ is linked: only Cyclone's C API, as a
// foreign client would have it. And the "musts" of that section are real: a command writer with
// a longer liveliness lease or shared ownership does not match the rig. Loopback, a domain of
// the test's own.
#include <dds/dds.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mpdrig.h"  // idlc's output for this test alone (tests/clients/CMakeLists.txt)
#include "tests/support/process.h"
#include "tests/support/test_domain.h"
#include "tests/support/within.h"

namespace {

using mpdrig::testing::ChildOptions;
using mpdrig::testing::ChildProcess;
using mpdrig::testing::Within;

// The documented loopback settings, as a whole document ("with the same loopback settings as a
// document"), and the fragment it says is enough for a Cyclone client.
const char* const kDocumentConfig =
    "<CycloneDDS><Domain id=\"any\"><General><Interfaces>"
    "<NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
    "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>";
const char* const kFragmentConfig =
    "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces></General>";

// Takes every valid sample of `reader` for rig `rig_id` and hands it to `visit`.
template <typename T>
void TakeAll(dds_entity_t reader, const char* rig_id, const std::function<void(const T&)>& visit) {
  for (;;) {
    void* samples[16] = {nullptr};
    dds_sample_info_t infos[16];
    const dds_return_t n = dds_take(reader, samples, infos, 16, 16);
    ASSERT_GE(n, 0) << dds_strretcode(n);
    for (int i = 0; i < n; ++i) {
      const T* s = static_cast<const T*>(samples[i]);
      if (infos[i].valid_data && std::strcmp(s->rig_id, rig_id) == 0) visit(*s);
    }
    if (n > 0) dds_return_loan(reader, samples, n);
    if (n < 16) return;
  }
}

// The QoS table of docs/service.md, one function per row kind.
dds_qos_t* SensorReaderQos() {  // reliable, volatile, keep all in lockstep
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  return q;
}
dds_qos_t* StatusReaderQos() {  // reliable, transient-local, keep last 1
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  return q;
}
// reliable, transient-local, keep last 1, exclusive ownership with a strength, automatic
// liveliness of `lease`, unregister (not dispose) when the writer goes.
dds_qos_t* CommandWriterQos(dds_duration_t lease = DDS_SECS(1),
                            dds_ownership_kind_t ownership = DDS_OWNERSHIP_EXCLUSIVE) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_ownership(q, ownership);
  dds_qset_ownership_strength(q, 10);
  dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, lease);
  dds_qset_writer_data_lifecycle(q, false);
  return q;
}
dds_qos_t* StepWriterQos() {  // reliable, volatile, keep all
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  return q;
}

bool Matched(dds_entity_t writer) {
  dds_publication_matched_status_t m{};
  dds_get_publication_matched_status(writer, &m);
  return m.current_count > 0;
}

TEST(WireContract, TypesAreRegisteredAsTheReadmeSays) {
  EXPECT_STREQ(mpdrig_RigSensors_desc.m_typename, "mpdrig::RigSensors");
  EXPECT_STREQ(mpdrig_ChokeCommand_desc.m_typename, "mpdrig::ChokeCommand");
  EXPECT_STREQ(mpdrig_StepRequest_desc.m_typename, "mpdrig::StepRequest");
  EXPECT_STREQ(mpdrig_RigStatus_desc.m_typename, "mpdrig::RigStatus");
  for (const dds_topic_descriptor_t* d :
       {&mpdrig_RigSensors_desc, &mpdrig_RigEstimate_desc, &mpdrig_ChokeCommand_desc,
        &mpdrig_StepRequest_desc, &mpdrig_RigStatus_desc}) {
    ASSERT_EQ(d->m_nkeys, 1u) << d->m_typename;
    EXPECT_STREQ(d->m_keys[0].m_name, "rig_id") << d->m_typename;
  }
}

class WireContract : public ::testing::TestWithParam<int> {  // 0: the document, 1: the fragment
 protected:
  void SetUp() override {
    domain_ = mpdrig::testing::ClaimTestDomain();
    ASSERT_GT(domain_, 0);
    service_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100",
                                 "--pump-lpm", "5", "--choke-deg", "31", "--sensor-noise", "none",
                                 "--rig", kRig, "--domain", std::to_string(domain_)},
        ChildOptions::Quiet());
    ASSERT_TRUE(service_->started()) << service_->error();
    domain_entity_ = dds_create_domain(static_cast<dds_domainid_t>(domain_),
                                       GetParam() == 0 ? kDocumentConfig : kFragmentConfig);
    ASSERT_GT(domain_entity_, 0) << dds_strretcode(domain_entity_);
    participant_ = dds_create_participant(static_cast<dds_domainid_t>(domain_), nullptr, nullptr);
    ASSERT_GT(participant_, 0) << dds_strretcode(participant_);
  }
  void TearDown() override {
    if (participant_ > 0) dds_delete(participant_);
    if (domain_entity_ > 0) dds_delete(domain_entity_);
  }
  dds_entity_t Topic(const dds_topic_descriptor_t* descriptor, const char* name) {
    const dds_entity_t t = dds_create_topic(participant_, descriptor, name, nullptr, nullptr);
    EXPECT_GT(t, 0) << name << ": " << dds_strretcode(t);
    return t;
  }
  dds_entity_t Reader(dds_entity_t topic, dds_qos_t* qos) {
    const dds_entity_t r = dds_create_reader(participant_, topic, qos, nullptr);
    dds_delete_qos(qos);
    EXPECT_GT(r, 0) << dds_strretcode(r);
    return r;
  }
  dds_entity_t Writer(dds_entity_t topic, dds_qos_t* qos) {
    const dds_entity_t w = dds_create_writer(participant_, topic, qos, nullptr);
    dds_delete_qos(qos);
    EXPECT_GT(w, 0) << dds_strretcode(w);
    return w;
  }

  static constexpr const char* kRig = "contract-1";
  int domain_ = 0;
  std::unique_ptr<ChildProcess> service_;  // `mpdrig serve`
  dds_entity_t domain_entity_ = 0, participant_ = 0;
};

TEST_P(WireContract, ForeignParticipantReadsCommandsAndStepsTheRig) {
  const dds_entity_t status =
      Reader(Topic(&mpdrig_RigStatus_desc, "mpdrig_status"), StatusReaderQos());
  const dds_entity_t sensors =
      Reader(Topic(&mpdrig_RigSensors_desc, "mpdrig_sensors"), SensorReaderQos());
  const dds_entity_t estimates =
      Reader(Topic(&mpdrig_RigEstimate_desc, "mpdrig_estimate"), SensorReaderQos());
  const dds_entity_t choke =
      Writer(Topic(&mpdrig_ChokeCommand_desc, "mpdrig_choke_command"), CommandWriterQos());
  const dds_entity_t steps =
      Writer(Topic(&mpdrig_StepRequest_desc, "mpdrig_step_request"), StepWriterQos());
  // The current status of a late joiner (transient-local): the rig exists and runs lockstep.
  mpdrig_RigStatus last{};
  std::uint64_t rejected = 0, completed = 0;
  std::string last_rejection;
  bool seen = false;
  auto take_status = [&] {
    TakeAll<mpdrig_RigStatus>(status, kRig, [&](const mpdrig_RigStatus& s) {
      seen = true;
      last.clock = s.clock;
      rejected = s.rejected_commands;
      completed = s.last_completed_step_request;
      last_rejection = s.last_rejection;
    });
    return seen;
  };
  ASSERT_TRUE(Within(30.0, take_status)) << "no mpdrig_status of rig " << kRig;
  EXPECT_EQ(last.clock, mpdrig_CLOCK_LOCKSTEP);
  ASSERT_TRUE(Within(30.0, [&] { return Matched(choke) && Matched(steps); }));

  // The lockstep rule: the command acknowledged, then the step request.
  auto step = [&](std::uint32_t n) {
    const std::uint64_t id = static_cast<std::uint64_t>(dds_time());
    mpdrig_StepRequest request{const_cast<char*>(kRig), id, n};
    EXPECT_EQ(dds_write(steps, &request), DDS_RETCODE_OK);
    EXPECT_TRUE(Within(30.0, [&] { return take_status() && completed == id; }))
        << "step request " << id << " not completed";
  };
  auto command = [&](double deg) {
    mpdrig_ChokeCommand c{const_cast<char*>(kRig), deg};
    ASSERT_EQ(dds_write(choke, &c), DDS_RETCODE_OK);
    ASSERT_EQ(dds_wait_for_acks(choke, DDS_SECS(10)), DDS_RETCODE_OK);
  };
  command(45.0);
  step(300);
  std::vector<mpdrig_RigSensors> got;
  std::vector<std::uint64_t> counters;
  TakeAll<mpdrig_RigSensors>(sensors, kRig, [&](const mpdrig_RigSensors& s) {
    counters.push_back(s.sample_counter);
    mpdrig_RigSensors copy = s;
    copy.rig_id = nullptr;  // the loan's string is gone after the take
    got.push_back(copy);
  });
  // Every sample of the 300 steps, in order (keep all), published before the status.
  ASSERT_EQ(got.size(), 300u);
  for (std::size_t i = 1; i < counters.size(); ++i) EXPECT_EQ(counters[i], counters[i - 1] + 1);
  // The command applied from the first step: the choke opened from 31 towards 45 deg (through
  // its lag and rate limit: there by 3 s), and opening it lowered C2 (the pressure upstream).
  EXPECT_GT(got.front().choke_position_deg, 31.0);
  EXPECT_NEAR(got.back().choke_position_deg, 45.0, 0.5);
  EXPECT_LT(got.back().C2_barg, got.front().C2_barg);
  bool estimated = false;
  TakeAll<mpdrig_RigEstimate>(estimates, kRig, [&](const mpdrig_RigEstimate& e) {
    estimated = estimated || e.sample_counter == counters.back();
  });
  EXPECT_TRUE(estimated) << "no mpdrig_estimate for the last sample";

  // A refused command is reported on the status, with its topic.
  const std::uint64_t rejected_before = rejected;
  command(std::nan(""));
  step(1);
  EXPECT_EQ(rejected, rejected_before + 1);
  EXPECT_NE(last_rejection.find("choke"), std::string::npos) << last_rejection;
}

// The section's "musts": a 2 s liveliness lease, or shared ownership, is incompatible with the
// rig's command reader (the writer is told so, and never matches).
TEST_P(WireContract, CommandWriterWithoutTheTablesQosDoesNotMatch) {
  const dds_entity_t status =
      Reader(Topic(&mpdrig_RigStatus_desc, "mpdrig_status"), StatusReaderQos());
  bool seen = false;
  ASSERT_TRUE(Within(30.0,
                     [&] {
                       TakeAll<mpdrig_RigStatus>(status, kRig,
                                                 [&](const mpdrig_RigStatus&) { seen = true; });
                       return seen;
                     }))
      << "no mpdrig_status of rig " << kRig;
  const dds_entity_t topic = Topic(&mpdrig_ChokeCommand_desc, "mpdrig_choke_command");
  const dds_entity_t long_lease = Writer(topic, CommandWriterQos(DDS_SECS(2)));
  const dds_entity_t shared = Writer(topic, CommandWriterQos(DDS_SECS(1), DDS_OWNERSHIP_SHARED));
  const dds_entity_t right = Writer(topic, CommandWriterQos());
  auto incompatible = [](dds_entity_t writer) {
    dds_offered_incompatible_qos_status_t s{};
    dds_get_offered_incompatible_qos_status(writer, &s);
    return s.total_count > 0 ? s.last_policy_id : 0u;
  };
  ASSERT_TRUE(Within(30.0, [&] { return Matched(right); })) << "the table's QoS did not match";
  EXPECT_TRUE(Within(10.0, [&] { return incompatible(long_lease) && incompatible(shared); }));
  EXPECT_EQ(incompatible(long_lease), static_cast<std::uint32_t>(DDS_LIVELINESS_QOS_POLICY_ID));
  EXPECT_EQ(incompatible(shared), static_cast<std::uint32_t>(DDS_OWNERSHIP_QOS_POLICY_ID));
  EXPECT_FALSE(Matched(long_lease));
  EXPECT_FALSE(Matched(shared));
  EXPECT_EQ(incompatible(right), 0u);
}

// The whole document of docs/python.md, and the fragment it says is enough for a Cyclone client.
INSTANTIATE_TEST_SUITE_P(ReadmeLoopbackSettings, WireContract, ::testing::Values(0, 1),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return std::string(info.param == 0 ? "Document" : "Fragment");
                         });

}  // namespace
