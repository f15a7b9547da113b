#include "clients/client/rig_streams.h"

#include <algorithm>
#include <chrono>
#include <optional>

#include "clients/client/client_wire.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::client {
namespace {

double ReceivedS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

struct RigStreams::Dds {
  std::shared_ptr<Participant> participant;  // first: the others are deleted before it goes
  dds::Entity sensors_topic, estimate_topic, profile_topic, status_topic, shadow_sensors_topic,
      shadow_status_topic;
  // One set of readers: every rig's (the default partition), or with security one rig's.
  struct Readers {
    std::optional<dds::Reader<mpdrig_RigSensors>> sensors, shadow_sensors;
    std::optional<dds::Reader<mpdrig_RigEstimate>> estimate;
    std::optional<dds::Reader<mpdrig_PressureProfile>> profile;
    std::optional<dds::Reader<mpdrig_RigStatus>> status;
    std::optional<dds::Reader<mpdrig_ShadowStatus>> shadow_status;
  };
  std::vector<Readers> readers;
};

namespace {

Status MakeTopic(dds_entity_t participant, const dds::TopicSpec& spec, dds::Entity* out) {
  auto created = dds::CreateTopic(participant, spec);
  if (!created.ok()) return created.status().Within(spec.name);
  *out = std::move(created).value();
  return Status::Ok();
}

template <typename T>
Status MakeReader(const Participant& participant, const std::string& rig_id,
                  dds_entity_t subscriber, const dds::Entity& topic, const dds::TopicSpec& spec,
                  std::optional<dds::Reader<T>>* out) {
  auto created = dds::Reader<T>::Create(subscriber, topic.handle(), dds::ReaderQos(spec));
  if (!created.ok()) {
    return participant.EndpointError(created.status(), rig_id, "reading").Within(spec.name);
  }
  out->emplace(std::move(created).value());
  return Status::Ok();
}

}  // namespace

RigStreams::RigStreams(const StreamOptions& options)
    : options_(options), dds_(std::make_unique<Dds>()) {}

RigStreams::~RigStreams() = default;

Result<std::unique_ptr<RigStreams>> RigStreams::Open(
    const std::shared_ptr<Participant>& participant, const StreamOptions& options) {
  if (!participant) return Status::Error("no participant");
  if (participant->secure() && options.rigs.empty()) {
    return Status::Error("with security, name the rigs to read (each is in its own partition)");
  }
  std::unique_ptr<RigStreams> streams(new RigStreams(options));
  Dds& d = *streams->dds_;
  d.participant = participant;
  const dds_entity_t p = participant->handle();
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kSensors, &d.sensors_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kEstimate, &d.estimate_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kPressureProfile, &d.profile_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kStatus, &d.status_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kShadowSensors, &d.shadow_sensors_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kShadowStatus, &d.shadow_status_topic));
  // Without security one set for every rig; with it one per rig, in the rig's partition.
  std::vector<std::string> partitions{std::string()};
  if (participant->secure()) partitions = options.rigs;
  for (const std::string& rig_id : partitions) {
    auto scope = participant->ScopeOf(rig_id);
    if (!scope.ok()) return scope.status();
    const dds_entity_t sub = scope->subscriber;
    Dds::Readers& r = d.readers.emplace_back();
    const Participant& who = *participant;
    MPDRIG_RETURN_IF_ERROR(
        MakeReader(who, rig_id, sub, d.sensors_topic, dds::topics::kSensors, &r.sensors));
    MPDRIG_RETURN_IF_ERROR(
        MakeReader(who, rig_id, sub, d.estimate_topic, dds::topics::kEstimate, &r.estimate));
    MPDRIG_RETURN_IF_ERROR(
        MakeReader(who, rig_id, sub, d.profile_topic, dds::topics::kPressureProfile, &r.profile));
    MPDRIG_RETURN_IF_ERROR(
        MakeReader(who, rig_id, sub, d.status_topic, dds::topics::kStatus, &r.status));
    MPDRIG_RETURN_IF_ERROR(MakeReader(who, rig_id, sub, d.shadow_sensors_topic,
                                      dds::topics::kShadowSensors, &r.shadow_sensors));
    MPDRIG_RETURN_IF_ERROR(MakeReader(who, rig_id, sub, d.shadow_status_topic,
                                      dds::topics::kShadowStatus, &r.shadow_status));
  }
  return streams;
}

bool RigStreams::Wanted(const char* rig_id) const {
  return options_.rigs.empty() ||
         std::find(options_.rigs.begin(), options_.rigs.end(), rig_id) != options_.rigs.end();
}

RigStreams::Taken RigStreams::Take(const Visitor& visit) {
  Taken taken;
  auto count = [&](const Result<int>& n) {
    if (n.ok()) {
      taken.samples += static_cast<std::uint64_t>(*n);
    } else {
      taken.error = n.status().message();
    }
  };
  // The rig's sensors and the shadow's are one type on two topics.
  using SensorVisit = std::function<void(const std::string&, const Sensors&)>;
  auto take_sensors = [&](const dds::Reader<mpdrig_RigSensors>& reader, const SensorVisit& to) {
    count(reader.TakeEach([&](const mpdrig_RigSensors& w, const dds_sample_info_t& info) {
      if (!Wanted(w.rig_id)) return;
      Sensors s = FromWire(w, info);
      s.received_s = ReceivedS();
      to(w.rig_id, s);
    }));
  };
  for (Dds::Readers& r : dds_->readers) {
    if (visit.sensors) take_sensors(*r.sensors, visit.sensors);
    if (visit.estimate) {
      count(r.estimate->TakeEach([&](const mpdrig_RigEstimate& w, const dds_sample_info_t&) {
        if (Wanted(w.rig_id)) visit.estimate(w.rig_id, FromWire(w));
      }));
    }
    if (visit.profile) {
      count(r.profile->TakeEach([&](const mpdrig_PressureProfile& w, const dds_sample_info_t&) {
        if (Wanted(w.rig_id)) visit.profile(w.rig_id, FromWire(w));
      }));
    }
    if (visit.status) {
      count(r.status->TakeEach([&](const mpdrig_RigStatus& w, const dds_sample_info_t&) {
        if (Wanted(w.rig_id)) visit.status(w.rig_id, FromWire(w));
      }));
    }
    if (visit.shadow_sensors) take_sensors(*r.shadow_sensors, visit.shadow_sensors);
    if (visit.shadow_status) {
      count(r.shadow_status->TakeEach([&](const mpdrig_ShadowStatus& w, const dds_sample_info_t&) {
        if (Wanted(w.rig_id) && options_.shadow_id == w.shadow_id) visit.shadow_status(FromWire(w));
      }));
    }
  }
  return taken;
}

}  // namespace mpdrig::client
