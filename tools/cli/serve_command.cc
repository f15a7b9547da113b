// mpdrig serve: the virtual rig as a DDS service (service/rig/rig_service.h).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "model/common/units.h"
#include "model/sim/sensor_noise.h"
#include "service/dds/topics.h"
#include "service/rig/log_playback.h"
#include "service/rig/rig_service.h"
#include "tools/cli/commands.h"
#include "tools/cli/hidden_effect.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

struct ServeArgs {
  ModelOptions model;
  std::vector<std::string> rigs = {"rig-1"};
  double rate_hz = 100.0;
  std::string clock = "realtime";
  int domain = 0;
  int wait_for_readers = 0;          // before the first sample: this many sensor readers
  double wait_for_readers_s = 30.0;  // ... for at most this long
  std::string dds_config;            // XML or a file; default: loopback only
  std::string security;              // DDS Security identity directory (make-class's OUT/service)
  std::uint32_t private_rigs = 0;
  std::size_t max_rigs = 0;  // 0: from the sensor rate (kRigSamplesPerSecond)
  double duration_s = 0.0;
  double choke_deg = 31.0;
  double pump_lpm = 0.0;
  double outlet_barg = 0.0;
  double safe_choke_deg = std::numeric_limits<double>::quiet_NaN();
  double heave_amp_m = 0.0;
  double heave_hz = 0.2;
  bool no_observer = false;
  double estimate_hz = 0.0;
  double profile_hz = 10.0;
  int profile_points = service::RigHost::kDefaultProfilePoints;
  double observer_start_hz = 0.2;
  std::vector<double> observer_pole{-40.0, 20.0};
  bool observer_pole_given = false;
  std::vector<double> observer_noise{0.0, 0.0};  // C2 [bar], FT1 [L/min]
  double observer_noise_window_s = 5.0;
  bool observer_linear_friction = false;
  std::string sensor_noise = "lab";
  std::uint64_t noise_seed = 1;
  std::string playback;       // a rig log to publish instead of simulating
  bool loop = false;          // with playback: start again after the last row
  riglog::ReadOptions read;   // with playback: the log's time limits (--max-gap-s)
  std::string hidden_effect;  // NAME[:k=v] or random: an effect the status does not name
  std::uint64_t seed = 1;     // of --hidden-effect random
};

// What every rig of the service starts from: the model, its options, the sensors and the heave.
struct RigTemplate {
  RigParams params;
  SimulationOptions options;
  service::SensorOptions sensors;
  service::InitialCommands initial;
  std::optional<service::PistonCommandIn> heave;  // none: the piston rests

  Result<service::RigHost> Create(const std::string& id, double rate_hz) const {
    auto rig = service::RigHost::Create(id, params, options, rate_hz, initial, {}, sensors);
    if (!rig.ok()) return rig.status();
    if (heave) MPDRIG_RETURN_IF_ERROR(rig->SetPiston(*heave).Within("--heave-amp-m/--heave-hz"));
    return rig;
  }
};

Result<RigTemplate> MakeRigTemplate(const ServeArgs& args) {
  auto params = args.model.LoadNtnuRigParams("serve");
  if (!params.ok()) return params.status();
  if (!args.hidden_effect.empty()) {
    MPDRIG_RETURN_IF_ERROR(
        ApplyEffectSpec(&*params, ResolveHiddenEffect(args.hidden_effect, args.seed))
            .Within("--hidden-effect"));
  }
  auto options = args.model.LoadSimulationOptions();
  if (!options.ok()) return options.status();
  for (int i = 0; i < args.profile_points; ++i) {
    options->pressure_positions_m.push_back(params->pipe_length_m * i / (args.profile_points - 1));
  }
  auto noise = ParseSensorNoise(args.sensor_noise);
  if (!noise.ok()) return noise.status().Within("--sensor-noise");
  RigTemplate rig{*std::move(params),
                  *std::move(options),
                  {*noise, args.noise_seed},
                  {args.choke_deg, args.pump_lpm, args.outlet_barg},
                  std::nullopt};
  if (args.heave_amp_m != 0.0) {
    service::PistonCommandIn heave;
    heave.mode = service::PistonCommandIn::Mode::kSine;
    heave.amplitude_m = args.heave_amp_m;
    heave.frequency_hz = args.heave_hz;
    rig.heave = heave;
  }
  return rig;
}

// The rigs named by --rig, or the one rig that plays a log back.
Result<std::vector<service::RigHost>> MakeRigs(const ServeArgs& args, const RigTemplate& from) {
  std::vector<service::RigHost> rigs;
  if (!args.playback.empty()) {
    if (args.rigs.size() != 1) {
      return Status::Error("--playback plays one log as one rig: give one --rig");
    }
    auto playback = service::LogPlayback::Open(args.playback, args.loop, args.read);
    if (!playback.ok()) return playback.status().Within("--playback");
    auto rig = service::RigHost::CreatePlayback(args.rigs.front(), from.params, from.options,
                                                std::move(playback).value());
    if (!rig.ok()) return rig.status();
    rigs.push_back(std::move(rig).value());
    return rigs;
  }
  for (const std::string& id : args.rigs) {
    auto rig = from.Create(id, args.rate_hz);
    if (!rig.ok()) return rig.status().Within("rig '" + id + "'");
    rigs.push_back(std::move(rig).value());
  }
  return rigs;
}

// --dds-config names a file or is the XML itself.
std::string ReadDdsConfig(const std::string& file_or_xml) {
  std::ifstream file(file_or_xml);
  if (!file) return file_or_xml;
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

void SetObserverOptions(const ServeArgs& args, double sensor_period_s,
                        service::ServeOptions& serve) {
  serve.observer = !args.no_observer;
  serve.estimate_hz = args.estimate_hz;
  observer::ObserverOptions& observer = serve.observer_options.observer;
  observer.disturbance_hz = args.observer_start_hz;
  observer.pole = {args.observer_pole[0], args.observer_pole[1]};
  if (args.observer_pole_given) observer.gain_design = observer::GainDesign::kPoles;
  observer.noise.outlet_pressure_pa = units::BarToPa(args.observer_noise[0]);
  observer.noise.outlet_flow_m3ps = units::LpmToM3ps(args.observer_noise[1]);
  observer.noise.sample_period_s = sensor_period_s;
  observer.quadratic_friction = !args.observer_linear_friction;
  serve.observer_options.noise_window_s = args.observer_noise_window_s;
}

// Private rigs (--private-rigs): how many a service may hold and how each is made.
Status SetPrivateRigs(const ServeArgs& args, const RigTemplate& from,
                      service::ServeOptions& serve) {
  if (args.security.empty()) {
    return Status::Error(
        "--private-rigs needs --security (a student asks for private rigs in their own rig's "
        "partition)");
  }
  serve.private_rigs = args.private_rigs;
  // Measured (docs/service.md, "Measured timing and capacity"): 120 rigs at 100 Hz with the
  // observer took about 20 % of one core; the default keeps a service below that many rig samples
  // per second.
  constexpr double kRigSamplesPerSecond = 12000.0;
  serve.max_rigs =
      args.max_rigs > 0
          ? args.max_rigs
          : std::max<std::size_t>(args.rigs.size(),
                                  static_cast<std::size_t>(kRigSamplesPerSecond / args.rate_hz));
  // A private rig starts as the others did: the same model, initial commands, heave, noise.
  serve.make_rig = [from, rate = args.rate_hz](const std::string& id) {
    return from.Create(id, rate);
  };
  return Status::Ok();
}

Result<service::ServeOptions> MakeServeOptions(const ServeArgs& args, const RigTemplate& from,
                                               double sensor_period_s) {
  service::ServeOptions serve;
  serve.clock = args.clock == "fast"       ? service::ClockMode::kFast
                : args.clock == "lockstep" ? service::ClockMode::kLockstep
                                           : service::ClockMode::kRealtime;
  serve.domain = static_cast<dds_domainid_t>(args.domain);
  serve.duration_s = args.duration_s;
  serve.safe_choke_deg = args.safe_choke_deg;
  serve.hide_effects = !args.hidden_effect.empty();
  serve.catch_up = !args.playback.empty();
  serve.wait_for_readers = args.wait_for_readers;
  serve.wait_for_readers_s = args.wait_for_readers_s;
  serve.profile_hz = args.profile_hz;
  SetObserverOptions(args, sensor_period_s, serve);
  if (!args.dds_config.empty()) serve.dds_config = ReadDdsConfig(args.dds_config);
  if (!args.security.empty()) {
    auto security = dds::LoadSecurityDirectory(args.security);
    if (!security.ok()) return security.status().Within("--security");
    serve.security = std::move(security).value();
  }
  if (args.private_rigs > 0) MPDRIG_RETURN_IF_ERROR(SetPrivateRigs(args, from, serve));
  return serve;
}

void PrintBanner(const ServeArgs& args, const service::ServeOptions& serve,
                 const service::RigService& service) {
  std::string ids;
  for (const std::string& id : args.rigs) ids += (ids.empty() ? "" : ", ") + id;
  const service::RigHost& first = service.rigs().front();
  std::fprintf(stderr,
               "mpdrig serve: rigs %s on DDS domain %d (%s), %s clock, sensors at %g Hz\n"
               "  topics: %s, %s, %s, %s (out); %s, %s, %s, %s, %s (in)\n"
               "  sensor noise: %s\n  security: %s\n  stop with Ctrl-C\n",
               ids.c_str(), args.domain,
               args.dds_config.empty() ? "loopback only" : "configured network", args.clock.c_str(),
               args.rate_hz, dds::topics::kSensors.name, dds::topics::kEstimate.name,
               dds::topics::kPressureProfile.name, dds::topics::kStatus.name,
               dds::topics::kChokeCommand.name, dds::topics::kPistonCommand.name,
               dds::topics::kPumpCommand.name, dds::topics::kOutletCommand.name,
               dds::topics::kStepRequest.name, first.DescribeSensorNoise().c_str(),
               args.security.empty() ? "none (any participant on the domain may command any rig)"
                                     : ("DDS Security with " + serve.security->dir +
                                        "; each rig's topics in partition rig.<rig id>")
                                           .c_str());
  if (!args.playback.empty()) {
    std::fprintf(stderr, "  playback: %s at %g Hz; commands are refused (a recording)\n",
                 first.playback()->Describe().c_str(), 1.0 / first.sensor_period_s());
  }
  if (!args.hidden_effect.empty()) {
    std::fprintf(stderr, "  a hidden effect is active%s\n",
                 args.hidden_effect == "random" ? " (mpdrig reveal --seed S tells which)" : "");
  }
}

void PrintRunSummary(const service::RigService& service, double wall_s, double cpu_s) {
  std::fprintf(stderr,
               "mpdrig serve: %.3f s wall, %.3f s CPU (%.0f%% of one core), %llu deadline misses, "
               "%llu periods lost, longest stall %.3f s\n",
               wall_s, cpu_s, wall_s > 0 ? 100.0 * cpu_s / wall_s : 0.0,
               static_cast<unsigned long long>(service.deadline_misses()),
               static_cast<unsigned long long>(service.lost_periods()), service.longest_stall_s());
  for (const service::RigHost& rig : service.rigs()) {
    std::fprintf(
        stderr, "mpdrig serve: %s ran %.3f s of rig time, %llu samples, %llu commands refused\n",
        rig.rig_id().c_str(), rig.time_s(), static_cast<unsigned long long>(rig.counters().samples),
        static_cast<unsigned long long>(rig.counters().rejected_commands));
  }
}

int RunServe(const ServeArgs& args) {
  const std::string name = "serve";
  if (args.loop && args.playback.empty()) {
    return Fail(name, Status::Error("--loop needs --playback LOG"));
  }
  auto from = MakeRigTemplate(args);
  if (!from.ok()) return Fail(name, from.status());
  auto rigs = MakeRigs(args, *from);
  if (!rigs.ok()) return Fail(name, rigs.status());
  auto serve = MakeServeOptions(args, *from, rigs->front().sensor_period_s());
  if (!serve.ok()) return Fail(name, serve.status());
  auto service = service::RigService::Create(*std::move(rigs), *serve);
  if (!service.ok()) return Fail(name, service.status());

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  PrintBanner(args, *serve, **service);
  const auto started = std::chrono::steady_clock::now();
  const std::clock_t cpu_started = std::clock();
  const Status run = (*service)->Run(g_stop);
  if (!run.ok()) return Fail(name, run);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu_started) / CLOCKS_PER_SEC;
  PrintRunSummary(**service, wall_s, cpu_s);
  return 0;
}

}  // namespace

void AddServeCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* command = app->add_subcommand("serve", "Run virtual rigs as a DDS service");
  command->footer(
      "Publishes every lab channel on mpdrig_sensors (lab units, keyed by rig id) and the rig's\n"
      "status on mpdrig_status; takes choke, piston, pump and outlet commands. Commands that are\n"
      "NaN, infinite, out of range or for an unknown rig are refused, counted and reported on\n"
      "status. DDS stays on loopback unless --dds-config says otherwise.\n"
      "Beside each rig runs the backstepping observer (thesis 10) on the topside channels C2 and\n"
      "FT1 only: mpdrig_estimate carries the estimated bottom-hole pressure, heave velocity and\n"
      "the disturbance frequency it assumes (the commanded sine's, else tracked online);\n"
      "mpdrig_pressure_profile the pressure along the pipe, simulated and estimated.\n"
      "The sensors carry the lab's noise (thesis Table 4.1.1; the observer sees it too), the\n"
      "status says which; --sensor-noise none publishes the model's channels as they are.\n"
      "  mpdrig serve --rig rig-1 --rig rig-2 --rate-hz 100 --clock realtime\n"
      "  mpdrig serve --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 20 --choke-deg 45\n"
      "  mpdrig serve --clock lockstep --domain 7   # advances only on mpdrig_step_request\n"
      "Watch it from another terminal: rig_echo --rig rig-1 --samples 1000 --out -");
  args->model.AddAll(command);
  CLI::Option_group* g_rigs =
      command->add_option_group("Rigs: what runs, how fast, from what start");
  g_rigs->add_option("--rig", args->rigs, "rig id to serve (repeatable)")->capture_default_str();
  g_rigs->add_option("--rate-hz", args->rate_hz, "sensor rate [Hz]")
      ->check(CLI::Range(0.1, 10000.0))
      ->capture_default_str();
  g_rigs->add_option("--clock", args->clock, "realtime, fast or lockstep")
      ->check(CLI::IsMember({"realtime", "fast", "lockstep"}))
      ->capture_default_str();
  g_rigs
      ->add_option("--duration", args->duration_s,
                   "stop after this much rig time [s] (realtime/fast; 0: run until Ctrl-C)")
      ->capture_default_str();
  g_rigs->add_option("--choke-deg", args->choke_deg, "initial choke opening [deg]")
      ->capture_default_str();
  g_rigs->add_option("--pump-lpm", args->pump_lpm, "initial pump flow [L/min]")
      ->capture_default_str();
  g_rigs->add_option("--outlet-barg", args->outlet_barg, "initial outlet pressure [barg]")
      ->capture_default_str();
  g_rigs
      ->add_option("--heave-amp-m", args->heave_amp_m,
                   "start each rig's heave generator on a sine of this amplitude [m] (0: hold; "
                   "a piston command replaces it)")
      ->check(CLI::Range(-0.6, 0.6))
      ->capture_default_str();
  g_rigs->add_option("--heave-hz", args->heave_hz, "frequency of that sine [Hz]")
      ->check(CLI::Range(0.0, 2.0))
      ->capture_default_str();
  g_rigs
      ->add_option("--safe-choke-deg", args->safe_choke_deg,
                   "choke opening when a rig's last choke controller goes [deg] (default: keep "
                   "the last command); the piston always holds")
      ->check(CLI::Range(0.0, 90.0));
  g_rigs
      ->add_option("--sensor-noise", args->sensor_noise,
                   "noise of the published sensor channels: none, lab (thesis Table 4.1.1) or "
                   "a SPEC (docs/sensor-noise.md)")
      ->capture_default_str();
  g_rigs
      ->add_option("--noise-seed", args->noise_seed,
                   "seed of the sensor noise (each rig mixes in its id)")
      ->capture_default_str();
  g_rigs->add_option("--hidden-effect", args->hidden_effect,
                     "a mystery rig: run with this effect (NAME[:k=v], or random: one from the "
                     "catalogue at its defaults, chosen by --seed) and let the status say only "
                     "\"a hidden effect is active\" (mpdrig reveal --seed S tells which)");
  g_rigs->add_option("--seed", args->seed, "seed of --hidden-effect random")->capture_default_str();
  g_rigs->add_option("--playback", args->playback,
                     "publish this rig log (rig-log-format.md) as the rig's sensors, one row per "
                     "period of the log's own sampling (median interval), paced by --clock; "
                     "channels the log lacks go out as NaN (not measured); the observer runs on "
                     "its topside channels; every command is refused (a recording). One --rig; "
                     "--rate-hz, the initial commands and --sensor-noise do not apply");
  g_rigs->add_flag("--loop", args->loop,
                   "with --playback: start again after the last row, the clock running on");
  // A bad row anywhere in the log (a gap, a repeated time, a truncated line) ends the playback
  // with its file:line:column and a non-zero exit; --max-gap-s admits longer gaps.
  AddLogReadOptions(g_rigs, &args->read);
  CLI::Option_group* g_dds = command->add_option_group("DDS and a class");
  g_dds
      ->add_option("--wait-for-readers", args->wait_for_readers,
                   "before the first sample, wait until each rig's sensors have this many "
                   "readers (a recorder started first then gets every row of a playback: a "
                   "sample written before a reader has matched reaches no one); 0: start at once")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  g_dds
      ->add_option("--wait-for-readers-s", args->wait_for_readers_s,
                   "the longest wait for --wait-for-readers [s]; then the rig starts anyway")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  g_dds->add_option("--domain", args->domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  g_dds->add_option("--dds-config", args->dds_config,
                    "Cyclone DDS configuration: a file or inline XML (default: loopback only)");
  g_dds->add_option(
      "--security", args->security,
      "DDS Security: the service's identity directory of a class (deploy/security/make-class "
      "OUT ...: OUT/service). Authenticated, access-controlled and encrypted; each rig's topics "
      "in partition rig.<rig id>, so a student's permissions name the rigs they may command and "
      "read. Refuses to start if the directory is not a valid identity, saying why");
  g_dds->add_option(
      "--private-rigs", args->private_rigs,
      "with --security: a student may ask (mpdrig_rig_request, in their rig's partition) for up "
      "to this many private rigs NAME.1 .. NAME.N, made while the service runs (0: none)");
  g_dds->add_option("--max-rigs", args->max_rigs,
                    "with --private-rigs: the most rigs the service runs in all (default: "
                    "12000 / --rate-hz, about 20 % of one core as measured; at least the "
                    "--rig count)");
  CLI::Option_group* g_observer = command->add_option_group("Observer and pressure profile");
  g_observer->add_flag("--no-observer", args->no_observer,
                       "do not run the observer (no mpdrig_estimate, profile without estimate)");
  g_observer
      ->add_option("--estimate-hz", args->estimate_hz,
                   "publish mpdrig_estimate at this rate [Hz] (0: with every sensor sample); "
                   "the observer steps on every sample regardless")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g_observer
      ->add_option("--profile-hz", args->profile_hz,
                   "publish mpdrig_pressure_profile at this rate [Hz] (0: off)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g_observer
      ->add_option("--profile-points", args->profile_points,
                   "points of the pressure profile, evenly from the inlet (0 m) to the choke")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  g_observer
      ->add_option("--observer-start-hz", args->observer_start_hz,
                   "disturbance frequency the observer assumes until its tracker locks, when the "
                   "heave is not a commanded sine [Hz]")
      ->check(CLI::Range(0.02, 2.0))
      ->capture_default_str();
  g_observer
      ->add_option("--observer-pole", args->observer_pole,
                   "place the poles of A - LC at RE +- IM i [rad/s] instead of choosing them from "
                   "the noise (thesis 10.3: -40 20). Default: the steady-state Kalman gain for "
                   "the sensor noise (configured, or estimated over --observer-noise-window-s), "
                   "the thesis's poles when it is negligible (docs/observer.md)")
      ->expected(2)
      ->each([args](const std::string&) { args->observer_pole_given = true; });
  g_observer
      ->add_option("--observer-noise", args->observer_noise,
                   "the sensors' noise the observer designs for: C2_BAR FT1_LPM (standard "
                   "deviations per sample; lab: 0.024 0.07); the estimate from the start-up "
                   "window can only raise it")
      ->expected(2)
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g_observer
      ->add_option("--observer-noise-window-s", args->observer_noise_window_s,
                   "rig time over which the observer estimates the noise of C2 and FT1 at start "
                   "(0: only --observer-noise)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g_observer->add_flag(
      "--observer-linear-friction", args->observer_linear_friction,
      "the thesis's observer: linear friction only in its pipe copy (default: also "
      "the quadratic friction f2 u|u|, about 50x smaller BHP error at 0.1 m strokes)");
  command->callback([args, exit_code]() { *exit_code = RunServe(*args); });
}

}  // namespace mpdrig::cli
