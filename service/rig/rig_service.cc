#include "service/rig/rig_service.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <sstream>
#include <thread>
#include <utility>

#include "service/rig/command_intake.h"
#include "service/rig/lockstep_queue.h"
#include "service/rig/log_playback.h"
#include "service/rig/pacer.h"
#include "service/rig/private_rigs.h"
#include "service/rig/rig_status.h"
#include "service/rig/wire.h"

namespace mpdrig::service {

using Clock = std::chrono::steady_clock;

// Lockstep: while a long request runs, its rig's status goes out this often [s of wall time], so
// that clients and dashboards see the rig time move (and any refusal) before the request completes.
constexpr double kLockstepStatusEveryS = 0.5;

struct RigService::Impl {
  ServeOptions options;
  std::vector<RigHost> rigs;
  std::vector<std::uint64_t> last_step_request;
  std::vector<std::optional<RigObserver>> observers;  // per rig; created on its first sample
  std::vector<bool> observer_failed;                  // per rig: stopped, the status says why
  std::uint64_t estimate_every = 1;                   // publish every this many samples
  std::uint64_t profile_every = 0;                    // 0: no profile topic
  ProfileBuffers profile_buffers;
  // Real time only: the wall clock's ticks and their stalls (pacer.h).
  std::optional<RealTimePacer> pacer;
  RealTimePacer::Stalls stalls() const { return pacer ? pacer->stalls() : RealTimePacer::Stalls{}; }
  Clock::time_point started;

  // Commands in (command_intake.h), with the topic filters of the command and step topics:
  // declared before the DDS entities, so it outlives the readers whose filters point at it.
  std::optional<CommandIntake> intake;
  std::optional<PrivateRigs> private_rigs;

  // Declared parent-first, so children are deleted before their participant and domain.
  std::optional<dds::Domain> domain;
  dds::Entity participant;
  dds::Entity sensors_topic, choke_topic, piston_topic, pump_topic, outlet_topic, step_topic,
      status_topic, estimate_topic, profile_topic;
  dds::Entity request_topic;  // private rigs (security)
  // The service's writers and readers: one set for every rig in the default partition, or, with
  // security, one set per rig in the rig's partition (permissions name partitions, not keys).
  struct Endpoints {
    int rig = -1;  // the rig whose partition this is; -1: every rig (the default partition)
    dds::Entity publisher, subscriber;  // with security: in the rig's partition
    std::optional<dds::Writer<mpdrig_RigSensors>> sensors;
    std::optional<dds::Writer<mpdrig_RigEstimate>> estimate;
    std::optional<dds::Writer<mpdrig_PressureProfile>> profile;
    std::optional<dds::Writer<mpdrig_RigStatus>> status;
    CommandReaders commands;  // choke, piston, pump, outlet
    std::optional<dds::Reader<mpdrig_StepRequest>> steps;
    std::optional<dds::Reader<mpdrig_RigRequest>> requests;  // private rigs (security)
    // Since when a reader of these sensors has left something unacknowledged (ProbeReaders);
    // unset while every reader has acknowledged everything.
    std::optional<Clock::time_point> unacknowledged_since;
    bool stopped_reader_published = false;        // the last status of these rigs named one
    Clock::time_point last_write = Clock::now();  // of a sensor sample (ProbeReaders)
  };
  std::vector<std::unique_ptr<Endpoints>> endpoints;
  dds::Entity step_waitset;  // every set's step requests (lockstep)

  Status CreateEndpoints(dds_entity_t pub, dds_entity_t sub, bool lockstep, Endpoints* set);

  // Lockstep: a reader that stops acknowledging (its client SIGSTOPped, held in a debugger, or
  // killed and its participant's lease not yet over) is not waited for (dds::SensorWriterQos)
  // but reported. A probe asks whether every reader has acknowledged every sample written so
  // far; it is asked only while the rig has written nothing for kProbeAfterIdleS, since a live
  // reader acknowledges within a heartbeat period (100 ms) but never the sample just written.
  // A reader that has not, over kStoppedReaderAfterS of such probes, is stopped; the status says
  // so until it acknowledges again or is gone. (Real time and fast keep the last 8 samples and
  // are not probed: a live reader always has the newest unacknowledged there.)
  static constexpr double kStoppedReaderAfterS = 2.0;
  static constexpr double kProbeAfterIdleS = 0.3;
  void ProbeReaders(Endpoints& set) {
    if (options.clock != ClockMode::kLockstep) return;
    if (std::chrono::duration<double>(Clock::now() - set.last_write).count() < kProbeAfterIdleS)
      return;
    const dds_return_t acked = dds_wait_for_acks(set.sensors->handle(), 0);
    if (acked == DDS_RETCODE_OK) {
      set.unacknowledged_since.reset();
    } else if (!set.unacknowledged_since) {
      set.unacknowledged_since = Clock::now();
    }
  }
  static double StoppedReaderSeconds(const Endpoints& set) {
    if (!set.unacknowledged_since) return 0.0;
    const double s =
        std::chrono::duration<double>(Clock::now() - *set.unacknowledged_since).count();
    return s >= kStoppedReaderAfterS ? s : 0.0;
  }
  static std::string StoppedReaderWarning(const Endpoints& set) {
    const double s = StoppedReaderSeconds(set);
    if (s <= 0.0) return "";
    char text[320];
    std::snprintf(text, sizeof text,
                  "a reader of the sensors has acknowledged nothing for %.1f s (a client stopped, "
                  "held in a debugger, or killed within its lease): the rig runs on without "
                  "waiting; that reader loses samples beyond the last %d",
                  s, dds::kLockstepSensorDepth);
    return text;
  }

  Endpoints& EndpointsOf(std::size_t rig_index) {
    return endpoints.front()->rig < 0 ? *endpoints.front() : *endpoints[rig_index];
  }
  // One set of endpoints: every rig's in the default partition (rig < 0), or with security rig
  // `rig`'s in its partition. Its step (and rig) requests wake the lockstep loop.
  Status AddEndpoints(int rig) {
    const dds_entity_t p = participant.handle();
    auto set = std::make_unique<Endpoints>();
    set->rig = rig;
    set->commands.partition_rig = rig;
    dds_entity_t pub = p;
    dds_entity_t sub = p;
    if (rig >= 0) {
      const std::string partition = dds::RigPartition(rigs[static_cast<std::size_t>(rig)].rig_id());
      auto publisher = dds::CreatePublisher(p, partition);
      if (!publisher.ok()) return publisher.status();
      set->publisher = std::move(publisher).value();
      auto subscriber = dds::CreateSubscriber(p, partition);
      if (!subscriber.ok()) return subscriber.status();
      set->subscriber = std::move(subscriber).value();
      pub = set->publisher.handle();
      sub = set->subscriber.handle();
    }
    MPDRIG_RETURN_IF_ERROR(
        CreateEndpoints(pub, sub, options.clock == ClockMode::kLockstep, set.get()));
    std::vector<dds_entity_t> wake = {set->steps->handle()};
    if (options.private_rigs > 0) {
      auto requests =
          dds::Reader<mpdrig_RigRequest>::Create(sub, request_topic.handle(), dds::RequestQos());
      if (!requests.ok()) return requests.status();
      set->requests.emplace(std::move(requests).value());
      wake.push_back(set->requests->handle());
    }
    for (dds_entity_t reader : wake) {
      const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
      if (condition < 0) return dds::Check(condition, "dds_create_readcondition");
      MPDRIG_RETURN_IF_ERROR(dds::Check(dds_waitset_attach(step_waitset.handle(), condition, 0),
                                        "dds_waitset_attach"));
    }
    endpoints.push_back(std::move(set));
    return Status::Ok();
  }

  // Where a sample of `reader` came in: its set's partition, and its writer.
  static CommandOrigin OriginOf(const Endpoints& set, dds_entity_t reader,
                                const dds_sample_info_t& info) {
    const dds_instance_handle_t publication = info.publication_handle;
    return CommandOrigin{set.rig,
                         [reader, publication] { return DescribeWriter(reader, publication); }};
  }

  // Private rigs students asked for (security), each made as private_rigs.h says, with its
  // endpoints in its own partition and its first status.
  Status TakeRigRequests() {
    if (!private_rigs->enabled()) return Status::Ok();
    std::vector<std::pair<std::size_t, std::uint32_t>> asked;  // requesting rig, how many
    for (std::size_t i = 0; i < endpoints.size(); ++i) {
      Endpoints& set = *endpoints[i];
      auto taken =
          set.requests->TakeEach([&](const mpdrig_RigRequest& r, const dds_sample_info_t& info) {
            if (!intake->FromItsPartition(dds::topics::kRigRequest.name, r.rig_id,
                                          OriginOf(set, set.requests->handle(), info)))
              return;
            asked.push_back({static_cast<std::size_t>(set.rig), r.private_rigs});
          });
      if (!taken.ok()) return taken.status();
    }
    for (auto [index, count] : asked) {
      MPDRIG_RETURN_IF_ERROR(private_rigs->Grant(rigs, index, count, [this](std::size_t made) {
        intake->Allow(rigs[made].rig_id());
        observers.emplace_back();
        observer_failed.push_back(false);
        last_step_request.push_back(0);
        MPDRIG_RETURN_IF_ERROR(AddEndpoints(static_cast<int>(made)));
        return PublishStatus(made);
      }));
      MPDRIG_RETURN_IF_ERROR(PublishStatus(index));
    }
    return Status::Ok();
  }

  // Applies every pending command (command_intake.h). Refusals are recorded by the rigs.
  Status TakeCommands() {
    intake->RefuseFiltered();
    for (auto& set : endpoints)
      MPDRIG_RETURN_IF_ERROR(service::TakeCommands(set->commands, *intake));
    return Status::Ok();
  }

  Status TickAndPublish(RigHost& rig) {
    auto sample = rig.Tick();
    if (!sample.ok() && rig.playback() != nullptr && !rig.playback()->failed().ok()) {
      // A recording with a bad row further on (its file, line and column): the playback has
      // nothing more it can truthfully publish, so the service ends with the error (mpdrig serve
      // prints it and exits non-zero) instead of ticking on without a word.
      (void)rig.Refuse("playback ended: " + sample.status().message());
      (void)PublishAllStatus();
      return sample.status().Within("playback of rig " + rig.rig_id());
    }
    if (!sample.ok()) {
      // The model failed (e.g. the solver): the rig keeps its last state and says why.
      (void)rig.Refuse("simulation step failed: " + sample.status().message());
      return Status::Ok();
    }
    const std::uint64_t counter = rig.counters().samples - 1;
    const double atmosphere = rig.params().atmospheric_pressure_pa;
    const std::size_t index = static_cast<std::size_t>(&rig - rigs.data());
    Endpoints& out = EndpointsOf(index);
    MPDRIG_RETURN_IF_ERROR(out.sensors->Write(ToWire(rig.rig_id(), counter, *sample, atmosphere)));
    out.last_write = Clock::now();

    RigObserver* observer = Observe(index, *sample);
    if (observer != nullptr && counter % estimate_every == 0) {
      MPDRIG_RETURN_IF_ERROR(out.estimate->Write(
          ToWire(rig.rig_id(), counter, sample->time_s, observer->Estimate(), atmosphere)));
    }
    if (profile_every > 0 && counter % profile_every == 0) {
      std::vector<double> estimated;
      if (observer != nullptr) {
        for (double x : rig.pressure_positions_m()) estimated.push_back(observer->PressureAtPa(x));
      }
      MPDRIG_RETURN_IF_ERROR(out.profile->Write(
          ToWire(rig.rig_id(), counter, sample->time_s, rig.pressure_positions_m(),
                 sample->pressure_at_positions_pa, estimated, atmosphere, &profile_buffers)));
    }
    return Status::Ok();
  }

  // Brings rig `index`'s observer to the sample; nullptr if there is none (off, or it failed:
  // then the rig runs on and its status says why).
  RigObserver* Observe(std::size_t index, const RigSample& sample) {
    if (!options.observer || observer_failed[index]) return nullptr;
    RigHost& rig = rigs[index];
    std::optional<RigObserver>& observer = observers[index];
    Status status = Status::Ok();
    // A playback may lack a topside channel (not measured: NaN); the observer cannot run on a
    // gap, and would otherwise publish NaN as if it were an estimate.
    if (!std::isfinite(sample[Channel::kC2]) || !std::isfinite(sample[Channel::kFT1])) {
      status = Status::Error("C2 or FT1 not measured at t = " + std::to_string(sample.time_s) +
                             " s: the observer needs both topside channels");
    }
    if (status.ok() && !observer) {
      auto created = RigObserver::Create(rig.params(), options.observer_options, sample);
      if (created.ok()) {
        observer.emplace(std::move(created).value());
      } else {
        status = created.status();
      }
    }
    if (status.ok()) status = observer->Update(sample, rig.piston_sine_hz());
    if (!status.ok()) {
      observer_failed[index] = true;
      observer.reset();
      rig.NoteEvent("observer stopped: " + status.message());
      return nullptr;
    }
    return &*observer;
  }

  Status PublishStatus(std::size_t index) {
    Endpoints& out = EndpointsOf(index);
    StatusContext context;
    context.clock = options.clock;
    context.wall_s = std::chrono::duration<double>(Clock::now() - started).count();
    context.stalls = stalls();
    context.last_completed_step_request = last_step_request[index];
    context.stopped_reader_warning = StoppedReaderWarning(out);
    context.actuator_owners = intake->Owners(index);
    context.hide_effects = options.hide_effects;
    out.stopped_reader_published = !context.stopped_reader_warning.empty();
    const RigStatusReport report = ReportStatus(rigs[index], context);
    StatusBuffers buffers;
    return out.status->Write(ToWire(report, &buffers));
  }

  // A run that ended as asked (a stop, the duration, a playback's last row) disposes each rig's
  // status: the clients read that as the rig's clean end, where a crash or a lease running out
  // leaves the instance without writers (clients/rig_watch.h). A recorder then ends its recording
  // as complete. Waits (up to 1 s in all) until the readers have the disposal, since the
  // participant, and with it the sensor writer whose leaving the clients see, goes right after.
  Status EndRigs() {
    for (std::size_t i = 0; i < rigs.size(); ++i) {
      mpdrig_RigStatus key{};
      key.rig_id = const_cast<char*>(rigs[i].rig_id().c_str());
      MPDRIG_RETURN_IF_ERROR(
          dds::Check(dds_dispose(EndpointsOf(i).status->handle(), &key), "dds_dispose"));
    }
    const dds_time_t deadline = dds::DeadlineAfter(1.0);
    for (auto& set : endpoints) {
      (void)dds_wait_for_acks(set->status->handle(),
                              std::max<dds_duration_t>(0, deadline - dds_time()));
    }
    return Status::Ok();
  }

  Status PublishAllStatus() {
    for (std::size_t i = 0; i < rigs.size(); ++i) MPDRIG_RETURN_IF_ERROR(PublishStatus(i));
    return Status::Ok();
  }

  // ServeOptions::wait_for_readers: every set of endpoints (one per rig with security) waits for
  // its readers, all within one deadline. Not reaching them is no error: the rig starts, and says
  // on stderr how many it had.
  Status AwaitSensorReaders() {
    if (options.wait_for_readers <= 0) return Status::Ok();
    // A client makes its sensor reader once it has seen its rig's status: that goes out first.
    MPDRIG_RETURN_IF_ERROR(PublishAllStatus());
    const dds_time_t deadline = dds::DeadlineAfter(options.wait_for_readers_s);
    for (auto& set : endpoints) {
      auto matched = dds::AwaitReader(set->sensors->handle(), deadline, options.wait_for_readers);
      if (!matched.ok()) return matched.status();
      if (!*matched) {
        std::fprintf(stderr,
                     "mpdrig serve: fewer than %d sensor readers after %.1f s; starting anyway\n",
                     options.wait_for_readers, options.wait_for_readers_s);
        return Status::Ok();
      }
    }
    // Discovery runs in each direction on its own: the writer has matched the readers, but a
    // reader that has not yet matched the writer drops what arrives from it (volatile: nothing is
    // resent). The other direction follows within milliseconds on one machine; half a second
    // covers a loaded one (measured without it: the first row lost, as with no wait at all).
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    started = Clock::now();  // the real-time factor counts from the first sample
    return Status::Ok();
  }

  Status RunPaced(const std::atomic<bool>& stop) {
    MPDRIG_RETURN_IF_ERROR(AwaitSensorReaders());
    const double period = rigs.front().sensor_period_s();
    if (options.clock == ClockMode::kRealtime) {
      // With catch_up (a playback) the ticks after a stall run at once: no period is lost.
      pacer.emplace(period, options.catch_up, Clock::now());
    }
    double next_status_s = 0.0;
    while (!stop.load()) {
      if (options.duration_s > 0.0 && rigs.front().time_s() >= options.duration_s - 0.5 * period)
        break;
      MPDRIG_RETURN_IF_ERROR(TakeRigRequests());
      MPDRIG_RETURN_IF_ERROR(TakeCommands());
      for (RigHost& rig : rigs) MPDRIG_RETURN_IF_ERROR(TickAndPublish(rig));
      if (rigs.front().time_s() >= next_status_s) {
        MPDRIG_RETURN_IF_ERROR(PublishAllStatus());
        next_status_s += options.status_period_s;
        // A playback's clock starts at its log's first time, which need not be 0.
        next_status_s = std::max(next_status_s, rigs.front().time_s());
      }
      // Playbacks that have played their last row: the service has nothing more to publish.
      if (std::all_of(rigs.begin(), rigs.end(), [](const RigHost& r) { return r.finished(); }))
        break;
      if (pacer) pacer->AfterTick(rigs.front().time_s());
    }
    return PublishAllStatus();
  }

  // Lockstep: the step requests are queued and served in turns (lockstep_queue.h); a request's
  // commands are taken when it starts, and its completion goes out on the rig's status.
  Status RunLockstep(const std::atomic<bool>& stop) {
    MPDRIG_RETURN_IF_ERROR(AwaitSensorReaders());
    MPDRIG_RETURN_IF_ERROR(PublishAllStatus());  // clients see the rigs are up
    struct Request {
      std::string rig_id;
      std::uint64_t id = 0, steps = 0;
    };
    LockstepQueue queue(rigs.front().sensor_period_s());
    std::vector<Clock::time_point> last_status_wall(rigs.size(), Clock::now());
    while (!stop.load()) {
      if (!queue.busy()) {
        const dds_return_t ready =
            dds_waitset_wait(step_waitset.handle(), nullptr, 0, DDS_MSECS(50));
        if (ready < 0) return dds::Check(ready, "dds_waitset_wait");
        // Refusals of the topic filters (unknown rig ids) are reported within this wait, and
        // so is a reader that stopped acknowledging (or started again).
        bool readers_changed = false;
        for (auto& set : endpoints) {
          ProbeReaders(*set);
          const bool stopped = StoppedReaderSeconds(*set) > 0.0;
          readers_changed = readers_changed || stopped != set->stopped_reader_published;
        }
        if (intake->RefuseFiltered() || readers_changed) MPDRIG_RETURN_IF_ERROR(PublishAllStatus());
        if (ready == 0) continue;
      }
      MPDRIG_RETURN_IF_ERROR(TakeRigRequests());
      last_status_wall.resize(rigs.size(), Clock::now());
      std::vector<Request> requests;
      bool refused = false;  // from another rig's partition (security), or an unknown rig's dispose
      for (auto& set : endpoints) {
        auto& steps = set->steps;
        auto taken = steps->TakeEach(
            [&](const mpdrig_StepRequest& r, const dds_sample_info_t& info) {
              if (!intake->FromItsPartition(dds::topics::kStepRequest.name, r.rig_id,
                                            OriginOf(*set, steps->handle(), info))) {
                refused = true;
                return;
              }
              requests.push_back({r.rig_id, r.request_id, r.steps});
            },
            {}, std::numeric_limits<int>::max(),
            // A dispose of an unknown rig's request (the filter does not see it), as the
            // command topics refuse theirs.
            [&](const mpdrig_StepRequest& r) {
              if (intake->Disposed(dds::topics::kStepRequest.name, r.rig_id)) refused = true;
            });
        if (!taken.ok()) return taken.status();
      }
      if (refused) MPDRIG_RETURN_IF_ERROR(PublishAllStatus());
      for (const Request& request : requests) {
        RigHost* rig = intake->Find(request.rig_id.c_str());
        if (rig == nullptr) {  // the topic filter lets none through; kept for safety
          MPDRIG_RETURN_IF_ERROR(TakeCommands());
          intake->RefuseUnknown(dds::topics::kStepRequest.name, ReportedId(request.rig_id.c_str()));
          MPDRIG_RETURN_IF_ERROR(PublishAllStatus());
          continue;
        }
        const std::size_t index = static_cast<std::size_t>(rig - rigs.data());
        if (auto refused_why = queue.Add(index, request.id, request.steps)) {
          (void)rig->Refuse(*refused_why);
          MPDRIG_RETURN_IF_ERROR(PublishStatus(index));
        }
      }
      for (std::size_t index = 0; index < rigs.size() && !stop.load(); ++index) {
        const std::optional<LockstepQueue::Turn> turn = queue.NextTurn(index);
        if (!turn) continue;
        if (turn->starts) MPDRIG_RETURN_IF_ERROR(TakeCommands());
        std::uint64_t ran = 0;
        for (; ran < turn->steps && !stop.load(); ++ran) {
          MPDRIG_RETURN_IF_ERROR(TickAndPublish(rigs[index]));
        }
        if (const std::optional<std::uint64_t> completed = queue.Ran(index, ran)) {
          last_step_request[index] = *completed;
          MPDRIG_RETURN_IF_ERROR(PublishStatus(index));
          last_status_wall[index] = Clock::now();
        } else if (std::chrono::duration<double>(Clock::now() - last_status_wall[index]).count() >=
                   kLockstepStatusEveryS) {
          MPDRIG_RETURN_IF_ERROR(PublishStatus(index));
          last_status_wall[index] = Clock::now();
        }
      }
    }
    return Status::Ok();
  }
};

Status RigService::Impl::CreateEndpoints(dds_entity_t pub, dds_entity_t sub, bool lockstep,
                                         Endpoints* set) {
  auto sensors = dds::Writer<mpdrig_RigSensors>::Create(pub, sensors_topic.handle(),
                                                        dds::SensorWriterQos(lockstep));
  if (!sensors.ok()) return sensors.status();
  set->sensors.emplace(std::move(sensors).value());
  // Estimates and profiles are sensor-like streams: the same QoS, for the same reasons.
  auto estimate = dds::Writer<mpdrig_RigEstimate>::Create(pub, estimate_topic.handle(),
                                                          dds::SensorWriterQos(lockstep));
  if (!estimate.ok()) return estimate.status();
  set->estimate.emplace(std::move(estimate).value());
  auto profile = dds::Writer<mpdrig_PressureProfile>::Create(pub, profile_topic.handle(),
                                                             dds::SensorWriterQos(lockstep));
  if (!profile.ok()) return profile.status();
  set->profile.emplace(std::move(profile).value());
  auto status = dds::Writer<mpdrig_RigStatus>::Create(pub, status_topic.handle(), dds::StatusQos());
  if (!status.ok()) return status.status();
  set->status.emplace(std::move(status).value());

  auto choke =
      dds::Reader<mpdrig_ChokeCommand>::Create(sub, choke_topic.handle(), dds::CommandQos());
  if (!choke.ok()) return choke.status();
  set->commands.choke.emplace(std::move(choke).value());
  auto piston =
      dds::Reader<mpdrig_PistonCommand>::Create(sub, piston_topic.handle(), dds::CommandQos());
  if (!piston.ok()) return piston.status();
  set->commands.piston.emplace(std::move(piston).value());
  auto pump = dds::Reader<mpdrig_PumpCommand>::Create(sub, pump_topic.handle(), dds::CommandQos());
  if (!pump.ok()) return pump.status();
  set->commands.pump.emplace(std::move(pump).value());
  auto outlet =
      dds::Reader<mpdrig_OutletCommand>::Create(sub, outlet_topic.handle(), dds::CommandQos());
  if (!outlet.ok()) return outlet.status();
  set->commands.outlet.emplace(std::move(outlet).value());
  auto steps = dds::Reader<mpdrig_StepRequest>::Create(sub, step_topic.handle(), dds::RequestQos());
  if (!steps.ok()) return steps.status();
  set->steps.emplace(std::move(steps).value());
  return Status::Ok();
}

Status ServeOptions::Validate(double sensor_rate_hz) const {
  auto out_of_range = [sensor_rate_hz](const char* what, double value, const char* zero) {
    std::ostringstream out;
    out << what << " " << value << " Hz must be in [0, " << sensor_rate_hz
        << "] Hz (the sensor rate; 0: " << zero << ")";
    return Status::Error(out.str());
  };
  if (!(estimate_hz >= 0.0 && estimate_hz <= sensor_rate_hz)) {
    return out_of_range("estimate rate", estimate_hz, "with every sample");
  }
  if (!(profile_hz >= 0.0 && profile_hz <= sensor_rate_hz)) {
    return out_of_range("profile rate", profile_hz, "off");
  }
  if (observer) return observer_options.observer.Validate();
  return Status::Ok();
}

RigService::RigService(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
RigService::~RigService() = default;

const std::vector<RigHost>& RigService::rigs() const { return impl_->rigs; }
std::uint64_t RigService::deadline_misses() const { return impl_->stalls().deadline_misses; }
std::uint64_t RigService::lost_periods() const { return impl_->stalls().lost_periods; }
double RigService::longest_stall_s() const { return impl_->stalls().longest_s; }

Result<std::unique_ptr<RigService>> RigService::Create(std::vector<RigHost> rigs,
                                                       const ServeOptions& options) {
  if (rigs.empty()) return Status::Error("no rigs to serve");
  for (std::size_t i = 0; i < rigs.size(); ++i) {
    MPDRIG_RETURN_IF_ERROR(CheckRigId(rigs[i].rig_id()));
    for (std::size_t j = 0; j < i; ++j) {
      if (rigs[i].rig_id() == rigs[j].rig_id()) {
        return Status::Error("rig id '" + rigs[i].rig_id() + "' given twice");
      }
    }
    if (rigs[i].sensor_period_s() != rigs.front().sensor_period_s()) {
      return Status::Error("all rigs of one service share the sensor rate");
    }
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->rigs = std::move(rigs);
  impl->last_step_request.assign(impl->rigs.size(), 0);
  impl->observers.resize(impl->rigs.size());
  impl->observer_failed.assign(impl->rigs.size(), false);
  impl->intake.emplace(&impl->rigs, options.safe_choke_deg);
  impl->private_rigs.emplace(options.private_rigs, options.max_rigs, options.make_rig);
  const double rate_hz = 1.0 / impl->rigs.front().sensor_period_s();
  MPDRIG_RETURN_IF_ERROR(options.Validate(rate_hz));
  if (options.security) {
    for (const RigHost& rig : impl->rigs)
      MPDRIG_RETURN_IF_ERROR(dds::CheckSecureRigId(rig.rig_id()));
  }
  if (options.private_rigs > 0 && (!options.security || !options.make_rig)) {
    return Status::Error("private rigs need security (a student asks in their own partition)");
  }
  // Every k-th sample: the nearest whole divisor of the sensor rate (at least every sample).
  if (options.estimate_hz > 0.0) {
    impl->estimate_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::lround(rate_hz / options.estimate_hz)));
  }
  if (options.profile_hz > 0.0) {
    impl->profile_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::lround(rate_hz / options.profile_hz)));
  }

  auto domain = dds::Domain::Create(
      options.domain, dds::AddConfigFragment(options.dds_config, dds::ServiceSampleLimitConfig()));
  if (!domain.ok()) return domain.status().Within("DDS domain " + std::to_string(options.domain));
  impl->domain.emplace(std::move(domain).value());
  auto participant =
      dds::CreateParticipant(options.domain, options.security ? &*options.security : nullptr);
  if (!participant.ok()) return participant.status();
  impl->participant = std::move(participant).value();
  const dds_entity_t p = impl->participant.handle();

  auto topic = [p](const dds::TopicSpec& spec, dds::Entity* out) -> Status {
    auto created = dds::CreateTopic(p, spec);
    if (!created.ok()) return created.status();
    *out = std::move(created).value();
    return Status::Ok();
  };
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kSensors, &impl->sensors_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kChokeCommand, &impl->choke_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kPistonCommand, &impl->piston_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kPumpCommand, &impl->pump_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kOutletCommand, &impl->outlet_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kStepRequest, &impl->step_topic));
  // Filters on the command and step topics, set before their readers are created (Cyclone
  // applies a topic's filter to the readers made from it afterwards).
  auto gate = [&impl](const char* name, dds_topic_filter_sample_arg_fn accept,
                      const dds::Entity& on) -> Status {
    UnknownRigGate* gate = impl->intake->AddGate(name);
    return dds::Check(dds_set_topic_filter_and_arg(on.handle(), accept, gate),
                      "dds_set_topic_filter_and_arg");
  };
  MPDRIG_RETURN_IF_ERROR(gate(dds::topics::kChokeCommand.name,
                              &UnknownRigGate::Accept<mpdrig_ChokeCommand>, impl->choke_topic));
  MPDRIG_RETURN_IF_ERROR(gate(dds::topics::kPistonCommand.name,
                              &UnknownRigGate::Accept<mpdrig_PistonCommand>, impl->piston_topic));
  MPDRIG_RETURN_IF_ERROR(gate(dds::topics::kPumpCommand.name,
                              &UnknownRigGate::Accept<mpdrig_PumpCommand>, impl->pump_topic));
  MPDRIG_RETURN_IF_ERROR(gate(dds::topics::kOutletCommand.name,
                              &UnknownRigGate::Accept<mpdrig_OutletCommand>, impl->outlet_topic));
  MPDRIG_RETURN_IF_ERROR(gate(dds::topics::kStepRequest.name,
                              &UnknownRigGate::Accept<mpdrig_StepRequest>, impl->step_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kStatus, &impl->status_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kEstimate, &impl->estimate_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kPressureProfile, &impl->profile_topic));

  // One set of endpoints in the default partition, or with security one per rig in its own.
  if (options.private_rigs > 0) {
    MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kRigRequest, &impl->request_topic));
  }
  dds::Entity step_waitset(dds_create_waitset(p));
  if (step_waitset.handle() < 0) return dds::Check(step_waitset.handle(), "dds_create_waitset");
  impl->step_waitset = std::move(step_waitset);
  if (options.security) {
    for (std::size_t i = 0; i < impl->rigs.size(); ++i) {
      MPDRIG_RETURN_IF_ERROR(impl->AddEndpoints(static_cast<int>(i)));
    }
  } else {
    MPDRIG_RETURN_IF_ERROR(impl->AddEndpoints(-1));
  }

  return std::unique_ptr<RigService>(new RigService(std::move(impl)));
}

Status RigService::Run(const std::atomic<bool>& stop) {
  impl_->started = Clock::now();
  const Status ran = impl_->options.clock == ClockMode::kLockstep ? impl_->RunLockstep(stop)
                                                                  : impl_->RunPaced(stop);
  if (!ran.ok()) return ran;  // a failure: the clients find the rig lost, as after a crash
  return impl_->EndRigs();
}

}  // namespace mpdrig::service
