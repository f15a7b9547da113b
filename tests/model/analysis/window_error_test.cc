// WindowError as a replay goes on (WindowErrorAccumulator, ReplayWindowError): the same number to
// the bit as WindowError of the whole replay, a bound below it at every sample that only rises, and
// a replay stopped only where its error would have exceeded the stop. Diagnose's scans rely on all
// three to stop replays without changing a result. On logs at the lab's noise (thesis Table
// 4.1.1): a sine, a sweep and an irregular two-tone heave, two noise seeds each, with a model that
// is off (a wave speed 3 % low, as a scan's point is) so that errors differ from the noise floor.
#include "model/analysis/window_error.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "tests/support/lab_scenario.h"

namespace mpdrig {
namespace {

using testing::LabNoise;
using testing::Scenario;
using testing::Sine;
using testing::TruthLog;

std::vector<Scenario> Scenarios() {
  return {
      {"sine_0.2Hz", 20.0, 0.0, [](double t) { return Sine(t, 0.05, 0.2); },
       [](double) { return 31.0; }, [](double) { return 5.0; }},
      {"sweep", 20.0, 0.0,
       [](double t) {
         const double f0 = 0.05, f1 = 1.2, T = 20.0;
         return 0.03 * std::sin(2.0 * std::numbers::pi * (f0 * t + 0.5 * (f1 - f0) * t * t / T));
       },
       [](double) { return 31.0; }, [](double) { return 6.0; }},
      {"two_tones_cut", 30.0, 10.0,
       [](double t) { return Sine(t, 0.04, 0.06) + Sine(t, 0.02, 0.23); },
       [](double) { return 31.0; }, [](double) { return 5.0; }},
  };
}

struct Prepared {
  MeasuredLog log;
  ReplayOptions replay;
};

Prepared NoisyLog(const Scenario& scenario, std::uint64_t seed) {
  auto log = MeasuredLogFromRigLog(LabNoise(TruthLog(scenario), seed), scenario.name);
  EXPECT_TRUE(log.ok()) << log.status().message();
  Prepared prepared{std::move(log).value(), ReplayOptions{}};
  const Status status = PrepareLogReplay(&prepared.log, RigParams{},
                                         testing::ScenarioReplayOptions(), &prepared.replay);
  EXPECT_TRUE(status.ok()) << status.message();
  return prepared;
}

RigParams OffModel() {
  RigParams params;
  params.wave_speed_mps *= 0.97;
  return params;
}

TEST(WindowErrorAccumulator, IsWindowErrorToTheBitWithABoundThatOnlyRisesToIt) {
  for (const Scenario& scenario : Scenarios()) {
    for (std::uint64_t seed : {1u, 2u}) {
      const Prepared p = NoisyLog(scenario, seed);
      auto traces = ReplayModel(p.log, OffModel(), testing::ScenarioReplayOptions(), p.replay);
      ASSERT_TRUE(traces.ok()) << traces.status().message();
      const std::vector<double>& t = p.log.time_s();
      // A window that leaves out the start and the end, as diagnose's fitting data do.
      const double begin = t.front() + 2.0, end = t.front() + 0.6 * (t.back() - t.front());
      const double whole = WindowError(p.log, *traces, begin, end);
      WindowErrorAccumulator accumulator(p.log, begin, end);
      std::vector<double> values(p.log.channels.size());
      double previous = 0.0;
      for (std::size_t n = 0; n < t.size(); ++n) {
        for (std::size_t c = 0; c < values.size(); ++c) values[c] = traces->values_si[c][n];
        accumulator.Add(n, values.data());
        const double bound = accumulator.LowerBound();
        ASSERT_GE(bound, previous) << scenario.name << " seed " << seed << " sample " << n;
        ASSERT_LE(bound, whole) << scenario.name << " seed " << seed << " sample " << n;
        previous = bound;
      }
      EXPECT_EQ(accumulator.Error(), whole) << scenario.name << " seed " << seed;
      EXPECT_GT(whole, 0.0);
    }
  }
}

TEST(ReplayWindowError, StopsOnlyWhereTheErrorWouldHaveExceededTheStop) {
  for (const Scenario& scenario : Scenarios()) {
    for (std::uint64_t seed : {1u, 2u}) {
      const Prepared p = NoisyLog(scenario, seed);
      const SimulationOptions options = testing::ScenarioReplayOptions();
      const std::vector<double>& t = p.log.time_s();
      const double begin = t.front() + 2.0, end = t.front() + 0.6 * (t.back() - t.front());
      const RigParams params = OffModel();
      auto traces = ReplayModel(p.log, params, options, p.replay);
      ASSERT_TRUE(traces.ok()) << traces.status().message();
      const double whole = WindowError(p.log, *traces, begin, end);
      const double never = std::numeric_limits<double>::infinity();
      auto full = ReplayWindowError(p.log, params, options, p.replay, begin, end, never);
      ASSERT_TRUE(full.ok() && full->has_value()) << scenario.name;
      EXPECT_EQ(**full, whole) << scenario.name << " seed " << seed;
      // At its own error it is never stopped (the bound cannot pass it) ...
      auto at = ReplayWindowError(p.log, params, options, p.replay, begin, end, whole);
      ASSERT_TRUE(at.ok() && at->has_value()) << scenario.name;
      EXPECT_EQ(**at, whole);
      // ... below it, it is: a stop at 90 % of the error comes before the window's end.
      auto below = ReplayWindowError(p.log, params, options, p.replay, begin, end, 0.9 * whole);
      ASSERT_TRUE(below.ok()) << below.status().message();
      EXPECT_FALSE(below->has_value()) << scenario.name << " seed " << seed;
    }
  }
}

}  // namespace
}  // namespace mpdrig
