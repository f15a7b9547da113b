// mpdrig shadow: the model beside a running rig (service/shadow/shadow_service.h).
#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "service/dds/topics.h"
#include "service/shadow/shadow_service.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

struct ShadowArgs {
  ModelOptions model;
  std::string rig_id = "rig-1";
  std::string shadow_id = service::kDefaultShadowId;
  int domain = 0;
  std::string dds_config;
  std::string log_path;
  double duration_s = 0.0;
  double window_s = 10.0;
  double warmup_s = kReplayWarmupS;
  double smoothing_s = 0.05;
  double status_period_s = 0.5;
  bool raw_inputs = false;
  double lookahead_s = 5.0;
  double fit_window_s = 180.0;
  std::string security;
};

int RunShadow(const ShadowArgs& args) {
  const std::string name = "shadow";
  auto params = args.model.LoadNtnuRigParams("shadow");
  if (!params.ok()) return Fail(name, params.status());
  auto simulation = args.model.LoadSimulationOptions();
  if (!simulation.ok()) return Fail(name, simulation.status());
  ShadowOptions model;
  model.simulation = *simulation;
  model.window_s = args.window_s;
  model.warmup_s = args.warmup_s;
  model.smoothing_s = args.smoothing_s;
  model.reconstruct_inputs = !args.raw_inputs;
  model.lookahead_s = args.lookahead_s;
  service::ShadowServeOptions serve;
  serve.rig_id = args.rig_id;
  serve.shadow_id = args.shadow_id;
  serve.domain = static_cast<dds_domainid_t>(args.domain);
  serve.duration_s = args.duration_s;
  serve.status_period_s = args.status_period_s;
  serve.log_path = args.log_path;
  serve.security_dir = args.security;
  serve.fit_window_s = args.fit_window_s;
  if (!args.dds_config.empty()) {
    std::ifstream file(args.dds_config);
    if (file) {
      std::ostringstream text;
      text << file.rdbuf();
      serve.dds_config = text.str();
    } else {
      serve.dds_config = args.dds_config;
    }
  }
  auto shadow = service::ShadowService::Create(*params, model, serve);
  if (!shadow.ok()) return Fail(name, shadow.status());
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  char inputs[160];
  std::snprintf(inputs, sizeof inputs, "%s",
                args.raw_inputs ? "as measured (--raw-inputs)" : "reconstructed under their noise");
  if (!args.raw_inputs) {
    std::snprintf(inputs, sizeof inputs,
                  "reconstructed under their noise, the model %g s behind the rig",
                  args.lookahead_s);
  }
  std::fprintf(
      stderr,
      "mpdrig shadow: rig %s (shadow '%s') on DDS domain %d; %s; window %g s after a %g s "
      "warm-up\n"
      "  inputs: %s\n"
      "  topics: %s (in), %s (in), %s, %s (out)\n  security: %s\n",
      args.rig_id.c_str(), args.shadow_id.c_str(), args.domain,
      args.model.Describe(*params).c_str(), args.window_s, args.warmup_s, inputs,
      dds::topics::kSensors.name, dds::topics::kShadowCommand.name,
      dds::topics::kShadowSensors.name, dds::topics::kShadowStatus.name,
      args.security.empty()
          ? "none"
          : ("DDS Security with " + args.security + ", partition rig." + args.rig_id).c_str());
  const Status run = (*shadow)->Run(g_stop);
  if (!run.ok()) return Fail(name, run);
  std::fprintf(stderr, "mpdrig shadow: %llu samples, error over the last %g s: %.4f\n",
               static_cast<unsigned long long>((*shadow)->samples()), args.window_s,
               (*shadow)->model().error());
  return 0;
}

}  // namespace

void AddShadowCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<ShadowArgs>();
  CLI::App* command =
      app->add_subcommand("shadow", "Run the model beside a live rig and publish its error");
  command->footer(
      "Subscribes to a rig's mpdrig_sensors, replays its measured inputs (piston, choke, FT2, C1)\n"
      "through the model beside it, and publishes the model's channels on\n"
      "mpdrig_shadow_sensors and its error over a sliding window (compare's NRMSE per channel\n"
      "and their mean) on mpdrig_shadow_status. mpdrig_shadow_command switches an effect on or\n"
      "off, sets a parameter, resets it, or fits now (c, f1 and the active effects' strengths\n"
      "on the last --fit-window-s, in the background; applied when done); the rows held\n"
      "(warm-up + window) are replayed with the changed model, so the error answers at once.\n"
      "The inputs are measurements, as noisy as the outputs: by default the shadow reconstructs\n"
      "them under their noise as compare does (each input's noise and the piston's band from\n"
      "the first 10 s of rows) and so runs --lookahead-s behind the rig; --raw-inputs replays\n"
      "them as measured (the choke's and FT2's noise then comes back as pressure noise).\n"
      "  mpdrig shadow --rig rig-1 --log error.csv\n"
      "  mpdrig shadow --rig rig-1 --effect unsteady_friction --duration 120");
  args->model.AddAll(command);
  command->add_option("--rig", args->rig_id, "the rig to shadow")->capture_default_str();
  command
      ->add_option("--shadow-id", args->shadow_id,
                   "this shadow's id: it takes only the model commands sent to it (shadow_ctl "
                   "--shadow ID), so several shadows of one rig can run side by side")
      ->check([](const std::string& id) {
        const Status valid = service::CheckShadowId(id);
        return valid.ok() ? std::string() : valid.message();
      })
      ->capture_default_str();
  command->add_option("--domain", args->domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  command->add_option("--dds-config", args->dds_config,
                      "Cyclone DDS configuration: a file or inline XML (default: loopback only)");
  command->add_option("--log", args->log_path,
                      "write the error over time as CSV: time_s, error, <channel>_nrmse");
  command
      ->add_option("--duration", args->duration_s,
                   "stop after this much of the rig's time [s] (0: until Ctrl-C)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_option("--window-s", args->window_s, "the error's sliding window [s]")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  command
      ->add_option("--warmup-s", args->warmup_s,
                   "model time not compared after a start or change (the pipe's transient) [s]")
      ->check(CLI::Range(0.0, 600.0))
      ->capture_default_str();
  command
      ->add_option("--piston-smoothing-s", args->smoothing_s,
                   "window of the local quadratic that smooths the piston position [s]")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command
      ->add_option("--status-period-s", args->status_period_s,
                   "status (and a --log row) every this much rig time [s]")
      ->check(CLI::Range(0.01, 60.0))
      ->capture_default_str();
  command->add_flag("--raw-inputs", args->raw_inputs,
                    "replay the inputs as measured (the piston smoothed) instead of reconstructed "
                    "under their noise; the model then keeps pace with the rig");
  command
      ->add_option("--lookahead-s", args->lookahead_s,
                   "reconstructed inputs: the model runs this far behind the rig, so each input "
                   "is smoothed over the samples on both sides [s]")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  command
      ->add_option("--fit-window-s", args->fit_window_s,
                   "fit now (shadow_ctl --fit-now) fits c, f1 and the active effects' strengths "
                   "on the rows of the last this many seconds, held for it [s]")
      ->check(CLI::Range(10.0, 3600.0))
      ->capture_default_str();
  command->add_option(
      "--security", args->security,
      "DDS Security: an identity directory of a class (deploy/security/make-class OUT NAME: "
      "OUT/NAME) allowed to read the rig; the shadow's topics are then in the rig's partition "
      "rig.<rig id>. Refuses an invalid directory, saying why");
  command->callback([args, exit_code]() { *exit_code = RunShadow(*args); });
}

}  // namespace mpdrig::cli
