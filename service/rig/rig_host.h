// One virtual rig as the service runs it: the simulator, the commands in force, and what was
// refused. Transport-free: the DDS adapter translates wire samples to these calls, and tests can
// drive a rig without DDS. Time is the rig's own (ticks of the sensor period); the scheduler that
// paces ticks against the wall clock lives elsewhere.
//
// Commands mirror the lab's actuators (lab units): choke opening reference in degrees (through
// the actuator lag and rate limit), heave generator (hold, a streamed position reference, or a
// sine or sweep generated here), back-pressure pump flow in L/min, choke outlet pressure in barg.
// A command with NaN, infinity or a value outside its range is refused: counted, its reason kept,
// and the last valid command stays in force (design.md, Errors).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig::service {

class LogPlayback;  // log_playback.h

// What the service accepts: physical limits of the lab rig, not tuning ranges.
struct CommandLimits {
  double choke_min_deg = 0.0, choke_max_deg = 90.0;
  double pump_min_lpm = 0.0, pump_max_lpm = 60.0;         // the lab's pump gives ~30 L/min
  double outlet_min_barg = -0.5, outlet_max_barg = 16.0;  // transmitters read 0..16 bar
  double piston_max_abs_m = 0.6;  // BHA travel in the 1.7 m compartment (Table 8.1.1)
  double piston_max_frequency_hz = 2.0;
};

struct PistonCommandIn {
  enum class Mode { kHold, kPosition, kSine, kSweep };
  Mode mode = Mode::kHold;
  double position_m = 0.0;
  double mean_m = 0.0;
  double amplitude_m = 0.0;
  double frequency_hz = 0.0;
  double sweep_end_hz = 0.0;
  double sweep_duration_s = 0.0;
};

// The commands a rig starts with; it starts in their steady state (pipe at rest, pump flow
// through the choke: RigSimulator's initial state).
struct InitialCommands {
  double choke_deg = 31.0;  // the thesis's usual opening
  double pump_lpm = 0.0;
  double outlet_barg = 0.0;
};

// What the rig's sensors add to the model's channels (model/sim/sensor_noise.h): every channel
// of a sample (Tick) is what a sensor reads, the observer beside the rig and every client see
// the same noisy values, as on the real rig; the commands and the model's state never carry
// noise. The default here is none (the model's output as is: what the service's physics tests
// check); `mpdrig serve` defaults to the lab's (thesis Table 4.1.1).
struct SensorOptions {
  SensorNoise noise;
  // Each rig draws its own noise from this seed and its rig id (MixSeed), so two rigs of one
  // service do not read the same numbers, and a rig reads the same ones in every run.
  std::uint64_t seed = 1;
};

struct RigCounters {
  std::uint64_t samples = 0;
  std::uint64_t rejected_commands = 0;
  std::string last_rejection;
  std::string last_event;  // e.g. "t = 12.3 s: no choke controller left: choke to 90 deg"
};

class RigHost {
 public:
  static Result<RigHost> Create(std::string rig_id, const RigParams& params,
                                SimulationOptions options, double sensor_rate_hz,
                                InitialCommands initial = {}, CommandLimits limits = {},
                                SensorOptions sensors = {});

  // A rig that plays a recorded log (log_playback.h) instead of simulating: each Tick is the
  // log's next row, as recorded (no sensor noise added); every command is refused with the
  // reason (it is a recording); `params` give the atmospheric pressure of the lab units (the
  // log's) and the observer's model.
  static Result<RigHost> CreatePlayback(std::string rig_id, RigParams params,
                                        SimulationOptions options,
                                        std::shared_ptr<LogPlayback> playback);
  const LogPlayback* playback() const { return playback_.get(); }
  // A playback whose last row has gone out (a simulated rig never finishes).
  bool finished() const;

  const std::string& rig_id() const { return rig_id_; }
  double sensor_period_s() const { return period_s_; }
  double time_s() const { return time_s_; }
  const RigCounters& counters() const { return counters_; }
  const RigParams& params() const { return sampler_.simulator().params(); }
  const SensorOptions& sensor_options() const { return sensor_options_; }
  // "none", or the noise's text form and the seed: "lab, seed 1" (the status topic).
  std::string DescribeSensorNoise() const;

  // Each returns OK if the command is now in force, or the reason it was refused (also counted
  // and kept in counters().last_rejection).
  Status SetChokeDeg(double opening_deg);
  Status SetPumpLpm(double flow_lpm);
  Status SetOutletBarg(double pressure_barg);
  Status SetPiston(const PistonCommandIn& command);
  // A refusal decided outside the rig (e.g. a command for another rig id): counted the same way;
  // `count` such commands at once, the last of them for `reason`.
  Status Refuse(const std::string& reason, std::uint64_t count = 1);
  // Notes an event the status should carry (e.g. a safe state taken), with the rig time.
  void NoteEvent(const std::string& what);
  // The first departure from the model's range, if any (the rig keeps running and reports it).
  const std::optional<RangeEvent>& range_event() const {
    return sampler_.simulator().first_range_event();
  }
  double choke_command_deg() const;
  double pump_command_lpm() const;
  double outlet_command_barg() const;
  const PistonCommandIn& piston_command() const { return piston_; }
  // The heave generator's sine frequency while it runs one with a non-zero amplitude: what the
  // observer's disturbance model needs (rig_observer.h).
  std::optional<double> piston_sine_hz() const;
  // Where each sample's pressure_at_positions_pa is taken along the pipe [m from the inlet]: the
  // pressure-profile topic. SimulationOptions::pressure_positions_m, or by default
  // kDefaultProfilePoints points evenly from the inlet to the outlet.
  const std::vector<double>& pressure_positions_m() const { return positions_m_; }
  static constexpr int kDefaultProfilePoints = 19;  // every 50 m on the 900 m pipe

  // Advances one sensor period with the commands in force and returns every channel then, as
  // the sensors read it (SensorOptions; the extra pressure positions stay the model's).
  // Fails only when the simulation itself fails (solver, or the model range if the options stop
  // on it); the caller reports that and may keep the rig's last state.
  Result<RigSample> Tick();

 private:
  RigHost(std::string rig_id, RigSampler sampler, double period_s, CommandLimits limits,
          RigInputs inputs, std::vector<double> positions_m, SensorOptions sensors);
  double PistonPositionAt(double time_s) const;
  Status RefuseRecorded(const char* what);

  std::string rig_id_;
  RigSampler sampler_;
  double period_s_;
  CommandLimits limits_;
  RigInputs inputs_;        // choke reference, pump, outlet (SI)
  PistonCommandIn piston_;  // in force since piston_since_s_
  double piston_since_s_ = 0.0;
  double piston_from_m_ = 0.0;  // position when the command arrived (ramps and holds start here)
  double time_s_ = 0.0;
  RigCounters counters_;
  std::vector<double> positions_m_;
  SensorOptions sensor_options_;
  SensorNoiseApplier sensors_;
  std::shared_ptr<LogPlayback> playback_;  // null: a simulated rig
};

}  // namespace mpdrig::service
