#include "service/rig/rig_host.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "model/common/units.h"
#include "service/rig/log_playback.h"

namespace mpdrig::service {
namespace {

std::string OutOfRange(const char* what, double value, double lo, double hi, const char* unit) {
  std::ostringstream out;
  out << what << " " << value << " " << unit << " refused: ";
  if (std::isnan(value)) {
    out << "not a number";
  } else if (std::isinf(value)) {
    out << "infinite";
  } else {
    out << "outside [" << lo << ", " << hi << "] " << unit;
  }
  return out.str();
}

bool Within(double value, double lo, double hi) { return value >= lo && value <= hi; }

}  // namespace

Result<RigHost> RigHost::Create(std::string rig_id, const RigParams& params,
                                SimulationOptions options, double sensor_rate_hz,
                                InitialCommands initial, CommandLimits limits,
                                SensorOptions sensors) {
  if (!(sensor_rate_hz > 0.0 && sensor_rate_hz <= 10000.0)) {
    return Status::Error("sensor rate must be in (0, 10000] Hz");
  }
  if (rig_id.empty()) return Status::Error("rig id must not be empty");
  MPDRIG_RETURN_IF_ERROR(sensors.noise.Validate());
  // A running rig reports leaving the model's range instead of stopping (design.md, Errors).
  options.stop_on_range_violation = false;
  options.choke_input = ChokeInput::kReference;
  if (options.pressure_positions_m.empty()) {
    for (int i = 0; i < kDefaultProfilePoints; ++i) {
      options.pressure_positions_m.push_back(params.pipe_length_m * i /
                                             (kDefaultProfilePoints - 1));
    }
  }
  if (!Within(initial.choke_deg, limits.choke_min_deg, limits.choke_max_deg) ||
      !Within(initial.pump_lpm, limits.pump_min_lpm, limits.pump_max_lpm) ||
      !Within(initial.outlet_barg, limits.outlet_min_barg, limits.outlet_max_barg)) {
    return Status::Error("initial commands outside the rig's limits");
  }
  RigInputs inputs;
  inputs.choke_opening_frac = units::ChokeDegToFrac(initial.choke_deg);
  inputs.pump_flow_m3ps = units::LpmToM3ps(initial.pump_lpm);
  inputs.outlet_pressure_pa =
      units::BargToPaAbs(initial.outlet_barg, params.atmospheric_pressure_pa);
  auto simulator = RigSimulator::Create(params, options, inputs);
  if (!simulator.ok()) return simulator.status();
  return RigHost(std::move(rig_id), RigSampler(std::move(simulator).value()), 1.0 / sensor_rate_hz,
                 limits, inputs, options.pressure_positions_m, sensors);
}

Result<RigHost> RigHost::CreatePlayback(std::string rig_id, RigParams params,
                                        SimulationOptions options,
                                        std::shared_ptr<LogPlayback> playback) {
  if (playback == nullptr) return Status::Error("playback without a log");
  params.atmospheric_pressure_pa = playback->atmospheric_pressure_pa();
  auto rig = Create(std::move(rig_id), params, std::move(options), 1.0 / playback->period_s());
  if (!rig.ok()) return rig.status();
  rig->playback_ = std::move(playback);
  return rig;
}

bool RigHost::finished() const { return playback_ != nullptr && playback_->finished(); }

RigHost::RigHost(std::string rig_id, RigSampler sampler, double period_s, CommandLimits limits,
                 RigInputs inputs, std::vector<double> positions_m, SensorOptions sensors)
    : rig_id_(std::move(rig_id)),
      sampler_(std::move(sampler)),
      period_s_(period_s),
      limits_(limits),
      inputs_(inputs),
      positions_m_(std::move(positions_m)),
      sensor_options_(sensors),
      sensors_(sensors.noise, MixSeed(sensors.seed, rig_id_)) {}

std::string RigHost::DescribeSensorNoise() const {
  if (playback_) return "as recorded: playback of " + playback_->Describe();
  if (sensor_options_.noise.IsNone()) return "none";
  return sensor_options_.noise.ToSpec() + ", seed " + std::to_string(sensor_options_.seed);
}

std::optional<double> RigHost::piston_sine_hz() const {
  if (piston_.mode == PistonCommandIn::Mode::kSine && piston_.frequency_hz > 0.0 &&
      piston_.amplitude_m != 0.0) {
    return piston_.frequency_hz;
  }
  return std::nullopt;
}

Status RigHost::RefuseRecorded(const char* what) {
  return Refuse(std::string(what) + " refused: rig " + rig_id_ + " plays back a recording (" +
                playback_->path() + "); it takes no commands");
}

Status RigHost::Refuse(const std::string& reason, std::uint64_t count) {
  counters_.rejected_commands += count;
  counters_.last_rejection = reason;
  return Status::Error(reason);
}

void RigHost::NoteEvent(const std::string& what) {
  std::ostringstream out;
  out << "t = " << time_s_ << " s: " << what;
  counters_.last_event = out.str();
}

double RigHost::choke_command_deg() const {
  return units::ChokeFracToDeg(inputs_.choke_opening_frac);
}
double RigHost::pump_command_lpm() const { return units::M3psToLpm(inputs_.pump_flow_m3ps); }
double RigHost::outlet_command_barg() const {
  return units::PaAbsToBarg(inputs_.outlet_pressure_pa, params().atmospheric_pressure_pa);
}

Status RigHost::SetChokeDeg(double opening_deg) {
  if (playback_) return RefuseRecorded("choke command");
  if (!Within(opening_deg, limits_.choke_min_deg, limits_.choke_max_deg)) {
    return Refuse(OutOfRange("choke opening", opening_deg, limits_.choke_min_deg,
                             limits_.choke_max_deg, "deg"));
  }
  inputs_.choke_opening_frac = units::ChokeDegToFrac(opening_deg);
  return Status::Ok();
}

Status RigHost::SetPumpLpm(double flow_lpm) {
  if (playback_) return RefuseRecorded("pump command");
  if (!Within(flow_lpm, limits_.pump_min_lpm, limits_.pump_max_lpm)) {
    return Refuse(
        OutOfRange("pump flow", flow_lpm, limits_.pump_min_lpm, limits_.pump_max_lpm, "L/min"));
  }
  inputs_.pump_flow_m3ps = units::LpmToM3ps(flow_lpm);
  return Status::Ok();
}

Status RigHost::SetOutletBarg(double pressure_barg) {
  if (playback_) return RefuseRecorded("outlet command");
  if (!Within(pressure_barg, limits_.outlet_min_barg, limits_.outlet_max_barg)) {
    return Refuse(OutOfRange("outlet pressure", pressure_barg, limits_.outlet_min_barg,
                             limits_.outlet_max_barg, "barg"));
  }
  inputs_.outlet_pressure_pa = units::BargToPaAbs(pressure_barg, params().atmospheric_pressure_pa);
  return Status::Ok();
}

Status RigHost::SetPiston(const PistonCommandIn& command) {
  if (playback_) return RefuseRecorded("piston command");
  using Mode = PistonCommandIn::Mode;
  const double x_max = limits_.piston_max_abs_m;
  const double f_max = limits_.piston_max_frequency_hz;
  switch (command.mode) {
    case Mode::kHold:
      break;
    case Mode::kPosition:
      if (!Within(command.position_m, -x_max, x_max)) {
        return Refuse(OutOfRange("piston position", command.position_m, -x_max, x_max, "m"));
      }
      break;
    case Mode::kSweep:
      if (!Within(command.sweep_end_hz, 0.0, f_max)) {
        return Refuse(OutOfRange("piston sweep end", command.sweep_end_hz, 0.0, f_max, "Hz"));
      }
      if (!(command.sweep_duration_s > 0.0 && std::isfinite(command.sweep_duration_s))) {
        return Refuse(
            OutOfRange("piston sweep duration", command.sweep_duration_s, 0.0, INFINITY, "s"));
      }
      [[fallthrough]];
    case Mode::kSine:
      if (!Within(command.frequency_hz, 0.0, f_max)) {
        return Refuse(OutOfRange("piston frequency", command.frequency_hz, 0.0, f_max, "Hz"));
      }
      if (!(std::isfinite(command.mean_m) && std::isfinite(command.amplitude_m) &&
            std::fabs(command.mean_m) + std::fabs(command.amplitude_m) <= x_max)) {
        return Refuse(OutOfRange("piston |mean| + |amplitude|",
                                 std::fabs(command.mean_m) + std::fabs(command.amplitude_m), 0.0,
                                 x_max, "m"));
      }
      break;
  }
  piston_from_m_ = PistonPositionAt(time_s_);
  piston_ = command;
  piston_since_s_ = time_s_;
  return Status::Ok();
}

double RigHost::PistonPositionAt(double t) const {
  using Mode = PistonCommandIn::Mode;
  const double since = t - piston_since_s_;
  switch (piston_.mode) {
    case Mode::kHold:
      return piston_from_m_;
    case Mode::kPosition: {
      // The generator follows a streamed reference: a ramp to it over one sensor period, so the
      // displaced flow stays finite.
      const double w = std::clamp(since / period_s_, 0.0, 1.0);
      return piston_from_m_ + w * (piston_.position_m - piston_from_m_);
    }
    case Mode::kSine:
      return piston_.mean_m +
             piston_.amplitude_m * std::sin(2.0 * std::numbers::pi * piston_.frequency_hz * since);
    case Mode::kSweep: {
      const double tc = std::clamp(since, 0.0, piston_.sweep_duration_s);
      double phase =
          2.0 * std::numbers::pi *
          (piston_.frequency_hz * tc + 0.5 * (piston_.sweep_end_hz - piston_.frequency_hz) * tc *
                                           tc / piston_.sweep_duration_s);
      if (since > piston_.sweep_duration_s) {
        phase += 2.0 * std::numbers::pi * piston_.sweep_end_hz * (since - piston_.sweep_duration_s);
      }
      return piston_.mean_m + piston_.amplitude_m * std::sin(phase);
    }
  }
  return piston_from_m_;
}

Result<RigSample> RigHost::Tick() {
  if (playback_) {
    auto row = playback_->Next(positions_m_.size());
    if (!row.ok()) return row.status();
    time_s_ = row->time_s;
    ++counters_.samples;
    return row;
  }
  const double target = time_s_ + period_s_;
  auto sample = sampler_.SampleAt(target, [this](double t_b, double dt) {
    StepInputs step;
    step.piston_velocity_mps =
        (PistonPositionAt(t_b + 0.5 * dt) - PistonPositionAt(t_b - 0.5 * dt)) / dt;
    step.piston_position_m = PistonPositionAt(t_b);
    step.rig = inputs_;
    return step;
  });
  if (!sample.ok()) return sample.status();
  // The sampler interpolates between simulator steps, the newer of which may have been computed
  // (up to one step, l/(N c) = 5.3 ms, ahead) with the commands before this tick's. The pure
  // inputs, pump flow FT2 and outlet pressure C1, are what the commands say now: the lab's pump
  // and pressure regulator follow a command at once, and a controller sees its command in the
  // next sample. FT3 = FT1 + FT2 stays consistent; the pipe answers on the model's next step.
  sample->values[Index(Channel::kFT2)] = inputs_.pump_flow_m3ps;
  sample->values[Index(Channel::kFT3)] = (*sample)[Channel::kFT1] + inputs_.pump_flow_m3ps;
  sample->values[Index(Channel::kC1)] = inputs_.outlet_pressure_pa;
  sensors_.MeasureSample(&*sample);
  time_s_ = target;
  ++counters_.samples;
  return sample;
}

}  // namespace mpdrig::service
