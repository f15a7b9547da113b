// The one place that translates between the DDS wire types (idl/mpdrig.idl, generated C structs)
// and the service's own types. Nothing else here: no physics, no transport.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"

#include "model/sim/rig_simulator.h"
#include "mpdrig.h"
#include "service/dds/topics.h"
#include "service/rig/rig_host.h"
#include "service/rig/rig_observer.h"
#include "service/rig/rig_status.h"

namespace mpdrig::service {

// Topic names, types and QoS: service/dds/topics.h.

// A rig id (the key of every topic) is 1 to kMaxRigIdBytes bytes of printable ASCII without
// spaces ('!' .. '~'): the service serves no other, so a sample whose id is longer is refused
// after reading at most kMaxRigIdBytes + 1 of its bytes, whatever its length (a stranger's 10 MB
// ids were compared and measured in full on Cyclone's receive thread). 128 holds a --security
// name (at most 64 bytes, CheckSecureRigId) with its private rigs' ".N".
inline constexpr std::size_t kMaxRigIdBytes = 128;
// OK, or an error naming the id (at most its first 64 bytes) and the rule.
Status CheckRigId(std::string_view rig_id);

// A sample in the lab's units (bar gauge with the rig's atmospheric pressure, L/min, deg, m).
// `rig_id` must outlive the returned struct (the wire struct points at it).
mpdrig_RigSensors ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                         const RigSample& sample, double atmospheric_pressure_pa);
RigSample FromWire(const mpdrig_RigSensors& wire, double atmospheric_pressure_pa);

PistonCommandIn FromWire(const mpdrig_PistonCommand& wire);

// The observer's estimate for the sensor sample `sample_counter` at `sim_time_s`, in lab units.
mpdrig_RigEstimate ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                          double sim_time_s, const RigObserverEstimate& estimate,
                          double atmospheric_pressure_pa);

// A pressure profile in lab units; the wire struct points into these buffers (and `rig_id`),
// which must outlive it. `estimated_pa` may be empty (no observer).
struct ProfileBuffers {
  std::vector<double> position_m, pressure_barg, pressure_est_barg;
};
mpdrig_PressureProfile ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                              double sim_time_s, const std::vector<double>& positions_m,
                              const std::vector<double>& pressure_pa,
                              const std::vector<double>& estimated_pa,
                              double atmospheric_pressure_pa, ProfileBuffers* buffers);

// A rig's status (rig_status.h); the wire struct points into `report` and `buffers`, which must
// outlive it. An empty sequence has no buffer.
struct StatusBuffers {
  std::vector<char*> warnings, active_effects, actuator_owners;
};
mpdrig_RigStatus ToWire(const RigStatusReport& report, StatusBuffers* buffers);

}  // namespace mpdrig::service
