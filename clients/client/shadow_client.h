// A shadow model of a rig (`mpdrig shadow`) as a client sees it: its status (how far the model
// is from the rig, what it runs with) and its commands (effects on and off, parameters, reset,
// fit). Only the topics mpdrig_shadow_status and mpdrig_shadow_command (idl/mpdrig.idl), through
// a Participant (participant.h): with security in the rig's partition.
//
//   auto shadow = client::Shadow::Open(participant, "rig-1", "shadow");
//   auto seen = (*shadow)->TakeStatus(1.0);              // the current status, once matched
//   if ((*shadow)->AwaitCommandReader(10.0).value_or(false))
//     auto id = (*shadow)->Send(client::ShadowAction::kEffectOn, "unsteady_friction");
//
// Each shadow answers only the commands with its shadow id; its status names the last command
// it took (last_command_id), applied or refused (rejected_commands, last_rejection).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clients/client/participant.h"
#include "model/common/status.h"

namespace mpdrig::client {

// mpdrig_shadow_status, in its units (rig time in s, NRMSE without unit).
struct ShadowStatus {
  std::string rig_id, shadow_id;
  double sim_time_s = 0.0;
  double window_s = 0.0;
  double error = 0.0;                 // mean NRMSE over the channels with one; NaN: warming up
  std::vector<std::string> channels;  // "P1", "PT1", ... in the order of nrmse
  std::vector<double> nrmse;          // NaN where undefined
  std::vector<std::string> active_effects, parameters, available_effects;
  std::string last_change;  // "" : none
  double last_change_sim_time_s = -1.0;
  double error_at_last_change = 0.0;
  std::uint64_t rejected_commands = 0;
  std::string last_rejection;
  std::uint64_t last_command_id = 0;
  std::string fit_state;  // "", "running: ...", "done: ...", "failed: ..."
};

enum class ShadowAction { kEffectOn, kEffectOff, kSet, kReset, kFitNow, kFitCancel };
// "effect_on", "effect_off", "set", "reset", "fit_now", "fit_cancel"; an unknown name is an
// error that lists them.
Result<ShadowAction> ShadowActionNamed(const std::string& name);
// Whether the action takes an argument (an effect, or KEY=VALUE).
bool ShadowActionNeedsArgument(ShadowAction action);

class Shadow {
 public:
  // The shadow `shadow_id` of rig `rig_id`; with `read_status` a reader of its status (reading
  // needs no right to command: the command writer is made only when asked for).
  static Result<std::unique_ptr<Shadow>> Open(const std::shared_ptr<Participant>& participant,
                                              const std::string& rig_id,
                                              const std::string& shadow_id,
                                              bool read_status = true);
  ~Shadow();
  Shadow(const Shadow&) = delete;
  Shadow& operator=(const Shadow&) = delete;

  const std::string& rig_id() const { return rig_id_; }
  const std::string& shadow_id() const { return shadow_id_; }

  // This shadow's statuses that arrived since the last call, in order; waits up to `wait_s`
  // for the first (0: does not wait). Transient-local: the current one arrives once matched.
  Result<std::vector<ShadowStatus>> TakeStatus(double wait_s);

  // Makes the command writer if there is none, and waits up to `timeout_s` until a shadow's
  // command reader has matched it (a command written before would reach no one): false if none.
  Result<bool> AwaitCommandReader(double timeout_s);
  // Writes a command (AwaitCommandReader first); its id, which the shadow's status names once
  // it has taken it. Ids come from the wall clock, so a status naming an earlier client's
  // command is not taken for this one's.
  Result<std::uint64_t> Send(ShadowAction action, const std::string& argument);

 private:
  struct Dds;
  Shadow(std::string rig_id, std::string shadow_id);

  std::string rig_id_, shadow_id_;
  std::unique_ptr<Dds> dds_;
};

}  // namespace mpdrig::client
