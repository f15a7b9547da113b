#include "clients/client/shadow_client.h"

#include <chrono>
#include <optional>

#include "clients/client/client_wire.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::client {

Result<ShadowAction> ShadowActionNamed(const std::string& name) {
  static const std::pair<const char*, ShadowAction> kNames[] = {
      {"effect_on", ShadowAction::kEffectOn},
      {"effect_off", ShadowAction::kEffectOff},
      {"set", ShadowAction::kSet},
      {"reset", ShadowAction::kReset},
      {"fit_now", ShadowAction::kFitNow},
      {"fit_cancel", ShadowAction::kFitCancel}};
  std::string known;
  for (const auto& [text, action] : kNames) {
    if (name == text) return action;
    known += (known.empty() ? "" : ", ") + std::string(text);
  }
  return Status::Error("unknown action '" + name + "' (" + known + ")");
}

bool ShadowActionNeedsArgument(ShadowAction action) {
  return action == ShadowAction::kEffectOn || action == ShadowAction::kEffectOff ||
         action == ShadowAction::kSet;
}

namespace {

mpdrig_ShadowAction ToWire(ShadowAction action) {
  switch (action) {
    case ShadowAction::kEffectOn:
      return mpdrig_SHADOW_EFFECT_ON;
    case ShadowAction::kEffectOff:
      return mpdrig_SHADOW_EFFECT_OFF;
    case ShadowAction::kSet:
      return mpdrig_SHADOW_SET;
    case ShadowAction::kReset:
      return mpdrig_SHADOW_RESET;
    case ShadowAction::kFitNow:
      return mpdrig_SHADOW_FIT_NOW;
    case ShadowAction::kFitCancel:
      return mpdrig_SHADOW_FIT_CANCEL;
  }
  return mpdrig_SHADOW_RESET;
}

}  // namespace

struct Shadow::Dds {
  std::shared_ptr<Participant> participant;  // first: the others are deleted before it goes
  Participant::Scope scope;
  dds::Entity status_topic, command_topic;
  std::optional<dds::Reader<mpdrig_ShadowStatus>> status;
  std::optional<dds::Writer<mpdrig_ShadowCommand>> command;  // made when first asked for
};

Shadow::Shadow(std::string rig_id, std::string shadow_id)
    : rig_id_(std::move(rig_id)), shadow_id_(std::move(shadow_id)), dds_(std::make_unique<Dds>()) {}

Shadow::~Shadow() = default;

Result<std::unique_ptr<Shadow>> Shadow::Open(const std::shared_ptr<Participant>& participant,
                                             const std::string& rig_id,
                                             const std::string& shadow_id, bool read_status) {
  if (!participant) return Status::Error("no participant");
  if (rig_id.empty()) return Status::Error("the rig id is empty");
  std::unique_ptr<Shadow> shadow(new Shadow(rig_id, shadow_id));
  Dds& d = *shadow->dds_;
  d.participant = participant;
  // With security the shadow's topics are in its rig's partition.
  auto scope = participant->ScopeOf(rig_id);
  if (!scope.ok()) return scope.status();
  d.scope = *scope;
  auto status_topic = dds::CreateTopic(participant->handle(), dds::topics::kShadowStatus);
  if (!status_topic.ok()) return status_topic.status();
  d.status_topic = std::move(status_topic).value();
  auto command_topic = dds::CreateTopic(participant->handle(), dds::topics::kShadowCommand);
  if (!command_topic.ok()) return command_topic.status();
  d.command_topic = std::move(command_topic).value();
  if (read_status) {
    auto status = dds::Reader<mpdrig_ShadowStatus>::Create(
        d.scope.subscriber, d.status_topic.handle(), dds::StatusQos());
    if (!status.ok()) return participant->EndpointError(status.status(), rig_id, "reading");
    d.status.emplace(std::move(status).value());
  }
  return shadow;
}

Result<std::vector<ShadowStatus>> Shadow::TakeStatus(double wait_s) {
  Dds& d = *dds_;
  if (!d.status) return Status::Error("this shadow handle reads no status (Shadow::Open)");
  std::vector<ShadowStatus> taken;
  const auto take = [&]() -> Status {
    auto took = d.status->TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
      if (rig_id_ != s.rig_id || shadow_id_ != s.shadow_id) return;
      taken.push_back(FromWire(s));
    });
    return took.ok() ? Status::Ok() : took.status();
  };
  MPDRIG_RETURN_IF_ERROR(take());
  if (!taken.empty() || wait_s <= 0.0) return taken;
  auto ready = d.status->Wait(static_cast<dds_duration_t>(wait_s * 1e9));
  if (!ready.ok()) return ready.status();
  MPDRIG_RETURN_IF_ERROR(take());
  return taken;
}

Result<bool> Shadow::AwaitCommandReader(double timeout_s) {
  Dds& d = *dds_;
  if (!d.command) {
    auto writer = dds::Writer<mpdrig_ShadowCommand>::Create(
        d.scope.publisher, d.command_topic.handle(), dds::RequestQos());
    if (!writer.ok()) return d.participant->EndpointError(writer.status(), rig_id_, "commanding");
    d.command.emplace(std::move(writer).value());
  }
  return dds::AwaitReader(d.command->handle(), dds::DeadlineAfter(std::max(0.0, timeout_s)));
}

Result<std::uint64_t> Shadow::Send(ShadowAction action, const std::string& argument) {
  Dds& d = *dds_;
  if (!d.command) return Status::Error("no command writer yet (Shadow::AwaitCommandReader)");
  std::string rig_id = rig_id_, shadow_id = shadow_id_, text = argument;
  mpdrig_ShadowCommand command{};
  command.rig_id = rig_id.data();
  command.shadow_id = shadow_id.data();
  command.command_id =
      static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count());
  command.action = ToWire(action);
  command.argument = text.data();
  MPDRIG_RETURN_IF_ERROR(d.command->Write(command));
  return static_cast<std::uint64_t>(command.command_id);
}

}  // namespace mpdrig::client
