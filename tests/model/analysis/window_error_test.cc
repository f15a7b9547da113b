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
#include <utility>
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

// The window's own side measured once (MeasureWindow) scores every replay as measuring it for each
// does, to the bit; and the window's samples are those with begin <= t <= end however the ends
// fall: between samples, on one, before the log's start or beyond its end, or past every sample
// (no sample: NaN). Checked against the error summed over every sample with that test, as the
// definition at the top of window_error.h says.
TEST(WindowErrorAccumulator, AWindowMeasuredOnceScoresEveryReplayAsOnItsOwn) {
  const auto by_definition = [](const MeasuredLog& log, const ModelTraces& model, double begin,
                                double end) {
    double total = 0.0;
    int count = 0;
    for (std::size_t c = 0; c < log.channels.size(); ++c) {
      const std::vector<double>& y = log.channels[c].values_si;
      double sum = 0.0, ss_res = 0.0, ss_tot = 0.0;
      long n_in = 0;
      for (std::size_t n = 0; n < y.size(); ++n) {
        if (log.time_s()[n] >= begin && log.time_s()[n] <= end && std::isfinite(y[n])) {
          sum += y[n], ++n_in;
        }
      }
      const double mean = n_in > 0 ? sum / n_in : 0.0;
      for (std::size_t n = 0; n < y.size(); ++n) {
        if (!(log.time_s()[n] >= begin && log.time_s()[n] <= end) || !std::isfinite(y[n])) continue;
        ss_res += (model.values_si[c][n] - y[n]) * (model.values_si[c][n] - y[n]);
        ss_tot += (y[n] - mean) * (y[n] - mean);
      }
      const double nrmse =
          n_in > 0 && !IsConstantSpread(log.channels[c].channel, mean, std::sqrt(ss_tot / n_in))
              ? Nrmse(ss_res, ss_tot)
              : std::numeric_limits<double>::quiet_NaN();
      if (std::isfinite(nrmse)) total += nrmse, ++count;
    }
    return count > 0 ? total / count : std::numeric_limits<double>::quiet_NaN();
  };
  const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (const Scenario& scenario : Scenarios()) {
    const Prepared p = NoisyLog(scenario, 3);
    const SimulationOptions options = testing::ScenarioReplayOptions();
    const std::vector<double>& t = p.log.time_s();
    const double dt = t[1] - t[0];
    const std::vector<std::pair<double, double>> windows = {
        {t.front() + 2.0, t.front() + 0.6 * (t.back() - t.front())},  // diagnose's fitting data
        {t[5] + 0.3 * dt, t[t.size() / 2] + 0.7 * dt},                // ends between samples
        {t[7], t[t.size() - 9]},                                      // ends on samples
        {t.front() - 1.0, t.back() + 1.0},                            // beyond the log
        {t.back() + 1.0, t.back() + 2.0}};                            // no sample
    for (const auto& [begin, end] : windows) {
      const WindowReference window = MeasureWindow(p.log, begin, end);
      for (const RigParams& params : {RigParams{}, OffModel()}) {
        auto traces = ReplayModel(p.log, params, options, p.replay);
        ASSERT_TRUE(traces.ok()) << traces.status().message();
        const double expected = by_definition(p.log, *traces, begin, end);
        EXPECT_TRUE(same(WindowError(p.log, *traces, begin, end), expected))
            << scenario.name << " [" << begin << ", " << end << "]";
        const double never = std::numeric_limits<double>::infinity();
        auto measured_once = ReplayWindowError(p.log, params, options, p.replay, window, never);
        auto on_its_own = ReplayWindowError(p.log, params, options, p.replay, begin, end, never);
        ASSERT_TRUE(measured_once.ok() && measured_once->has_value()) << scenario.name;
        ASSERT_TRUE(on_its_own.ok() && on_its_own->has_value()) << scenario.name;
        EXPECT_TRUE(same(**measured_once, **on_its_own)) << scenario.name;
        EXPECT_TRUE(same(**measured_once, expected)) << scenario.name;
      }
    }
  }
}

}  // namespace
}  // namespace mpdrig
