// The real-time clock of a paced rig (ClockMode::kRealtime): one tick per sensor period on the
// wall clock, and the account of the ticks that came too late.
//
// A tick that ends more than a whole period after its deadline is a stall (the process was
// stopped, starved of CPU, swapped). The periods between the deadline and now are skipped: the
// rig runs on that far behind the wall clock, and the stall is counted (deadline misses, the
// periods lost, the longest and the last stall, the rig time at which it happened) for the status
// (RigStatus, idl/mpdrig.idl). With catch_up (a playback, whose rows must all go out) the schedule
// stands instead: the ticks after a stall run at once until they are on it again, and no period
// is lost. A tick that is late by less than a period is not a stall: the next deadline is one
// period after its own, so a late tick is made up by a shorter wait.
//
// The clock and the wait are injected (the service uses std::chrono::steady_clock and
// std::this_thread::sleep_until), so the rule is tested without waiting on a real clock.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace mpdrig::service {

class RealTimePacer {
 public:
  using Clock = std::chrono::steady_clock;
  using Now = std::function<Clock::time_point()>;
  using SleepUntil = std::function<void(Clock::time_point)>;

  // What the stalls cost so far.
  struct Stalls {
    std::uint64_t deadline_misses = 0;  // ticks more than a period late
    std::uint64_t lost_periods = 0;     // sensor periods those misses skipped (0 with catch_up)
    double longest_s = 0.0;             // the longest miss, from its deadline [s of wall time]
    double last_s = 0.0;                // the last miss, from its deadline [s of wall time]
    double last_sim_time_s = -1.0;      // rig time at the last miss; -1: none

    // "fell behind real time at rig time ...": empty while there was no stall.
    std::string Warning() const;
  };

  // The first deadline is one period after `start`. period_s > 0.
  RealTimePacer(double period_s, bool catch_up, Clock::time_point start, Now now = Clock::now,
                SleepUntil sleep_until = DefaultSleepUntil);

  // Called after each tick's work, with the rig time the tick reached: waits until the next
  // deadline, or, more than a period past it, counts the stall and returns at once.
  void AfterTick(double sim_time_s);

  const Stalls& stalls() const { return stalls_; }
  Clock::time_point next_deadline() const { return next_; }

 private:
  static void DefaultSleepUntil(Clock::time_point t);

  double period_s_;
  Clock::duration period_;
  bool catch_up_;
  Clock::time_point next_;
  Now now_;
  SleepUntil sleep_until_;
  Stalls stalls_;
};

}  // namespace mpdrig::service
