#include "service/rig/wire.h"

#include "model/common/units.h"

namespace mpdrig::service {

Status CheckRigId(std::string_view rig_id) {
  bool printable = true;
  for (char c : rig_id) printable = printable && c >= '!' && c <= '~';
  if (!rig_id.empty() && rig_id.size() <= kMaxRigIdBytes && printable) return Status::Ok();
  std::string shown;
  for (char c : rig_id.substr(0, 64)) shown += c >= ' ' && c <= '~' ? c : '?';
  return Status::Error("rig id '" + shown + (rig_id.size() > 64 ? "...' (" : "' (") +
                       std::to_string(rig_id.size()) + " bytes): a rig id is 1 to " +
                       std::to_string(kMaxRigIdBytes) +
                       " bytes of printable ASCII without spaces ('!' .. '~')");
}

mpdrig_RigSensors ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                         const RigSample& s, double atmosphere_pa) {
  auto barg = [atmosphere_pa](double pa) { return units::PaAbsToBarg(pa, atmosphere_pa); };
  mpdrig_RigSensors wire{};
  wire.rig_id = const_cast<char*>(rig_id.c_str());  // written, never freed or changed by DDS
  wire.sample_counter = sample_counter;
  wire.sim_time_s = s.time_s;
  wire.piston_position_m = s[Channel::kPistonPosition];
  wire.choke_position_deg = units::ChokeFracToDeg(s[Channel::kChokePosition]);
  wire.P1_barg = barg(s[Channel::kP1]);
  wire.P2_barg = barg(s[Channel::kP2]);
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    wire.PT_barg[k] = barg(s.values[Index(Channel::kPT1) + k]);
  }
  wire.C1_barg = barg(s[Channel::kC1]);
  wire.C2_barg = barg(s[Channel::kC2]);
  wire.FT1_lpm = units::M3psToLpm(s[Channel::kFT1]);
  wire.FT2_lpm = units::M3psToLpm(s[Channel::kFT2]);
  wire.FT3_lpm = units::M3psToLpm(s[Channel::kFT3]);
  wire.FT4_lpm = units::M3psToLpm(s[Channel::kFT4]);
  return wire;
}

RigSample FromWire(const mpdrig_RigSensors& wire, double atmosphere_pa) {
  auto pa = [atmosphere_pa](double barg) { return units::BargToPaAbs(barg, atmosphere_pa); };
  RigSample s;
  s.time_s = wire.sim_time_s;
  auto& v = s.values;
  v[Index(Channel::kTime)] = wire.sim_time_s;
  v[Index(Channel::kPistonPosition)] = wire.piston_position_m;
  v[Index(Channel::kChokePosition)] = units::ChokeDegToFrac(wire.choke_position_deg);
  v[Index(Channel::kP1)] = pa(wire.P1_barg);
  v[Index(Channel::kP2)] = pa(wire.P2_barg);
  for (int k = 0; k < kPipeTransmitterCount; ++k) v[Index(Channel::kPT1) + k] = pa(wire.PT_barg[k]);
  v[Index(Channel::kC1)] = pa(wire.C1_barg);
  v[Index(Channel::kC2)] = pa(wire.C2_barg);
  v[Index(Channel::kFT1)] = units::LpmToM3ps(wire.FT1_lpm);
  v[Index(Channel::kFT2)] = units::LpmToM3ps(wire.FT2_lpm);
  v[Index(Channel::kFT3)] = units::LpmToM3ps(wire.FT3_lpm);
  v[Index(Channel::kFT4)] = units::LpmToM3ps(wire.FT4_lpm);
  return s;
}

PistonCommandIn FromWire(const mpdrig_PistonCommand& wire) {
  PistonCommandIn command;
  switch (wire.mode) {
    case mpdrig_PISTON_HOLD:
      command.mode = PistonCommandIn::Mode::kHold;
      break;
    case mpdrig_PISTON_POSITION:
      command.mode = PistonCommandIn::Mode::kPosition;
      break;
    case mpdrig_PISTON_SINE:
      command.mode = PistonCommandIn::Mode::kSine;
      break;
    case mpdrig_PISTON_SWEEP:
      command.mode = PistonCommandIn::Mode::kSweep;
      break;
  }
  command.position_m = wire.position_m;
  command.mean_m = wire.mean_m;
  command.amplitude_m = wire.amplitude_m;
  command.frequency_hz = wire.frequency_hz;
  command.sweep_end_hz = wire.sweep_end_hz;
  command.sweep_duration_s = wire.sweep_duration_s;
  return command;
}

mpdrig_RigEstimate ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                          double sim_time_s, const RigObserverEstimate& in, double atmosphere_pa) {
  const observer::ObserverEstimate& e = in.estimate;
  mpdrig_RigEstimate wire{};
  wire.rig_id = const_cast<char*>(rig_id.c_str());  // written, never freed or changed by DDS
  wire.sample_counter = sample_counter;
  wire.sim_time_s = sim_time_s;
  wire.observer_time_s = e.time_s;
  wire.BHP_est_barg = units::PaAbsToBarg(e.bhp_pa, atmosphere_pa);
  wire.piston_velocity_est_mps = e.piston_velocity_mps;
  wire.piston_position_est_m = e.piston_position_m;
  wire.FT4_est_lpm = units::M3psToLpm(e.inlet_flow_m3ps);
  wire.disturbance_frequency_hz = e.disturbance_hz;
  switch (in.frequency_source) {
    case FrequencySource::kPistonSine:
      wire.frequency_source = mpdrig_FREQUENCY_PISTON_SINE;
      break;
    case FrequencySource::kTracked:
      wire.frequency_source = mpdrig_FREQUENCY_TRACKED;
      break;
    case FrequencySource::kUnlocked:
      wire.frequency_source = mpdrig_FREQUENCY_UNLOCKED;
      break;
  }
  return wire;
}

mpdrig_PressureProfile ToWire(const std::string& rig_id, std::uint64_t sample_counter,
                              double sim_time_s, const std::vector<double>& positions_m,
                              const std::vector<double>& pressure_pa,
                              const std::vector<double>& estimated_pa, double atmosphere_pa,
                              ProfileBuffers* buffers) {
  buffers->position_m = positions_m;
  buffers->pressure_barg.clear();
  for (double p : pressure_pa)
    buffers->pressure_barg.push_back(units::PaAbsToBarg(p, atmosphere_pa));
  buffers->pressure_est_barg.clear();
  for (double p : estimated_pa) {
    buffers->pressure_est_barg.push_back(units::PaAbsToBarg(p, atmosphere_pa));
  }
  // Sequences that borrow the buffers: _release = false, DDS never frees them.
  auto borrow = [](std::vector<double>& v) {
    dds_sequence_double seq{};
    seq._maximum = seq._length = static_cast<std::uint32_t>(v.size());
    seq._buffer = v.empty() ? nullptr : v.data();
    seq._release = false;
    return seq;
  };
  mpdrig_PressureProfile wire{};
  wire.rig_id = const_cast<char*>(rig_id.c_str());
  wire.sample_counter = sample_counter;
  wire.sim_time_s = sim_time_s;
  wire.position_m = borrow(buffers->position_m);
  wire.pressure_barg = borrow(buffers->pressure_barg);
  wire.pressure_est_barg = borrow(buffers->pressure_est_barg);
  return wire;
}

namespace {

// A sequence<string> that points into `texts` through `pointers` (DDS only reads it).
dds_sequence_string StringSequence(const std::vector<std::string>& texts,
                                   std::vector<char*>* pointers) {
  pointers->clear();
  for (const std::string& text : texts) pointers->push_back(const_cast<char*>(text.c_str()));
  dds_sequence_string sequence{};
  sequence._length = sequence._maximum = static_cast<std::uint32_t>(pointers->size());
  sequence._buffer = pointers->empty() ? nullptr : pointers->data();
  sequence._release = false;
  return sequence;
}

}  // namespace

mpdrig_RigStatus ToWire(const RigStatusReport& report, StatusBuffers* buffers) {
  mpdrig_RigStatus wire{};
  wire.rig_id = const_cast<char*>(report.rig_id.c_str());  // written, never freed or changed
  wire.clock = report.clock == ClockMode::kRealtime ? mpdrig_CLOCK_REALTIME
               : report.clock == ClockMode::kFast   ? mpdrig_CLOCK_FAST
                                                    : mpdrig_CLOCK_LOCKSTEP;
  wire.sim_time_s = report.sim_time_s;
  wire.real_time_factor = report.real_time_factor;
  wire.deadline_misses = report.deadline_misses;
  wire.lost_periods = report.lost_periods;
  wire.longest_stall_s = report.longest_stall_s;
  wire.last_stall_sim_time_s = report.last_stall_sim_time_s;
  wire.atmospheric_pressure_pa = report.atmospheric_pressure_pa;
  wire.rejected_commands = report.rejected_commands;
  wire.last_rejection = const_cast<char*>(report.last_rejection.c_str());
  wire.last_completed_step_request = report.last_completed_step_request;
  wire.warnings = StringSequence(report.warnings, &buffers->warnings);
  wire.active_effects = StringSequence(report.active_effects, &buffers->active_effects);
  wire.actuator_owners = StringSequence(report.actuator_owners, &buffers->actuator_owners);
  wire.sensor_noise = const_cast<char*>(report.sensor_noise.c_str());
  return wire;
}

}  // namespace mpdrig::service
