#include "service/rig/lockstep_queue.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "service/dds/topics.h"

namespace mpdrig::service {

LockstepQueue::LockstepQueue(double sensor_period_s)
    : max_steps_(static_cast<std::uint64_t>(std::floor(kMaxRequestRigTimeS / sensor_period_s))) {}

std::optional<std::string> LockstepQueue::Add(std::size_t rig, std::uint64_t id,
                                              std::uint64_t steps) {
  if (steps > max_steps_) {
    char reason[300];
    std::snprintf(reason, sizeof reason,
                  "%s %llu of %llu steps refused: more than %.0f s of rig time (%llu steps "
                  "at this rate) in one request; send several",
                  dds::topics::kStepRequest.name, static_cast<unsigned long long>(id),
                  static_cast<unsigned long long>(steps), kMaxRequestRigTimeS,
                  static_cast<unsigned long long>(max_steps_));
    return std::string(reason);
  }
  if (queues_.size() <= rig) queues_.resize(rig + 1);
  queues_[rig].push_back(Pending{id, steps, false});
  return std::nullopt;
}

bool LockstepQueue::busy() const {
  return std::any_of(queues_.begin(), queues_.end(), [](const auto& q) { return !q.empty(); });
}

std::optional<LockstepQueue::Turn> LockstepQueue::NextTurn(std::size_t rig) {
  if (rig >= queues_.size() || queues_[rig].empty()) return std::nullopt;
  Pending& request = queues_[rig].front();
  const Turn turn{std::min(request.remaining, kSliceSteps), !request.started};
  request.started = true;
  return turn;
}

std::optional<std::uint64_t> LockstepQueue::Ran(std::size_t rig, std::uint64_t steps) {
  if (rig >= queues_.size() || queues_[rig].empty()) return std::nullopt;
  Pending& request = queues_[rig].front();
  request.remaining -= std::min(steps, request.remaining);
  if (request.remaining > 0) return std::nullopt;
  const std::uint64_t id = request.id;
  queues_[rig].pop_front();
  return id;
}

}  // namespace mpdrig::service
