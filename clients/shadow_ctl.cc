// shadow_ctl: changes a running `mpdrig shadow` (its mpdrig_shadow_command topic) and prints the
// shadow's answer: its error before, the change, and its error over the window after. A client on
// the client library (clients/client/shadow_client.h): it speaks only the DDS topics.
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

#include "clients/client/participant.h"
#include "clients/client/shadow_client.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "shadow_ctl: %s\n", what.c_str());
  return 1;
}

using mpdrig::client::ShadowAction;
using mpdrig::client::ShadowStatus;

void Print(const ShadowStatus& s) {
  std::printf("shadow '%s' of %s at t = %.2f s: error %.4f over %.0f s\n", s.shadow_id.c_str(),
              s.rig_id.c_str(), s.sim_time_s, s.error, s.window_s);
  for (std::size_t i = 0; i < s.channels.size() && i < s.nrmse.size(); ++i) {
    if (!std::isnan(s.nrmse[i]))
      std::printf("  %-5s NRMSE %.4f\n", s.channels[i].c_str(), s.nrmse[i]);
  }
  std::printf("  effects:");
  for (const std::string& effect : s.active_effects) std::printf(" [%s]", effect.c_str());
  std::printf("%s\n  parameters set:", s.active_effects.empty() ? " none" : "");
  for (const std::string& parameter : s.parameters) std::printf(" %s", parameter.c_str());
  std::printf("%s\n", s.parameters.empty() ? " none" : "");
  if (!s.last_change.empty()) {
    std::printf("  last change: %s at t = %.2f s (error then %.4f)\n", s.last_change.c_str(),
                s.last_change_sim_time_s, s.error_at_last_change);
  }
  if (!s.fit_state.empty()) std::printf("  fit: %s\n", s.fit_state.c_str());
  if (s.rejected_commands > 0) {
    std::printf("  %llu commands refused, the last: %s\n",
                static_cast<unsigned long long>(s.rejected_commands), s.last_rejection.c_str());
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
std::optional<std::pair<ShadowAction, std::string>> RequestedAction(const Args& args) {
  if (!args.effect_on.empty()) return std::pair{ShadowAction::kEffectOn, args.effect_on};
  if (!args.effect_off.empty()) return std::pair{ShadowAction::kEffectOff, args.effect_off};
  if (!args.set.empty()) return std::pair{ShadowAction::kSet, args.set};
  if (args.reset) return std::pair{ShadowAction::kReset, std::string()};
  if (args.fit_now) return std::pair{ShadowAction::kFitNow, std::string()};
  if (args.cancel_fit) return std::pair{ShadowAction::kFitCancel, std::string()};
  return std::nullopt;
}

using Clock = std::chrono::steady_clock;
using Deadline = std::chrono::time_point<Clock, std::chrono::duration<double>>;
constexpr double kPollS = 0.1;

// The shadow's current status (transient-local: it arrives once matched), printed; its count of
// refused commands, or nothing if no shadow of the rig answered before the deadline.
mpdrig::Result<std::optional<std::uint64_t>> ReadCurrentStatus(mpdrig::client::Shadow& shadow,
                                                               Deadline deadline) {
  std::optional<std::uint64_t> rejected;
  while (!rejected && Clock::now() < deadline) {
    auto taken = shadow.TakeStatus(kPollS);
    if (!taken.ok()) return taken.status();
    for (const ShadowStatus& s : *taken) {
      rejected = s.rejected_commands;
      Print(s);
    }
  }
  return rejected;
}

// The answer: the status that names the command; for a fit, then the one that ends it (waited
// for up to fit_timeout_s past the deadline). The exit code.
int AwaitAnswer(mpdrig::client::Shadow& shadow, const Args& args, ShadowAction action,
                std::uint64_t command_id, std::uint64_t before_rejected, Deadline deadline) {
  bool fitting = false;
  auto until = deadline;
  while (Clock::now() < until) {
    auto taken = shadow.TakeStatus(kPollS);
    if (!taken.ok()) return Fail(taken.status().message());
    int code = -1;
    for (const ShadowStatus& s : *taken) {
      if (code >= 0 || s.last_command_id != command_id) continue;
      if (s.rejected_commands > before_rejected) {
        std::printf("refused: %s\n", s.last_rejection.c_str());
        code = 1;
      } else if (action == ShadowAction::kFitNow && s.fit_state.rfind("running:", 0) == 0) {
        if (!fitting) std::printf("fit %s\n", s.fit_state.c_str());
        fitting = true;
      } else if (action == ShadowAction::kFitNow && fitting) {
        std::printf("after the fit:\n");
        Print(s);
        code = s.fit_state.rfind("done:", 0) == 0 ? 0 : 1;
      } else if (action != ShadowAction::kFitNow) {
        std::printf("after the change:\n");
        Print(s);
        code = 0;
      }
    }
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
  // With --security the shadow's topics are in its rig's partition.
  auto participant = client::Participant::Join(
      {.domain = args.domain, .dds_config = args.dds_config, .security_dir = args.security});
  if (!participant.ok()) return Fail(participant.status().message());
  auto shadow = client::Shadow::Open(*participant, args.rig_id, args.shadow_id);
  if (!shadow.ok()) return Fail(shadow.status().message());
  const Deadline deadline = Clock::now() + std::chrono::duration<double>(args.timeout_s);
  auto before_rejected = ReadCurrentStatus(**shadow, deadline);
  if (!before_rejected.ok()) return Fail(before_rejected.status().message());
  if (!*before_rejected) {
    return Fail("no shadow '" + args.shadow_id + "' of rig '" + args.rig_id +
                "' answered (is `mpdrig shadow --rig " + args.rig_id + " --shadow-id " +
                args.shadow_id + "` running?)");
  }
  auto action = RequestedAction(args);
  if (!action) return 0;

  // Only now: reading the status needs no right to command (a watcher under security has none).
  // A command written before the shadow's reader has matched would be lost (volatile).
  const std::chrono::duration<double> left = deadline - Clock::now();
  const auto matched = (*shadow)->AwaitCommandReader(left.count());
  if (!matched.ok()) return Fail(matched.status().message());
  if (!*matched) return Fail("the shadow's command reader did not match within --timeout");
  auto sent = (*shadow)->Send(action->first, action->second);
  if (!sent.ok()) return Fail(sent.status().message());
  return AwaitAnswer(**shadow, args, action->first, *sent, **before_rejected, deadline);
}
