// The lockstep clock's step requests without DDS: rigs with work take turns of at most 100
// steps, so a long request starves no other rig; a request's commands are taken at its first
// turn only; it completes after its last step, also when a stop cut a turn short; more than an
// hour of rig time in one request is refused with the reason.
#include "service/rig/lockstep_queue.h"

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "service/dds/topics.h"

namespace mpdrig::service {
namespace {

// Serves the queue as the service does, rig by rig, running every step of each turn; returns
// (rig, steps, starts, completed id or 0) per turn.
struct TurnSeen {
  std::size_t rig;
  std::uint64_t steps;
  bool starts;
  std::uint64_t completed;
  bool operator==(const TurnSeen&) const = default;
};
std::vector<TurnSeen> Serve(LockstepQueue& queue, std::size_t rigs) {
  std::vector<TurnSeen> seen;
  while (queue.busy()) {
    for (std::size_t rig = 0; rig < rigs; ++rig) {
      const auto turn = queue.NextTurn(rig);
      if (!turn) continue;
      const auto completed = queue.Ran(rig, turn->steps);
      seen.push_back({rig, turn->steps, turn->starts, completed.value_or(0)});
    }
  }
  return seen;
}

TEST(LockstepQueue, ALongRequestTakesTurnsAndStarvesNoOtherRig) {
  LockstepQueue queue(0.01);
  ASSERT_FALSE(queue.Add(0, 7, 250));
  ASSERT_FALSE(queue.Add(1, 8, 1));
  ASSERT_FALSE(queue.Add(1, 9, 120));
  EXPECT_TRUE(queue.busy());
  const std::vector<TurnSeen> expected = {{0, 100, true, 0}, {1, 1, true, 8},   {0, 100, false, 0},
                                          {1, 100, true, 0}, {0, 50, false, 7}, {1, 20, false, 9}};
  EXPECT_EQ(Serve(queue, 2), expected);
  EXPECT_FALSE(queue.busy());
  EXPECT_FALSE(queue.NextTurn(0));
  EXPECT_FALSE(queue.NextTurn(5)) << "a rig never asked";
}

TEST(LockstepQueue, AStopCutATurnShortAndTheRequestGoesOnFromThere) {
  LockstepQueue queue(0.01);
  ASSERT_FALSE(queue.Add(0, 3, 150));
  auto turn = queue.NextTurn(0);
  ASSERT_TRUE(turn);
  EXPECT_EQ(turn->steps, 100u);
  EXPECT_FALSE(queue.Ran(0, 40));  // stopped after 40
  turn = queue.NextTurn(0);
  ASSERT_TRUE(turn);
  EXPECT_FALSE(turn->starts) << "its commands were taken at its first turn";
  EXPECT_EQ(turn->steps, 100u);
  EXPECT_FALSE(queue.Ran(0, 100));
  turn = queue.NextTurn(0);
  ASSERT_TRUE(turn);
  EXPECT_EQ(turn->steps, 10u);
  EXPECT_EQ(queue.Ran(0, 10), std::optional<std::uint64_t>(3));
}

TEST(LockstepQueue, MoreThanAnHourOfRigTimeInOneRequestIsRefusedWithTheReason) {
  LockstepQueue lab(0.01);  // 100 Hz: an hour is 360 000 steps
  EXPECT_EQ(lab.max_steps(), 360000u);
  EXPECT_FALSE(lab.Add(0, 1, 360000));
  const auto refused = lab.Add(0, 2, 4294967295u);
  ASSERT_TRUE(refused);
  EXPECT_EQ(*refused, std::string(dds::topics::kStepRequest.name) +
                          " 2 of 4294967295 steps refused: more than 3600 s of rig time (360000 "
                          "steps at this rate) in one request; send several");
  LockstepQueue fast(0.001);  // 1 kHz
  EXPECT_EQ(fast.max_steps(), 3600000u);
  EXPECT_TRUE(fast.Add(0, 1, 3600001));
}

}  // namespace
}  // namespace mpdrig::service
