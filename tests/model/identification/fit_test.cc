// Parameter identification (model/identification/fit.h) on logs the model itself produced with
// known parameters and known noise: the fit must recover the parameters within what the noise
// allows (its own standard errors), reach the noise floor, and not move on an exact log.
// Logs are built in memory (Simulate + MeasuredLogFromRigLog), at 50 cells as `mpdrig fit`.
#include "model/identification/fit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "model/analysis/compare.h"
#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/common/units.h"
#include "model/effects/param_by_key.h"
#include "model/identification/synthetic_log.h"
#include "model/riglog/rig_log.h"
#include "model/sim/log_inputs.h"
#include "model/sim/sensor_noise.h"
#include "tests/support/lab_scenario.h"

namespace mpdrig {
namespace {

using riglog::Channel;

constexpr double kRateHz = 100.0;
constexpr double kDurationS = 60.0;
constexpr int kCells = 50;
// Transmitter noise of the generated logs: 0.005 bar on pressures, 0.05 L/min on flows.
constexpr double kPressureNoisePa = 500.0;
const double kFlowNoiseM3ps = units::LpmToM3ps(0.05);

// Inputs that excite what is fitted: a piston sweep 0.05..0.8 Hz across the pipe's resonances
// (c/4L, c/2L: wave speed; their damping: friction), choke steps between open (31 deg, 25 deg)
// and closed-to-the-leak (10 deg, where G = leak) with 1 L/min of pump flow through it (the
// closed choke's pressure is set by the leak, (5.3.2)).
// Choke steps 31 -> 10 -> 25 -> 10 deg at 15, 30, 45 s, each a 0.3 s ramp (the actuator's rate
// limit is 90 deg/s, thesis 8.4).
double ChokeDeg(double t) {
  const double times[] = {15.0, 30.0, 45.0};
  const double levels[] = {31.0, 10.0, 25.0, 10.0};
  double deg = levels[0];
  for (int k = 0; k < 3; ++k) {
    const double fraction = std::clamp((t - times[k]) / 0.3, 0.0, 1.0);
    deg += fraction * (levels[k + 1] - levels[k]);
  }
  return deg;
}

riglog::RigLog InputLog() {
  riglog::RigLog log;
  const long count = std::lround(kDurationS * kRateHz);
  for (long i = 0; i <= count; ++i) log.time_s.push_back(i / kRateHz);
  std::vector<double> position, choke, pump, outlet;
  for (double t : log.time_s) {
    const double f0 = 0.05, f1 = 0.8;
    const double phase = 2.0 * std::numbers::pi * (f0 * t + 0.5 * (f1 - f0) * t * t / kDurationS);
    position.push_back(0.02 * std::sin(phase));
    const double deg = ChokeDeg(t);
    choke.push_back(units::ChokeDegToFrac(deg));
    pump.push_back(units::LpmToM3ps(1.0));
    outlet.push_back(log.atmospheric_pressure_pa);
  }
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kPistonPosition), position).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kChokePosition), choke).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kFT2), pump).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kC1), outlet).ok());
  return log;
}

SimulationOptions FitSimulation() {
  SimulationOptions options;
  options.cells = kCells;
  options.choke_input = ChokeInput::kMeasured;
  return options;
}

bool IsFlow(Channel channel) {
  return channel == Channel::kFT1 || channel == Channel::kFT3 || channel == Channel::kFT4;
}

// A "measured" log: the model with `truth` on InputLog(), every compared channel, plus Gaussian
// noise (none if noise_scale is 0).
MeasuredLog MakeLog(const RigParams& truth, double noise_scale, unsigned seed = 7) {
  const riglog::RigLog inputs = InputLog();
  auto signals = SignalsFromLog(inputs, "inputs", ReplayOptions{});
  EXPECT_TRUE(signals.ok()) << signals.status().message();
  auto run = Simulate(truth, FitSimulation(), *signals, inputs.time_s);
  EXPECT_TRUE(run.ok()) << run.status().message();
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  riglog::RigLog log = inputs;
  for (Channel channel : ComparedChannels()) {
    const double sigma = noise_scale * (IsFlow(channel) ? kFlowNoiseM3ps : kPressureNoisePa);
    std::vector<double> values;
    for (const RigSample& sample : run->samples)
      values.push_back(sample[channel] + sigma * normal(random));
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(channel), values).ok());
  }
  auto measured = MeasuredLogFromRigLog(log, "generated.csv");
  EXPECT_TRUE(measured.ok()) << measured.status().message();
  return std::move(measured).value();
}

FitOptions Options() {
  FitOptions options;
  options.simulation = FitSimulation();
  return options;
}

std::vector<FitParameter> Defaults(const std::vector<std::string>& keys) {
  std::vector<FitParameter> parameters;
  for (const std::string& key : keys) {
    auto parameter = DefaultFitParameter(key);
    EXPECT_TRUE(parameter.ok()) << parameter.status().message();
    parameters.push_back(*parameter);
  }
  return parameters;
}

void ExpectValidCorrelation(const FitResult& fit) {
  const std::size_t p = fit.keys.size();
  ASSERT_EQ(fit.correlation.size(), p);
  for (std::size_t i = 0; i < p; ++i) {
    ASSERT_EQ(fit.correlation[i].size(), p);
    EXPECT_DOUBLE_EQ(fit.correlation[i][i], 1.0);
    for (std::size_t j = 0; j < p; ++j) {
      EXPECT_NEAR(fit.correlation[i][j], fit.correlation[j][i], 1e-12);
      EXPECT_LE(std::abs(fit.correlation[i][j]), 1.0 + 1e-12);
    }
  }
}

// The rig the generated logs of the base-parameter fits come from: c, f1 and leak away from the
// thesis values the fits start at.
RigParams Truth() {
  RigParams truth;
  truth.wave_speed_mps = 1000.0;
  truth.friction_f1_per_s = 0.3;
  truth.choke_leak_m2 = 1.0e-6;
  return truth;
}

TEST(FitTest, RecoversWaveSpeedFrictionAndLeakFromANoisyLog) {
  const RigParams truth = Truth();
  const MeasuredLog log = MakeLog(truth, 1.0);
  // Noise floor: the error of the true parameters.
  auto exact = ReplayModel(log, truth, FitSimulation());
  ASSERT_TRUE(exact.ok());
  const double noise_floor = WindowError(log, *exact, -INFINITY, INFINITY);

  int progress_calls = 0;
  FitOptions options = Options();
  options.progress = [&](int, double error) {
    ++progress_calls;
    EXPECT_TRUE(std::isfinite(error));
  };
  auto fit =
      FitParameters(log, RigParams{},
                    Defaults({"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"}), options);
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  SCOPED_TRACE(fit->solver_report);
  const double expected[] = {1000.0, 0.3, 1.0e-6};
  const double thesis[] = {850.0, 0.15, 6.0e-7};
  for (std::size_t j = 0; j < 3; ++j) {
    SCOPED_TRACE(fit->keys[j]);
    EXPECT_DOUBLE_EQ(fit->initial[j], thesis[j]);
    ASSERT_TRUE(std::isfinite(fit->standard_errors[j]));
    EXPECT_GT(fit->standard_errors[j], 0.0);
    // Unbiased up to the noise and the fit's resolution: within 3 standard errors (the noise's
    // spread of the estimate) plus one finite-difference step (the replay is only piecewise
    // smooth below it: c moves the time grid against the samples, about 0.5 m/s of texture at
    // 50 cells), and within 1%.
    EXPECT_NEAR(fit->estimates[j], expected[j],
                3.0 * fit->standard_errors[j] + options.relative_step * expected[j]);
    EXPECT_NEAR(fit->estimates[j], expected[j], 0.01 * expected[j]);
  }
  EXPECT_TRUE(fit->converged);
  EXPECT_GT(fit->error_before, 5.0 * noise_floor);
  // At the noise floor: the error of the true parameters, within that texture (0.5%).
  EXPECT_NEAR(fit->error_after, noise_floor, 0.005 * noise_floor);
  ExpectValidCorrelation(*fit);
  EXPECT_GT(progress_calls, 1);
  EXPECT_GT(fit->replays, fit->iterations);
  EXPECT_DOUBLE_EQ(fit->params.wave_speed_mps, fit->estimates[0]);
  // error_after is compare's metric on the fitted params.
  auto replay = ReplayModel(log, fit->params, FitSimulation());
  ASSERT_TRUE(replay.ok());
  EXPECT_NEAR(WindowError(log, *replay, -INFINITY, INFINITY), fit->error_after, 1e-12);
  auto comparison = CompareTraces(log, *replay);
  ASSERT_TRUE(comparison.ok());
  EXPECT_NEAR(comparison->error, fit->error_after, 1e-12);
}

// The acceptance for fitting at the lab's noise (thesis Table 4.1.1 on every channel,
// inputs too): on effect-free synthetic logs (120 s at 100 Hz, the lab's excitation, random base
// parameters), the wave speed within 1 % and both friction coefficients within 20 %, as the
// thesis tuned them (Table 9.4.1). Replayed as measured, the input noise biases them far more
// (f1 up to twice its value, c stuck near its start): the reconstruction is what makes this hold.
TEST(FitTest, WaveSpeedAndFrictionAtLabNoise) {
  // Seeds 3-8 in the suite; MPDRIG_FIT_SEEDS=FIRST-LAST runs others (docs/fitting.md's
  // measurement).
  std::uint64_t first = 3, last = 8;
  if (const char* seeds = std::getenv("MPDRIG_FIT_SEEDS")) {
    std::sscanf(seeds, "%lu-%lu", &first, &last);
  }
  for (std::uint64_t seed = first; seed <= last; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    SyntheticLogOptions synth;
    synth.seed = seed;
    synth.sensor_noise = SensorNoise::Lab();
    auto made = MakeSyntheticLog(synth);
    ASSERT_TRUE(made.ok()) << made.status().message();
    auto log = MeasuredLogFromRigLog(made->log, "lab noise");
    ASSERT_TRUE(log.ok()) << log.status().message();
    for (ChannelWeighting weighting : {ChannelWeighting::kVariation, ChannelWeighting::kNoise}) {
      const bool noise = weighting == ChannelWeighting::kNoise;
      SCOPED_TRACE(noise ? "noise weights" : "variation weights");
      FitOptions options;
      options.simulation.cells = synth.cells;
      options.weighting = weighting;
      // As `mpdrig fit` prepares the replay: the start and the input levels, from the start
      // parameters.
      MeasuredLog prepared = *log;
      ASSERT_TRUE(PrepareLogReplay(&prepared, RigParams{}, options.simulation, &options.replay,
                                   InputLevels::kAfterTheFit)
                      .ok());
      auto fit = FitParametersAndInputLevels(
          &prepared, RigParams{},
          Defaults({"wave_speed_mps", "friction_f1_per_s", "friction_f2_per_m"}), options);
      ASSERT_TRUE(fit.ok()) << fit.status().message();
      const RigParams& truth = made->truth;
      std::printf("seed %d, %s weights: c %.1f (%.1f), f1 %.4f (%.4f), f2 %.3f (%.3f)\n",
                  static_cast<int>(seed), noise ? "noise" : "variation", fit->estimates[0],
                  truth.wave_speed_mps, fit->estimates[1], truth.friction_f1_per_s,
                  fit->estimates[2], truth.friction_f2_per_m);
      EXPECT_NEAR(fit->estimates[0], truth.wave_speed_mps, 0.01 * truth.wave_speed_mps);
      EXPECT_NEAR(fit->estimates[1], truth.friction_f1_per_s, 0.2 * truth.friction_f1_per_s);
      EXPECT_NEAR(fit->estimates[2], truth.friction_f2_per_m, 0.2 * truth.friction_f2_per_m);
    }
  }
}

// While the choke is open (31 deg until 15 s) its characteristic is above the leak, G =
// max(G_table, leak) (9.4), so the leak changes nothing: it is held at its start value and
// reported as held (not as an estimate), and the wave speed and friction are still fitted.
TEST(FitTest, AParameterWithoutInfluenceIsHeldAndTheOthersStillFit) {
  const RigParams truth = Truth();
  const MeasuredLog log = MakeLog(truth, 1.0);
  FitOptions options = Options();
  options.window_end_s = 14.5;
  auto fit =
      FitParameters(log, RigParams{},
                    Defaults({"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"}), options);
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  SCOPED_TRACE(fit->solver_report);
  ASSERT_EQ(fit->held.size(), 3u);
  EXPECT_FALSE(fit->held[0]);
  EXPECT_FALSE(fit->held[1]);
  EXPECT_TRUE(fit->held[2]);
  EXPECT_EQ(fit->estimates[2], fit->initial[2]);
  EXPECT_TRUE(std::isnan(fit->standard_errors[2]));
  EXPECT_NEAR(fit->estimates[0], 1000.0, 0.01 * 1000.0);
  EXPECT_NEAR(fit->estimates[1], 0.3, 0.03 * 0.3);
  EXPECT_TRUE(fit->converged);
}

// Standard errors left out of the fit and added later (diagnose keeps one of several fits):
// the same numbers as the fit's own, for 2p replays, and none before.
TEST(FitTest, StandardErrorsAddedLaterAreTheFitsOwn) {
  const MeasuredLog log = MakeLog(Truth(), 1.0);
  const std::vector<FitParameter> parameters =
      Defaults({"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"});
  FitOptions options = Options();
  options.window_end_s = 14.5;  // the leak is held there: a NaN standard error to carry
  auto with = FitParameters(log, RigParams{}, parameters, options);
  ASSERT_TRUE(with.ok()) << with.status().message();
  options.standard_errors = false;
  auto without = FitParameters(log, RigParams{}, parameters, options);
  ASSERT_TRUE(without.ok()) << without.status().message();
  EXPECT_EQ(without->estimates, with->estimates);
  for (double se : without->standard_errors) EXPECT_TRUE(std::isnan(se));
  const int replays = without->replays;
  ASSERT_TRUE(EstimateStandardErrors(log, parameters, options, &*without).ok());
  EXPECT_EQ(without->replays, replays + 2 * static_cast<int>(parameters.size()));
  for (std::size_t j = 0; j < parameters.size(); ++j) {
    SCOPED_TRACE(parameters[j].key);
    if (std::isnan(with->standard_errors[j])) {
      EXPECT_TRUE(std::isnan(without->standard_errors[j]));
    } else {
      EXPECT_EQ(without->standard_errors[j], with->standard_errors[j]);
    }
    for (std::size_t k = 0; k < parameters.size(); ++k) {
      if (std::isnan(with->correlation[j][k])) continue;
      EXPECT_EQ(without->correlation[j][k], with->correlation[j][k]);
    }
  }
  // Another fit's parameters are refused.
  EXPECT_FALSE(EstimateStandardErrors(log, Defaults({"wave_speed_mps"}), options, &*without).ok());
}

TEST(FitTest, RecoversAnEffectParameter) {
  RigParams truth;
  truth.effects.push_back({"sensor_lag", {{"time_constant_s", 0.15}}});
  const MeasuredLog log = MakeLog(truth, 1.0);
  RigParams start;
  start.effects.push_back({"sensor_lag", {}});
  ASSERT_TRUE(SetParamValue(&start, "sensor_lag.time_constant_s", 0.05).ok());
  auto fit = FitParameters(log, start, Defaults({"sensor_lag.time_constant_s"}), Options());
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  SCOPED_TRACE(fit->solver_report);
  EXPECT_DOUBLE_EQ(fit->initial[0], 0.05);
  EXPECT_NEAR(fit->estimates[0], 0.15,
              3.0 * fit->standard_errors[0] + FitOptions{}.relative_step * 0.15);
  EXPECT_NEAR(fit->estimates[0], 0.15, 0.01 * 0.15);
  auto value = GetParamValue(fit->params, "sensor_lag.time_constant_s");
  ASSERT_TRUE(value.ok());
  EXPECT_DOUBLE_EQ(*value, fit->estimates[0]);
  EXPECT_LT(fit->error_after, fit->error_before);
}

TEST(FitTest, AnExactLogAtTheStartValuesDoesNotMove) {
  const MeasuredLog log = MakeLog(RigParams{}, 0.0);
  auto fit =
      FitParameters(log, RigParams{},
                    Defaults({"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"}), Options());
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  EXPECT_LT(fit->error_before, 1e-9);
  EXPECT_LT(fit->error_after, 1e-9);
  for (std::size_t j = 0; j < fit->keys.size(); ++j) {
    EXPECT_NEAR(fit->estimates[j], fit->initial[j], 1e-6 * std::abs(fit->initial[j]))
        << fit->keys[j];
  }
}

TEST(FitTest, TheWindowRestrictsTheResiduals) {
  const MeasuredLog log = MakeLog(RigParams{}, 1.0);
  auto replay = ReplayModel(log, RigParams{}, FitSimulation());
  ASSERT_TRUE(replay.ok());
  FitOptions options = Options();
  options.window_begin_s = 30.0;
  options.window_end_s = 50.0;
  options.max_iterations = 0;
  auto fit = FitParameters(log, RigParams{}, Defaults({"friction_f1_per_s"}), options);
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  EXPECT_NEAR(fit->error_before, WindowError(log, *replay, 30.0, 50.0), 1e-12);
  EXPECT_NE(WindowError(log, *replay, 30.0, 50.0), WindowError(log, *replay, 0.0, 60.0));
}

TEST(FitTest, BadInputIsAnErrorThatSaysWhy) {
  const MeasuredLog log = MakeLog(RigParams{}, 0.0);
  auto unknown = DefaultFitParameter("wave_speed");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("wave_speed_mps"), std::string::npos);
  auto unknown_effect = DefaultFitParameter("no_such_effect.k");
  ASSERT_FALSE(unknown_effect.ok());
  EXPECT_NE(unknown_effect.status().message().find("sensor_lag"), std::string::npos);
  auto unknown_effect_key = DefaultFitParameter("sensor_lag.tau");
  ASSERT_FALSE(unknown_effect_key.ok());
  EXPECT_NE(unknown_effect_key.status().message().find("sensor_lag.time_constant_s"),
            std::string::npos);
  // The effect is not switched on in the start params.
  auto off = FitParameters(log, RigParams{}, Defaults({"sensor_lag.time_constant_s"}), Options());
  ASSERT_FALSE(off.ok());
  EXPECT_NE(off.status().message().find("not switched on"), std::string::npos);
  // Bounds: reversed, or outside the parameter table's.
  auto reversed = FitParameters(log, RigParams{}, {{"wave_speed_mps", 1200.0, 800.0}}, Options());
  ASSERT_FALSE(reversed.ok());
  EXPECT_NE(reversed.status().message().find("lower < upper"), std::string::npos);
  auto outside = FitParameters(log, RigParams{}, {{"wave_speed_mps", 1.0, 800.0}}, Options());
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.status().message().find("outside"), std::string::npos);
  auto twice =
      FitParameters(log, RigParams{}, Defaults({"wave_speed_mps", "wave_speed_mps"}), Options());
  ASSERT_FALSE(twice.ok());
}

TEST(FitTest, DefaultBoundsAreTuningRangesInsideTheTables) {
  auto c = DefaultFitParameter("wave_speed_mps");
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->lower, 300.0);
  EXPECT_EQ(c->upper, 1500.0);
  auto leak = DefaultFitParameter("choke_leak_m2");
  ASSERT_TRUE(leak.ok());
  EXPECT_EQ(leak->lower, 0.0);
  EXPECT_EQ(leak->upper, 1.0e-5);
  auto lag = DefaultFitParameter("sensor_lag.time_constant_s");
  ASSERT_TRUE(lag.ok());
  EXPECT_EQ(lag->lower, 0.0);
  EXPECT_EQ(lag->upper, 1.0);
  for (const ParamInfo& info : ParamTable()) {
    auto parameter = DefaultFitParameter(info.key);
    ASSERT_TRUE(parameter.ok()) << info.key;
    EXPECT_LT(parameter->lower, parameter->upper) << info.key;
    EXPECT_GE(parameter->lower, info.min_value) << info.key;
    EXPECT_LE(parameter->upper, info.max_value) << info.key;
  }
}

// The choke's leak (the floor of G, 9.4) shows only where the choke is closed and flow must pass
// through it: a closed choke, 2 L/min from the pump, a heave, lab noise, a rig whose leak,
// wave speed and friction differ from the defaults. `mpdrig fit`'s path (the levels estimated at
// the first fit's parameters) finds the leak within 2 % (measured 0.2 %), c within 1 % and f1
// within 20 %. (f2, the quadratic friction, needs faster flow than this heave gives: not asserted.)
TEST(FitAtLabNoise, LeakThroughAClosedChoke) {
  RigParams rig;
  rig.choke_leak_m2 = 8.0e-7;
  rig.wave_speed_mps = 950.0;
  rig.friction_f1_per_s = 0.2;
  // Two tones, as the thesis identified c from more than one frequency (a lone 0.2 Hz sine far
  // below the first resonance leaves c's valley flat: seed 1 stopped at 959 m/s with f1 = 0).
  const testing::Scenario closed{
      "closed_pumping",
      60.0,
      0.0,
      [](double t) { return testing::Sine(t, 0.04, 0.2) + testing::Sine(t, 0.01, 0.45); },
      [](double) { return 0.0; },
      [](double) { return 2.0; }};
  const riglog::RigLog truth = testing::TruthLog(closed, rig);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    auto log = MeasuredLogFromRigLog(testing::LabNoise(truth, seed), "closed choke");
    ASSERT_TRUE(log.ok());
    FitOptions options;
    options.simulation = testing::ScenarioReplayOptions();
    ASSERT_TRUE(PrepareLogReplay(&*log, RigParams{}, options.simulation, &options.replay,
                                 InputLevels::kAfterTheFit)
                    .ok());
    std::vector<FitParameter> parameters;
    for (const char* key : {"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"}) {
      auto parameter = DefaultFitParameter(key);
      ASSERT_TRUE(parameter.ok());
      parameters.push_back(*parameter);
    }
    auto fit = FitParametersAndInputLevels(&*log, RigParams{}, parameters, options);
    ASSERT_TRUE(fit.ok()) << fit.status().message();
    std::printf("seed %d: c %.1f (950), f1 %.4f (0.2), leak %.4g (8e-7)\n", static_cast<int>(seed),
                fit->estimates[0], fit->estimates[1], fit->estimates[2]);
    EXPECT_NEAR(fit->estimates[0], rig.wave_speed_mps, 0.01 * rig.wave_speed_mps);
    EXPECT_NEAR(fit->estimates[1], rig.friction_f1_per_s, 0.2 * rig.friction_f1_per_s);
    EXPECT_NEAR(fit->estimates[2], rig.choke_leak_m2, 0.02 * rig.choke_leak_m2);
  }
}

}  // namespace
}  // namespace mpdrig
