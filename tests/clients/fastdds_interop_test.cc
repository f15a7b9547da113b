// Another vendor on the wire: eProsima Fast DDS (Debian's libfastrtps-dev) talks to `mpdrig serve`
// (Cyclone DDS) with only what the documented contract gives (docs: "From MATLAB, ROS 2 or
// another DDS client"): the domain, loopback with a unicast initial peer 127.0.0.1, the topic
// and type names, the QoS of the table, and the types of idl/mpdrig.idl written out by hand in
// CDR (XCDR1, @final: plain CDR, as fastddsgen would generate them). Fast DDS is ROS 2's default
// middleware and one of the two that MATLAB's DDS Blockset supports, so this is what a MATLAB or
// ROS 2 client does on the wire. Loopback, a domain of the test's own.
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastrtps/utils/md5.h>
#include <gtest/gtest.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>

#include "tests/support/process.h"
#include "tests/support/test_domain.h"
#include "tests/support/within.h"

namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastcdr::Cdr;
using eprosima::fastcdr::FastBuffer;
using mpdrig::testing::ChildOptions;
using mpdrig::testing::ChildProcess;
using mpdrig::testing::Within;

// The IDL's structs, as far as this test reads or writes them (field order of idl/mpdrig.idl).
struct StepRequest {
  std::string rig_id;
  std::uint64_t request_id = 0;
  std::uint32_t steps = 0;
  void Write(Cdr& c) const { c << rig_id << request_id << steps; }
  void Read(Cdr& c) { c >> rig_id >> request_id >> steps; }
};
struct ChokeCommand {
  std::string rig_id;
  double opening_deg = 0.0;
  void Write(Cdr& c) const { c << rig_id << opening_deg; }
  void Read(Cdr& c) { c >> rig_id >> opening_deg; }
};
struct RigStatus {  // read up to last_completed_step_request; the rest is not needed
  std::string rig_id;
  std::uint32_t clock = 0;  // enum ClockMode: 0 realtime, 1 fast, 2 lockstep
  double sim_time_s = 0.0, real_time_factor = 0.0;
  std::uint64_t deadline_misses = 0, rejected_commands = 0;
  std::string last_rejection;
  std::uint64_t last_completed_step_request = 0;
  void Write(Cdr&) const {}
  void Read(Cdr& c) {
    c >> rig_id >> clock >> sim_time_s >> real_time_factor >> deadline_misses >>
        rejected_commands >> last_rejection >> last_completed_step_request;
  }
};
struct RigSensors {
  std::string rig_id;
  std::uint64_t sample_counter = 0;
  double sim_time_s = 0.0, piston_position_m = 0.0, choke_position_deg = 0.0;
  double P1_barg = 0.0, P2_barg = 0.0, PT_barg[10] = {};
  double C1_barg = 0.0, C2_barg = 0.0;
  void Write(Cdr&) const {}
  void Read(Cdr& c) {
    c >> rig_id >> sample_counter >> sim_time_s >> piston_position_m >> choke_position_deg >>
        P1_barg >> P2_barg;
    for (double& pt : PT_barg) c >> pt;
    c >> C1_barg >> C2_barg;
  }
};

// A type of the contract: its registered name, plain CDR (XCDR1) of a @final struct, key rig_id
// (the key hash: the key's big-endian CDR, MD5 when longer than 16 bytes, as DDS-RTPS 9.6.3.8).
template <typename T>
class Type : public dds::TopicDataType {
 public:
  explicit Type(const char* name) {
    setName(name);
    m_typeSize = 65536;
    m_isGetKeyDefined = true;
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->max_size);
    Cdr cdr(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);
    payload->encapsulation = cdr.endianness() == Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    cdr.serialize_encapsulation();
    static_cast<T*>(data)->Write(cdr);
    payload->length = static_cast<std::uint32_t>(cdr.getSerializedDataLength());
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    try {
      FastBuffer buffer(reinterpret_cast<char*>(payload->data), payload->length);
      Cdr cdr(buffer, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR);
      cdr.read_encapsulation();
      static_cast<T*>(data)->Read(cdr);
      return true;
    } catch (...) {
      return false;
    }
  }
  std::function<std::uint32_t()> getSerializedSizeProvider(void*) override {
    return [] { return 65536u; };
  }
  void* createData() override { return new T(); }
  void deleteData(void* data) override { delete static_cast<T*>(data); }
  bool getKey(void* data, rtps::InstanceHandle_t* handle, bool force_md5) override {
    char bytes[512] = {};
    FastBuffer buffer(bytes, sizeof bytes);
    Cdr cdr(buffer, Cdr::BIG_ENDIANNESS);
    cdr << static_cast<T*>(data)->rig_id;
    const std::size_t n = cdr.getSerializedDataLength();
    if (force_md5 || n > 16) {
      MD5 md5;
      md5.update(bytes, static_cast<unsigned int>(n));
      md5.finalize();
      for (int i = 0; i < 16; ++i) handle->value[i] = md5.digest[i];
    } else {
      for (int i = 0; i < 16; ++i) handle->value[i] = static_cast<rtps::octet>(bytes[i]);
    }
    return true;
  }
};

// Takes every sample of `reader` for rig `rig`.
template <typename T>
void TakeAll(dds::DataReader* reader, const std::string& rig,
             const std::function<void(const T&)>& visit) {
  T sample;
  dds::SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data && sample.rig_id == rig) visit(sample);
  }
}

bool Matched(dds::DataWriter* writer) {
  dds::PublicationMatchedStatus status;
  writer->get_publication_matched_status(status);
  return status.current_count > 0;
}

TEST(FastDdsInterop, ReadsCommandsAndStepsTheRig) {
  const int domain = mpdrig::testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  const std::string rig = "fastdds-1";
  ChildProcess serve({MPDRIG_EXE, "serve", "--clock", "lockstep", "--rate-hz", "100", "--pump-lpm",
                      "5", "--choke-deg", "31", "--sensor-noise", "none", "--rig", rig, "--domain",
                      std::to_string(domain)},
                     ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();

  // Loopback only, UDP (the service's Cyclone has no shared-memory transport), and the unicast
  // initial peer 127.0.0.1 (the service does not use multicast).
  dds::DomainParticipantQos pqos;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  pqos.transport().user_transports.push_back(udp);
  pqos.transport().use_builtin_transports = false;
  rtps::Locator_t peer;
  rtps::IPLocator::setIPv4(peer, "127.0.0.1");
  pqos.wire_protocol().builtin.initialPeersList.push_back(peer);
  auto* factory = dds::DomainParticipantFactory::get_instance();
  dds::DomainParticipant* participant = factory->create_participant(domain, pqos);
  ASSERT_NE(participant, nullptr);
  struct Cleanup {
    dds::DomainParticipant* p;
    ~Cleanup() {
      p->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(p);
    }
  } cleanup{participant};

  dds::TypeSupport status_type(new Type<RigStatus>("mpdrig::RigStatus"));
  dds::TypeSupport sensors_type(new Type<RigSensors>("mpdrig::RigSensors"));
  dds::TypeSupport choke_type(new Type<ChokeCommand>("mpdrig::ChokeCommand"));
  dds::TypeSupport step_type(new Type<StepRequest>("mpdrig::StepRequest"));
  for (auto* t : {&status_type, &sensors_type, &choke_type, &step_type}) {
    ASSERT_EQ(t->register_type(participant), ReturnCode_t::RETCODE_OK);
  }
  auto* status_topic =
      participant->create_topic("mpdrig_status", "mpdrig::RigStatus", dds::TOPIC_QOS_DEFAULT);
  auto* sensors_topic =
      participant->create_topic("mpdrig_sensors", "mpdrig::RigSensors", dds::TOPIC_QOS_DEFAULT);
  auto* choke_topic = participant->create_topic("mpdrig_choke_command", "mpdrig::ChokeCommand",
                                                dds::TOPIC_QOS_DEFAULT);
  auto* step_topic = participant->create_topic("mpdrig_step_request", "mpdrig::StepRequest",
                                               dds::TOPIC_QOS_DEFAULT);
  ASSERT_TRUE(status_topic && sensors_topic && choke_topic && step_topic);
  dds::Subscriber* sub = participant->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  dds::Publisher* pub = participant->create_publisher(dds::PUBLISHER_QOS_DEFAULT);

  // The table: status reliable, transient-local, keep last 1; sensors reliable, volatile, keep
  // all in lockstep; commands reliable, transient-local, keep last 1, exclusive ownership,
  // automatic liveliness of 1 s; step requests reliable, volatile, keep all.
  dds::DataReaderQos status_qos;
  status_qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  status_qos.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
  status_qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  status_qos.history().depth = 1;
  dds::DataReaderQos sensors_qos;
  sensors_qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  sensors_qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  sensors_qos.history().kind = dds::KEEP_ALL_HISTORY_QOS;
  dds::DataWriterQos choke_qos;
  choke_qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  choke_qos.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
  choke_qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  choke_qos.history().depth = 1;
  choke_qos.ownership().kind = dds::EXCLUSIVE_OWNERSHIP_QOS;
  choke_qos.ownership_strength().value = 10;
  choke_qos.liveliness().kind = dds::AUTOMATIC_LIVELINESS_QOS;
  choke_qos.liveliness().lease_duration = eprosima::fastrtps::Duration_t(1, 0);
  choke_qos.liveliness().announcement_period = eprosima::fastrtps::Duration_t(0, 500000000);
  choke_qos.writer_data_lifecycle().autodispose_unregistered_instances = false;
  dds::DataWriterQos step_qos;
  step_qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  step_qos.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  step_qos.history().kind = dds::KEEP_ALL_HISTORY_QOS;
  dds::DataReader* status = sub->create_datareader(status_topic, status_qos);
  dds::DataReader* sensors = sub->create_datareader(sensors_topic, sensors_qos);
  dds::DataWriter* choke = pub->create_datawriter(choke_topic, choke_qos);
  dds::DataWriter* steps = pub->create_datawriter(step_topic, step_qos);
  ASSERT_TRUE(status && sensors && choke && steps);

  RigStatus last;
  bool seen = false;
  auto take_status = [&] {
    TakeAll<RigStatus>(status, rig, [&](const RigStatus& s) {
      seen = true;
      last = s;
    });
    return seen;
  };
  ASSERT_TRUE(Within(30.0, take_status)) << "Fast DDS saw no mpdrig_status of rig " << rig;
  EXPECT_EQ(last.clock, 2u) << "lockstep";
  ASSERT_TRUE(Within(30.0, [&] { return Matched(choke); }))
      << "the rig's command reader did not match a Fast DDS writer with the table's QoS";
  ASSERT_TRUE(Within(30.0, [&] { return Matched(steps); }));

  ChokeCommand command{rig, 45.0};
  ASSERT_TRUE(choke->write(&command));
  ASSERT_EQ(choke->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(10, 0)),
            ReturnCode_t::RETCODE_OK);
  StepRequest request{
      rig, static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count()),
      300};
  ASSERT_TRUE(steps->write(&request));
  ASSERT_TRUE(Within(30.0, [&] {
    take_status();
    return last.last_completed_step_request == request.request_id;
  })) << "the step request was not completed";
  std::vector<RigSensors> got;
  ASSERT_TRUE(Within(10.0, [&] {
    TakeAll<RigSensors>(sensors, rig, [&](const RigSensors& s) { got.push_back(s); });
    return got.size() >= 300;
  }));
  ASSERT_EQ(got.size(), 300u);
  for (std::size_t i = 1; i < got.size(); ++i) {
    EXPECT_EQ(got[i].sample_counter, got[i - 1].sample_counter + 1);
  }
  // The command applied from the first step (acknowledged before the request): the choke moved
  // from 31 towards 45 deg and is there after 3 s; C2 fell as the choke opened.
  EXPECT_GT(got.front().choke_position_deg, 31.0);
  EXPECT_NEAR(got.back().choke_position_deg, 45.0, 0.5);
  EXPECT_LT(got.back().C2_barg, got.front().C2_barg);
  std::printf("Fast DDS: %zu samples of rig %s, choke %.3f deg, C2 %.4f -> %.4f barg\n", got.size(),
              rig.c_str(), got.back().choke_position_deg, got.front().C2_barg, got.back().C2_barg);
}

}  // namespace
