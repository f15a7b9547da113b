#include "service/rig/command_intake.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string_view>
#include <type_traits>
#include <utility>

#include "service/dds/security.h"
#include "service/dds/topics.h"
#include "service/rig/wire.h"

namespace mpdrig::service {

std::string ReportedId(const char* rig_id) {
  const std::string_view id(rig_id);
  if (id.size() <= kMaxReportedIdBytes) return "'" + std::string(id) + "'";
  std::size_t end = kMaxReportedIdBytes;
  while (end > 0 && (static_cast<unsigned char>(id[end]) & 0xC0) == 0x80) --end;
  return "'" + std::string(id.substr(0, end)) + "...' (" + std::to_string(id.size()) + " bytes)";
}

void UnknownRigGate::Allow(std::string rig_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  known_.push_back(std::move(rig_id));
}

bool UnknownRigGate::Admit(const char* rig_id) {
  const char* id = rig_id != nullptr ? rig_id : "";
  // Every served id passes CheckRigId: one longer than kMaxRigIdBytes is no rig of ours, told
  // after reading kMaxRigIdBytes + 1 bytes of it, not all of it.
  const std::size_t length = strnlen(id, kMaxRigIdBytes + 1);
  std::lock_guard<std::mutex> lock(mutex_);
  for (const std::string& known : known_) {
    if (length <= kMaxRigIdBytes && known.size() == length && known.compare(0, length, id) == 0)
      return true;
  }
  std::string reported = ReportedId(id);
  ++refused_.count;
  refused_.reported_id = std::move(reported);
  return false;
}

UnknownRigGate::Refused UnknownRigGate::Drain() {
  std::lock_guard<std::mutex> lock(mutex_);
  return std::exchange(refused_, Refused{});
}

CommandIntake::CommandIntake(std::vector<RigHost>* rigs, double safe_choke_deg)
    : rigs_(rigs), safe_choke_deg_(safe_choke_deg) {}

RigHost* CommandIntake::Find(const char* rig_id) {
  for (RigHost& rig : *rigs_) {
    if (rig.rig_id() == rig_id) return &rig;
  }
  return nullptr;
}

bool CommandIntake::FromItsPartition(const char* topic, const char* rig_id,
                                     const CommandOrigin& origin) {
  if (origin.partition_rig < 0) return true;
  RigHost& own = (*rigs_)[static_cast<std::size_t>(origin.partition_rig)];
  if (own.rig_id() == rig_id) return true;
  const std::string writer = origin.writer ? origin.writer() : "unknown writer";
  const std::string reason = std::string(topic) + " for rig " + ReportedId(rig_id) +
                             " refused: it came in rig '" + own.rig_id() + "''s partition " +
                             dds::RigPartition(own.rig_id()) + " (" + writer +
                             "); a client commands only its partition's rig";
  (void)own.Refuse(reason);
  if (RigHost* target = Find(rig_id)) (void)target->Refuse(reason);
  return false;
}

void CommandIntake::RefuseUnknown(const char* topic, const std::string& reported_id,
                                  std::uint64_t count) {
  std::string serving;
  for (const RigHost& rig : *rigs_) serving += (serving.empty() ? "" : ", ") + rig.rig_id();
  const std::string reason = std::string(topic) + " for unknown rig " + reported_id +
                             " refused (this service runs: " + serving + ")";
  for (RigHost& rig : *rigs_) (void)rig.Refuse(reason, count);
}

void CommandIntake::NoteOwner(const char* rig_id, const char* actuator, const std::string& owner) {
  for (std::size_t i = 0; i < rigs_->size(); ++i) {
    if ((*rigs_)[i].rig_id() == rig_id) owners_[i][actuator] = owner;
  }
}

std::vector<std::string> CommandIntake::Owners(std::size_t rig_index) const {
  std::vector<std::string> texts;
  const auto found = owners_.find(rig_index);
  if (found == owners_.end()) return texts;
  for (const auto& [actuator, owner] : found->second) texts.push_back(actuator + ": " + owner);
  return texts;
}

template <typename Apply>
void CommandIntake::Command(const char* topic, const char* actuator, const char* rig_id,
                            const CommandOrigin& origin, const Apply& apply) {
  if (!FromItsPartition(topic, rig_id, origin)) return;
  RigHost* rig = Find(rig_id);
  if (rig == nullptr) {  // the topic filter lets none through; kept for safety
    RefuseUnknown(topic, ReportedId(rig_id));
    return;
  }
  NoteOwner(rig_id, actuator, origin.writer ? origin.writer() : "unknown writer");
  (void)apply(*rig);  // a refusal is counted and kept by the rig
}

void CommandIntake::Choke(const mpdrig_ChokeCommand& c, const CommandOrigin& origin) {
  Command(dds::topics::kChokeCommand.name, "choke", c.rig_id, origin,
          [&](RigHost& rig) { return rig.SetChokeDeg(c.opening_deg); });
}
void CommandIntake::Pump(const mpdrig_PumpCommand& c, const CommandOrigin& origin) {
  Command(dds::topics::kPumpCommand.name, "pump", c.rig_id, origin,
          [&](RigHost& rig) { return rig.SetPumpLpm(c.flow_lpm); });
}
void CommandIntake::Outlet(const mpdrig_OutletCommand& c, const CommandOrigin& origin) {
  Command(dds::topics::kOutletCommand.name, "outlet", c.rig_id, origin,
          [&](RigHost& rig) { return rig.SetOutletBarg(c.pressure_barg); });
}
void CommandIntake::Piston(const mpdrig_PistonCommand& c, const CommandOrigin& origin) {
  Command(dds::topics::kPistonCommand.name, "piston", c.rig_id, origin,
          [&](RigHost& rig) { return rig.SetPiston(FromWire(c)); });
}

// An instance whose writers are gone matters only in its own rig's partition: that rig, or
// nullptr.
RigHost* CommandIntake::LostOwner(const char* rig_id, int partition_rig, const char* actuator) {
  if (partition_rig >= 0 && (*rigs_)[static_cast<std::size_t>(partition_rig)].rig_id() != rig_id)
    return nullptr;
  NoteOwner(rig_id, actuator, "none");
  return Find(rig_id);
}

void CommandIntake::ChokeLost(const char* rig_id, int partition_rig) {
  RigHost* rig = LostOwner(rig_id, partition_rig, "choke");
  if (rig == nullptr) return;
  if (std::isnan(safe_choke_deg_)) {
    rig->NoteEvent("no choke controller left: the choke keeps its last command");
  } else if (rig->SetChokeDeg(safe_choke_deg_).ok()) {
    rig->NoteEvent("no choke controller left: safe state, choke to " +
                   std::to_string(safe_choke_deg_) + " deg");
  }
}

void CommandIntake::PistonLost(const char* rig_id, int partition_rig) {
  RigHost* rig = LostOwner(rig_id, partition_rig, "piston");
  if (rig == nullptr) return;
  (void)rig->SetPiston(PistonCommandIn{});  // hold
  rig->NoteEvent("no piston controller left: safe state, piston holds");
}

bool CommandIntake::Disposed(const char* topic, const char* rig_id) {
  if (Find(rig_id) != nullptr) return false;
  RefuseUnknown(topic, ReportedId(rig_id));
  return true;
}

UnknownRigGate* CommandIntake::AddGate(const char* topic) {
  std::vector<std::string> known;
  for (const RigHost& rig : *rigs_) known.push_back(rig.rig_id());
  gates_.push_back(std::make_unique<UnknownRigGate>(topic, std::move(known)));
  return gates_.back().get();
}

void CommandIntake::Allow(const std::string& rig_id) {
  for (const auto& gate : gates_) gate->Allow(rig_id);
}

bool CommandIntake::RefuseFiltered() {
  bool any = false;
  for (const auto& gate : gates_) {
    const UnknownRigGate::Refused refused = gate->Drain();
    if (refused.count == 0) continue;
    RefuseUnknown(gate->topic(), refused.reported_id, refused.count);
    any = true;
  }
  return any;
}

std::string DescribeWriter(dds_entity_t reader, dds_instance_handle_t publication) {
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, publication);
  if (endpoint == nullptr) return "unknown writer";
  int32_t strength = 0;
  if (endpoint->qos != nullptr) (void)dds_qget_ownership_strength(endpoint->qos, &strength);
  char guid[2 * sizeof(endpoint->key.v) + 1];
  for (std::size_t i = 0; i < sizeof(endpoint->key.v); ++i) {
    std::snprintf(guid + 2 * i, 3, "%02x", endpoint->key.v[i]);
  }
  dds_builtintopic_free_endpoint(endpoint);
  return "strength " + std::to_string(strength) + ", writer " + guid;
}

namespace {

// Takes every pending sample of one command topic into the intake: `apply` for a command,
// `lost` for an instance without writers, and an unknown rig's dispose refused.
template <typename T, typename Apply, typename Lost>
Status TakeTopic(const dds::Reader<T>& reader, int partition_rig, CommandIntake& intake,
                 const char* topic, const Apply& apply, const Lost& lost) {
  std::function<void(const T&)> on_lost;
  if constexpr (!std::is_same_v<Lost, std::nullptr_t>) {
    on_lost = [&](const T& c) { lost(c.rig_id, partition_rig); };
  }
  auto taken = reader.TakeEach(
      [&](const T& c, const dds_sample_info_t& info) {
        const CommandOrigin origin{
            partition_rig,
            [&reader, &info] { return DescribeWriter(reader.handle(), info.publication_handle); }};
        apply(c, origin);
      },
      on_lost, kMaxCommandsPerTick, [&](const T& c) { (void)intake.Disposed(topic, c.rig_id); });
  return taken.ok() ? Status::Ok() : taken.status();
}

}  // namespace

Status TakeCommands(const CommandReaders& readers, CommandIntake& intake) {
  const int rig = readers.partition_rig;
  MPDRIG_RETURN_IF_ERROR(TakeTopic(
      *readers.choke, rig, intake, dds::topics::kChokeCommand.name,
      [&](const mpdrig_ChokeCommand& c, const CommandOrigin& o) { intake.Choke(c, o); },
      [&](const char* id, int partition) { intake.ChokeLost(id, partition); }));
  MPDRIG_RETURN_IF_ERROR(TakeTopic(
      *readers.pump, rig, intake, dds::topics::kPumpCommand.name,
      [&](const mpdrig_PumpCommand& c, const CommandOrigin& o) { intake.Pump(c, o); }, nullptr));
  MPDRIG_RETURN_IF_ERROR(TakeTopic(
      *readers.outlet, rig, intake, dds::topics::kOutletCommand.name,
      [&](const mpdrig_OutletCommand& c, const CommandOrigin& o) { intake.Outlet(c, o); },
      nullptr));
  return TakeTopic(
      *readers.piston, rig, intake, dds::topics::kPistonCommand.name,
      [&](const mpdrig_PistonCommand& c, const CommandOrigin& o) { intake.Piston(c, o); },
      [&](const char* id, int partition) { intake.PistonLost(id, partition); });
}

}  // namespace mpdrig::service
