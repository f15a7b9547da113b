#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::dds {

Status Check(dds_return_t code, const char* call) {
  if (code >= 0) return Status::Ok();
  return Status::Error(std::string(call) + ": " + dds_strretcode(code));
}

std::string LoopbackConfig() {
  return "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>40</MaxAutoParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>";
}

std::string ServiceSampleLimitConfig() {
  return std::string("<Internal><MaxSampleSize>") + kServiceMaxSampleSize +
         "</MaxSampleSize></Internal>";
}

std::string AddConfigFragment(const std::string& config, const std::string& fragment) {
  const std::size_t first = config.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return LoopbackConfig() + fragment;
  if (config[first] == '<' && config.find("CycloneDDS") == std::string::npos) {
    return config + fragment;
  }
  return config + "," + fragment;
}

std::string FastAckConfig() {
  return "<Internal><HeartbeatInterval min=\"1ms\" minsched=\"1ms\">1ms</HeartbeatInterval>"
         "</Internal>";
}

Qos SensorQos(bool keep_all) {
  Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  if (keep_all) {
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  } else {
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 8);
  }
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Qos SensorWriterQos(bool lockstep) {
  Qos qos = SensorQos(false);
  if (lockstep) dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, kLockstepSensorDepth);
  return qos;
}

Qos CommandQos(int ownership_strength) {
  Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_ownership(qos.get(), DDS_OWNERSHIP_EXCLUSIVE);
  dds_qset_ownership_strength(qos.get(), ownership_strength);
  dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, kCommandLivelinessLease);
  // A controller that leaves unregisters its instances instead of disposing them: the rig's
  // command stays in force while another controller is alive, and when none is, the instance
  // becomes "no writers" (the service's cue for the safe state), not "disposed".
  dds_qset_writer_data_lifecycle(qos.get(), false);
  return qos;
}

Qos StatusQos() {
  Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
  // A status writer that goes (a crash, its lease running out, an error exit) unregisters its
  // instances and does not dispose them: a disposal is the service's word that a rig's run ended
  // as asked (RigService::EndRigs), which the clients read as a clean end.
  dds_qset_writer_data_lifecycle(qos.get(), false);
  return qos;
}

Qos RequestQos() {
  Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  return qos;
}

Result<bool> AwaitReader(dds_entity_t writer, dds_time_t deadline, std::int32_t readers) {
  MPDRIG_RETURN_IF_ERROR(
      Check(dds_set_status_mask(writer, DDS_PUBLICATION_MATCHED_STATUS), "dds_set_status_mask"));
  const dds_entity_t participant = dds_get_participant(writer);
  if (participant < 0) return Check(participant, "dds_get_participant");
  Entity waitset(dds_create_waitset(participant));
  if (waitset.handle() < 0) return Check(waitset.handle(), "dds_create_waitset");
  MPDRIG_RETURN_IF_ERROR(
      Check(dds_waitset_attach(waitset.handle(), writer, 0), "dds_waitset_attach"));
  for (;;) {
    dds_publication_matched_status_t matched{};
    MPDRIG_RETURN_IF_ERROR(Check(dds_get_publication_matched_status(writer, &matched),
                                 "dds_get_publication_matched_status"));
    if (matched.current_count >= std::max(readers, 1)) return true;
    const dds_return_t woke = dds_waitset_wait_until(waitset.handle(), nullptr, 0, deadline);
    if (woke < 0) return Check(woke, "dds_waitset_wait_until");
    if (woke == 0) return false;
  }
}

Result<Domain> Domain::Create(dds_domainid_t id, const std::string& config_xml) {
  const dds_entity_t handle = dds_create_domain(id, config_xml.c_str());
  if (handle < 0) return Check(handle, "dds_create_domain");
  return Domain(id, Entity(handle));
}

Result<Entity> CreateParticipant(dds_domainid_t domain) {
  const dds_entity_t handle = dds_create_participant(domain, nullptr, nullptr);
  if (handle < 0) return Check(handle, "dds_create_participant");
  return Entity(handle);
}

Result<Entity> CreateTopic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                           const std::string& name) {
  const dds_entity_t handle =
      dds_create_topic(participant, descriptor, name.c_str(), nullptr, nullptr);
  if (handle < 0) return Check(handle, ("dds_create_topic " + name).c_str());
  return Entity(handle);
}

Result<Entity> CreateTopic(dds_entity_t participant, const TopicSpec& topic) {
  return CreateTopic(participant, topic.type, topic.name);
}

Qos ReaderQos(const TopicSpec& topic, bool keep_all) {
  switch (topic.qos) {
    case QosClass::kSensor:
      return SensorQos(keep_all);
    case QosClass::kCommand:
      return CommandQos();
    case QosClass::kStatus:
      return StatusQos();
    case QosClass::kRequest:
      return RequestQos();
  }
  return RequestQos();  // unreachable: every class is handled above
}

}  // namespace mpdrig::dds
