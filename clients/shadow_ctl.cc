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
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/dds/topics.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "shadow_ctl: %s\n", what.c_str());
  return 1;
}

void Print(const mpdrig_ShadowStatus& s) {
  std::printf("shadow '%s' of %s at t = %.2f s: error %.4f over %.0f s\n", s.shadow_id, s.rig_id,
              s.sim_time_s, s.error, s.window_s);
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

struct Args {
  std::string rig_id = "rig-1";
  // `mpdrig shadow --shadow-id`'s default: the one shadow of a rig.
  std::string shadow_id = "shadow";
  int domain = 0;
  std::string dds_config;
  std::string effect_on, effect_off, set;
  bool reset = false, fit_now = false, cancel_fit = false;
  double timeout_s = 10.0, fit_timeout_s = 600.0;
  std::string security;
};

void AddOptions(CLI::App& app, Args& args) {
  app.add_option("--rig", args.rig_id, "the rig the shadow follows")->capture_default_str();
  app.add_option("--shadow", args.shadow_id,
                 "which shadow of the rig (`mpdrig shadow --shadow-id`): only it takes the "
                 "command")
      ->capture_default_str();
  app.add_option("--domain", args.domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  app.add_option("--dds-config", args.dds_config, "Cyclone DDS XML (default: loopback only)");
  auto* on = app.add_option("--effect-on", args.effect_on, "switch an effect on: NAME[:k=v,...]");
  auto* off = app.add_option("--effect-off", args.effect_off, "switch an effect off: NAME");
  auto* param = app.add_option("--set", args.set, "set a parameter: KEY=VALUE (EFFECT.KEY too)");
  auto* again = app.add_flag("--reset", args.reset, "back to the model the shadow started with");
  auto* fit = app.add_flag("--fit-now", args.fit_now,
                           "fit c, f1 and the active effects' strengths on the shadow's last "
                           "minutes of rows, in the background; waits for the result");
  auto* cancel = app.add_flag("--cancel-fit", args.cancel_fit,
                              "stop the shadow's running fit (its result is dropped)");
  on->excludes(off, param, again, fit, cancel);
  off->excludes(param, again, fit, cancel);
  param->excludes(again, fit, cancel);
  again->excludes(fit, cancel);
  fit->excludes(cancel);
  app.add_option("--fit-timeout", args.fit_timeout_s,
                 "with --fit-now: wait this long for the fit [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--security", args.security,
                 "DDS Security: an identity directory of a class (deploy/security/make-class OUT "
                 "NAME: OUT/NAME) allowed to use the rig's shadow; its topics are then in "
                 "partition rig.<rig id>. Refuses an invalid directory, saying why");
  app.add_option("--timeout", args.timeout_s, "give up after this long [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// The change the flags ask for, with its argument; none: only print the status.
std::optional<std::pair<mpdrig_ShadowAction, std::string>> RequestedAction(const Args& args) {
  if (!args.effect_on.empty()) return std::pair{mpdrig_SHADOW_EFFECT_ON, args.effect_on};
  if (!args.effect_off.empty()) return std::pair{mpdrig_SHADOW_EFFECT_OFF, args.effect_off};
  if (!args.set.empty()) return std::pair{mpdrig_SHADOW_SET, args.set};
  if (args.reset) return std::pair{mpdrig_SHADOW_RESET, std::string()};
  if (args.fit_now) return std::pair{mpdrig_SHADOW_FIT_NOW, std::string()};
  if (args.cancel_fit) return std::pair{mpdrig_SHADOW_FIT_CANCEL, std::string()};
  return std::nullopt;
}

using Reader = mpdrig::dds::Reader<mpdrig_ShadowStatus>;
using Clock = std::chrono::steady_clock;
using Deadline = std::chrono::time_point<Clock, std::chrono::duration<double>>;

// The shadow's current status (transient-local: it arrives once matched), printed; its count of
// refused commands, or nothing if no shadow of the rig answered before the deadline.
mpdrig::Result<std::optional<std::uint64_t>> ReadCurrentStatus(Reader& status, const Args& args,
                                                               Deadline deadline) {
  std::optional<std::uint64_t> rejected;
  while (!rejected && Clock::now() < deadline) {
    auto ready = status.Wait(DDS_MSECS(100));
    if (!ready.ok()) return ready.status();
    (void)status.TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
      if (args.rig_id != s.rig_id || args.shadow_id != s.shadow_id) return;
      rejected = s.rejected_commands;
      Print(s);
    });
  }
  return rejected;
}

// The answer: the status that names the command; for a fit, then the one that ends it (waited
// for up to fit_timeout_s past the deadline). The exit code.
int AwaitAnswer(Reader& status, const Args& args, const mpdrig_ShadowCommand& command,
                std::uint64_t before_rejected, Deadline deadline) {
  bool fitting = false;
  auto until = deadline;
  while (Clock::now() < until) {
    auto ready = status.Wait(DDS_MSECS(100));
    if (!ready.ok()) return Fail(ready.status().message());
    int code = -1;
    (void)status.TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
      if (code >= 0 || args.rig_id != s.rig_id || args.shadow_id != s.shadow_id ||
          s.last_command_id != command.command_id)
        return;
      const std::string fit_state = s.fit_state;
      if (s.rejected_commands > before_rejected) {
        std::printf("refused: %s\n", s.last_rejection);
        code = 1;
      } else if (command.action == mpdrig_SHADOW_FIT_NOW && fit_state.rfind("running:", 0) == 0) {
        if (!fitting) std::printf("fit %s\n", s.fit_state);
        fitting = true;
      } else if (command.action == mpdrig_SHADOW_FIT_NOW && fitting) {
        std::printf("after the fit:\n");
        Print(s);
        code = fit_state.rfind("done:", 0) == 0 ? 0 : 1;
      } else if (command.action != mpdrig_SHADOW_FIT_NOW) {
        std::printf("after the change:\n");
        Print(s);
        code = 0;
      }
    });
    if (code >= 0) return code;
    if (fitting) {
      until = std::max(until, deadline + std::chrono::duration<double>(args.fit_timeout_s));
    }
  }
  if (fitting) return Fail("the fit did not end within --fit-timeout (it goes on in the shadow)");
  return Fail("the shadow did not answer the command within --timeout");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("shadow_ctl - switch a running shadow model's effects and parameters");
  Args args;
  AddOptions(app, args);
  CLI11_PARSE(app, argc, argv);

  using namespace mpdrig;
  auto created = dds::Domain::Create(
      args.domain, args.dds_config.empty() ? dds::LoopbackConfig() : args.dds_config);
  if (!created.ok()) return Fail(created.status().message());
  // With --security the shadow's topics are in its rig's partition.
  auto scope = dds::CreateClientScope(args.domain, args.security, args.rig_id);
  if (!scope.ok()) return Fail(scope.status().message());
  const dds_entity_t p = scope->participant.handle();
  auto command_topic = dds::CreateTopic(p, dds::topics::kShadowCommand);
  auto status_topic = dds::CreateTopic(p, dds::topics::kShadowStatus);
  if (!command_topic.ok()) return Fail(command_topic.status().message());
  if (!status_topic.ok()) return Fail(status_topic.status().message());
  auto status = Reader::Create(scope->sub(), status_topic->handle(), dds::StatusQos());
  if (!status.ok()) return Fail(status.status().message());
  const Deadline deadline = Clock::now() + std::chrono::duration<double>(args.timeout_s);
  auto before_rejected = ReadCurrentStatus(*status, args, deadline);
  if (!before_rejected.ok()) return Fail(before_rejected.status().message());
  if (!*before_rejected) {
    return Fail("no shadow '" + args.shadow_id + "' of rig '" + args.rig_id +
                "' answered (is `mpdrig shadow --rig " + args.rig_id + " --shadow-id " +
                args.shadow_id + "` running?)");
  }
  auto action = RequestedAction(args);
  if (!action) return 0;

  // Only now: reading the status needs no right to command (a watcher under security has none).
  auto writer = dds::Writer<mpdrig_ShadowCommand>::Create(scope->pub(), command_topic->handle(),
                                                          dds::RequestQos());
  if (!writer.ok()) return Fail(writer.status().message());
  // A command written before the shadow's reader has matched would be lost (volatile).
  const std::chrono::duration<double> left = deadline - Clock::now();
  const auto matched = dds::AwaitReader(writer->handle(), dds::DeadlineAfter(left.count()));
  if (!matched.ok()) return Fail(matched.status().message());
  if (!*matched) return Fail("the shadow's command reader did not match within --timeout");

  mpdrig_ShadowCommand command{};
  command.rig_id = args.rig_id.data();
  command.shadow_id = args.shadow_id.data();
  command.command_id =
      static_cast<unsigned long long>(std::chrono::system_clock::now().time_since_epoch().count());
  command.action = action->first;
  command.argument = action->second.data();
  auto written = writer->Write(command);
  if (!written.ok()) return Fail(written.message());
  return AwaitAnswer(*status, args, command, **before_rejected, deadline);
}
