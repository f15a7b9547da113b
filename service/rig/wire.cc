#include "service/rig/wire.h"

#include "model/common/units.h"

namespace mpdrig::service {

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

}  // namespace mpdrig::service
