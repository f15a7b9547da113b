// The virtual rig as a DDS service: several rigs (one per rig id) in one process, commands in,
// sensors and status out, paced by a clock:
//   realtime - one sensor period of rig time per period of wall time; late ticks are counted as
//              deadline misses (a tick that starts more than one period late); the periods a
//              late tick skips are not caught up (the rig runs on behind the wall clock): the
//              status counts them (lost_periods), gives the longest stall and the rig time of
//              the last one, and its warnings say when the rig fell behind;
//   fast     - as fast as the machine goes;
//   lockstep - the rig advances only when a client asks (StepRequest): all pending commands are
//              taken first, then `steps` sensor periods run and each one's sensors are published,
//              then the status carries last_completed_step_request. A client that needs its
//              command applied in a given step waits for the command's acknowledgement
//              (dds_wait_for_acks) before it sends the step request. Requests queue per rig;
//              rigs with pending steps take turns of at most 100 steps, so a long request
//              starves no other rig, and a stop ends it within one step. A request for more
//              than an hour of rig time is refused (on the status, with the reason); while a
//              long one runs, its rig's status goes out every 0.5 s of wall time.
//              A command sent while its rig's request runs may apply in the middle of it.
// A command that is NaN, infinite, out of range or for an unknown rig is refused, counted and
// reported on status; the rig runs on. Nothing a client sends stops the service.
// Several controllers may command one rig: each actuator's topic uses exclusive ownership, so
// the strongest live writer wins and the next takes over when it goes; when none is left, the
// actuator goes to its safe state (ServeOptions) and the status says so.
// Sensors read with the rig's noise (RigHost's SensorOptions); the status names it.
// Beside each rig runs the backstepping observer on the rig's topside channels, as the sensors
// read them (with their noise, as on the real rig); its estimate
// (bottom-hole pressure, heave velocity, the disturbance frequency it uses) goes out on
// mpdrig_estimate right after the sensor sample it belongs to, and the pressure along the pipe,
// simulated and estimated, on mpdrig_pressure_profile at a lower rate.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/rig/clock_mode.h"
#include "service/rig/rig_host.h"
#include "service/rig/rig_observer.h"

namespace mpdrig::service {

struct ServeOptions {
  ClockMode clock = ClockMode::kRealtime;
  dds_domainid_t domain = 0;
  std::string dds_config = dds::LoopbackConfig();
  double duration_s = 0.0;       // realtime/fast: stop after this much rig time (0: run on)
  double status_period_s = 0.5;  // realtime/fast: status every this much rig time
  // Safe state when a rig's last controller of an actuator goes (deleted, or its 1 s liveliness
  // lease ran out): the piston holds where it is; the choke goes to this opening (NaN: it keeps
  // its last command). Pump and outlet keep theirs.
  double safe_choke_deg = std::numeric_limits<double>::quiet_NaN();
  // The backstepping observer beside each rig (rig_observer.h), published on mpdrig_estimate
  // at estimate_hz (0: with every sensor sample); it steps on every sample either way.
  bool observer = true;
  RigObserverOptions observer_options;
  double estimate_hz = 0.0;
  // Pressure along the pipe (RigHost::pressure_positions_m) on mpdrig_pressure_profile at this
  // rate of rig time (0: off); with the observer's estimate at the same positions.
  double profile_hz = 10.0;
  // DDS Security (service/dds/security.h; the identity of make-class's OUT/service): then each
  // rig's topics live in partition "rig.<rig id>", so permissions decide who commands and reads
  // which rig, and a command that arrives in one rig's partition for another rig is refused
  // (counted, reported on both rigs' status with its writer). Unset: no security, the default
  // partition, as before.
  std::optional<dds::SecurityFiles> security;
  // Private rigs, with security only: a student's RigRequest (sent in their rig's partition)
  // makes the service run "<student>.1" .. "<student>.N", N up to `private_rigs` per student
  // (0: requests are not taken), each made by `make_rig`, while the service runs fewer than
  // `max_rigs` rigs in all (0: no limit). A request beyond a limit is refused on the student's
  // status.
  std::uint32_t private_rigs = 0;
  std::size_t max_rigs = 0;
  std::function<Result<RigHost>(const std::string& rig_id)> make_rig;
  // A mystery rig for teaching (`mpdrig serve --hidden-effect`): the status names no effect, it
  // says only "a hidden effect is active" (`mpdrig reveal` tells which).
  bool hide_effects = false;
  // Realtime: a late tick is caught up (the ticks after it run at once until the rig is back
  // on the wall clock's schedule) instead of skipped. A playback keeps to its recording's clock
  // this way: an hour of log plays in an hour of wall time, whatever stalls the process met.
  // deadline_misses and the longest stall still count; no periods are lost.
  bool catch_up = false;
  // Before the first sample, wait until each rig's sensors have this many readers (0: do not
  // wait), up to wait_for_readers_s of wall time: a sample written before a reader has matched
  // reaches no one, so a recorder that was already waiting would miss a playback's first rows.
  std::int32_t wait_for_readers = 0;
  double wait_for_readers_s = 30.0;

  Status Validate(double sensor_rate_hz) const;
};

class RigService {
 public:
  static Result<std::unique_ptr<RigService>> Create(std::vector<RigHost> rigs,
                                                    const ServeOptions& options);
  ~RigService();

  // Serves until `stop` is set (SIGINT/SIGTERM in mpdrig serve) or the duration is reached.
  // Fails only when the transport fails, or when a playback meets a bad row (the error names its
  // file, line and column; a playback cannot go on past it).
  Status Run(const std::atomic<bool>& stop);

  const std::vector<RigHost>& rigs() const;
  // Ticks (of all rigs together) that started more than one sensor period late (realtime).
  std::uint64_t deadline_misses() const;
  // The sensor periods those late ticks skipped (the rigs run on that far behind the wall
  // clock), and the longest of the stalls [s of wall time] (realtime).
  std::uint64_t lost_periods() const;
  double longest_stall_s() const;

 private:
  struct Impl;
  explicit RigService(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpdrig::service
