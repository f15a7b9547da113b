// The zero-crossing frequency tracker (beyond the thesis).
#include "model/observer/frequency_tracker.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace mpdrig::observer {
namespace {

// A noisy sine with an offset: the estimate locks within 0.5 % of the true frequency (noise of
// 5 % of the amplitude moves a crossing by ~0.05/omega = 0.04 s over a 5 s period; averaging
// three periods, the period error is ~0.3 %).
TEST(FrequencyTrackerTest, LocksOntoNoisySine) {
  for (double hz : {0.1, 0.25, 0.6}) {
    FrequencyTrackerOptions options;
    options.initial_hz = 0.2;
    auto tracker = FrequencyTracker::Create(options, 0.0, 3.0);
    ASSERT_TRUE(tracker.ok()) << tracker.status().message();
    std::mt19937 rng(3);
    std::normal_distribution<double> noise(0.0, 0.05);
    const double dt = 0.01;
    for (int k = 1; k * dt < 40.0 / hz; ++k) {
      const double t = k * dt;
      tracker->Update(t, 3.0 + std::sin(2 * M_PI * hz * t) + noise(rng));
    }
    EXPECT_TRUE(tracker->locked());
    EXPECT_NEAR(tracker->frequency_hz(), hz, 0.005 * hz);
  }
}

TEST(FrequencyTrackerTest, KeepsInitialFrequencyWithoutOscillation) {
  FrequencyTrackerOptions options;
  options.initial_hz = 0.3;
  auto tracker = FrequencyTracker::Create(options, 0.0, 1.0);
  ASSERT_TRUE(tracker.ok());
  for (int k = 1; k < 10000; ++k) tracker->Update(k * 0.01, 1.0);
  EXPECT_FALSE(tracker->locked());
  EXPECT_EQ(tracker->frequency_hz(), 0.3);
}

TEST(FrequencyTrackerTest, RejectsBadOptions) {
  FrequencyTrackerOptions options;
  options.initial_hz = 5.0;  // above max_hz
  EXPECT_FALSE(FrequencyTracker::Create(options, 0.0, 0.0).ok());
  options = {};
  options.periods_averaged = 0;
  EXPECT_FALSE(FrequencyTracker::Create(options, 0.0, 0.0).ok());
}

}  // namespace
}  // namespace mpdrig::observer
