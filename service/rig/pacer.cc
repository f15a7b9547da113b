#include "service/rig/pacer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>
#include <utility>

namespace mpdrig::service {

std::string RealTimePacer::Stalls::Warning() const {
  if (last_sim_time_s < 0.0) return "";
  char text[240];
  std::snprintf(text, sizeof text,
                "fell behind real time at rig time %.3f s: a %.3f s stall (%llu periods lost in "
                "%llu stalls, the longest %.3f s)",
                last_sim_time_s, last_s, static_cast<unsigned long long>(lost_periods),
                static_cast<unsigned long long>(deadline_misses), longest_s);
  return text;
}

RealTimePacer::RealTimePacer(double period_s, bool catch_up, Clock::time_point start, Now now,
                             SleepUntil sleep_until)
    : period_s_(period_s),
      period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s))),
      catch_up_(catch_up),
      next_(start + period_),
      now_(std::move(now)),
      sleep_until_(std::move(sleep_until)) {}

void RealTimePacer::DefaultSleepUntil(Clock::time_point t) { std::this_thread::sleep_until(t); }

void RealTimePacer::AfterTick(double sim_time_s) {
  const Clock::time_point now = now_();
  if (now <= next_ + period_) {
    sleep_until_(next_);
    next_ += period_;
    return;
  }
  // More than a whole period late: a missed deadline.
  const double late_s = std::chrono::duration<double>(now - next_).count();
  ++stalls_.deadline_misses;
  stalls_.longest_s = std::max(stalls_.longest_s, late_s);
  stalls_.last_s = late_s;
  stalls_.last_sim_time_s = sim_time_s;
  if (catch_up_) {
    next_ += period_;  // the schedule stands: the next ticks run at once until they are on it
  } else {
    stalls_.lost_periods += static_cast<std::uint64_t>(std::floor(late_s / period_s_));
    next_ = now + period_;
  }
}

}  // namespace mpdrig::service
