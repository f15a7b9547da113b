// mpdrig simulate: drive the rig model with a log's inputs or with profiles; write a rig log.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/analysis/log_file_replay.h"
#include "model/common/units.h"
#include "model/riglog/rig_log.h"
#include "model/sim/log_inputs.h"
#include "model/sim/profile.h"
#include "model/sim/sensor_noise.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"
#include "tools/cli/rig_log_output.h"

namespace mpdrig::cli {
namespace {

struct SimulateArgs {
  ModelOptions model;
  std::string inputs_path;
  std::string piston_spec;
  std::string choke_spec = "31";
  double pump_lpm = 0.0;
  double outlet_barg = 0.0;
  double duration_s = 20.0;
  double rate_hz = 100.0;
  InputReplayOptions replay;
  riglog::ReadOptions read;
  bool allow_negative_pressure = false;
  std::vector<double> pressure_at_m;
  std::string out_path;
  std::string sensor_noise = "lab";
  std::uint64_t noise_seed = 1;
  bool rate_given = false;
  bool model_given = false;
  // The NTNU rig's inputs given on the command line (--piston, --choke-deg, --pump-lpm,
  // --outlet-barg, --inputs): refused on a reservoir - pipe - valve rig, which its closure law
  // drives.
  std::vector<std::string> ntnu_inputs_given;
};

// Output rate of a reservoir - pipe - valve run when --rate-hz is not given: its transients last
// a few L/c (28 ms on the 37 m apparatus), far faster than the NTNU rig's 100 Hz log shows.
constexpr double kValveRigRateHz = 10000.0;

// Limits of a profile run: its output times are held in memory (8 B each; the samples stream to
// the log, about 250 B each on disk) and the solver steps the whole duration, so an absurd value
// would run out of memory, disk or time instead of failing (as --duration inf, 1e17, 1e9 and
// --rate-hz inf once did).
constexpr double kMaxDurationS = 86400.0;    // one day of rig time per run
constexpr double kMaxRateHz = 100000.0;      // far above the lab's 100 Hz and the solver's grid
constexpr double kMaxOutputSamples = 1.0e7;  // 1 kHz for 2.8 h: 80 MB of times, 2.5 GB of log

Status CheckProfileRunLimits(double duration_s, double rate_hz) {
  auto format = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value);
    return std::string(text);
  };
  if (!(duration_s > 0.0 && duration_s <= kMaxDurationS)) {
    return Status::Error("--duration " + format(duration_s) + " s must be in (0, " +
                         format(kMaxDurationS) + "] s (one day of rig time; split longer runs)");
  }
  if (!(rate_hz > 0.0 && rate_hz <= kMaxRateHz)) {
    return Status::Error("--rate-hz " + format(rate_hz) + " Hz must be in (0, " +
                         format(kMaxRateHz) + "] Hz");
  }
  if (duration_s * rate_hz > kMaxOutputSamples) {
    return Status::Error("--duration x --rate-hz = " + format(duration_s * rate_hz) +
                         " samples, at most " + format(kMaxOutputSamples) +
                         ": shorten the run or lower the rate");
  }
  return Status::Ok();
}

// Runs the model and hands every sample to the sink as it comes; progress gets the share done.
using RunFn = std::function<Result<RunSummary>(const std::function<void(const RigSample&)>& sink,
                                               const std::function<void(double)>& progress)>;

// What drives a run: how it runs, the time it spans and the atmosphere of its log.
struct Drive {
  RunFn run;
  double span_s = 0.0;
  double atmosphere_pa = 0.0;
  std::string description;  // the log's `drive` metadata
};

// A run of `params` driven by `signals`, sampled at `rate_hz` from 0 to `duration_s`.
Drive SampledDrive(const RigParams& params, const SimulationOptions& options, InputSignals signals,
                   double duration_s, double rate_hz) {
  const long count = std::lround(duration_s * rate_hz);
  std::vector<double> output_times;
  for (long i = 0; i <= count; ++i) output_times.push_back(i / rate_hz);
  Drive drive;
  drive.span_s = output_times.back() - output_times.front();
  drive.run = [params, options, signals = std::move(signals),
               output_times = std::move(output_times)](
                  const std::function<void(const RigSample&)>& sink,
                  const std::function<void(double)>& progress) {
    return SimulateEach(params, options, signals, output_times, sink, progress);
  };
  drive.atmosphere_pa = params.atmospheric_pressure_pa;
  return drive;
}

// The inputs of a measured log (--inputs). A log that starts mid-heave starts after a warm-up,
// where its pressures say so, and its choke and FT2 levels are corrected from its pressures, as
// compare's. The log is read twice and never held (log_file_replay.h): 1e6 rows took 522 MB
// in memory.
Result<Drive> DriveFromLog(const SimulateArgs& args, const RigParams& params,
                           SimulationOptions* options) {
  options->choke_input = ChokeInput::kMeasured;
  auto prepared =
      LogFileReplay::Prepare(args.inputs_path, params, *options, args.replay, args.read);
  if (!prepared.ok()) return prepared.status();
  auto replay = std::make_shared<const LogFileReplay>(std::move(prepared).value());
  if (replay->prepared_from_measurements()) {
    DescribeReplay(replay->reconstruction() ? &*replay->reconstruction() : nullptr,
                   replay->replay(), InputLevels::kWithTheseParams);
  }
  Drive drive;
  drive.run = [replay](const std::function<void(const RigSample&)>& sink,
                       const std::function<void(double)>& progress) {
    return replay->Run(sink, progress);
  };
  drive.span_s = replay->end_s() - replay->start_s();
  drive.atmosphere_pa = replay->atmospheric_pressure_pa();
  drive.description = "inputs of " + args.inputs_path;
  return drive;
}

// Profiles of the piston and the choke, a constant pump and outlet pressure (--piston, ...).
Result<Drive> DriveFromProfiles(const SimulateArgs& args, const RigParams& params,
                                SimulationOptions* options) {
  MPDRIG_RETURN_IF_ERROR(CheckProfileRunLimits(args.duration_s, args.rate_hz));
  options->choke_input = ChokeInput::kReference;
  auto piston = ParseProfile(args.piston_spec, "m", args.duration_s);
  if (!piston.ok()) return piston.status().Within("--piston");
  auto choke = ParseProfile(args.choke_spec, "deg", args.duration_s);
  if (!choke.ok()) return choke.status().Within("--choke-deg");
  std::shared_ptr<Profile> piston_profile = std::move(piston).value();
  std::shared_ptr<Profile> choke_profile = std::move(choke).value();
  const double pump = units::LpmToM3ps(args.pump_lpm);
  const double outlet = units::BargToPaAbs(args.outlet_barg, params.atmospheric_pressure_pa);
  InputSignals signals;
  signals.piston_position_m = [piston_profile](double t) { return piston_profile->ValueAt(t); };
  signals.rig = [choke_profile, pump, outlet](double t) {
    RigInputs in;
    in.choke_opening_frac = units::ChokeDegToFrac(choke_profile->ValueAt(t));
    in.pump_flow_m3ps = pump;
    in.outlet_pressure_pa = outlet;
    return in;
  };
  Drive drive = SampledDrive(params, *options, std::move(signals), args.duration_s, args.rate_hz);
  drive.description = "piston " + piston_profile->Describe() + " m, choke " +
                      choke_profile->Describe() + " deg (through the actuator)";
  return drive;
}

// The reservoir - pipe - valve rig (RigParams::layout): the valve's closure law drives it, from
// steady flow; the piston and choke inputs are not used.
Result<Drive> DriveValveRig(const SimulateArgs& args, const RigParams& params,
                            SimulationOptions* options) {
  if (!args.ntnu_inputs_given.empty()) {
    return Status::Error(args.ntnu_inputs_given.front() + " does not apply: the config's rig is " +
                         params.layout.Describe() +
                         ", driven by the valve's closure law (give --duration)");
  }
  const double rate_hz = args.rate_given ? args.rate_hz : kValveRigRateHz;
  MPDRIG_RETURN_IF_ERROR(CheckProfileRunLimits(args.duration_s, rate_hz));
  options->choke_input = ChokeInput::kMeasured;
  InputSignals signals;
  signals.piston_position_m = [](double) { return 0.0; };
  const double atmosphere = params.atmospheric_pressure_pa;
  signals.rig = [atmosphere](double) {
    RigInputs in;
    in.outlet_pressure_pa = atmosphere;
    return in;
  };
  Drive drive = SampledDrive(params, *options, std::move(signals), args.duration_s, rate_hz);
  drive.description = params.layout.Describe();
  return drive;
}

// The log's header: what ran, on what, and the sensors' noise when there is any.
riglog::Metadata RunMetadata(const SimulateArgs& args, const RigParams& params, const Drive& drive,
                             const SensorNoise& noise) {
  riglog::Metadata metadata = {
      {"source", "mpdrig simulate"},
      {"model", args.model.Describe(params)},
      {"drive", drive.description},
  };
  if (!args.model.config_path.empty()) metadata.emplace_back("config", args.model.config_path);
  for (const std::string& assignment : args.model.overrides) {
    metadata.emplace_back("set", assignment);
  }
  if (!noise.IsNone()) {
    metadata.emplace_back("sensor_noise",
                          noise.ToSpec() + ", seed " + std::to_string(args.noise_seed));
  }
  return metadata;
}

// The pipe law of a reservoir - pipe - valve rig unless --model says otherwise: the linear law
// (thesis 7.0), the water-hammer equations of that literature (Wylie & Streeter 1993; Bergant &
// Simpson 1999), which neglect the convective terms. With the quasi-linear law the front that
// reaches the valve is interpolated over a node (its characteristics move at u +- c), and in the
// vapour zone behind a cavity, where nothing couples the two grid-points of a liquid segment, that
// half-arrived value stays. On the 1999 apparatus (200 cells) the first cavity at the valve then
// lasted 6 % less after a 0.1 ms closure, and 60 ms instead of 0.30 s after the 9 ms one.
constexpr const char* kValveRigModel = "linear";

int RunSimulate(SimulateArgs args) {
  const std::string name = "simulate";
  auto params = args.model.LoadParams();
  if (!params.ok()) return Fail(name, params.status());
  if (!params->layout.is_ntnu_rig() && !args.model_given) args.model.model = kValveRigModel;
  auto options = args.model.LoadSimulationOptions();
  if (!options.ok()) return Fail(name, options.status());
  options->stop_on_range_violation = !args.allow_negative_pressure;
  options->pressure_positions_m = args.pressure_at_m;

  auto noise = ParseSensorNoise(args.sensor_noise);
  if (!noise.ok()) return Fail(name, noise.status().Within("--sensor-noise"));

  if (params->layout.is_ntnu_rig() && args.inputs_path.empty() && args.piston_spec.empty()) {
    return Fail(name, Status::Error("give --inputs LOG.csv or --piston PROFILE"));
  }
  auto drive = !params->layout.is_ntnu_rig() ? DriveValveRig(args, *params, &*options)
               : args.inputs_path.empty()    ? DriveFromProfiles(args, *params, &*options)
                                             : DriveFromLog(args, *params, &*options);
  if (!drive.ok()) return Fail(name, drive.status());
  const double span_s = drive->span_s;
  const bool show_progress = span_s > 600.0;
  // What the lab's sensors would read (sensor_noise.h); the extra --pressure-at outputs are the
  // model's, not sensors, and stay noise-free. `none` writes the model's output untouched.
  std::optional<SensorNoiseApplier> sensors;
  if (!noise->IsNone()) sensors.emplace(*noise, args.noise_seed);
  // The samples go to the log as they come (a long run is not held in memory); a failed run
  // leaves no log behind (rig_log_output.h).
  auto out = SampleLogStream::Open(args.out_path, RunMetadata(args, *params, *drive, *noise),
                                   drive->atmosphere_pa, args.pressure_at_m);
  if (!out.ok()) return Fail(name, out.status());
  Status written = Status::Ok();
  const auto started = std::chrono::steady_clock::now();
  auto run = drive->run(
      [&](const RigSample& sample) {
        if (!written.ok()) return;
        RigSample measured = sample;
        if (sensors) sensors->MeasureSample(&measured);
        written = out->Write(measured);
      },
      [&](double fraction) {
        if (show_progress) std::fprintf(stderr, "mpdrig simulate: %3.0f%%\n", 100.0 * fraction);
      });
  if (!run.ok()) {
    if (run.status().code() != Status::Code::kModelRange) return Fail(name, run.status());
    return Fail(name, Status::Error(run.status().message() +
                                    "\n  (raise the outlet pressure, reduce the piston amplitude, "
                                    "or pass --allow-negative-pressure to continue anyway)"));
  }
  if (!written.ok()) return Fail(name, written);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  riglog::Metadata warnings;
  if (run->first_range_event) {
    warnings.emplace_back("warning", run->first_range_event->Describe());
    std::fprintf(stderr, "mpdrig simulate: warning: %s\n",
                 run->first_range_event->Describe().c_str());
  }
  written = out->Finish(warnings);
  if (!written.ok()) return Fail(name, written);
  if (args.out_path != "-") {
    std::printf(
        "simulated %.6g s of the rig (%s) in %.3f s: %ld steps, %zu samples of %zu "
        "channels written to %s\n",
        span_s, args.model.Describe(*params).c_str(), elapsed_s, run->steps, out->samples_written(),
        SimulatedColumns(args.pressure_at_m)->size() + 1, args.out_path.c_str());
  }
  return 0;
}

}  // namespace

void AddSimulateCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* command =
      app->add_subcommand("simulate", "Run the rig model; write every lab channel as a rig log");
  command->footer(
      "Writes a rig log (rig-log-format.md) with every lab channel, as the lab's sensors read\n"
      "it: with their noise (--sensor-noise, default lab; none: the model's output as is).\n"
      "Drive it with the inputs of a measured log (--inputs), or with profiles:\n"
      "  mpdrig simulate --piston sine:amp_m=0.1,freq_hz=0.2 --choke-deg 31 --pump-lpm 5 \\\n"
      "                  --outlet-barg 0 --duration 60 --out sim.csv\n"
      "  mpdrig simulate --inputs lab.csv --out replay.csv --set wave_speed_mps=900\n"
      "Profiles: sine:amp_U=..,freq_hz=..[,mean_U=..][,phase_deg=..]\n"
      "          sweep:amp_U=..,f0_hz=..,f1_hz=..[,duration_s=..][,mean_U=..]\n"
      "          step:amp_U=..,t_s=..[,rise_s=..][,mean_U=..]   or a plain number\n"
      "with U = m for the piston and deg for the choke.\n"
      "A config with `reservoir`, `valve` and `steady_flow` (docs/bergant-simpson.md) is the\n"
      "reservoir - pipe - valve rig: its valve's closure law drives it, from steady flow, and\n"
      "it writes 10 kHz unless --rate-hz says otherwise, with the linear pipe law unless\n"
      "--model says otherwise:\n"
      "  mpdrig simulate --config docs/examples/bergant-simpson-1999.pbtxt --duration 0.8 \\\n"
      "                  --pressure-at 37.23 --sensor-noise none --out valve.csv");
  args->model.AddAll(command);
  auto* inputs = command
                     ->add_option("--inputs", args->inputs_path,
                                  "rig log whose piston_position, choke_position (and FT2, C1 "
                                  "if present) drive the model; outputs at its time stamps")
                     ->check(CLI::ExistingFile);
  auto* piston =
      command->add_option("--piston", args->piston_spec, "piston (BHA) position profile [m]");
  inputs->excludes(piston);
  command
      ->add_option("--choke-deg", args->choke_spec,
                   "choke opening reference profile [deg], 0 closed .. 90 open")
      ->capture_default_str();
  command->add_option("--pump-lpm", args->pump_lpm, "back-pressure pump flow FT2 [L/min]")
      ->capture_default_str();
  command->add_option("--outlet-barg", args->outlet_barg, "choke outlet pressure C1 [bar gauge]")
      ->capture_default_str();
  command->add_option("--duration", args->duration_s, "simulated time [s] (profiles)")
      ->capture_default_str();
  auto* rate =
      command
          ->add_option("--rate-hz", args->rate_hz,
                       "output sample rate [Hz] (profiles; a reservoir - pipe - valve rig: 10000)")
          ->capture_default_str();
  AddInputReplayOptions(command, &args->replay);
  AddLogReadOptions(command, &args->read);
  command
      ->add_option("--pressure-at", args->pressure_at_m,
                   "extra pressure outputs along the pipe, metres from the inlet, e.g. "
                   "--pressure-at 50,450,850 (columns p_50m_barg, ...; thesis 6.8)")
      ->delimiter(',');
  command->add_flag("--allow-negative-pressure", args->allow_negative_pressure,
                    "keep going when the absolute pressure falls to zero (reported as a warning)");
  command
      ->add_option("--sensor-noise", args->sensor_noise,
                   "noise of the written sensor channels: none, lab (thesis Table 4.1.1) or a "
                   "SPEC (docs/sensor-noise.md)")
      ->capture_default_str();
  command->add_option("--noise-seed", args->noise_seed, "seed of the sensor noise")
      ->capture_default_str();
  command->add_option("--out", args->out_path, "output rig log ('-' for stdout)")->required();
  command->callback([args, exit_code, command, rate]() {
    args->rate_given = rate->count() > 0;
    args->model_given = command->get_option("--model")->count() > 0;
    args->ntnu_inputs_given.clear();
    for (const char* flag :
         {"--inputs", "--piston", "--choke-deg", "--pump-lpm", "--outlet-barg"}) {
      if (command->get_option(flag)->count() > 0) args->ntnu_inputs_given.push_back(flag);
    }
    *exit_code = RunSimulate(*args);
  });
}

}  // namespace mpdrig::cli
