#include "clients/client/rig_client.h"

#include <chrono>
#include <cmath>
#include <map>
#include <mutex>

#include "mpdrig.h"
#include "service/dds/dds.h"

namespace mpdrig::client {
namespace {

// Cyclone allows one domain object per id in a process; Rigs on the same id share it, and the
// first one's configuration holds for all of them.
std::shared_ptr<dds::Domain> SharedDomain(int id, const std::string& config, Status* error) {
  static std::mutex mutex;
  static std::map<int, std::weak_ptr<dds::Domain>> domains;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto existing = domains[id].lock()) return existing;
  auto created = dds::Domain::Create(id, config);
  if (!created.ok()) {
    *error = created.status();
    return nullptr;
  }
  auto shared = std::make_shared<dds::Domain>(std::move(created).value());
  domains[id] = shared;
  return shared;
}

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

constexpr std::size_t kQueueLimit = 10000;
constexpr std::size_t kEstimateLimit = 512;
constexpr dds_duration_t kPoll = DDS_MSECS(100);

enum CommandTopic { kChoke = 0, kPump = 1, kOutlet = 2, kPiston = 3 };
constexpr const char* kCommandTopicNames[] = {"mpdrig_choke_command", "mpdrig_pump_command",
                                              "mpdrig_outlet_command", "mpdrig_piston_command"};

Sensors FromWire(const mpdrig_RigSensors& s) {
  Sensors out;
  out.sample_counter = s.sample_counter;
  out.time_s = s.sim_time_s;
  out.piston_position_m = s.piston_position_m;
  out.choke_position_deg = s.choke_position_deg;
  out.P1_barg = s.P1_barg;
  out.P2_barg = s.P2_barg;
  for (int i = 0; i < 10; ++i) out.PT_barg[i] = s.PT_barg[i];
  out.C1_barg = s.C1_barg;
  out.C2_barg = s.C2_barg;
  out.FT1_lpm = s.FT1_lpm;
  out.FT2_lpm = s.FT2_lpm;
  out.FT3_lpm = s.FT3_lpm;
  out.FT4_lpm = s.FT4_lpm;
  return out;
}

std::vector<double> FromSequence(const dds_sequence_double& seq) {
  return std::vector<double>(seq._buffer, seq._buffer + seq._length);
}

std::vector<std::string> FromSequence(const dds_sequence_string& seq) {
  std::vector<std::string> out;
  for (std::uint32_t i = 0; i < seq._length; ++i) out.emplace_back(seq._buffer[i]);
  return out;
}

}  // namespace

struct Rig::Dds {
  std::shared_ptr<dds::Domain> domain;
  dds::Entity participant;
  dds::Entity sensors_topic, estimate_topic, profile_topic, status_topic, step_topic;
  std::array<dds::Entity, 4> command_topics;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors;
  std::optional<dds::Reader<mpdrig_RigEstimate>> estimates;
  std::optional<dds::Reader<mpdrig_PressureProfile>> profiles;
  std::optional<dds::Reader<mpdrig_RigStatus>> status;
  std::optional<dds::Writer<mpdrig_StepRequest>> steps;
  std::array<dds::Entity, 4> command_writers;  // made on the first command of each kind
  dds::Entity waitset;                         // every reader's data, for one wait
  std::uint64_t status_received = 0;           // statuses taken so far
  // Deleting the participant deletes its children; the writers go first so that their instances
  // are unregistered while the readers still exist.
  ~Dds() {
    for (dds::Entity& writer : command_writers) writer.Reset();
  }
};

Rig::Rig(const RigOptions& options)
    : options_(options), dds_(std::make_unique<Dds>()), watch_(options.timeout_s) {}

Rig::~Rig() = default;

void Rig::Close() { dds_.reset(); }

Status Rig::Fail(Failure kind, const std::string& message) {
  last_failure_ = kind;
  return Status::Error(message);
}

Result<std::unique_ptr<Rig>> Rig::Connect(const RigOptions& options, const Interrupt& interrupt) {
  if (options.rig_id.empty()) return Status::Error("the rig id is empty");
  if (options.domain < 0 || options.domain > 232) {
    return Status::Error("DDS domain " + std::to_string(options.domain) + " is not in 0..232");
  }
  // At most a day: the timeout becomes DDS nanoseconds (int64) in places.
  if (!(options.timeout_s > 0.0 && options.timeout_s <= 86400.0)) {
    return Status::Error("the timeout must be a number of seconds in (0, 86400]");
  }
  std::unique_ptr<Rig> rig(new Rig(options));
  Dds& d = *rig->dds_;
  std::string config = options.dds_config.empty() ? dds::LoopbackConfig() : options.dds_config;
  if (config.find("CycloneDDS") == std::string::npos) config += dds::FastAckConfig();
  Status error = Status::Ok();
  d.domain = SharedDomain(options.domain, config, &error);
  if (!d.domain) return error;
  auto participant = dds::CreateParticipant(options.domain);
  if (!participant.ok()) return participant.status();
  d.participant = std::move(participant).value();
  const dds_entity_t p = d.participant.handle();
  auto topic = [p](dds::Entity* out, const dds_topic_descriptor_t* desc, const char* name) {
    auto created = dds::CreateTopic(p, desc, name);
    if (!created.ok()) return created.status();
    *out = std::move(created).value();
    return Status::Ok();
  };
  MPDRIG_RETURN_IF_ERROR(topic(&d.sensors_topic, &mpdrig_RigSensors_desc, "mpdrig_sensors"));
  MPDRIG_RETURN_IF_ERROR(topic(&d.estimate_topic, &mpdrig_RigEstimate_desc, "mpdrig_estimate"));
  MPDRIG_RETURN_IF_ERROR(
      topic(&d.profile_topic, &mpdrig_PressureProfile_desc, "mpdrig_pressure_profile"));
  MPDRIG_RETURN_IF_ERROR(topic(&d.status_topic, &mpdrig_RigStatus_desc, "mpdrig_status"));
  MPDRIG_RETURN_IF_ERROR(topic(&d.step_topic, &mpdrig_StepRequest_desc, "mpdrig_step_request"));
  MPDRIG_RETURN_IF_ERROR(
      topic(&d.command_topics[kChoke], &mpdrig_ChokeCommand_desc, kCommandTopicNames[kChoke]));
  MPDRIG_RETURN_IF_ERROR(
      topic(&d.command_topics[kPump], &mpdrig_PumpCommand_desc, kCommandTopicNames[kPump]));
  MPDRIG_RETURN_IF_ERROR(
      topic(&d.command_topics[kOutlet], &mpdrig_OutletCommand_desc, kCommandTopicNames[kOutlet]));
  MPDRIG_RETURN_IF_ERROR(
      topic(&d.command_topics[kPiston], &mpdrig_PistonCommand_desc, kCommandTopicNames[kPiston]));

  // One waitset over every reader, so a wait wakes on whatever arrives first.
  d.waitset = dds::Entity(dds_create_waitset(p));
  if (d.waitset.handle() < 0) return dds::Check(d.waitset.handle(), "dds_create_waitset");
  auto attach = [&d](dds_entity_t reader) {
    const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
    if (condition < 0) return dds::Check(condition, "dds_create_readcondition");
    return dds::Check(dds_waitset_attach(d.waitset.handle(), condition, 0), "dds_waitset_attach");
  };
  auto status = dds::Reader<mpdrig_RigStatus>::Create(p, d.status_topic.handle(), dds::StatusQos());
  if (!status.ok()) return status.status();
  d.status.emplace(std::move(status).value());
  MPDRIG_RETURN_IF_ERROR(attach(d.status->handle()));
  // The rig's status says it exists and which clock it runs: the sensor readers' history depends
  // on that (keep all in lockstep, where the client sets the pace and must see every step).
  rig->last_failure_ = Failure::kNone;
  const Status found = rig->WaitFor(
      [&] { return rig->rig_status_.has_value(); },
      "no rig '" + options.rig_id + "' on DDS domain " + std::to_string(options.domain) +
          " (is `mpdrig serve --rig " + options.rig_id + "` running there?)",
      interrupt);
  if (!found.ok()) return found;
  rig->lockstep_ = rig->rig_status_->clock == "lockstep";
  rig->rejections_seen_ = rig->rig_status_->rejected_commands;

  auto sensors = dds::Reader<mpdrig_RigSensors>::Create(p, d.sensors_topic.handle(),
                                                        dds::SensorQos(rig->lockstep_));
  if (!sensors.ok()) return sensors.status();
  d.sensors.emplace(std::move(sensors).value());
  auto estimates = dds::Reader<mpdrig_RigEstimate>::Create(p, d.estimate_topic.handle(),
                                                           dds::SensorQos(rig->lockstep_));
  if (!estimates.ok()) return estimates.status();
  d.estimates.emplace(std::move(estimates).value());
  auto profiles = dds::Reader<mpdrig_PressureProfile>::Create(p, d.profile_topic.handle(),
                                                              dds::SensorQos(false));
  if (!profiles.ok()) return profiles.status();
  d.profiles.emplace(std::move(profiles).value());
  dds::Qos step_qos;  // README's QoS table: reliable, volatile, keep all
  dds_qset_reliability(step_qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(step_qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  auto steps = dds::Writer<mpdrig_StepRequest>::Create(p, d.step_topic.handle(), step_qos);
  if (!steps.ok()) return steps.status();
  d.steps.emplace(std::move(steps).value());

  for (dds_entity_t reader : {d.sensors->handle(), d.estimates->handle(), d.profiles->handle()}) {
    MPDRIG_RETURN_IF_ERROR(attach(reader));
  }
  // Request ids of this client start from the wall clock, so a status naming an earlier
  // client's request is not taken for ours.
  rig->request_id_ = static_cast<std::uint64_t>(dds_time());
  rig->last_sample_wall_s_ = WallSeconds();
  return rig;
}

Status Rig::Drain() {
  Dds& d = *dds_;
  const std::string& id = options_.rig_id;
  if (d.sensors) {
    auto took = d.sensors->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
      if (id != s.rig_id || lost_) return;
      lost_ = watch_.Sample(s.sample_counter, s.sim_time_s);
      if (lost_) return;
      last_sample_wall_s_ = WallSeconds();
      Sensors sample = FromWire(s);
      queue_.push_back(sample);
      if (queue_.size() > kQueueLimit) queue_.pop_front();
      newest_ = sample;
      newest_returned_ = false;
    });
    if (!took.ok()) return Fail(Failure::kError, took.status().message());
  }
  if (d.estimates) {
    auto took = d.estimates->TakeEach([&](const mpdrig_RigEstimate& e, const dds_sample_info_t&) {
      if (id != e.rig_id) return;
      Estimate out;
      out.sample_counter = e.sample_counter;
      out.time_s = e.sim_time_s;
      out.observer_time_s = e.observer_time_s;
      out.BHP_est_barg = e.BHP_est_barg;
      out.piston_velocity_est_mps = e.piston_velocity_est_mps;
      out.piston_position_est_m = e.piston_position_est_m;
      out.FT4_est_lpm = e.FT4_est_lpm;
      out.disturbance_frequency_hz = e.disturbance_frequency_hz;
      out.frequency_source = e.frequency_source == mpdrig_FREQUENCY_PISTON_SINE ? "piston_sine"
                             : e.frequency_source == mpdrig_FREQUENCY_TRACKED   ? "tracked"
                                                                                : "unlocked";
      estimates_.push_back(std::move(out));
      if (estimates_.size() > kEstimateLimit) estimates_.pop_front();
    });
    if (!took.ok()) return Fail(Failure::kError, took.status().message());
  }
  if (d.profiles) {
    auto took =
        d.profiles->TakeEach([&](const mpdrig_PressureProfile& p, const dds_sample_info_t&) {
          if (id != p.rig_id) return;
          Profile out;
          out.sample_counter = p.sample_counter;
          out.time_s = p.sim_time_s;
          out.position_m = FromSequence(p.position_m);
          out.pressure_barg = FromSequence(p.pressure_barg);
          out.pressure_est_barg = FromSequence(p.pressure_est_barg);
          profile_ = std::move(out);
        });
    if (!took.ok()) return Fail(Failure::kError, took.status().message());
  }
  auto took = d.status->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
    if (id != s.rig_id) return;
    RigStatus out;
    out.clock = s.clock == mpdrig_CLOCK_REALTIME ? "realtime"
                : s.clock == mpdrig_CLOCK_FAST   ? "fast"
                                                 : "lockstep";
    out.sim_time_s = s.sim_time_s;
    out.real_time_factor = s.real_time_factor;
    out.deadline_misses = s.deadline_misses;
    out.rejected_commands = s.rejected_commands;
    out.last_rejection = s.last_rejection;
    out.last_completed_step_request = s.last_completed_step_request;
    out.warnings = FromSequence(s.warnings);
    out.active_effects = FromSequence(s.active_effects);
    out.actuator_owners = FromSequence(s.actuator_owners);
    out.sensor_noise = s.sensor_noise;
    rig_status_ = std::move(out);
    ++d.status_received;
  });
  if (!took.ok()) return Fail(Failure::kError, took.status().message());
  if (lost_) return Fail(Failure::kLost, "rig " + id + " lost: " + *lost_);
  if (d.sensors) {
    dds_subscription_matched_status_t matched{};
    dds_get_subscription_matched_status(d.sensors->handle(), &matched);
    lost_ = watch_.Check(WallSeconds() - last_sample_wall_s_, matched.current_count > 0);
    if (lost_) return Fail(Failure::kLost, "rig " + id + " lost: " + *lost_);
  }
  return Status::Ok();
}

Status Rig::WaitFor(const std::function<bool()>& done, const std::string& what,
                    const Interrupt& interrupt) {
  if (!dds_)
    return Fail(Failure::kError, "the connection to rig " + options_.rig_id + " is closed");
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  const double deadline = WallSeconds() + options_.timeout_s;
  for (;;) {
    MPDRIG_RETURN_IF_ERROR(Drain());
    if (done()) return Status::Ok();
    const double left_s = deadline - WallSeconds();
    if (left_s <= 0.0) return Fail(Failure::kTimeout, what);
    if (interrupt && interrupt()) return Fail(Failure::kInterrupted, "interrupted");
    const dds_duration_t wait =
        std::min<dds_duration_t>(kPoll, static_cast<dds_duration_t>(left_s * 1e9) + 1);
    const dds_return_t woke = dds_waitset_wait(dds_->waitset.handle(), nullptr, 0, wait);
    if (woke < 0) return Fail(Failure::kError, dds::Check(woke, "dds_waitset_wait").message());
  }
}

Result<Sensors> Rig::Latest(bool fresh, const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(
      WaitFor([&] { return newest_.has_value() && !(fresh && newest_returned_); },
              "no new sample from rig " + options_.rig_id + " within " +
                  std::to_string(options_.timeout_s) + " s" +
                  (lockstep_ ? " (a lockstep rig moves only when stepped: Step)" : ""),
              interrupt));
  queue_.clear();
  newest_returned_ = true;
  return *newest_;
}

Result<Sensors> Rig::Next(const Interrupt& interrupt) {
  MPDRIG_RETURN_IF_ERROR(WaitFor([&] { return !queue_.empty(); },
                                 "no sample from rig " + options_.rig_id + " within " +
                                     std::to_string(options_.timeout_s) + " s" +
                                     (lockstep_ ? " (a lockstep rig moves only when stepped)" : ""),
                                 interrupt));
  Sensors s = queue_.front();
  queue_.pop_front();
  if (queue_.empty()) newest_returned_ = true;
  return s;
}

Result<std::vector<Sensors>> Rig::TakeArrived() {
  if (!dds_)
    return Fail(Failure::kError, "the connection to rig " + options_.rig_id + " is closed");
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  MPDRIG_RETURN_IF_ERROR(Drain());
  std::vector<Sensors> out(queue_.begin(), queue_.end());
  queue_.clear();
  return out;
}

Result<Estimate> Rig::EstimateFor(std::optional<std::uint64_t> counter,
                                  const Interrupt& interrupt) {
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

template <typename T>
Status Rig::SendCommand(int topic_index, const T& sample, const Interrupt& interrupt) {
  if (!dds_)
    return Fail(Failure::kError, "the connection to rig " + options_.rig_id + " is closed");
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  Dds& d = *dds_;
  dds::Entity& writer = d.command_writers[topic_index];
  const char* topic_name = kCommandTopicNames[topic_index];
  if (writer.handle() <= 0) {
    dds::Entity created(dds_create_writer(d.participant.handle(),
                                          d.command_topics[topic_index].handle(),
                                          dds::CommandQos(options_.strength).get(), nullptr));
    if (created.handle() < 0) {
      return Fail(Failure::kError, dds::Check(created.handle(), "dds_create_writer").message());
    }
    writer = std::move(created);
    // A sample written before the service's reader matched may reach no one.
    const Status matched = WaitFor(
        [&] {
          dds_publication_matched_status_t m{};
          dds_get_publication_matched_status(writer.handle(), &m);
          return m.current_count > 0;
        },
        std::string("no reader of ") + topic_name + " (is the service running?)", interrupt);
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

Result<Sensors> Rig::Step(std::uint32_t steps, const Interrupt& interrupt) {
  if (!lockstep_) {
    return Fail(Failure::kError, "rig " + options_.rig_id + " runs a " +
                                     (rig_status_ ? rig_status_->clock : std::string("real-time")) +
                                     " clock: only a lockstep rig (`mpdrig serve --clock "
                                     "lockstep`) is stepped");
  }
  if (steps == 0) return Fail(Failure::kError, "steps must be at least 1");
  if (!dds_)
    return Fail(Failure::kError, "the connection to rig " + options_.rig_id + " is closed");
  if (lost_) return Fail(Failure::kLost, "rig " + options_.rig_id + " lost: " + *lost_);
  Dds& d = *dds_;
  // The service takes the commands when it starts a request: each must be acknowledged (in the
  // service's reader) before the request is sent.
  for (int i = 0; i < 4; ++i) {
    if (!unacknowledged_[i]) continue;
    const dds_return_t acked = dds_wait_for_acks(
        d.command_writers[i].handle(), static_cast<dds_duration_t>(options_.timeout_s * 1e9));
    if (acked == DDS_RETCODE_TIMEOUT) {
      return Fail(Failure::kTimeout, std::string("no acknowledgement of the ") +
                                         kCommandTopicNames[i] + " within the timeout");
    }
    if (acked < 0) return Fail(Failure::kError, dds::Check(acked, "dds_wait_for_acks").message());
    unacknowledged_[i] = false;
  }
  // The first request must reach the service's reader: wait for it to match.
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] {
        dds_publication_matched_status_t m{};
        dds_get_publication_matched_status(d.steps->handle(), &m);
        return m.current_count > 0;
      },
      "no reader of mpdrig_step_request (is the service running?)", interrupt));
  const std::uint64_t id = ++request_id_;
  mpdrig_StepRequest request{options_.rig_id.data(), id, steps};
  const Status written = d.steps->Write(request);
  if (!written.ok()) return Fail(Failure::kError, written.message());
  // Done when the status names the request; its sim_time_s is the last step's sample time, and
  // the sensors of the steps were published before it (another writer: wait for them too).
  double done_time_s = 0.0;
  MPDRIG_RETURN_IF_ERROR(WaitFor(
      [&] {
        if (!rig_status_ || rig_status_->last_completed_step_request != id) return false;
        done_time_s = rig_status_->sim_time_s;
        return true;
      },
      "step request of " + std::to_string(steps) + " steps not completed by rig " +
          options_.rig_id + " within " + std::to_string(options_.timeout_s) + " s",
      interrupt));
  MPDRIG_RETURN_IF_ERROR(
      WaitFor([&] { return newest_.has_value() && newest_->time_s >= done_time_s - 1e-9; },
              "the samples of a completed step did not arrive", interrupt));
  newest_returned_ = true;
  return *newest_;
}

}  // namespace mpdrig::client
