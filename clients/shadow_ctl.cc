// shadow_ctl: changes a running `mpdrig shadow` (its mpdrig_shadow_command topic) and prints the
// shadow's answer: its error before, the change, and its error over the window after. A client:
// it speaks only the DDS topics.
//
//   shadow_ctl --rig rig-1 --effect-on unsteady_friction
//   shadow_ctl --rig rig-1 --set wave_speed_mps=900
//   shadow_ctl --rig rig-1 --effect-off unsteady_friction
//   shadow_ctl --rig rig-1 --reset
//   shadow_ctl --rig rig-1 --fit-now              # waits for the fit (up to --fit-timeout)
//   shadow_ctl --rig rig-1                       # only print the shadow's status
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "shadow_ctl: %s\n", what.c_str());
  return 1;
}

void Print(const mpdrig_ShadowStatus& s) {
  std::printf("shadow of %s at t = %.2f s: error %.4f over %.0f s\n", s.rig_id, s.sim_time_s,
              s.error, s.window_s);
  for (std::uint32_t i = 0; i < s.channels._length && i < s.nrmse._length; ++i) {
    if (!std::isnan(s.nrmse._buffer[i]))
      std::printf("  %-5s NRMSE %.4f\n", s.channels._buffer[i], s.nrmse._buffer[i]);
  }
  std::printf("  effects:");
  for (std::uint32_t i = 0; i < s.active_effects._length; ++i)
    std::printf(" [%s]", s.active_effects._buffer[i]);
  std::printf("%s\n  parameters set:", s.active_effects._length == 0 ? " none" : "");
  for (std::uint32_t i = 0; i < s.parameters._length; ++i)
    std::printf(" %s", s.parameters._buffer[i]);
  std::printf("%s\n", s.parameters._length == 0 ? " none" : "");
  if (s.last_change[0] != '\0') {
    std::printf("  last change: %s at t = %.2f s (error then %.4f)\n", s.last_change,
                s.last_change_sim_time_s, s.error_at_last_change);
  }
  if (s.fit_state[0] != '\0') std::printf("  fit: %s\n", s.fit_state);
  if (s.rejected_commands > 0) {
    std::printf("  %llu commands refused, the last: %s\n",
                static_cast<unsigned long long>(s.rejected_commands), s.last_rejection);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("shadow_ctl - switch a running shadow model's effects and parameters");
  std::string rig_id = "rig-1";
  int domain = 0;
  std::string dds_config;
  std::string effect_on, effect_off, set;
  bool reset = false, fit_now = false;
  double timeout_s = 10.0, fit_timeout_s = 600.0;
  std::string security;
  app.add_option("--rig", rig_id, "the rig the shadow follows")->capture_default_str();
  app.add_option("--domain", domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  app.add_option("--dds-config", dds_config, "Cyclone DDS XML (default: loopback only)");
  auto* on = app.add_option("--effect-on", effect_on, "switch an effect on: NAME[:k=v,...]");
  auto* off = app.add_option("--effect-off", effect_off, "switch an effect off: NAME");
  auto* param = app.add_option("--set", set, "set a parameter: KEY=VALUE (EFFECT.KEY too)");
  auto* again = app.add_flag("--reset", reset, "back to the model the shadow started with");
  auto* fit = app.add_flag("--fit-now", fit_now,
                           "fit c, f1 and the active effects' strengths on the shadow's last "
                           "minutes of rows, in the background; waits for the result");
  on->excludes(off, param, again, fit);
  off->excludes(param, again, fit);
  param->excludes(again, fit);
  again->excludes(fit);
  app.add_option("--fit-timeout", fit_timeout_s, "with --fit-now: wait this long for the fit [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--security", security,
                 "DDS Security: an identity directory of a class (deploy/security/make-class OUT "
                 "NAME: OUT/NAME) allowed to use the rig's shadow; its topics are then in "
                 "partition rig.<rig id>. Refuses an invalid directory, saying why");
  app.add_option("--timeout", timeout_s, "give up after this long [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  using namespace mpdrig;
  auto created =
      dds::Domain::Create(domain, dds_config.empty() ? dds::LoopbackConfig() : dds_config);
  if (!created.ok()) return Fail(created.status().message());
  // With --security the shadow's topics are in its rig's partition.
  auto scope = dds::CreateClientScope(domain, security, rig_id);
  if (!scope.ok()) return Fail(scope.status().message());
  const dds_entity_t p = scope->participant.handle();
  auto command_topic = dds::CreateTopic(p, &mpdrig_ShadowCommand_desc, "mpdrig_shadow_command");
  auto status_topic = dds::CreateTopic(p, &mpdrig_ShadowStatus_desc, "mpdrig_shadow_status");
  if (!command_topic.ok()) return Fail(command_topic.status().message());
  if (!status_topic.ok()) return Fail(status_topic.status().message());
  auto status = dds::Reader<mpdrig_ShadowStatus>::Create(scope->sub(), status_topic->handle(),
                                                         dds::StatusQos());
  if (!status.ok()) return Fail(status.status().message());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  // The shadow's current status first (transient-local: it arrives once matched).
  bool have = false;
  std::uint64_t before_rejected = 0;
  while (!have && std::chrono::steady_clock::now() < deadline) {
    auto ready = status->Wait(DDS_MSECS(100));
    if (!ready.ok()) return Fail(ready.status().message());
    (void)status->TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
      if (rig_id != s.rig_id) return;
      have = true;
      before_rejected = s.rejected_commands;
      Print(s);
    });
  }
  if (!have)
    return Fail("no shadow of rig '" + rig_id + "' answered (is `mpdrig shadow` running?)");
  std::string argument;
  mpdrig_ShadowAction action;
  if (!effect_on.empty()) {
    action = mpdrig_SHADOW_EFFECT_ON, argument = effect_on;
  } else if (!effect_off.empty()) {
    action = mpdrig_SHADOW_EFFECT_OFF, argument = effect_off;
  } else if (!set.empty()) {
    action = mpdrig_SHADOW_SET, argument = set;
  } else if (reset) {
    action = mpdrig_SHADOW_RESET;
  } else if (fit_now) {
    action = mpdrig_SHADOW_FIT_NOW;
  } else {
    return 0;
  }
  // Only now: reading the status needs no right to command (a watcher under security has none).
  auto writer = dds::Writer<mpdrig_ShadowCommand>::Create(scope->pub(), command_topic->handle(),
                                                          dds::RequestQos());
  if (!writer.ok()) return Fail(writer.status().message());
  // A command written before the shadow's reader has matched would be lost (volatile).
  const std::chrono::duration<double> left = deadline - std::chrono::steady_clock::now();
  const auto matched = dds::AwaitReader(writer->handle(), dds::DeadlineAfter(left.count()));
  if (!matched.ok()) return Fail(matched.status().message());
  if (!*matched) return Fail("the shadow's command reader did not match within --timeout");

  mpdrig_ShadowCommand command{};
  command.rig_id = rig_id.data();
  command.command_id =
      static_cast<unsigned long long>(std::chrono::system_clock::now().time_since_epoch().count());
  command.action = action;
  command.argument = argument.data();
  auto written = writer->Write(command);
  if (!written.ok()) return Fail(written.message());
  // The answer: the status that names this command; for a fit, then the one that ends it.
  bool fitting = false;
  auto until = deadline;
  while (std::chrono::steady_clock::now() < until) {
    auto ready = status->Wait(DDS_MSECS(100));
    if (!ready.ok()) return Fail(ready.status().message());
    int code = -1;
    (void)status->TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
      if (code >= 0 || rig_id != s.rig_id || s.last_command_id != command.command_id) return;
      const std::string fit_state = s.fit_state;
      if (s.rejected_commands > before_rejected) {
        std::printf("refused: %s\n", s.last_rejection);
        code = 1;
      } else if (action == mpdrig_SHADOW_FIT_NOW && fit_state.rfind("running:", 0) == 0) {
        if (!fitting) std::printf("fit %s\n", s.fit_state);
        fitting = true;
      } else if (action == mpdrig_SHADOW_FIT_NOW && fitting) {
        std::printf("after the fit:\n");
        Print(s);
        code = fit_state.rfind("done:", 0) == 0 ? 0 : 1;
      } else if (action != mpdrig_SHADOW_FIT_NOW) {
        std::printf("after the change:\n");
        Print(s);
        code = 0;
      }
    });
    if (code >= 0) return code;
    if (fitting) {
      until = std::max(until,
                       deadline + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(fit_timeout_s)));
    }
  }
  if (fitting) return Fail("the fit did not end within --fit-timeout (it goes on in the shadow)");
  return Fail("the shadow did not answer the command within --timeout");
}
