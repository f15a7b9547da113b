#include "clients/client/rig_client.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>

#include "clients/client/client_wire.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::client {
namespace {

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr std::size_t kQueueLimit = 10000;
constexpr std::size_t kEstimateLimit = 512;
constexpr dds_duration_t kPoll = DDS_MSECS(100);

enum CommandTopic { kChoke = 0, kPump = 1, kOutlet = 2, kPiston = 3 };
constexpr const dds::TopicSpec* kCommandTopics[] = {
    &dds::topics::kChokeCommand, &dds::topics::kPumpCommand, &dds::topics::kOutletCommand,
    &dds::topics::kPistonCommand};

}  // namespace

struct Rig::Dds {
  std::shared_ptr<Participant> participant;  // first: the others are deleted before it goes
  Participant::Scope scope;                  // with security, the rig's partition
  dds::Entity sensors_topic, estimate_topic, profile_topic, status_topic, step_topic;
  std::array<dds::Entity, 4> command_topics;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors;
  std::optional<dds::Reader<mpdrig_RigEstimate>> estimates;
  std::optional<dds::Reader<mpdrig_PressureProfile>> profiles;
  std::optional<dds::Reader<mpdrig_RigStatus>> status;
  std::optional<dds::Writer<mpdrig_StepRequest>> steps;  // made on the first Step
  std::array<dds::Entity, 4> command_writers;            // made on the first command of each kind
  dds::Entity waitset;                                   // every reader's data, for one wait
  // Deleting the participant deletes its children; the writers go first so that their instances
  // are unregistered while the readers still exist.
  ~Dds() {
    for (dds::Entity& writer : command_writers) writer.Reset();
  }
};

namespace {

template <typename T>
Status MakeReader(const Participant& participant, dds_entity_t subscriber, const dds::Entity& topic,
                  const dds::Qos& qos, const RigOptions& o, std::optional<dds::Reader<T>>* out) {
  auto reader = dds::Reader<T>::Create(subscriber, topic.handle(), qos);
  if (!reader.ok()) return participant.EndpointError(reader.status(), o.rig_id, "reading");
  out->emplace(std::move(reader).value());
  return Status::Ok();
}

Status MakeTopic(dds_entity_t participant, const dds::TopicSpec& spec, dds::Entity* out) {
  auto created = dds::CreateTopic(participant, spec);
  if (!created.ok()) return created.status();
  *out = std::move(created).value();
  return Status::Ok();
}

std::string Seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

}  // namespace

Rig::Rig(const RigOptions& options)
    : options_(options), dds_(std::make_unique<Dds>()), watch_(options.timeout_s) {}

Rig::~Rig() { Close(); }

void Rig::Close() {
  if (!dds_) return;
  // A one-shot command's rule (dds::SendOnce): what was written is acknowledged before the
  // writer goes, even by a script that exits right after. Not for a lost rig: its reader may
  // stay matched until its lease runs out, and nothing it acknowledges matters any more.
  const double limit_s = options_.timeout_s > 0.0 ? std::min(options_.timeout_s, 10.0) : 10.0;
  if (!lost_) (void)AwaitCommandAcks(limit_s);
  dds_.reset();
}

Status Rig::Fail(Failure kind, const std::string& message) {
  last_failure_ = kind;
  return Status::Error(message);
}

Status Rig::ClosedOrLost() {
  if (!dds_) {
    return Fail(Failure::kError, "the connection to rig " + options_.rig_id + " is closed");
  }
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  return Status::Ok();
}

Status Rig::MakeEndpoints() {
  Dds& d = *dds_;
  const dds_entity_t p = d.participant->handle();
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kSensors, &d.sensors_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kEstimate, &d.estimate_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kPressureProfile, &d.profile_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kStatus, &d.status_topic));
  MPDRIG_RETURN_IF_ERROR(MakeTopic(p, dds::topics::kStepRequest, &d.step_topic));
  for (int i = 0; i < 4; ++i) {
    MPDRIG_RETURN_IF_ERROR(MakeTopic(p, *kCommandTopics[i], &d.command_topics[i]));
  }
  // One waitset over every reader, so a wait wakes on whatever arrives first.
  d.waitset = dds::Entity(dds_create_waitset(p));
  if (d.waitset.handle() < 0) return dds::Check(d.waitset.handle(), "dds_create_waitset");
  MPDRIG_RETURN_IF_ERROR(MakeReader(*d.participant, d.scope.subscriber, d.status_topic,
                                    dds::StatusQos(), options_, &d.status));
  return Attach(d.status->handle());
}

Status Rig::Attach(dds_entity_t reader) {
  const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
  if (condition < 0) return dds::Check(condition, "dds_create_readcondition");
  return dds::Check(dds_waitset_attach(dds_->waitset.handle(), condition, 0), "dds_waitset_attach");
}

// The stream readers: keep all in lockstep (the client sets the pace and sees every step) or for
// a recorder, else the newest 8 (a slow reader must not hold back a real-time rig).
Status Rig::MakeStreamReaders(bool keep_all) {
  Dds& d = *dds_;
  const dds_entity_t sub = d.scope.subscriber;
  MPDRIG_RETURN_IF_ERROR(MakeReader(*d.participant, sub, d.sensors_topic, dds::SensorQos(keep_all),
                                    options_, &d.sensors));
  MPDRIG_RETURN_IF_ERROR(Attach(d.sensors->handle()));
  if (options_.read_estimates) {
    MPDRIG_RETURN_IF_ERROR(MakeReader(*d.participant, sub, d.estimate_topic,
                                      dds::SensorQos(keep_all), options_, &d.estimates));
    MPDRIG_RETURN_IF_ERROR(Attach(d.estimates->handle()));
  }
  if (options_.read_profiles) {
    MPDRIG_RETURN_IF_ERROR(MakeReader(*d.participant, sub, d.profile_topic, dds::SensorQos(false),
                                      options_, &d.profiles));
    MPDRIG_RETURN_IF_ERROR(Attach(d.profiles->handle()));
  }
  return Status::Ok();
}

namespace {

Status CheckRigOptions(const RigOptions& options) {
  if (options.rig_id.empty()) return Status::Error("the rig id is empty");
  // At most a day: the timeout becomes DDS nanoseconds (int64) in places.
  if (!(options.timeout_s >= 0.0 && options.timeout_s <= 86400.0)) {
    return Status::Error(
        "the timeout must be a number of seconds in [0, 86400] (0: wait for ever)");
  }
  return Status::Ok();
}

}  // namespace

Result<std::unique_ptr<Rig>> Rig::Connect(const RigOptions& options, const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(CheckRigOptions(options));
  auto participant = Participant::Join({.domain = options.domain,
                                        .dds_config = options.dds_config,
                                        .security_dir = options.security_dir});
  if (!participant.ok()) return participant.status();
  return Connect(*participant, options, interrupt);
}

Result<std::unique_ptr<Rig>> Rig::Connect(const std::shared_ptr<Participant>& participant,
                                          const RigOptions& given, const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(CheckRigOptions(given));
  if (!participant) return Status::Error("no participant");
  RigOptions options = given;  // the participant's domain and identity, whatever `given` says
  options.domain = participant->options().domain;
  options.dds_config = participant->options().dds_config;
  options.security_dir = participant->options().security_dir;
  std::unique_ptr<Rig> rig(new Rig(options));
  Dds& d = *rig->dds_;
  d.participant = participant;
  // With security the rig's topics are in its partition (make-class's permissions name it).
  auto scope = participant->ScopeOf(options.rig_id);
  if (!scope.ok()) return scope.status();
  d.scope = *scope;
  MPDRIG_RETURN_IF_ERROR(rig->MakeEndpoints());
  // A recorder's readers do not depend on the clock: made before the rig is found, they miss
  // none of its first samples.
  if (options.keep_every_sample) MPDRIG_RETURN_IF_ERROR(rig->MakeStreamReaders(true));
  // The rig's status (transient-local: a running service has one for each of its rigs) says it
  // exists and which clock it runs.
  rig->last_failure_ = Failure::kNone;
  const Status found = rig->WaitFor(
      [&] { return rig->rig_status_.has_value(); },
      "no rig '" + options.rig_id + "' on DDS domain " + std::to_string(options.domain) +
          " (is `mpdrig serve --rig " + options.rig_id + "` running there?)",
      interrupt);
  if (!found.ok()) return found;
  rig->lockstep_ = rig->rig_status_->clock == "lockstep";
  rig->rejections_seen_ = rig->rig_status_->rejected_commands;
  if (!options.keep_every_sample) MPDRIG_RETURN_IF_ERROR(rig->MakeStreamReaders(rig->lockstep_));
  // Request ids of this client start from the wall clock, so a status naming an earlier
  // client's request is not taken for ours.
  rig->request_id_ = static_cast<std::uint64_t>(dds_time());
  rig->last_sample_wall_s_ = WallSeconds();
  return rig;
}

Status Rig::TakeSensors() {
  Dds& d = *dds_;
  if (!d.sensors) return Status::Ok();
  const std::string& id = options_.rig_id;
  auto took = d.sensors->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t& info) {
    if (id != s.rig_id || lost_) return;
    std::string why;
    const auto verdict =
        watch_.Sample(s.sample_counter, s.sim_time_s, info.publication_handle, &why);
    if (verdict == clients::RigWatch::Verdict::kLost) lost_ = why;
    if (verdict != clients::RigWatch::Verdict::kAccept) return;
    last_sample_wall_s_ = WallSeconds();
    Sensors sample = FromWire(s, info);
    sample.received_s = last_sample_wall_s_;
    queue_.push_back(sample);
    if (queue_.size() > kQueueLimit) queue_.pop_front();
    newest_ = sample;
    newest_returned_ = false;
  });
  return took.ok() ? Status::Ok() : Fail(Failure::kError, took.status().message());
}

Status Rig::TakeEstimates() {
  Dds& d = *dds_;
  if (!d.estimates) return Status::Ok();
  const std::string& id = options_.rig_id;
  auto took = d.estimates->TakeEach([&](const mpdrig_RigEstimate& e, const dds_sample_info_t&) {
    if (id != e.rig_id) return;
    Estimate out = FromWire(e);
    estimates_.push_back(std::move(out));
    if (estimates_.size() > kEstimateLimit) estimates_.pop_front();
  });
  return took.ok() ? Status::Ok() : Fail(Failure::kError, took.status().message());
}

Status Rig::TakeProfiles() {
  Dds& d = *dds_;
  if (!d.profiles) return Status::Ok();
  const std::string& id = options_.rig_id;
  auto took = d.profiles->TakeEach([&](const mpdrig_PressureProfile& p, const dds_sample_info_t&) {
    if (id != p.rig_id) return;
    profile_ = FromWire(p);
  });
  return took.ok() ? Status::Ok() : Fail(Failure::kError, took.status().message());
}

Status Rig::TakeStatus() {
  const std::string& id = options_.rig_id;
  auto took = dds_->status->TakeEach(
      [&](const mpdrig_RigStatus& s, const dds_sample_info_t& info) {
        if (id != s.rig_id) return;
        // A disposal that finds the last status unread marks that sample instead of adding one.
        if (info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED) ended_ = true;
        rig_status_ = FromWire(s);
      },
      {}, std::numeric_limits<int>::max(),
      [&](const mpdrig_RigStatus& s) {
        // The service disposes a rig's status when its run ends as asked (RigService::EndRigs).
        if (id == s.rig_id) ended_ = true;
      });
  return took.ok() ? Status::Ok() : Fail(Failure::kError, took.status().message());
}

Status Rig::Drain() {
  MPDRIG_RETURN_IF_ERROR(TakeSensors());
  MPDRIG_RETURN_IF_ERROR(TakeEstimates());
  MPDRIG_RETURN_IF_ERROR(TakeProfiles());
  MPDRIG_RETURN_IF_ERROR(TakeStatus());
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  if (!dds_->sensors) return Status::Ok();
  // The rig's own sensor writer, not any: a stranger's writer on the topic keeps no rig alive.
  bool matched = false;
  if (watch_.writer() != 0) {
    dds_builtintopic_endpoint_t* writer =
        dds_get_matched_publication_data(dds_->sensors->handle(), watch_.writer());
    matched = writer != nullptr;
    if (writer != nullptr) dds_builtintopic_free_endpoint(writer);
  }
  std::optional<std::string> why = watch_.Check(WallSeconds() - last_sample_wall_s_, matched);
  if (!why) return Status::Ok();
  // What the departed writer sent before it went is in the reader by now: keep it.
  MPDRIG_RETURN_IF_ERROR(TakeSensors());
  MPDRIG_RETURN_IF_ERROR(TakeStatus());
  if (!lost_ && ended_) {
    lost_ = "the rig's service ended its run (it stopped as asked, not a crash)";
  }
  if (!lost_) lost_ = why;
  return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
}

Status Rig::WaitFor(const std::function<bool()>& done, const std::string& what,
                    const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(ClosedOrLost());
  const bool forever = options_.timeout_s == 0.0;
  const double deadline = WallSeconds() + options_.timeout_s;
  for (;;) {
    MPDRIG_RETURN_IF_ERROR(Drain());
    if (done()) return Status::Ok();
    const double left_s = forever ? 1.0 : deadline - WallSeconds();
    if (left_s <= 0.0) return Fail(Failure::kTimeout, what);
    if (interrupt && interrupt()) return Fail(Failure::kInterrupted, "interrupted");
    const dds_duration_t wait =
        std::min<dds_duration_t>(kPoll, static_cast<dds_duration_t>(left_s * 1e9) + 1);
    const dds_return_t woke = dds_waitset_wait(dds_->waitset.handle(), nullptr, 0, wait);
    if (woke < 0) return Fail(Failure::kError, dds::Check(woke, "dds_waitset_wait").message());
  }
}

Result<Sensors> Rig::Latest(bool fresh, const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] { return newest_.has_value() && !(fresh && newest_returned_); },
      "no new sample from rig " + options_.rig_id + " within " + Seconds(options_.timeout_s) +
          (lockstep_ ? " (a lockstep rig moves only when stepped: Step)" : ""),
      interrupt));
  queue_.clear();
  newest_returned_ = true;
  return *newest_;
}

Result<Sensors> Rig::Next(const Interrupt& interrupt) {
  if (queue_.empty()) {
    const Status waited =
        WaitFor([&] { return !queue_.empty(); },
                "no sample from rig " + options_.rig_id + " within " + Seconds(options_.timeout_s) +
                    (lockstep_ ? " (a lockstep rig moves only when stepped)" : ""),
                interrupt);
    // A lost rig's samples from before the loss still come out, then the loss.
    if (!waited.ok() && queue_.empty()) return waited;
  }
  Sensors s = queue_.front();
  queue_.pop_front();
  if (queue_.empty()) newest_returned_ = true;
  return s;
}

Result<std::vector<Sensors>> Rig::TakeArrived() {
  if (!dds_) return ClosedOrLost();
  if (!lost_) {
    const Status drained = Drain();
    if (!drained.ok() && last_failure_ != Failure::kLost) return drained;
  }
  if (queue_.empty() && lost_) return ClosedOrLost();
  std::vector<Sensors> out(queue_.begin(), queue_.end());
  queue_.clear();
  return out;
}

std::optional<Estimate> Rig::NewestEstimate() const {
  if (estimates_.empty()) return std::nullopt;
  return estimates_.back();
}

Result<Estimate> Rig::EstimateFor(std::optional<std::uint64_t> counter,
                                  const Interrupt& interrupt) {
  if (!options_.read_estimates) {
    return Fail(Failure::kError, "this client does not read estimates (RigOptions)");
  }
  const Estimate* found = nullptr;
  auto find = [&] {
    found = nullptr;
    for (auto it = estimates_.rbegin(); it != estimates_.rend(); ++it) {
      if (!counter || it->sample_counter == *counter) {
        found = &*it;
        return true;
      }
    }
    return false;
  };
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      find,
      counter
          ? "no estimate for sample " + std::to_string(*counter) + " of rig " + options_.rig_id +
                " (does the service run its observer? --no-observer, "
                "--estimate-hz)"
          : "no estimate from rig " + options_.rig_id + " (is its observer off?)",
      interrupt));
  return *found;
}

Result<Profile> Rig::LatestProfile(const Interrupt& interrupt) {
  if (!options_.read_profiles) {
    return Fail(Failure::kError, "this client does not read profiles (RigOptions)");
  }
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] { return profile_.has_value(); },
      "no pressure profile from rig " + options_.rig_id + " (serve --profile-hz 0 turns it off)",
      interrupt));
  return *profile_;
}

Result<RigStatus> Rig::LatestStatus(const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(WaitFor([&] { return rig_status_.has_value(); },
                                 "no status from rig " + options_.rig_id, interrupt));
  return *rig_status_;
}

Result<std::pair<std::uint64_t, std::string>> Rig::NewRejections(const Interrupt& interrupt) {
  auto status = LatestStatus(interrupt);
  if (!status.ok()) return status.status();
  const std::uint64_t now = status->rejected_commands;
  const std::uint64_t grown = now > rejections_seen_ ? now - rejections_seen_ : 0;
  rejections_seen_ = now;
  return std::make_pair(grown, grown > 0 ? status->last_rejection : std::string());
}

// Waits until `writer` has matched a reader: a sample written before may reach no one.
Status Rig::AwaitMatch(std::int32_t writer, const char* topic_name, const Interrupt& interrupt) {
  // A failing status read is a DDS error to report now, not a reader that never comes.
  dds_return_t read = DDS_RETCODE_OK;
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] {
        dds_publication_matched_status_t m{};
        read = dds_get_publication_matched_status(writer, &m);
        return read < 0 || m.current_count > 0;
      },
      std::string("no reader of ") + topic_name + " for rig " + options_.rig_id +
          " (is the service running?)",
      interrupt));
  if (read < 0) {
    return Fail(Failure::kError, dds::Check(read, "dds_get_publication_matched_status").message());
  }
  return Status::Ok();
}

template <typename T>
Status Rig::SendCommand(int topic_index, const T& sample, const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(ClosedOrLost());
  Dds& d = *dds_;
  dds::Entity& writer = d.command_writers[topic_index];
  if (writer.handle() <= 0) {
    dds::Entity created(dds_create_writer(d.scope.publisher, d.command_topics[topic_index].handle(),
                                          dds::CommandQos(options_.strength).get(), nullptr));
    if (created.handle() < 0) {
      return Fail(Failure::kError,
                  d.participant
                      ->EndpointError(dds::Check(created.handle(), "dds_create_writer"),
                                      options_.rig_id, "commanding")
                      .message());
    }
    writer = std::move(created);
    const Status matched =
        AwaitMatch(writer.handle(), kCommandTopics[topic_index]->name, interrupt);
    if (!matched.ok()) {
      writer.Reset();
      return matched;
    }
  }
  const dds_return_t written = dds_write(writer.handle(), &sample);
  if (written < 0) return Fail(Failure::kError, dds::Check(written, "dds_write").message());
  unacknowledged_[topic_index] = true;
  return Status::Ok();
}

Result<std::optional<std::string>> Rig::ChokeCommandedByOther() {
  MPDRIG_RETURN_IF_ERROR(ClosedOrLost());
  MPDRIG_RETURN_IF_ERROR(Drain());
  const dds_entity_t writer = dds_->command_writers[kChoke].handle();
  if (writer <= 0 || !rig_status_) return std::optional<std::string>();
  std::string owner;  // the status's "choke: <owner>"
  for (const std::string& entry : rig_status_->actuator_owners) {
    if (entry.rfind("choke: ", 0) == 0) owner = entry.substr(7);
  }
  if (owner.empty()) return std::optional<std::string>();
  // The service names a writer by its GUID in hex (rig_service.cc, DescribeWriter).
  dds_guid_t guid{};
  if (dds_get_guid(writer, &guid) < 0) return std::optional<std::string>();
  char hex[2 * sizeof guid.v + 1];
  for (std::size_t i = 0; i < sizeof guid.v; ++i) std::snprintf(hex + 2 * i, 3, "%02x", guid.v[i]);
  if (owner.find(std::string("writer ") + hex) != std::string::npos) {
    return std::optional<std::string>();
  }
  return std::optional<std::string>(owner);
}

Status Rig::Choke(double opening_deg, const Interrupt& interrupt) {
  mpdrig_ChokeCommand c{options_.rig_id.data(), opening_deg};
  return SendCommand(kChoke, c, interrupt);
}

Status Rig::Pump(double flow_lpm, const Interrupt& interrupt) {
  mpdrig_PumpCommand c{options_.rig_id.data(), flow_lpm};
  return SendCommand(kPump, c, interrupt);
}

Status Rig::Outlet(double pressure_barg, const Interrupt& interrupt) {
  mpdrig_OutletCommand c{options_.rig_id.data(), pressure_barg};
  return SendCommand(kOutlet, c, interrupt);
}

Status Rig::Piston(const PistonCommand& command, const Interrupt& interrupt) {
  mpdrig_PistonCommand c{};
  c.rig_id = options_.rig_id.data();
  switch (command.mode) {
    case PistonCommand::Mode::kHold:
      c.mode = mpdrig_PISTON_HOLD;
      break;
    case PistonCommand::Mode::kPosition:
      c.mode = mpdrig_PISTON_POSITION;
      break;
    case PistonCommand::Mode::kSine:
      c.mode = mpdrig_PISTON_SINE;
      break;
    case PistonCommand::Mode::kSweep:
      c.mode = mpdrig_PISTON_SWEEP;
      break;
  }
  c.position_m = command.position_m;
  c.mean_m = command.mean_m;
  c.amplitude_m = command.amplitude_m;
  c.frequency_hz = command.frequency_hz;
  c.sweep_end_hz = command.sweep_end_hz;
  c.sweep_duration_s = command.sweep_duration_s;
  return SendCommand(kPiston, c, interrupt);
}

// The service takes the commands when it starts a request: each must be acknowledged (in the
// service's reader) before the request is sent.
Status Rig::AwaitCommandAcks(double timeout_s) {
  for (int i = 0; i < 4; ++i) {
    if (!unacknowledged_[i] || dds_->command_writers[i].handle() <= 0) continue;
    const dds_duration_t timeout =
        timeout_s > 0.0 ? static_cast<dds_duration_t>(timeout_s * 1e9) : DDS_INFINITY;
    const dds_return_t acked = dds_wait_for_acks(dds_->command_writers[i].handle(), timeout);
    if (acked == DDS_RETCODE_TIMEOUT) {
      return Fail(Failure::kTimeout, std::string("no acknowledgement of the ") +
                                         kCommandTopics[i]->name + " within " + Seconds(timeout_s));
    }
    if (acked < 0) return Fail(Failure::kError, dds::Check(acked, "dds_wait_for_acks").message());
    unacknowledged_[i] = false;
  }
  return Status::Ok();
}

Result<Sensors> Rig::Step(std::uint32_t steps, const Interrupt& interrupt) {
  if (!lockstep_) {
    return Fail(Failure::kError, "rig " + options_.rig_id + " runs a " +
                                     (rig_status_ ? rig_status_->clock : std::string("real-time")) +
                                     " clock: only a lockstep rig (`mpdrig serve --clock "
                                     "lockstep`) is stepped");
  }
  if (steps == 0) return Fail(Failure::kError, "steps must be at least 1");
  MPDRIG_RETURN_IF_ERROR(ClosedOrLost());
  MPDRIG_RETURN_IF_ERROR(AwaitCommandAcks(options_.timeout_s));
  MPDRIG_RETURN_IF_ERROR(MakeStepWriter(interrupt));
  const std::uint64_t id = ++request_id_;
  mpdrig_StepRequest request{options_.rig_id.data(), id, steps};
  const Status written = dds_->steps->Write(request);
  if (!written.ok()) return Fail(Failure::kError, written.message());
  // Done when the status names the request; its sim_time_s is the last step's sample time, and
  // the sensors of the steps were published before it (another writer: wait for them too).
  // Or the service refused it (more than an hour of rig time): its status names the request.
  double done_time_s = 0.0;
  const std::string refusal =
      std::to_string(id) + " of " + std::to_string(steps) + " steps refused";
  bool refused = false;
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] {
        if (!rig_status_) return false;
        refused = rig_status_->last_rejection.find(refusal) != std::string::npos;
        if (refused) return true;
        if (rig_status_->last_completed_step_request != id) return false;
        done_time_s = rig_status_->sim_time_s;
        return true;
      },
      "step request of " + std::to_string(steps) + " steps not completed by rig " +
          options_.rig_id + " within " + Seconds(options_.timeout_s),
      interrupt));
  if (refused) return Fail(Failure::kError, rig_status_->last_rejection);
  MPDRIG_RETURN_IF_ERROR(
      WaitFor([&] { return newest_.has_value() && newest_->time_s >= done_time_s - 1e-9; },
              "the samples of a completed step did not arrive", interrupt));
  newest_returned_ = true;
  return *newest_;
}

// The step writer, made on the first Step: a client that only watches a rig needs none (and
// with security may not have one in another student's partition). docs/service.md's QoS table:
// reliable, volatile, keep all. The first request must reach the service's reader: it waits for the
// match.
Status Rig::MakeStepWriter(const Interrupt& interrupt) {
  Dds& d = *dds_;
  if (d.steps) return Status::Ok();
  auto steps = dds::Writer<mpdrig_StepRequest>::Create(d.scope.publisher, d.step_topic.handle(),
                                                       dds::RequestQos());
  if (!steps.ok()) {
    return Fail(
        Failure::kError,
        d.participant->EndpointError(steps.status(), options_.rig_id, "stepping").message());
  }
  d.steps.emplace(std::move(steps).value());
  const Status matched = AwaitMatch(d.steps->handle(), dds::topics::kStepRequest.name, interrupt);
  if (!matched.ok()) d.steps.reset();
  return matched;
}

}  // namespace mpdrig::client
