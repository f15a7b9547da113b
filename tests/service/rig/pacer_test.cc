// The real-time pacer's rule on a clock the test moves: on-time ticks wait for their deadlines,
// a tick late by less than a period is made up, a stall of more than a period is counted with
// the periods it skips (or, with catch_up, run after at once), and the status warning says so.
#include "service/rig/pacer.h"

#include <chrono>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig::service {
namespace {

using Clock = RealTimePacer::Clock;
using std::chrono::milliseconds;

// A wall clock that moves only when the test or the pacer's wait moves it.
struct FakeClock {
  Clock::time_point now{};
  std::vector<Clock::time_point> waits;  // every deadline the pacer waited for
  RealTimePacer Pacer(double period_s, bool catch_up) {
    return RealTimePacer(
        period_s, catch_up, now, [this] { return now; },
        [this](Clock::time_point t) {
          waits.push_back(t);
          now = std::max(now, t);
        });
  }
};

TEST(RealTimePacer, OnTimeTicksWaitForTheirDeadlinesAndALateOneIsMadeUp) {
  FakeClock clock;
  RealTimePacer pacer = clock.Pacer(0.01, false);
  const Clock::time_point start = clock.now;
  for (int k = 1; k <= 3; ++k) {
    clock.now += milliseconds(2);  // the tick's work
    pacer.AfterTick(0.01 * k);
    EXPECT_EQ(clock.now, start + milliseconds(10 * k)) << "tick " << k;
  }
  // 8 ms of work plus 9 ms late is 17 ms past the last deadline, less than a period past the
  // next one: no stall, the next deadline keeps the schedule (no wait left to do).
  clock.now += milliseconds(17);
  pacer.AfterTick(0.04);
  EXPECT_EQ(pacer.next_deadline(), start + milliseconds(50));
  EXPECT_EQ(pacer.stalls().deadline_misses, 0u);
  EXPECT_TRUE(pacer.stalls().Warning().empty());
}

TEST(RealTimePacer, AStallIsCountedWithThePeriodsItSkips) {
  FakeClock clock;
  RealTimePacer pacer = clock.Pacer(0.01, false);
  const Clock::time_point start = clock.now;
  pacer.AfterTick(0.01);  // waits until 10 ms
  // Stopped for 45 ms past the 20 ms deadline: 4 whole periods lost, the schedule restarts from
  // now without a wait.
  clock.now = start + milliseconds(65);
  const std::size_t waits = clock.waits.size();
  pacer.AfterTick(0.02);
  EXPECT_EQ(clock.waits.size(), waits) << "a stalled tick must not wait";
  EXPECT_EQ(pacer.stalls().deadline_misses, 1u);
  EXPECT_EQ(pacer.stalls().lost_periods, 4u);
  EXPECT_NEAR(pacer.stalls().last_s, 0.045, 1e-9);
  EXPECT_NEAR(pacer.stalls().longest_s, 0.045, 1e-9);
  EXPECT_DOUBLE_EQ(pacer.stalls().last_sim_time_s, 0.02);
  EXPECT_EQ(pacer.next_deadline(), start + milliseconds(75));
  // A shorter second stall: counted, the longest kept.
  clock.now = start + milliseconds(75 + 25);
  pacer.AfterTick(0.03);
  EXPECT_EQ(pacer.stalls().deadline_misses, 2u);
  EXPECT_EQ(pacer.stalls().lost_periods, 6u);
  EXPECT_NEAR(pacer.stalls().longest_s, 0.045, 1e-9);
  EXPECT_NEAR(pacer.stalls().last_s, 0.025, 1e-9);
  EXPECT_EQ(pacer.stalls().Warning(),
            "fell behind real time at rig time 0.030 s: a 0.025 s stall (6 periods lost in 2 "
            "stalls, the longest 0.045 s)");
}

// A playback's rows must all go out: after a stall the ticks due meanwhile run at once, each
// still more than a period late counted as a late tick (docs/live.md: "late ticks caught up"),
// until the schedule is met again; no period is lost.
TEST(RealTimePacer, CatchUpKeepsTheScheduleAndLosesNoPeriod) {
  FakeClock clock;
  RealTimePacer pacer = clock.Pacer(0.01, true);
  const Clock::time_point start = clock.now;
  clock.now = start + milliseconds(45);  // the first tick ends 35 ms past its deadline
  pacer.AfterTick(0.01);
  // The ticks due at 20 and 30 ms are still more than a period behind: run at once, counted.
  pacer.AfterTick(0.02);
  pacer.AfterTick(0.03);
  EXPECT_TRUE(clock.waits.empty());
  EXPECT_EQ(pacer.stalls().deadline_misses, 3u);
  EXPECT_NEAR(pacer.stalls().longest_s, 0.035, 1e-9);
  // The one due at 40 ms is within a period: on the schedule again (its deadline has passed, so
  // the wait returns at once), and the next one waits for 50 ms.
  pacer.AfterTick(0.04);
  pacer.AfterTick(0.05);
  ASSERT_EQ(clock.waits.size(), 2u);
  EXPECT_EQ(clock.waits[0], start + milliseconds(40));
  EXPECT_EQ(clock.waits[1], start + milliseconds(50));
  EXPECT_EQ(clock.now, start + milliseconds(50));
  EXPECT_EQ(pacer.next_deadline(), start + milliseconds(60));
  EXPECT_EQ(pacer.stalls().deadline_misses, 3u);
  EXPECT_EQ(pacer.stalls().lost_periods, 0u);
}

}  // namespace
}  // namespace mpdrig::service
