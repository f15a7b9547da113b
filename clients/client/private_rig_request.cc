#include "clients/client/private_rig_request.h"

#include <chrono>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::client {
namespace {

using StatusReader = dds::Reader<mpdrig_RigStatus>;
using Clock = std::chrono::steady_clock;

// What the rig's status said last: its newest event and refusal, so only news is reported.
struct LastSaid {
  std::string event, rejection;
};

LastSaid ReadLastSaid(const StatusReader& status, const std::string& rig_id) {
  LastSaid said;
  (void)status.Wait(DDS_MSECS(500));
  (void)status.TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
    if (rig_id != s.rig_id) return;
    said.rejection = s.last_rejection;
    for (std::uint32_t i = 0; i < s.warnings._length; ++i) said.event = s.warnings._buffer[i];
  });
  return said;
}

// The status the service publishes after the request: what changed since `before`.
Result<PrivateRigAnswer> AwaitAnswer(const StatusReader& status, const std::string& rig_id,
                                     const LastSaid& before, Clock::time_point until) {
  PrivateRigAnswer answer;
  while (Clock::now() < until) {
    auto ready = status.Wait(DDS_MSECS(200));
    if (!ready.ok()) return ready.status();
    (void)status.TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
      if (rig_id != s.rig_id) return;
      if (s.last_rejection != before.rejection) {
        answer.said.push_back(std::string("refused: ") + s.last_rejection);
        answer.refused = answer.answered = true;
      }
      for (std::uint32_t i = 0; i < s.warnings._length; ++i) {
        if (before.event != s.warnings._buffer[i]) {
          answer.said.emplace_back(s.warnings._buffer[i]);
          answer.answered = true;
        }
      }
    });
    if (answer.answered) return answer;
  }
  return answer;
}

}  // namespace

Result<PrivateRigAnswer> RequestPrivateRigs(const std::shared_ptr<Participant>& participant,
                                            const std::string& rig_id, std::uint32_t count,
                                            double timeout_s) {
  if (!participant) return Status::Error("no participant");
  auto scope = participant->ScopeOf(rig_id);
  if (!scope.ok()) return scope.status();
  const dds_entity_t p = participant->handle();
  auto request_topic = dds::CreateTopic(p, dds::topics::kRigRequest);
  if (!request_topic.ok()) return request_topic.status();
  auto status_topic = dds::CreateTopic(p, dds::topics::kStatus);
  if (!status_topic.ok()) return status_topic.status();
  auto writer = dds::Writer<mpdrig_RigRequest>::Create(scope->publisher, request_topic->handle(),
                                                       dds::RequestQos());
  if (!writer.ok()) return participant->EndpointError(writer.status(), rig_id, "asking for");
  auto status = StatusReader::Create(scope->subscriber, status_topic->handle(), dds::StatusQos());
  if (!status.ok()) return participant->EndpointError(status.status(), rig_id, "reading");

  // The service's request reader must have matched (authentication, secure discovery) first.
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(timeout_s));
  const auto matched = dds::AwaitReader(writer->handle(), dds::DeadlineAfter(timeout_s));
  if (!matched.ok()) return matched.status();
  if (!*matched) {
    return Status::Error("no service takes private-rig requests for rig '" + rig_id +
                         "' on domain " + std::to_string(participant->options().domain) +
                         " (mpdrig serve --security ... --private-rigs N)");
  }
  const LastSaid before = ReadLastSaid(*status, rig_id);
  std::string id = rig_id;
  mpdrig_RigRequest request{id.data(), count};
  MPDRIG_RETURN_IF_ERROR(writer->Write(request));
  if (dds_wait_for_acks(writer->handle(), DDS_SECS(5)) != DDS_RETCODE_OK) {
    return Status::Error("the service did not acknowledge the request");
  }
  return AwaitAnswer(*status, rig_id, before, until);
}

}  // namespace mpdrig::client
