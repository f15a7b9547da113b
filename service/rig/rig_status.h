// What a rig's status says (the mpdrig_RigStatus topic, idl/mpdrig.idl), built from the rig and
// what the service knows beside it, before it goes on the wire (wire.h ToWire). No transport.
//
// Units as on the wire: rig time and stalls in s (stalls of wall time), the rig's own
// atmospheric pressure in Pa absolute (every *_barg of its samples is gauge against it), the
// real-time factor rig time over wall time since the service started (0 before any wall time).
//   warnings         - in this order, each only when there is one: the model's range left, the
//                      rig fell behind real time, a reader of its sensors stopped acknowledging
//                      (lockstep), the rig's last event (e.g. a safe state taken);
//   active_effects   - "<name> key=value ..." per effect; with hide_effects (the mystery rig)
//                      only "a hidden effect is active", and nothing when the rig has none;
//   actuator_owners  - "<actuator>: strength N, writer <guid>", or "<actuator>: none" once lost;
//   sensor_noise     - "none", or the noise and its seed ("lab, seed 1").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "service/rig/clock_mode.h"
#include "service/rig/pacer.h"
#include "service/rig/rig_host.h"

namespace mpdrig::service {

// What the service, not the rig, knows for a status.
struct StatusContext {
  ClockMode clock = ClockMode::kRealtime;
  double wall_s = 0.0;                            // wall time since the service started [s]
  RealTimePacer::Stalls stalls;                   // real time; none with the other clocks
  std::uint64_t last_completed_step_request = 0;  // lockstep
  std::string stopped_reader_warning;             // lockstep; empty: none
  std::vector<std::string> actuator_owners;       // "choke: strength 20, writer ..."
  bool hide_effects = false;
};

struct RigStatusReport {
  std::string rig_id;
  ClockMode clock = ClockMode::kRealtime;
  double sim_time_s = 0.0;
  double real_time_factor = 0.0;
  std::uint64_t deadline_misses = 0;
  std::uint64_t lost_periods = 0;
  double longest_stall_s = 0.0;
  double last_stall_sim_time_s = -1.0;
  double atmospheric_pressure_pa = 0.0;
  std::uint64_t rejected_commands = 0;
  std::string last_rejection;
  std::uint64_t last_completed_step_request = 0;
  std::vector<std::string> warnings;
  std::vector<std::string> active_effects;
  std::vector<std::string> actuator_owners;
  std::string sensor_noise;
};

RigStatusReport ReportStatus(const RigHost& rig, const StatusContext& context);

}  // namespace mpdrig::service
