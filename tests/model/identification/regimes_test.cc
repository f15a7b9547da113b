// Regimes of a log (regimes.h) and the split that leaves each on both sides: on the synthetic
// generator's step-test logs (none: their split stays where it was, so diagnose's verdicts on
// them stay), on logs with a pump stop and a choke closure (MakeSyntheticLog's regimes, at the
// lab's noise), on a heave that stops and one that is only slow (logs made here), and on splits
// that cannot serve every regime.
#include "model/identification/regimes.h"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/measured_log.h"
#include "model/identification/synthetic_log.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig {
namespace {

// The generator's transitions take 0.5 s (its pump's ramp, its choke actuator): the 10 % and
// the closed-choke thresholds are crossed inside them.
constexpr double kTransitionS = 0.5;

MeasuredLog Synthetic(SyntheticLogOptions options, double duration_s = 40.0,
                      double rate_hz = 50.0) {
  options.duration_s = duration_s;
  options.rate_hz = rate_hz;
  auto made = MakeSyntheticLog(options);
  EXPECT_TRUE(made.ok()) << made.status().message();
  if (!made.ok()) return {};
  auto log = MeasuredLogFromRigLog(made->log, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  return log.ok() ? *log : MeasuredLog{};
}

const Regime* Find(const std::vector<Regime>& regimes, const std::string& name) {
  for (const Regime& regime : regimes) {
    if (regime.name == name) return &regime;
  }
  return nullptr;
}

// The step tests the identification tests were tuned on (quiet and lab noise, the low-pressure
// runs too; diagnose_test's 10 seeds at 40 s and 50 Hz, its 120 s, 100 Hz logs): no regime, so
// the split is fit_fraction's, bit for bit.
TEST(Regimes, NoneInTheStepTestLogs) {
  for (int k = 1; k <= 12; ++k) {
    // Seeds 1-10 at 40 s and 50 Hz, then seeds 1-2 at 120 s and 100 Hz.
    const bool long_log = k > 10;
    const std::uint64_t seed = long_log ? k - 10 : k;
    for (bool lab : {false, true}) {
      SyntheticLogOptions options;
      options.seed = seed;
      if (lab) options.sensor_noise = SensorNoise::Lab();
      options.low_pressure = !long_log && seed % 3 == 0;
      const MeasuredLog log = long_log ? Synthetic(options, 120.0, 100.0) : Synthetic(options);
      SCOPED_TRACE("seed " + std::to_string(seed) + (lab ? " lab" : " quiet") +
                   (long_log ? " 120 s" : " 40 s"));
      const std::vector<Regime> regimes = DetectRegimes(log, RigParams());
      for (const Regime& regime : regimes) ADD_FAILURE() << regime.name;
      const double t0 = log.time_s().front(), t1 = log.time_s().back();
      const RegimeSplit split = SplitByRegimes(regimes, t0, t1, 0.6);
      EXPECT_EQ(split.split_s, t0 + 0.6 * (t1 - t0));
      EXPECT_TRUE(split.one_sided.empty());
    }
  }
}

// A pump stop and, later, a choke closure: each found where the generator put it (within its
// transition), and the split moved from 24 s to leave the stop on both sides.
TEST(Regimes, PumpStopAndChokeClosureFoundAndSplitAcrossThem) {
  SyntheticLogOptions options;
  options.seed = 2;
  options.sensor_noise = SensorNoise::Lab();
  options.pump_stops = {{12.0, 8.0}};
  options.choke_closures = {{27.0, 6.0}};
  const MeasuredLog log = Synthetic(options);
  const std::vector<Regime> regimes = DetectRegimes(log, RigParams());
  ASSERT_EQ(regimes.size(), 4u);
  const Regime* stopped = Find(regimes, "pump stopped");
  const Regime* closed = Find(regimes, "choke closed");
  ASSERT_NE(stopped, nullptr);
  ASSERT_NE(closed, nullptr);
  ASSERT_NE(Find(regimes, "pump running"), nullptr);
  ASSERT_NE(Find(regimes, "choke open"), nullptr);
  EXPECT_EQ(stopped->input, "FT2");
  EXPECT_EQ(closed->input, "choke_position");
  ASSERT_EQ(stopped->intervals.size(), 1u);
  ASSERT_EQ(closed->intervals.size(), 1u);
  EXPECT_GE(stopped->intervals[0].begin_s, 12.0);
  EXPECT_LE(stopped->intervals[0].begin_s, 12.0 + kTransitionS);
  EXPECT_GE(stopped->intervals[0].end_s, 20.0 - kTransitionS);
  EXPECT_LE(stopped->intervals[0].end_s, 20.0);
  EXPECT_GE(closed->intervals[0].begin_s, 27.0);
  EXPECT_LE(closed->intervals[0].begin_s, 27.0 + kTransitionS);
  EXPECT_GE(closed->intervals[0].end_s, 33.0 - kTransitionS);
  EXPECT_LE(closed->intervals[0].end_s, 33.0);
  EXPECT_TRUE(Find(regimes, "heave stopped") == nullptr) << "the heave runs throughout";

  // One split cannot serve both (the stop ends at 20 s, the closure starts at 27 s): at most one
  // of them on both sides, and the other named as on one side.
  const RegimeSplit split = SplitByRegimes(regimes, 0.0, 40.0, 0.6);
  EXPECT_EQ(split.requested_s, 24.0);
  EXPECT_FALSE(split.one_sided.empty());
  for (const std::string& note : split.one_sided) std::printf("one side: %s\n", note.c_str());
  int two_sided = 0;
  for (const Regime& regime : split.regimes) {
    two_sided += OnSide(regime, regime.fit_s) && OnSide(regime, regime.score_s);
  }
  EXPECT_EQ(two_sided, 3) << "the most a single split can serve: both states of one input and "
                             "the running state of the other";

  // The stop alone: the split moves to the nearest point that leaves a fifth of it scored.
  const std::vector<Regime> pump_only = {*stopped, *Find(regimes, "pump running")};
  const RegimeSplit moved = SplitByRegimes(pump_only, 0.0, 40.0, 0.6);
  EXPECT_TRUE(moved.one_sided.empty());
  EXPECT_LT(moved.split_s, 24.0);
  const double latest = stopped->intervals[0].end_s - kMinRegimeShare * stopped->duration_s;
  EXPECT_LE(moved.split_s, latest);
  EXPECT_GE(moved.split_s, latest - 40.0 * 0.4 / 400.0) << "the nearest on the split grid";
  for (const Regime& regime : moved.regimes) {
    EXPECT_TRUE(OnSide(regime, regime.fit_s) && OnSide(regime, regime.score_s)) << regime.name;
  }
}

// A log made here: a two-tone heave (0.2 and 0.37 Hz, irregular: not periodic over the log) that
// stops for 10 s, and one at 0.06 Hz (16.7 s period: the slowest the window is made for) that
// never stops.
MeasuredLog Heave(bool stops, double freq_hz) {
  MeasuredLog log;
  const double rate_hz = 50.0;
  for (int n = 0; n <= 60 * 50; ++n) {
    const double t = n / rate_hz;
    const double w = 2.0 * std::numbers::pi;
    double x =
        0.03 * std::sin(w * freq_hz * t) + (freq_hz > 0.1 ? 0.015 * std::sin(w * 0.37 * t) : 0.0);
    if (stops && t >= 20.0 && t < 30.0) x = 0.0;
    log.inputs.time_s.push_back(t);
    log.inputs.piston_position_m.push_back(x);
    log.inputs.choke_opening_frac.push_back(30.0 / 90.0);
    log.inputs.pump_flow_m3ps.push_back(1.3e-4);
    log.inputs.outlet_pressure_pa.push_back(101325.0);
  }
  log.reconstructed_inputs = log.inputs;
  return log;
}

TEST(Regimes, HeaveStopFoundSlowHeaveNot) {
  const std::vector<Regime> regimes = DetectRegimes(Heave(true, 0.2), RigParams());
  const Regime* still = Find(regimes, "heave stopped");
  ASSERT_NE(still, nullptr);
  ASSERT_EQ(still->intervals.size(), 1u);
  // The window's RMS falls below 5 % only once the window is nearly all inside the stop.
  EXPECT_NEAR(still->intervals[0].begin_s, 20.0 + 0.5 * kPistonWindowS, 0.5);
  EXPECT_NEAR(still->intervals[0].end_s, 30.0 - 0.5 * kPistonWindowS, 0.5);
  EXPECT_TRUE(DetectRegimes(Heave(false, 0.06), RigParams()).empty());
  EXPECT_TRUE(DetectRegimes(Heave(false, 0.2), RigParams()).empty());
}

TEST(Regimes, SyntheticLogRefusesARegimeOutsideTheLog) {
  SyntheticLogOptions options;
  options.duration_s = 20.0;
  options.rate_hz = 20.0;
  options.pump_stops = {{15.0, 8.0}};
  auto made = MakeSyntheticLog(options);
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.status().message().find("pump stop at 15 s for 8 s"), std::string::npos)
      << made.status().message();
  options.pump_stops.clear();
  options.choke_closures = {{5.0, 0.2}};
  made = MakeSyntheticLog(options);
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.status().message().find("choke closure"), std::string::npos);
}

}  // namespace
}  // namespace mpdrig
