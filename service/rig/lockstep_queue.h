// The lockstep clock's step requests (ClockMode::kLockstep, rig_service.h): the rig advances
// only when a client asks. Each rig has a queue of requests; the rigs with work are served in
// turns of at most kSliceSteps steps, so one long request (up to an hour of rig time) neither
// starves another rig nor delays a stop by more than one step. A request's commands are taken
// when it starts (Turn::starts); it completes after its last step (Ran gives its id, the status's
// last_completed_step_request).
//
// A request for more than kMaxRequestRigTimeS of rig time is refused, with the reason for the
// rig's status: a request cannot be cancelled, and the rig's later requests (its own
// controller's) wait behind it (2^32 - 1 steps ran about 15 h while the rig's controller failed).
// An hour (360 000 steps at the lab's 100 Hz, 10-20 s of wall time here) is far beyond any one
// control step and any experiment a client would not split.
//
// No transport, no clock: the service takes the requests from DDS and runs the steps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace mpdrig::service {

class LockstepQueue {
 public:
  static constexpr std::uint64_t kSliceSteps = 100;
  static constexpr double kMaxRequestRigTimeS = 3600.0;

  // Every rig of a service shares the sensor period [s] (> 0).
  explicit LockstepQueue(double sensor_period_s);

  // Request `id` for `steps` sensor periods of rig `rig` (an index; the queue grows with the
  // rigs): queued, or the reason it is refused.
  std::optional<std::string> Add(std::size_t rig, std::uint64_t id, std::uint64_t steps);
  // Some rig has a request.
  bool busy() const;

  struct Turn {
    std::uint64_t steps = 0;  // to run now: at most kSliceSteps
    bool starts = false;      // the request's first turn: take the commands first
  };
  // Rig `rig`'s next turn; none while it has no request.
  std::optional<Turn> NextTurn(std::size_t rig);
  // The turn ran `steps` (fewer after a stop): the request's id if it is complete now.
  std::optional<std::uint64_t> Ran(std::size_t rig, std::uint64_t steps);

  // The most steps one request may ask for at this sensor period.
  std::uint64_t max_steps() const { return max_steps_; }

 private:
  struct Pending {
    std::uint64_t id = 0;
    std::uint64_t remaining = 0;
    bool started = false;
  };
  std::uint64_t max_steps_;
  std::vector<std::deque<Pending>> queues_;  // per rig
};

}  // namespace mpdrig::service
