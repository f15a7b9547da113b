// Synthetic lab logs with hidden effects (the test data of diagnose, and a way for a user to try
// `diagnose` on data whose answer is known): the model with one or more catalogue effects
// switched on at random (or given) strengths, perturbed base parameters, the lab's kind of
// excitation and sensor noise.
//
// Excitation (what the lab runs): piston sines at two frequencies (each sines part at a full and
// then a lower amplitude), a sweep, choke steps, pump flow steps between two levels. Every
// change is smooth (tapered piston joins, 0.5 s choke and pump transitions): the model is
// replayed on a grid whose time step is about a sample, and a jump would leave the grid's
// fingerprint in the log (synthetic_log.cc). Noise: white, Gaussian, per channel kind, on the
// inputs too (the model replays them as measured); the noise-free log comes with it.
// Heave, on request: an irregular sea instead of the sines and the sweep (SyntheticHeave).
// Regimes, on request: the back-pressure pump stopped for a while (FT2 ramps to 0 and back), the
// choke closed for a while (to 0 deg, where only its leak passes, and back): a rig's log holds
// such stops besides its step tests, and they change what the pipe does (no flow through the
// choke, a closed outlet). Without them the excitation above runs throughout.
// Deterministic for a seed (std::mt19937_64 with explicit distributions written out here, so the
// same seed gives the same log with any standard library).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/riglog/rig_log.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig {

// Limits of a synthetic log (held in memory twice, with the replay beside it).
constexpr double kMaxSyntheticDurationS = 86400.0;  // one day
constexpr double kMaxSyntheticRateHz = 10000.0;
constexpr double kMaxSyntheticSamples = 1.0e7;

// An interval of a regime: from start_s for duration_s (the transitions into and out of it take
// the actuator's time, 0.5 s, inside the interval).
struct SyntheticInterval {
  double start_s = 0.0;
  double duration_s = 0.0;
};

// The piston's motion.
enum class SyntheticHeave {
  // The lab's series: two sines at a full and a lower amplitude, a sweep, the sines again.
  kLabSeries,
  // A floating rig's heave in an irregular sea: a random-phase sum of kSeaTones tones over
  // 0.04-0.5 Hz, their amplitudes from a Pierson-Moskowitz spectrum (S(f) ~ f^-5 exp(-1.25
  // (f_p / f)^4), a_k = sqrt(2 S(f_k) df); Pierson & Moskowitz, J. Geophys. Res. 69(24), 1964)
  // with the peak f_p drawn in 0.08-0.15 Hz (wave periods of 7-12 s), each tone's frequency
  // jittered within its bin so the sum never repeats over the log. Its standard deviation is
  // that of the lab series at the same amplitude (0.5 of piston_amp_m, drawn as there). Phases
  // and frequencies come from a stream of their own: the same seed gives the same parameters,
  // noise and choke and pump steps as the lab series.
  kIrregularSea,
};
inline constexpr int kSeaTones = 24;

struct SyntheticLogOptions {
  std::uint64_t seed = 1;
  double duration_s = 120.0;
  double rate_hz = 100.0;
  // The grid diagnose uses (kDiagnoseCells). A finer grid makes a different model: the unsteady
  // friction's discretisation along the characteristics depends on dx, so its k at 100 cells is
  // not its k at 50, and the error left after adding the right effect would measure the grid,
  // not the diagnosis. (Noise on the inputs still keeps the replay from being the generator.)
  int cells = 50;
  // The hidden effects, each "NAME" or "NAME:key=value,..." (the --effect syntax); none: the base
  // model only. A fitted parameter given a value keeps it, the others are drawn (below).
  std::vector<std::string> hidden_effects;
  bool perturb_base = true;  // wave speed +-10%, f1 +-30%, choke leak +-30%
  // The low-pressure runs (open choke, little pump flow, larger heave) where column separation
  // shows; unset: where column_separation is one of the hidden effects. Set it to compare a log
  // with the same excitation without the effect.
  std::optional<bool> low_pressure;
  // Regimes: the pump stopped (FT2 at 0) and the choke closed (0 deg) over these intervals, on
  // top of the step tests (none by default: the logs the identification tests were tuned on).
  // They draw nothing from the random streams: the same seed gives the same parameters, noise and
  // excitation elsewhere.
  std::vector<SyntheticInterval> pump_stops;
  std::vector<SyntheticInterval> choke_closures;
  SyntheticHeave heave = SyntheticHeave::kLabSeries;
  // Sensor noise. Unset (the default for callers in C++): the quiet sigmas below, drawn from the
  // excitation's random stream; the identification tests (fit_test, diagnose_test) were tuned on
  // these logs, so the default stays. Set: this spec through SensorNoiseApplier seeded with
  // `seed` (sensor_noise.h), the four sigmas below unused. `mpdrig synth` sets it, to the lab's
  // (SensorNoise::Lab(), thesis Table 4.1.1) unless told otherwise.
  std::optional<SensorNoise> sensor_noise;
  double pressure_noise_pa = 300.0;  // 0.003 bar, transmitters of 0.1% of 3-10 bar span
  double flow_noise_m3ps = 5.0e-7;   // 0.03 L/min
  double piston_noise_m = 2.0e-5;
  double choke_noise_deg = 0.01;  // position feedback; near 30 deg G changes 15%/deg, so
                                  // more would swamp C2 with the replay of the noise itself

  // Duration and rate within the limits above, the sensor noise valid, every hidden effect one of
  // the catalogue (once) with known keys and values within bounds, every regime interval inside
  // the log and at least 1 s long (its two transitions); else an error that says which.
  [[nodiscard]] Status Validate() const;
};

struct SyntheticLog {
  riglog::RigLog log;
  // The same run without sensor noise: same time stamps, columns and metadata as `log` (a
  // perfect model's output, to compare `log` with).
  riglog::RigLog truth_log;
  RigParams truth;          // what generated it (with the hidden effects, if any)
  std::string description;  // "unsteady_friction k=0.071 + sensor_lag ...; wave speed 912 m/s, ..."
};

// A hidden effect's fitted parameters are drawn uniformly in [default / 2, 2 default] (within
// the effect's bounds), or log-uniformly in their plausible range where the catalogue gives one
// (EffectParamInfo::plausible_min/max); an effect with default 0 draws in the lower fifth of its
// range. The draws come from a stream of their own, effect after effect, in the order given
// (drawn also where a value is given): the same seed with and without hidden effects gives the
// same base parameters, excitation and noise, and the first effect the same strength alone as
// with a second one.
Result<SyntheticLog> MakeSyntheticLog(const SyntheticLogOptions& options);

}  // namespace mpdrig
