// Command intake: what the service does with each command a client sends (choke, piston, pump,
// outlet). A command for a rig this service runs is handed to the rig, which applies it or
// refuses it (NaN, infinite, out of range: counted, the reason kept for the status, the last
// valid command stays in force: rig_host.h). A command for an unknown rig id is refused on every
// rig's status, with at most kMaxReportedIdBytes of its id; with security, a command that came in
// one rig's partition for another rig is refused on both, with its writer. The intake keeps who
// commands each actuator (exclusive ownership: the strongest live writer) and takes the safe
// state (ServeOptions::safe_choke_deg; the piston holds) when an actuator's last writer goes.
//
// CommandIntake is transport-free: it takes the wire structs (idl/mpdrig.idl) and where they
// came from, so it is tested without DDS. UnknownRigGate is the topic filter that drops commands
// for unknown ids before Cyclone holds them; TakeCommands reads a set of command readers into an
// intake.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/rig/rig_host.h"

namespace mpdrig::service {

// The most bytes of an unknown rig id that a status repeats.
inline constexpr std::size_t kMaxReportedIdBytes = 64;

// 'id', or its first kMaxReportedIdBytes (not cutting a UTF-8 character) and its length.
std::string ReportedId(const char* rig_id);

// Commands for rig ids this service does not run never reach a reader's cache: a topic filter
// drops them before Cyclone makes an instance of their key, so a stranger who writes to many
// distinct ids costs the service nothing per id (an instance held while its writer lives, and a
// "no writers" sample for each when the writer goes, all taken in one tick, before). The filter
// still counts each refusal and keeps the last id (bounded, ReportedId) for the status.
// Cyclone calls the filter on its receive threads: the tally is under a mutex.
class UnknownRigGate {
 public:
  UnknownRigGate(const char* topic, std::vector<std::string> known)
      : topic_(topic), known_(std::move(known)) {}

  const char* topic() const { return topic_; }
  // A rig made while the service runs (a student's private rig).
  void Allow(std::string rig_id);

  // A dds_topic_filter_sample_arg_fn for the command type T (its key field is rig_id).
  template <typename T>
  static bool Accept(const void* sample, void* gate) {
    return static_cast<UnknownRigGate*>(gate)->Admit(static_cast<const T*>(sample)->rig_id);
  }
  // True if `rig_id` is a rig of this service; otherwise counts the refusal.
  bool Admit(const char* rig_id);

  struct Refused {
    std::uint64_t count = 0;
    std::string reported_id;  // the last one, as ReportedId gives it
  };
  // The refusals since the last call.
  Refused Drain();

 private:
  const char* topic_;
  std::vector<std::string> known_;  // under mutex_: Cyclone's receive threads read it
  std::mutex mutex_;
  Refused refused_;
};

// Where a command came from.
struct CommandOrigin {
  // The rig in whose partition it arrived (security: one partition per rig); -1: the default
  // partition, where every rig's commands arrive.
  int partition_rig = -1;
  // Its writer ("strength 20, writer <guid>"), asked only when needed.
  std::function<std::string()> writer;
};

class CommandIntake {
 public:
  // `rigs` (the service's, which may grow: private rigs) outlives the intake. The choke goes to
  // safe_choke_deg when its last controller goes (NaN: it keeps its last command).
  CommandIntake(std::vector<RigHost>* rigs, double safe_choke_deg);

  RigHost* Find(const char* rig_id);

  // Each applies the command to its rig or refuses it (counted and reported, never an error).
  void Choke(const mpdrig_ChokeCommand& command, const CommandOrigin& origin);
  void Pump(const mpdrig_PumpCommand& command, const CommandOrigin& origin);
  void Outlet(const mpdrig_OutletCommand& command, const CommandOrigin& origin);
  void Piston(const mpdrig_PistonCommand& command, const CommandOrigin& origin);
  // An actuator's instance has no writer left (seen in `partition_rig`'s partition): the owner
  // is "none" and the actuator takes its safe state (the pump and the outlet keep theirs).
  void ChokeLost(const char* rig_id, int partition_rig);
  void PistonLost(const char* rig_id, int partition_rig);
  // A dispose carries only the key and passes no topic filter: one for an unknown rig is
  // refused; true if it was.
  bool Disposed(const char* topic, const char* rig_id);

  // With security, a command (or request) for another rig than its partition's is refused on
  // both rigs' status with its writer; true if it came in its own rig's partition.
  bool FromItsPartition(const char* topic, const char* rig_id, const CommandOrigin& origin);
  // `count` commands on `topic` for unknown rigs, the last for `reported_id` (ReportedId's form):
  // refused on every rig's status, with the rigs this service runs.
  void RefuseUnknown(const char* topic, const std::string& reported_id, std::uint64_t count = 1);

  // The topic filters: one per topic, knowing the rigs run so far (Allow tells them of another).
  UnknownRigGate* AddGate(const char* topic);
  void Allow(const std::string& rig_id);
  // Refuses, as RefuseUnknown, what the filters dropped since the last call; true if any.
  bool RefuseFiltered();

  // Who commands rig `rig_index`'s actuators: "choke: strength 20, writer <guid>", "piston: none",
  // in the actuators' alphabetical order; empty before the first command.
  std::vector<std::string> Owners(std::size_t rig_index) const;

 private:
  template <typename Apply>
  void Command(const char* topic, const char* actuator, const char* rig_id,
               const CommandOrigin& origin, const Apply& apply);
  void NoteOwner(const char* rig_id, const char* actuator, const std::string& owner);
  RigHost* LostOwner(const char* rig_id, int partition_rig, const char* actuator);

  std::vector<RigHost>* rigs_;
  double safe_choke_deg_;
  std::map<std::size_t, std::map<std::string, std::string>> owners_;  // rig index -> actuator
  std::vector<std::unique_ptr<UnknownRigGate>> gates_;
};

// The most samples of one command topic a real-time tick takes; the rest wait for the next tick,
// so no burst (e.g. many instances losing their writer together) stalls one tick. A rig has one
// instance per command topic, so legitimate traffic is far below it.
inline constexpr int kMaxCommandsPerTick = 256;

// A dispose or unregister carries only the key, and Cyclone applies topic filters to samples with
// data only: a stranger who disposes many distinct unknown ids still makes each command reader
// hold an instance per id while the stranger's writer lives (measured, bench/unknown_id_flood.sh
// with DISPOSE=1: 100 000 ids, RSS 16 -> 76 MB). The service refuses and reports each such
// dispose, but does not bound the instances: with a resource limit on the readers, Cyclone
// rejects the excess and its reliable delivery then retries the rejected sample, which held up
// every other writer's commands (measured: a controller's command from another process was not
// delivered within 10 s while a stranger disposed 2000 ids). Where strangers can join the
// domain, --security keeps them out.

// One set of command readers: every rig's (the default partition) or one rig's partition's.
struct CommandReaders {
  int partition_rig = -1;  // as CommandOrigin
  std::optional<dds::Reader<mpdrig_ChokeCommand>> choke;
  std::optional<dds::Reader<mpdrig_PistonCommand>> piston;
  std::optional<dds::Reader<mpdrig_PumpCommand>> pump;
  std::optional<dds::Reader<mpdrig_OutletCommand>> outlet;
};

// The writer of a sample `reader` received, from Cyclone's discovery data: its ownership strength
// and GUID ("strength 20, writer 1a2b..."), or "unknown writer".
std::string DescribeWriter(dds_entity_t reader, dds_instance_handle_t publication);

// Hands every pending command of `readers` (at most kMaxCommandsPerTick per topic) to `intake`.
// Fails only when the transport fails.
Status TakeCommands(const CommandReaders& readers, CommandIntake& intake);

}  // namespace mpdrig::service
