// A client library for one rig over the DDS topics (docs/service.md):
// what a controller, a recorder or a plot needs, without DDS in its code. It speaks only the
// topics of idl/mpdrig.idl with the project's QoS (service/dds), so it talks to the virtual rig
// and to the lab's rig behind a bridge alike. The Python module (clients/python) is a thin
// binding of this class.
//
//   auto rig = client::Rig::Connect({.rig_id = "rig-1", .domain = 0});
//   if (!rig.ok()) ...                      // no such rig on the domain within the timeout
//   auto s = (*rig)->Step(1);               // lockstep: advance one period, return its sample
//   (*rig)->Choke(30.0);                    // a command, applied at the rig's next step
//
// A program with several rigs connects each through one Participant (participant.h):
// Rig::Connect(participant, options).
//
// Rules it keeps for its user:
//   - Commands use dds::CommandQos(strength): exclusive ownership, transient-local, a 1 s
//     liveliness lease. A command writer is made on the first command of its kind and waits for
//     the service's reader to match first (a sample written before that may reach no one).
//     Closing the Rig deletes the writers, which unregisters them: another controller of the
//     same strength takes over at once.
//   - Lockstep: Step() first waits for the acknowledgement of every command written since the
//     last step (the service takes the commands when a step request starts, so an unacknowledged
//     command could miss the step), then asks for the steps and returns when the service's
//     status names the request as completed, with the last sample of those steps.
//   - A lost rig (clients/rig_watch.h): time or sample counter going back, the sensor writer
//     gone, or no sample for `timeout_s` after the first. Samples that arrived before still come
//     out of Next and TakeArrived (a recording keeps them); every other call then fails with
//     Failure::kLost and the reason; a Rig never carries its state over to another run.
//   - Leaving (Close, or the destructor) is a one-shot command's rule (dds::SendOnce): each
//     command writer first waits for the acknowledgement of what it wrote, then is deleted, so a
//     script that sends one command and exits loses none, and leaves no stale owner behind.
//   - With `security_dir` (DDS Security, make-class's OUT/NAME) the participant authenticates
//     with those files and every endpoint is in the rig's partition rig.<rig id>; the permissions
//     decide what the identity may read and command, and a refusal says so.
//   - The service, not this library, decides what command is valid: a refused command shows in
//     RigStatus (rejected_commands, last_rejection) and in NewRejections().
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clients/client/participant.h"
#include "clients/rig_watch.h"
#include "model/common/status.h"

namespace mpdrig::client {

struct RigOptions {
  std::string rig_id = "rig-1";
  int domain = 0;
  // Cyclone DDS configuration: an XML fragment, a whole <CycloneDDS> document, or file URIs
  // ("file:///lab.xml", Cyclone's comma-separated list) (empty: loopback only). A fragment or a
  // file list gets dds::FastAckConfig() added, for lockstep acknowledgements; a whole document
  // should set it itself.
  std::string dds_config;
  int strength = 0;  // ownership strength of this client's commands
  // Waiting for the rig, a sample, an acknowledgement or a step; after the first sample, this long
  // without one means the rig is lost. 0: wait for ever, and silence alone never loses the rig.
  double timeout_s = 10.0;
  // DDS Security: an identity directory of a class (deploy/security/make-class OUT NAME:
  // OUT/NAME); empty: no security. The rig's topics are then in partition rig.<rig id>.
  std::string security_dir;
  // Keep every sensor sample even on a real-time rig (a recorder), instead of the newest 8 that
  // a real-time reader keeps (a slow client must not hold back the rig). Lockstep keeps all.
  bool keep_every_sample = false;
  // Which of the rig's other streams to read (a recorder of the sensors needs neither).
  bool read_estimates = true;
  bool read_profiles = true;
};

// One sample of every lab channel (mpdrig_sensors), in the wire's lab units.
struct Sensors {
  std::uint64_t sample_counter = 0;
  double time_s = 0.0;
  double piston_position_m = 0.0;
  double choke_position_deg = 0.0;
  double P1_barg = 0.0, P2_barg = 0.0;
  std::array<double, 10> PT_barg{};  // PT1..PT10 at x = 0, 100, ..., 900 m
  double C1_barg = 0.0, C2_barg = 0.0;
  double FT1_lpm = 0.0, FT2_lpm = 0.0, FT3_lpm = 0.0, FT4_lpm = 0.0;
  // When the rig published it (its writer's clock, s since 1970) and when this client took it
  // (steady clock, s): what a client sees of the rig's sensor clock (rig_echo --timing).
  double published_s = 0.0;
  double received_s = 0.0;
};

// The observer's estimate for one sample (mpdrig_estimate).
struct Estimate {
  std::uint64_t sample_counter = 0;
  double time_s = 0.0;
  double observer_time_s = 0.0;
  double BHP_est_barg = 0.0;
  double piston_velocity_est_mps = 0.0;
  double piston_position_est_m = 0.0;
  double FT4_est_lpm = 0.0;
  double disturbance_frequency_hz = 0.0;
  std::string frequency_source;  // "piston_sine", "tracked" or "unlocked"
};

// Pressure along the pipe (mpdrig_pressure_profile).
struct Profile {
  std::uint64_t sample_counter = 0;
  double time_s = 0.0;
  std::vector<double> position_m, pressure_barg, pressure_est_barg;
};

// What the rig reports about itself (mpdrig_status).
struct RigStatus {
  std::string clock;  // "realtime", "fast" or "lockstep"
  double sim_time_s = 0.0;
  double real_time_factor = 0.0;
  std::uint64_t deadline_misses = 0;
  // Real time: the sensor periods the late ticks skipped, the longest stall [s of wall time] and
  // the rig time of the last one (-1: never).
  std::uint64_t lost_periods = 0;
  double longest_stall_s = 0.0;
  double last_stall_sim_time_s = -1.0;
  std::uint64_t rejected_commands = 0;
  std::string last_rejection;
  std::uint64_t last_completed_step_request = 0;
  std::vector<std::string> warnings, active_effects, actuator_owners;
  std::string sensor_noise;
  double atmospheric_pressure_pa = 101325.0;  // the atmosphere the rig's *_barg are gauge against
};

// The heave generator's command (mpdrig_piston_command).
struct PistonCommand {
  enum class Mode { kHold, kPosition, kSine, kSweep };
  Mode mode = Mode::kHold;
  double position_m = 0.0;
  double mean_m = 0.0, amplitude_m = 0.0, frequency_hz = 0.0;
  double sweep_end_hz = 0.0, sweep_duration_s = 0.0;
};

// Why the last call failed, for callers that react differently (Python raises TimeoutError,
// RigLost or RigError).
enum class Failure { kNone, kTimeout, kLost, kInterrupted, kError };

class Rig {
 public:
  // Called about every 100 ms while a call blocks; true stops the call (Failure::kInterrupted).
  // The Python binding checks for Ctrl-C here.
  using Interrupt = std::function<bool()>;

  // Joins the domain and waits up to options.timeout_s for the rig's status (transient-local: a
  // running service has one for each of its rigs), which says the rig exists and its clock.
  static Result<std::unique_ptr<Rig>> Connect(const RigOptions& options,
                                              const Interrupt& interrupt = {});
  // The same through a participant the program holds (participant.h): several rigs on one.
  // The participant's domain, configuration and identity hold, not those of `options`.
  static Result<std::unique_ptr<Rig>> Connect(const std::shared_ptr<Participant>& participant,
                                              const RigOptions& options,
                                              const Interrupt& interrupt = {});
  ~Rig();
  Rig(const Rig&) = delete;
  Rig& operator=(const Rig&) = delete;

  const RigOptions& options() const { return options_; }
  bool lockstep() const { return lockstep_; }

  // The newest sample that has arrived, discarding older unread ones; waits (up to the timeout)
  // only if none has arrived since the last call returned one... or ever, when `fresh` is false.
  Result<Sensors> Latest(bool fresh, const Interrupt& interrupt = {});
  // The next sample in order (every sample, as long as the caller keeps up: the queue holds the
  // newest 10000), waiting up to the timeout for it.
  Result<Sensors> Next(const Interrupt& interrupt = {});
  // Every sample that has arrived and not been returned by Next or TakeArrived, in order, without
  // waiting (e.g. the samples of a Step of many periods).
  Result<std::vector<Sensors>> TakeArrived();
  // The estimate for sample `counter` (waits for it up to the timeout), or with nullopt the
  // newest estimate (waiting only if none has arrived yet).
  Result<Estimate> EstimateFor(std::optional<std::uint64_t> counter,
                               const Interrupt& interrupt = {});
  // The newest estimate that has arrived, without waiting (nullopt: none yet). What a real-time
  // controller pairs with the sample it has just read.
  std::optional<Estimate> NewestEstimate() const;
  // The newest pressure profile (waits up to the timeout if none has arrived yet).
  Result<Profile> LatestProfile(const Interrupt& interrupt = {});
  // The newest status (a running service always has one: see Connect).
  Result<RigStatus> LatestStatus(const Interrupt& interrupt = {});
  // Rejections reported by the service since the previous call (or since Connect): the number
  // the rejected-commands counter grew by and the last reason. Reads the newest status.
  Result<std::pair<std::uint64_t, std::string>> NewRejections(const Interrupt& interrupt = {});

  mpdrig::Status Choke(double opening_deg, const Interrupt& interrupt = {});
  mpdrig::Status Pump(double flow_lpm, const Interrupt& interrupt = {});
  mpdrig::Status Outlet(double pressure_barg, const Interrupt& interrupt = {});
  mpdrig::Status Piston(const PistonCommand& command, const Interrupt& interrupt = {});

  // Who commands the rig's choke, by the newest status's actuator_owners (exclusive ownership:
  // the strongest live writer wins, a tie goes by GUID, and a loser's commands are dropped
  // without a word): nullopt while this client's own writer does, or before the status names
  // any writer (this client has not commanded yet, or the rig has not applied it); else the
  // status's words for the owner ("strength 20, writer 1a2b...", or "none"). Does not wait.
  Result<std::optional<std::string>> ChokeCommandedByOther();

  // Lockstep only: advances the rig `steps` sensor periods (commands written before are applied
  // from the first) and returns the last sample of them. Failure on a real-time rig.
  Result<Sensors> Step(std::uint32_t steps = 1, const Interrupt& interrupt = {});

  // Leaves the rig: waits (up to the timeout, 10 s at most) for the acknowledgement of the
  // commands written, then deletes the command writers (unregistering their instances, so
  // another controller takes over at once) and the participant. Every later call fails.
  void Close();
  bool closed() const { return dds_ == nullptr; }

  // Why the rig is lost, once it is (then every call fails with Failure::kLost).
  const std::optional<std::string>& lost() const { return lost_; }
  // Whether the rig's service ended its run as asked (a stop, its duration, a playback's last
  // row), not by a crash: it disposed the rig's status before it went. A lost rig that ended
  // is a run that is over, e.g. a recording that is complete.
  bool ended() const { return ended_; }
  // What kind of failure the last failed call had.
  Failure last_failure() const { return last_failure_; }

 private:
  struct Dds;
  explicit Rig(const RigOptions& options);

  mpdrig::Status Fail(Failure kind, const std::string& message);
  // Connect's parts: topics, the status reader and the waitset; the stream readers.
  mpdrig::Status MakeEndpoints();
  mpdrig::Status MakeStreamReaders(bool keep_all);
  mpdrig::Status Attach(std::int32_t reader);  // to the waitset
  // Takes what has arrived on every topic into the local buffers and applies the lost-rig rule.
  mpdrig::Status Drain();
  mpdrig::Status TakeSensors();
  mpdrig::Status TakeEstimates();
  mpdrig::Status TakeProfiles();
  mpdrig::Status TakeStatus();
  // Waits until `done` is true, draining every 100 ms at most, up to the timeout.
  mpdrig::Status WaitFor(const std::function<bool()>& done, const std::string& what,
                         const Interrupt& interrupt);
  template <typename T>
  mpdrig::Status SendCommand(int topic_index, const T& sample, const Interrupt& interrupt);
  // The lockstep rule: every command written since the last step is acknowledged first.
  mpdrig::Status AwaitCommandAcks(double timeout_s);
  mpdrig::Status ClosedOrLost();
  mpdrig::Status AwaitMatch(std::int32_t writer, const char* topic_name,
                            const Interrupt& interrupt);
  mpdrig::Status MakeStepWriter(const Interrupt& interrupt);

  RigOptions options_;
  std::unique_ptr<Dds> dds_;
  bool lockstep_ = false;
  clients::RigWatch watch_;
  double last_sample_wall_s_ = 0.0;
  std::optional<std::string> lost_;
  bool ended_ = false;
  Failure last_failure_ = Failure::kNone;

  std::deque<Sensors> queue_;  // arrived, not yet returned by Next
  std::optional<Sensors> newest_;
  bool newest_returned_ = false;
  std::deque<Estimate> estimates_;  // the newest few hundred, for pairing by counter
  std::optional<Profile> profile_;
  std::optional<RigStatus> rig_status_;
  std::uint64_t rejections_seen_ = 0;
  std::uint64_t request_id_ = 0;
  std::array<bool, 4> unacknowledged_{};  // per command topic: written since the last step
};

}  // namespace mpdrig::client
