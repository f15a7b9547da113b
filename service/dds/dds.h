// A thin C++ layer over Cyclone DDS's C API (Debian ships no C++ binding). It owns entities
// (RAII: deleting a participant deletes its children), turns negative return codes into Status
// values with dds_strretcode, and gives typed topics, writers and readers for the structs idlc
// generates from idl/mpdrig.idl. Transport only: no physics, no model types.
#pragma once

#include <dds/dds.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>

#include "model/common/status.h"

namespace mpdrig::dds {

// Status for a DDS call: OK for a non-negative return, otherwise "<call>: <dds_strretcode>".
Status Check(dds_return_t code, const char* call);

// Cyclone configuration that keeps all traffic on loopback (127.0.0.1, no multicast, unicast
// discovery to localhost): every test and single-machine run uses it.
std::string LoopbackConfig();

// The largest serialised sample the rig service sends or takes (Cyclone's Internal/MaxSampleSize):
// its own are a few kB (a pressure profile of at most 1000 points is 24 kB), and Cyclone drops a
// larger one as its first fragment comes in, before it reassembles or copies any of it. Without
// it a stranger's 10 MB rig id was received, copied and filtered in full: ten of them cost a
// 1 kHz service about 1300 lost periods and a 0.21 s stall (bench/unknown_id_flood.sh, ID_BYTES).
// Such a sample is not counted: Cyclone drops it below any reader.
inline constexpr const char* kServiceMaxSampleSize = "256KiB";
std::string ServiceSampleLimitConfig();

// `config` (an XML fragment, a whole <CycloneDDS> document or a comma-separated list of file URIs
// and fragments; empty: LoopbackConfig) with `fragment` added: appended to a fragment, one more
// element of the list otherwise (Cyclone merges them; two <Internal> elements combine).
std::string AddConfigFragment(const std::string& config, const std::string& fragment);

// Configuration fragment for a client that waits for its commands' acknowledgements every step
// (a lockstep controller): Cyclone 0.10 asks readers for an acknowledgement with its writer's
// heartbeat, which a write carries only if the last one is older than the heartbeat interval
// (100 ms by default). Then dds_wait_for_acks after each of a run of writes takes up to 100 ms
// across processes (measured: 100 ms per lockstep step); with a 1 ms interval it takes about a
// round trip. Append it to the domain configuration (it is an <Internal> element).
std::string FastAckConfig();

// Owns one entity handle; deleting it deletes its children too.
class Entity {
 public:
  Entity() = default;
  explicit Entity(dds_entity_t handle) : handle_(handle) {}
  ~Entity() { Reset(); }
  Entity(Entity&& other) noexcept : handle_(std::exchange(other.handle_, 0)) {}
  Entity& operator=(Entity&& other) noexcept {
    if (this != &other) {
      Reset();
      handle_ = std::exchange(other.handle_, 0);
    }
    return *this;
  }
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;

  dds_entity_t handle() const { return handle_; }
  void Reset() {
    if (handle_ > 0) dds_delete(handle_);
    handle_ = 0;
  }

 private:
  dds_entity_t handle_ = 0;
};

// Owns a QoS object; QoS objects live briefly (style.md).
class Qos {
 public:
  Qos() : qos_(dds_create_qos()) {}
  ~Qos() {
    if (qos_ != nullptr) dds_delete_qos(qos_);
  }
  Qos(Qos&& other) noexcept : qos_(std::exchange(other.qos_, nullptr)) {}
  Qos& operator=(Qos&&) = delete;
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

// The project's QoS choices, one place (docs/service.md, "Topics and QoS", explains them):
//   sensors  - reliable, volatile; keep last 8 (a slow reader must not hold back a real-time rig;
//              a late joiner wants the present, not history), or keep all in lockstep, where the
//              client sets the pace and must see every step.
//   commands - reliable, keep last 1, transient-local: a late-joining rig (or a restarted one)
//              gets the current command. Exclusive ownership: of several controllers the
//              strongest alive writer wins, the next takes over when it goes. Automatic liveliness
//              with a 1 s lease: a controller that dies is noticed within a second (readers and
//              writers use the same QoS, so every client must offer a lease of at most 1 s).
//              Writers unregister (not dispose) their instances when they go.
//   status   - reliable, keep last 1, transient-local: a late joiner sees the current status.
//              Writers do not dispose when they go: a disposal is a rig's clean end.
//   requests - step requests, private-rig requests, the shadow's commands: reliable, keep all,
//              volatile. A request is an event, not state: every one counts, a late joiner must
//              not act on an old one.
Qos SensorQos(bool keep_all = false);
// The service's side of a sensor-like stream (sensors, estimates, profiles). In lockstep the
// writer keeps the last kLockstepSensorDepth samples of each rig, not all of them: Cyclone
// throttles only reliable keep-all writers (its writer-history watermarks: a write waits, up to
// the reliability's max blocking time, while a reader leaves too much unacknowledged), so one
// reader that stops acknowledging (a client killed and not yet expired, held in a debugger, or
// SIGSTOPped) would hold up every rig of the service and then fail its writes. A keep-last
// writer never waits for a reader; a reader that falls more than the depth behind loses the
// oldest samples (it sees a gap in the sample counter) and nobody else does. The depth covers a
// live reader's retransmissions at full lockstep speed (about 5e4 samples/s for a heartbeat
// period of 100 ms: 5e3 samples) with room to spare, and bounds what a stopped reader costs
// the service (kLockstepSensorDepth samples of each rig and stream, until its lease ends).
inline constexpr int kLockstepSensorDepth = 8192;
Qos SensorWriterQos(bool lockstep);
inline constexpr dds_duration_t kCommandLivelinessLease = DDS_SECS(1);
Qos CommandQos(int ownership_strength = 0);
Qos StatusQos();
Qos RequestQos();

// A domain with an explicit configuration (created before any participant on that id), and a
// participant in it.
class Domain {
 public:
  static Result<Domain> Create(dds_domainid_t id, const std::string& config_xml);
  dds_domainid_t id() const { return id_; }

 private:
  Domain(dds_domainid_t id, Entity entity) : id_(id), entity_(std::move(entity)) {}
  dds_domainid_t id_;
  Entity entity_;
};

Result<Entity> CreateParticipant(dds_domainid_t domain);
Result<Entity> CreateTopic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                           const std::string& name);

// Typed writer for an idlc-generated struct T. `participant` may also be a publisher.
template <typename T>
class Writer {
 public:
  static Result<Writer> Create(dds_entity_t participant, dds_entity_t topic, const Qos& qos) {
    const dds_entity_t handle = dds_create_writer(participant, topic, qos.get(), nullptr);
    if (handle < 0) return Check(handle, "dds_create_writer");
    return Writer(Entity(handle));
  }
  Status Write(const T& sample) const {
    return Check(dds_write(entity_.handle(), &sample), "dds_write");
  }
  dds_entity_t handle() const { return entity_.handle(); }

 private:
  explicit Writer(Entity entity) : entity_(std::move(entity)) {}
  Entity entity_;
};

// Waits on a waitset until `writer` has matched at least `readers` readers (true) or until
// `deadline` (false); a DDS failure is an error. A sample written before the match reaches no one:
// a volatile one is lost, and a process that exits takes a transient-local one with it.
Result<bool> AwaitReader(dds_entity_t writer, dds_time_t deadline, std::int32_t readers = 1);
// The DDS time `seconds` from now (at least now; DDS_NEVER for a wait as long as DDS can express),
// for AwaitReader and the waitsets' deadlines.
inline dds_time_t DeadlineAfter(double seconds) {
  const dds_time_t now = dds_time();
  const double left_ns = std::max(seconds, 0.0) * 1e9;
  if (!(left_ns < static_cast<double>(DDS_NEVER - now))) return DDS_NEVER;
  return now + static_cast<dds_duration_t>(left_ns);
}

// Sends one command (CommandQos, `strength`) from a writer of its own, the way a script or a
// short-lived process should: it waits until the service's reader has matched (a sample written
// before that reaches no one once the process is gone), writes, waits for the acknowledgement
// (the process may exit right after), and deletes the writer, which unregisters the instance:
// under exclusive ownership the next writer of the same strength then owns it at once, where a
// writer that merely exits keeps it until its liveliness lease (1 s) runs out, and a later
// writer's command in that second is dropped whenever the stale owner's GUID sorts first.
template <typename T>
Status SendOnce(dds_entity_t participant, dds_entity_t topic, const T& sample,
                dds_duration_t timeout, int strength = 0) {
  Entity writer(dds_create_writer(participant, topic, CommandQos(strength).get(), nullptr));
  if (writer.handle() < 0) return Check(writer.handle(), "dds_create_writer");
  const dds_time_t deadline = dds_time() + timeout;
  auto matched = AwaitReader(writer.handle(), deadline);
  if (!matched.ok()) return matched.status();
  if (!*matched) return Status::Error("no reader of the topic (is the service running?)");
  MPDRIG_RETURN_IF_ERROR(Check(dds_write(writer.handle(), &sample), "dds_write"));
  const dds_duration_t left = std::max<dds_duration_t>(deadline - dds_time(), DDS_MSECS(1));
  MPDRIG_RETURN_IF_ERROR(Check(dds_wait_for_acks(writer.handle(), left), "dds_wait_for_acks"));
  writer.Reset();  // deleting the writer unregisters the instance
  return Status::Ok();
}

// Typed reader with a waitset on "data available". `participant` may also be a subscriber.
template <typename T>
class Reader {
 public:
  static Result<Reader> Create(dds_entity_t participant, dds_entity_t topic, const Qos& qos) {
    Entity reader(dds_create_reader(participant, topic, qos.get(), nullptr));
    if (reader.handle() < 0) return Check(reader.handle(), "dds_create_reader");
    // `participant` may be a subscriber (a partition of its own): the waitset needs the
    // participant.
    const dds_entity_t owner = dds_get_participant(reader.handle());
    if (owner < 0) return Check(owner, "dds_get_participant");
    Entity waitset(dds_create_waitset(owner));
    if (waitset.handle() < 0) return Check(waitset.handle(), "dds_create_waitset");
    const dds_entity_t condition = dds_create_readcondition(reader.handle(), DDS_ANY_STATE);
    if (condition < 0) return Check(condition, "dds_create_readcondition");
    MPDRIG_RETURN_IF_ERROR(
        Check(dds_waitset_attach(waitset.handle(), condition, 0), "dds_waitset_attach"));
    return Reader(std::move(reader), std::move(waitset));
  }

  // Blocks until data is available or the timeout passes; true if data is there.
  Result<bool> Wait(dds_duration_t timeout) const {
    const dds_return_t n = dds_waitset_wait(waitset_.handle(), nullptr, 0, timeout);
    if (n < 0) return Check(n, "dds_waitset_wait");
    return n > 0;
  }

  // Takes every available sample (at most `max_samples`, the rest stay for the next call) and
  // hands each valid one to `visit` while it is on loan (its strings belong to DDS and are gone
  // after the call). When an instance has lost all its writers (deleted, or their liveliness
  // lease ran out), `on_no_writers` gets the sample, whose key fields identify the instance;
  // when a writer disposed an instance, `on_disposed` does.
  // Returns how many valid samples were visited.
  Result<int> TakeEach(const std::function<void(const T&, const dds_sample_info_t&)>& visit,
                       const std::function<void(const T&)>& on_no_writers = {},
                       int max_samples = std::numeric_limits<int>::max(),
                       const std::function<void(const T&)>& on_disposed = {}) const {
    constexpr int kBatch = 16;
    int visited = 0;
    for (int taken = 0; taken < max_samples;) {
      void* samples[kBatch] = {nullptr};
      dds_sample_info_t infos[kBatch];
      const dds_return_t n = dds_take(entity_.handle(), samples, infos, kBatch, kBatch);
      if (n < 0) return Check(n, "dds_take");
      for (int i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          visit(*static_cast<const T*>(samples[i]), infos[i]);
          ++visited;
        } else if (on_no_writers && infos[i].instance_state == DDS_IST_NOT_ALIVE_NO_WRITERS) {
          on_no_writers(*static_cast<const T*>(samples[i]));
        } else if (on_disposed && infos[i].instance_state == DDS_IST_NOT_ALIVE_DISPOSED) {
          on_disposed(*static_cast<const T*>(samples[i]));
        }
      }
      if (n > 0) {
        MPDRIG_RETURN_IF_ERROR(
            Check(dds_return_loan(entity_.handle(), samples, n), "dds_return_loan"));
      }
      if (n < kBatch) return visited;
      taken += n;
    }
    return visited;
  }

  dds_entity_t handle() const { return entity_.handle(); }

 private:
  Reader(Entity reader, Entity waitset)
      : entity_(std::move(reader)), waitset_(std::move(waitset)) {}
  Entity entity_;
  Entity waitset_;
};

}  // namespace mpdrig::dds
