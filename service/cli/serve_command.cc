// mpdrig serve: the virtual rig as a DDS service (service/rig/rig_service.h).
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "service/cli/commands.h"
#include "service/cli/model_options.h"
#include "service/rig/rig_service.h"

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
  std::string dds_config;  // XML or a file; default: loopback only
  double duration_s = 0.0;
  double choke_deg = 31.0;
  double pump_lpm = 0.0;
  double outlet_barg = 0.0;
  double safe_choke_deg = std::numeric_limits<double>::quiet_NaN();
};

int RunServe(const ServeArgs& args) {
  const std::string name = "serve";
  auto params = args.model.LoadParams();
  if (!params.ok()) return Fail(name, params.status());
  auto options = args.model.LoadSimulationOptions();
  if (!options.ok()) return Fail(name, options.status());

  std::vector<service::RigHost> rigs;
  for (const std::string& id : args.rigs) {
    auto rig = service::RigHost::Create(id, *params, *options, args.rate_hz,
                                        {args.choke_deg, args.pump_lpm, args.outlet_barg});
    if (!rig.ok()) return Fail(name, rig.status().Within("rig '" + id + "'"));
    rigs.push_back(std::move(rig).value());
  }
  service::ServeOptions serve;
  serve.clock = args.clock == "fast"       ? service::ClockMode::kFast
                : args.clock == "lockstep" ? service::ClockMode::kLockstep
                                           : service::ClockMode::kRealtime;
  serve.domain = static_cast<dds_domainid_t>(args.domain);
  serve.duration_s = args.duration_s;
  serve.safe_choke_deg = args.safe_choke_deg;
  if (!args.dds_config.empty()) {
    std::ifstream file(args.dds_config);
    if (file) {
      std::ostringstream text;
      text << file.rdbuf();
      serve.dds_config = text.str();
    } else {
      serve.dds_config = args.dds_config;  // inline XML
    }
  }
  auto service = service::RigService::Create(std::move(rigs), serve);
  if (!service.ok()) return Fail(name, service.status());

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::string ids;
  for (const std::string& id : args.rigs) ids += (ids.empty() ? "" : ", ") + id;
  std::fprintf(stderr,
               "mpdrig serve: rigs %s on DDS domain %d (%s), %s clock, sensors at %g Hz\n"
               "  topics: mpdrig_sensors, mpdrig_status (out); mpdrig_choke_command, "
               "mpdrig_piston_command, mpdrig_pump_command, mpdrig_outlet_command, "
               "mpdrig_step_request (in)\n  stop with Ctrl-C\n",
               ids.c_str(), args.domain,
               args.dds_config.empty() ? "loopback only" : "configured network", args.clock.c_str(),
               args.rate_hz);
  const auto started = std::chrono::steady_clock::now();
  const std::clock_t cpu_started = std::clock();
  const Status run = (*service)->Run(g_stop);
  if (!run.ok()) return Fail(name, run);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu_started) / CLOCKS_PER_SEC;
  std::fprintf(stderr,
               "mpdrig serve: %.3f s wall, %.3f s CPU (%.0f%% of one core), %llu deadline misses\n",
               wall_s, cpu_s, wall_s > 0 ? 100.0 * cpu_s / wall_s : 0.0,
               static_cast<unsigned long long>((*service)->deadline_misses()));
  for (const service::RigHost& rig : (*service)->rigs()) {
    std::fprintf(
        stderr, "mpdrig serve: %s ran %.3f s of rig time, %llu samples, %llu commands refused\n",
        rig.rig_id().c_str(), rig.time_s(), static_cast<unsigned long long>(rig.counters().samples),
        static_cast<unsigned long long>(rig.counters().rejected_commands));
  }
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
      "  mpdrig serve --rig rig-1 --rig rig-2 --rate-hz 100 --clock realtime\n"
      "  mpdrig serve --clock lockstep --domain 7   # advances only on mpdrig_step_request");
  args->model.AddAll(command);
  command->add_option("--rig", args->rigs, "rig id to serve (repeatable)")->capture_default_str();
  command->add_option("--rate-hz", args->rate_hz, "sensor rate [Hz]")
      ->check(CLI::Range(0.1, 10000.0))
      ->capture_default_str();
  command->add_option("--clock", args->clock, "realtime, fast or lockstep")
      ->check(CLI::IsMember({"realtime", "fast", "lockstep"}))
      ->capture_default_str();
  command->add_option("--domain", args->domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  command->add_option("--dds-config", args->dds_config,
                      "Cyclone DDS configuration: a file or inline XML (default: loopback only)");
  command
      ->add_option("--duration", args->duration_s,
                   "stop after this much rig time [s] (realtime/fast; 0: run until Ctrl-C)")
      ->capture_default_str();
  command->add_option("--choke-deg", args->choke_deg, "initial choke opening [deg]")
      ->capture_default_str();
  command->add_option("--pump-lpm", args->pump_lpm, "initial pump flow [L/min]")
      ->capture_default_str();
  command->add_option("--outlet-barg", args->outlet_barg, "initial outlet pressure [barg]")
      ->capture_default_str();
  command
      ->add_option("--safe-choke-deg", args->safe_choke_deg,
                   "choke opening when a rig's last choke controller goes [deg] (default: keep "
                   "the last command); the piston always holds")
      ->check(CLI::Range(0.0, 90.0));
  command->callback([args, exit_code]() { *exit_code = RunServe(*args); });
}

}  // namespace mpdrig::cli
