#include "clients/client/client_wire.h"

#include <string>
#include <vector>

namespace mpdrig::client {
namespace {

std::vector<double> FromSequence(const dds_sequence_double& seq) {
  return std::vector<double>(seq._buffer, seq._buffer + seq._length);
}

std::vector<std::string> FromSequence(const dds_sequence_string& seq) {
  std::vector<std::string> out;
  out.reserve(seq._length);
  for (std::uint32_t i = 0; i < seq._length; ++i) out.emplace_back(seq._buffer[i]);
  return out;
}

}  // namespace

Sensors FromWire(const mpdrig_RigSensors& s, const dds_sample_info_t& info) {
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
  out.published_s = 1e-9 * static_cast<double>(info.source_timestamp);
  return out;
}

Estimate FromWire(const mpdrig_RigEstimate& e) {
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
  return out;
}

Profile FromWire(const mpdrig_PressureProfile& p) {
  Profile out;
  out.sample_counter = p.sample_counter;
  out.time_s = p.sim_time_s;
  out.position_m = FromSequence(p.position_m);
  out.pressure_barg = FromSequence(p.pressure_barg);
  out.pressure_est_barg = FromSequence(p.pressure_est_barg);
  return out;
}

RigStatus FromWire(const mpdrig_RigStatus& s) {
  RigStatus out;
  out.clock = s.clock == mpdrig_CLOCK_REALTIME ? "realtime"
              : s.clock == mpdrig_CLOCK_FAST   ? "fast"
                                               : "lockstep";
  out.sim_time_s = s.sim_time_s;
  out.real_time_factor = s.real_time_factor;
  out.deadline_misses = s.deadline_misses;
  out.lost_periods = s.lost_periods;
  out.longest_stall_s = s.longest_stall_s;
  out.last_stall_sim_time_s = s.last_stall_sim_time_s;
  out.rejected_commands = s.rejected_commands;
  out.last_rejection = s.last_rejection;
  out.last_completed_step_request = s.last_completed_step_request;
  out.warnings = FromSequence(s.warnings);
  out.active_effects = FromSequence(s.active_effects);
  out.actuator_owners = FromSequence(s.actuator_owners);
  out.sensor_noise = s.sensor_noise;
  out.atmospheric_pressure_pa = s.atmospheric_pressure_pa;
  return out;
}

ShadowStatus FromWire(const mpdrig_ShadowStatus& w) {
  ShadowStatus out;
  out.rig_id = w.rig_id;
  out.shadow_id = w.shadow_id;
  out.sim_time_s = w.sim_time_s;
  out.window_s = w.window_s;
  out.error = w.error;
  out.channels = FromSequence(w.channels);
  out.nrmse = FromSequence(w.nrmse);
  out.active_effects = FromSequence(w.active_effects);
  out.parameters = FromSequence(w.parameters);
  out.available_effects = FromSequence(w.available_effects);
  out.last_change = w.last_change;
  out.last_change_sim_time_s = w.last_change_sim_time_s;
  out.error_at_last_change = w.error_at_last_change;
  out.rejected_commands = w.rejected_commands;
  out.last_rejection = w.last_rejection;
  out.last_command_id = w.last_command_id;
  out.fit_state = w.fit_state;
  return out;
}

}  // namespace mpdrig::client
