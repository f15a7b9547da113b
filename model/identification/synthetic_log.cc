#include "model/identification/synthetic_log.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <string>

#include "model/analysis/measured_log.h"
#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig {
namespace {

// Portable uniform and normal draws (the standard distributions differ between libraries).
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double Uniform(double lo, double hi) {
    const double u = static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    return lo + (hi - lo) * u;
  }
  double Normal() {  // Box-Muller
    const double u1 = std::max(Uniform(0.0, 1.0), 1e-300);
    const double u2 = Uniform(0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// The lab's actuators take time, and the replay needs them to: a choke step is a smooth
// transition over kChokeTransitionS (its actuator could go faster, 90 deg/s, thesis 8.4), a pump
// step one over kPumpTransitionS (the pump's speed ramp). At the actuator's full rate the step
// sends a front of a few samples down the pipe, and at diagnose's grid (a time step of about one
// sample at 50 Hz) its sampled shape depends on where the steps fall: the fit's cost then has a
// dip of ~2% at exactly the generator's wave speed, a fingerprint of the grid that no real log
// has, and a texture of the same size around it that stalls the local fits.
constexpr double kChokeTransitionS = 0.5;
constexpr double kPumpTransitionS = 0.5;
constexpr double kPistonTaperS = 2.0;
constexpr double kLowAmplitude = 0.4;

struct Excitation {
  double piston_amp_m = 0.05;
  double sine_hz[2] = {0.15, 0.35};
  double sweep_lo_hz = 0.05, sweep_hi_hz = 0.8;
  std::vector<std::pair<double, double>> choke_steps;  // (time, deg)
  std::vector<std::pair<double, double>> pump_steps;   // (time, lpm)
  std::vector<SyntheticInterval> pump_stops;           // FT2 at 0 (SyntheticLogOptions)
  std::vector<SyntheticInterval> choke_closures;       // choke at 0 deg
  // SyntheticHeave::kIrregularSea: the tones (empty: the lab series).
  std::vector<double> sea_hz, sea_amplitude, sea_phase_rad;
};

// Raised-cosine taper: 0 at distance 0 from a join, 1 from `width` on, smooth in between.
double Taper(double distance, double width) {
  if (distance >= width) return 1.0;
  if (distance <= 0.0) return 0.0;
  return 0.5 * (1.0 - std::cos(std::numbers::pi * distance / width));
}

// The irregular sea's tones (SyntheticHeave::kIrregularSea), from their own stream.
void DrawSea(std::uint64_t seed, Excitation* e) {
  Random random(seed ^ 0x5eaULL * 0x2545f4914f6cdd1dULL);
  constexpr double kLowHz = 0.04, kHighHz = 0.5;
  const double peak_hz = random.Uniform(0.08, 0.15);
  const double bin_hz = (kHighHz - kLowHz) / kSeaTones;
  double variance = 0.0;
  for (int k = 0; k < kSeaTones; ++k) {
    const double f = kLowHz + bin_hz * (k + random.Uniform(0.0, 1.0));
    const double spectrum = std::pow(f, -5.0) * std::exp(-1.25 * std::pow(peak_hz / f, 4.0));
    e->sea_hz.push_back(f);
    e->sea_amplitude.push_back(std::sqrt(2.0 * spectrum * bin_hz));
    e->sea_phase_rad.push_back(random.Uniform(0.0, 2.0 * std::numbers::pi));
    variance += 0.5 * e->sea_amplitude.back() * e->sea_amplitude.back();
  }
  // The lab series' standard deviation at the same amplitude: about 0.5 piston_amp_m.
  const double scale = 0.5 * e->piston_amp_m / std::sqrt(variance);
  for (double& a : e->sea_amplitude) a *= scale;
}

double PistonAt(const Excitation& e, double duration, double t) {
  if (!e.sea_hz.empty()) {
    // The sea from rest: faded in over the first kPistonTaperS (the position and its velocity
    // continuous), and out over the last.
    double x = 0.0;
    for (std::size_t k = 0; k < e.sea_hz.size(); ++k) {
      x += e.sea_amplitude[k] *
           std::sin(2.0 * std::numbers::pi * e.sea_hz[k] * t + e.sea_phase_rad[k]);
    }
    return Taper(t, kPistonTaperS) * Taper(duration - t, kPistonTaperS) * x;
  }
  // First third: two sines; second third: a linear sweep; last third: the sines again, so the
  // scoring part of a diagnosis sees what the fitting part saw. Every part fades in and out over
  // kPistonTaperS, so the position and its velocity are continuous (a heave generator cannot
  // jump). A jump would send a pulse of a sample's width down the pipe: its sampled shape then
  // depends on where the solver's steps fall between samples, and the fit's cost in the wave
  // speed turns rough (measured: +-25% over 0.1% of c).
  const double third = duration / 3.0;
  const double w = 2.0 * std::numbers::pi;
  const double start = t < third ? 0.0 : t < 2.0 * third ? third : 2.0 * third;
  const double end = start + third;
  const double taper = Taper(t - start, kPistonTaperS) * Taper(end - t, kPistonTaperS);
  if (t < third || t >= 2.0 * third) {
    // The second half of each sines part at kLowAmplitude of the first: the same frequencies at
    // two amplitudes, so a damping that grows with the flow (helical friction) differs from one
    // that grows with the frequency (unsteady friction), as the lab's amplitude series do.
    const double middle = start + 0.5 * third;
    const double level =
        1.0 - (1.0 - kLowAmplitude) * Taper(t - middle + 0.5 * kPistonTaperS, kPistonTaperS);
    return taper * level * e.piston_amp_m *
           (0.6 * std::sin(w * e.sine_hz[0] * t) + 0.4 * std::sin(w * e.sine_hz[1] * t));
  }
  const double tau = t - third;
  const double rate = (e.sweep_hi_hz - e.sweep_lo_hz) / third;
  const double phase = w * (e.sweep_lo_hz * tau + 0.5 * rate * tau * tau);
  return taper * e.piston_amp_m * 0.8 * std::sin(phase);
}

// The level of a sequence of (time, level) steps at t, each step a raised-cosine transition
// over `transition_s` from the level before it (smooth: no kink for a sharp front to start from).
double Stepped(const std::vector<std::pair<double, double>>& steps, double t, double transition_s) {
  double value = steps.front().second;
  for (const auto& [time, level] : steps) {
    if (t <= time) break;
    value += (level - value) * Taper(t - time, transition_s);
  }
  return value;
}

// How far a regime's intervals hold at t: 1 inside one, 0 outside all, a raised-cosine
// transition over `transition_s` at each end inside the interval (as the steps: smooth).
double Held(const std::vector<SyntheticInterval>& intervals, double t, double transition_s) {
  double held = 0.0;
  for (const SyntheticInterval& interval : intervals) {
    held = std::max(held, Taper(t - interval.start_s, transition_s) *
                              Taper(interval.start_s + interval.duration_s - t, transition_s));
  }
  return held;
}

// A hidden effect (`setting`: its name and the values given) with its fitted parameters drawn
// from their own stream where not given, written into `truth`; its part of the description.
std::string DrawHiddenEffect(const EffectSetting& given, Random& random, RigParams& truth) {
  const EffectInfo* info = FindEffectInfo(given.name);
  MPDRIG_CHECK(info != nullptr);  // SyntheticLogOptions::Validate refused an unknown name
  EffectSetting setting{std::string(info->name), {}};
  std::ostringstream description;
  description.precision(4);
  description << info->name;
  for (const EffectParamInfo& param : info->params) {
    const double* value_given = given.Find(param.key);
    if (!param.fitted) {
      if (value_given != nullptr) {
        setting.values.emplace_back(std::string(param.key), *value_given);
        description << " " << param.key << "=" << *value_given;
      }
      continue;
    }
    double lo = param.default_value / 2.0, hi = param.default_value * 2.0;
    if (param.default_value == 0.0)
      lo = param.min_value, hi = param.min_value + 0.2 * (param.max_value - param.min_value);
    lo = std::max(lo, param.min_value);
    hi = std::min(hi, param.max_value);
    double value = random.Uniform(lo, hi);
    if (param.plausible_min > 0.0 && param.plausible_min < param.plausible_max) {
      // Log-uniform over the plausible range (it spans decades).
      value = param.plausible_min *
              std::pow(param.plausible_max / param.plausible_min, random.Uniform(0.0, 1.0));
    }
    // Drawn even where given: the next effect's draws stay those of the same seed.
    if (value_given != nullptr) value = *value_given;
    setting.values.emplace_back(std::string(param.key), value);
    description << " " << param.key << "=" << value;
  }
  truth.effects.push_back(std::move(setting));
  return description.str();
}

// The setting a hidden effect's spec ("NAME" or "NAME:key=value,...") gives, checked.
Result<EffectSetting> ParseHiddenEffect(const std::string& spec) {
  RigParams scratch;
  MPDRIG_RETURN_IF_ERROR(ApplyEffectSpec(&scratch, spec).Within("hidden effect '" + spec + "'"));
  MPDRIG_CHECK(scratch.effects.size() == 1);
  return scratch.effects.front();
}

bool HidesColumnSeparation(const SyntheticLogOptions& options) {
  for (const std::string& spec : options.hidden_effects) {
    if (spec.substr(0, spec.find(':')) == "column_separation") return true;
  }
  return false;
}

Excitation DrawExcitation(bool low_pressure, double duration_s, Random& random) {
  Excitation excitation;
  excitation.piston_amp_m = low_pressure ? random.Uniform(0.06, 0.1) : random.Uniform(0.03, 0.05);
  excitation.sine_hz[0] = random.Uniform(0.1, 0.2);
  excitation.sine_hz[1] = random.Uniform(0.3, 0.5);
  // Step tests: the choke and the pump alternate between a low and a high band every 8-14 s
  // (the pump a few seconds after the choke), so every step is a step of a few degrees or L/min
  // (uniform levels in one band could step by nothing, and a log without a real choke step says
  // nothing about the choke's dynamics).
  const double choke_bands[2][2] = {{low_pressure ? 40.0 : 28.0, low_pressure ? 48.0 : 30.0},
                                    {low_pressure ? 52.0 : 31.0, low_pressure ? 60.0 : 33.0}};
  const double pump_bands[2][2] = {{low_pressure ? 2.0 : 6.0, low_pressure ? 2.8 : 7.5},
                                   {low_pressure ? 3.2 : 8.5, low_pressure ? 4.0 : 10.0}};
  int band = 0;
  for (double t = 0.0; t < duration_s; t += random.Uniform(8.0, 14.0), band ^= 1) {
    excitation.choke_steps.emplace_back(t,
                                        random.Uniform(choke_bands[band][0], choke_bands[band][1]));
    excitation.pump_steps.emplace_back(t + random.Uniform(3.0, 6.0),
                                       random.Uniform(pump_bands[band][0], pump_bands[band][1]));
  }
  excitation.pump_steps.insert(excitation.pump_steps.begin(), {0.0, low_pressure ? 3.0 : 8.0});
  return excitation;
}

// The inputs as commanded, column by column, and the model's run on them.
struct CommandedRun {
  std::vector<std::pair<Channel, std::vector<double>>> inputs;
  RunResult run;
};

// Runs `truth` on the excitation's inputs as commanded (noise-free: the model sees the true
// inputs). A heave that would take the pressure below zero absolute (outside the model's range,
// thesis 11.5) is scaled down until it does not, as an operator would (column_separation logs
// keep the first try).
Result<CommandedRun> RunCommanded(const RigParams& truth, Excitation excitation,
                                  const riglog::RigLog& log, double duration_s, int cells) {
  SimulationOptions simulation;
  simulation.cells = cells;
  simulation.choke_input = ChokeInput::kMeasured;
  std::vector<double> position, choke, pump, outlet;
  Result<RunResult> run = Status::Error("not run");
  for (int attempt = 0; attempt < 6; ++attempt) {
    position.clear(), choke.clear(), pump.clear(), outlet.clear();
    for (double t : log.time_s) {
      position.push_back(PistonAt(excitation, duration_s, t));
      // A regime holds the step tests' input at 0 (a stopped pump, a closed choke).
      const double open = 1.0 - Held(excitation.choke_closures, t, kChokeTransitionS);
      const double running = 1.0 - Held(excitation.pump_stops, t, kPumpTransitionS);
      choke.push_back(
          units::ChokeDegToFrac(open * Stepped(excitation.choke_steps, t, kChokeTransitionS)));
      pump.push_back(
          units::LpmToM3ps(running * Stepped(excitation.pump_steps, t, kPumpTransitionS)));
      outlet.push_back(log.atmospheric_pressure_pa);
    }
    riglog::RigLog inputs = log;
    MPDRIG_RETURN_IF_ERROR(inputs.AddColumn(riglog::LabColumn(Channel::kPistonPosition), position));
    MPDRIG_RETURN_IF_ERROR(inputs.AddColumn(riglog::LabColumn(Channel::kChokePosition), choke));
    MPDRIG_RETURN_IF_ERROR(inputs.AddColumn(riglog::LabColumn(Channel::kFT2), pump));
    MPDRIG_RETURN_IF_ERROR(inputs.AddColumn(riglog::LabColumn(Channel::kC1), outlet));
    // The generator's inputs are exact: replayed as they are (no reconstruction).
    InputReplayOptions exact;
    exact.reconstruct_inputs = false;
    auto signals = SignalsFromLog(inputs, "synthetic", exact);
    if (!signals.ok()) return signals.status();
    run = Simulate(truth, simulation, *signals, log.time_s);
    if (run.ok() || run.status().code() != Status::Code::kModelRange) break;
    excitation.piston_amp_m *= 0.6;
    for (double& a : excitation.sea_amplitude) a *= 0.6;
  }
  if (!run.ok()) return run.status();
  return CommandedRun{{{Channel::kPistonPosition, std::move(position)},
                       {Channel::kChokePosition, std::move(choke)},
                       {Channel::kFT2, std::move(pump)},
                       {Channel::kC1, std::move(outlet)}},
                      *std::move(run)};
}

// The quiet per-kind sigmas of SyntheticLogOptions, drawn in the columns' order from the
// excitation's stream (the logs the identification tests were tuned on).
void AddQuietNoise(const SyntheticLogOptions& options, Channel channel, std::vector<double>& values,
                   Random& random) {
  const riglog::Quantity quantity = riglog::QuantityOf(channel);
  const double sigma = quantity == riglog::Quantity::kFlow       ? options.flow_noise_m3ps
                       : quantity == riglog::Quantity::kPosition ? options.piston_noise_m
                       : quantity == riglog::Quantity::kChokeOpening
                           ? units::ChokeDegToFrac(options.choke_noise_deg)
                           : options.pressure_noise_pa;
  for (double& v : values) v += sigma * random.Normal();
}

}  // namespace

Status SyntheticLogOptions::Validate() const {
  // Upper bounds: the log, its noise-free twin and the replay grid are held in memory, so an
  // absurd duration or rate would run out of memory or time instead of failing.
  if (!(duration_s >= 10.0 && duration_s <= kMaxSyntheticDurationS) ||
      !(rate_hz >= 10.0 && rate_hz <= kMaxSyntheticRateHz)) {
    std::ostringstream out;
    out << "synthetic log: duration " << duration_s << " s must be in [10, "
        << kMaxSyntheticDurationS << "] s and rate " << rate_hz << " Hz in [10, "
        << kMaxSyntheticRateHz << "] Hz";
    return Status::Error(out.str());
  }
  if (duration_s * rate_hz > kMaxSyntheticSamples) {
    std::ostringstream out;
    out << "synthetic log: duration x rate = " << duration_s * rate_hz << " samples, at most "
        << kMaxSyntheticSamples << " (held in memory)";
    return Status::Error(out.str());
  }
  if (sensor_noise) MPDRIG_RETURN_IF_ERROR(sensor_noise->Validate().Within("synthetic log"));
  for (const auto& [intervals, name] :
       {std::pair{&pump_stops, "pump stop"}, std::pair{&choke_closures, "choke closure"}}) {
    for (const SyntheticInterval& interval : *intervals) {
      // At least its two transitions long, and inside the log.
      if (!(interval.start_s >= 0.0 && interval.duration_s >= 2.0 * kPumpTransitionS &&
            interval.start_s + interval.duration_s <= duration_s)) {
        std::ostringstream out;
        out << "synthetic log: " << name << " at " << interval.start_s << " s for "
            << interval.duration_s << " s must lie inside the log (0 to " << duration_s
            << " s) and last at least " << 2.0 * kPumpTransitionS << " s";
        return Status::Error(out.str());
      }
    }
  }
  std::vector<std::string> names;
  for (const std::string& spec : hidden_effects) {
    auto setting = ParseHiddenEffect(spec);
    if (!setting.ok()) return setting.status();
    if (std::find(names.begin(), names.end(), setting->name) != names.end()) {
      return Status::Error("synthetic log: hidden effect '" + setting->name + "' given twice");
    }
    names.push_back(setting->name);
  }
  return Status::Ok();
}

Result<SyntheticLog> MakeSyntheticLog(const SyntheticLogOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  Random random(options.seed);
  // The effects' strengths come from a stream of their own, so a seed gives the same base
  // parameters, excitation and noise with and without hidden effects.
  Random effect_random(options.seed ^ 0x9e3779b97f4a7c15ULL);
  SyntheticLog result;
  RigParams& truth = result.truth;
  std::ostringstream description;
  description.precision(4);
  for (std::size_t i = 0; i < options.hidden_effects.size(); ++i) {
    auto setting = ParseHiddenEffect(options.hidden_effects[i]);
    MPDRIG_CHECK(setting.ok());  // Validate parsed it
    description << (i > 0 ? " + " : "") << DrawHiddenEffect(*setting, effect_random, truth);
  }
  if (options.hidden_effects.empty()) description << "no hidden effect";
  if (options.perturb_base) {
    truth.wave_speed_mps *= random.Uniform(0.9, 1.1);
    truth.friction_f1_per_s *= random.Uniform(0.7, 1.3);
    truth.choke_leak_m2 *= random.Uniform(0.7, 1.3);
  }
  description << "; wave speed " << truth.wave_speed_mps << " m/s, f1 " << truth.friction_f1_per_s
              << " 1/s, choke leak " << truth.choke_leak_m2 << " m^2";
  result.description = description.str();

  // Column separation needs low pressure to show: an open choke and little pump flow, as in the
  // runs where the thesis's model went below zero absolute pressure (11.5).
  const bool low_pressure = options.low_pressure.value_or(HidesColumnSeparation(options));
  Excitation excitation = DrawExcitation(low_pressure, options.duration_s, random);
  if (options.heave == SyntheticHeave::kIrregularSea) DrawSea(options.seed, &excitation);
  excitation.pump_stops = options.pump_stops;
  excitation.choke_closures = options.choke_closures;

  riglog::RigLog& log = result.log;
  log.metadata.push_back({"source", "mpdrig synthetic log, seed " + std::to_string(options.seed)});
  const long count = std::lround(options.duration_s * options.rate_hz);
  for (long i = 0; i <= count; ++i) log.time_s.push_back(i / options.rate_hz);
  Result<CommandedRun> commanded =
      RunCommanded(truth, excitation, log, options.duration_s, options.cells);
  if (!commanded.ok()) {
    return commanded.status().Within("synthetic log (" + result.description + ")");
  }

  // The truth: the same run without sensor noise, column for column.
  std::vector<std::pair<Channel, std::vector<double>>> clean = std::move(commanded->inputs);
  for (Channel channel : ComparedChannels()) {
    std::vector<double> values;
    values.reserve(commanded->run.samples.size());
    for (const RigSample& sample : commanded->run.samples) values.push_back(sample[channel]);
    clean.emplace_back(channel, std::move(values));
  }
  result.truth_log = log;
  for (const auto& [channel, values] : clean) {
    MPDRIG_RETURN_IF_ERROR(result.truth_log.AddColumn(riglog::LabColumn(channel), values));
  }

  // ...and measured with noise (inputs too: the lab measures them).
  std::optional<SensorNoiseApplier> sensors;
  if (options.sensor_noise) sensors.emplace(*options.sensor_noise, options.seed);
  for (auto& [channel, values] : clean) {
    if (sensors) {
      sensors->MeasureColumn(channel, values);
    } else {
      AddQuietNoise(options, channel, values, random);
    }
    MPDRIG_RETURN_IF_ERROR(log.AddColumn(riglog::LabColumn(channel), std::move(values)));
  }
  return result;
}

}  // namespace mpdrig
