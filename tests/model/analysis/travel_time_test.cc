// The front speed from the transmitters (thesis 8.3.2): a closed form (fronts travelling at a
// known speed and reflected at the pipe's ends), and lab-like logs of the simulator at the lab's
// sensor noise (Table 4.1.1) with choke steps, for several wave speeds, seeds and sampling rates.
#include "model/analysis/travel_time.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "model/identification/synthetic_log.h"
#include "model/params/rig_params.h"
#include "tests/support/lab_scenario.h"

namespace mpdrig {
namespace {

constexpr double kLengthM = 900.0;

// A smooth step of rise time ~`rise_s` centred on 0.
double Front(double t, double rise_s) { return 0.5 * (1.0 + std::tanh(2.0 * t / rise_s)); }

// Choke fronts leaving x = L at `starts`, each reflected at the piston (x = 0, +1) and at the choke
// (-0.5: a partly open choke), three passes; every transmitter PT1..PT10 sees them delayed by its
// distance over c. White noise of `noise_pa`.
void ClosedFormLog(double c, double rate_hz, double noise_pa, std::vector<double>* time_s,
                   std::vector<PressureTrace>* traces) {
  const std::vector<double> starts = {2.0, 9.0, 16.0, 23.0};
  const double rise = 0.08, duration = 30.0;
  std::mt19937_64 random(7);
  std::normal_distribution<double> normal(0.0, noise_pa);
  time_s->clear();
  for (long i = 0; i <= std::lround(duration * rate_hz); ++i) time_s->push_back(i / rate_hz);
  traces->clear();
  for (int k = 0; k < 10; ++k) {
    PressureTrace trace{"PT" + std::to_string(k + 1), 100.0 * k, {}};
    const double x = trace.position_m;
    for (double t : *time_s) {
      double p = 3e5;
      for (std::size_t e = 0; e < starts.size(); ++e) {
        const double size = (e % 2 == 0 ? 1.0 : -1.0) * 5e4;
        double gain = 1.0;
        for (int pass = 0; pass < 3; ++pass) {
          const double down = starts[e] + (2 * pass * kLengthM + kLengthM - x) / c;
          const double up = starts[e] + (2 * pass * kLengthM + kLengthM + x) / c;
          p += gain * size * (Front(t - down, rise) + Front(t - up, rise));
          gain *= -0.5;
        }
      }
      trace.pressure_pa.push_back(p + normal(random));
    }
    traces->push_back(std::move(trace));
  }
}

TEST(TravelTime, ClosedFormFrontsAtAKnownSpeed) {
  // Noise-free, 100 Hz: within 0.2 % (delays of 8-95 samples located to a fiftieth of one; what
  // is left is the reflections' peaks leaning on some pairs' direct ones), the end-to-end pair
  // PT1-PT10 (the thesis's own measurement, L / c) within 0.1 %. With the transmitters' noise
  // (0.024 bar, Table 4.1.1) on these four 0.5 bar fronts: within 1 % and within three of its
  // own standard errors.
  for (double c : {950.0, 1173.0, 1300.0}) {
    for (double noise_pa : {0.0, 2400.0}) {
      std::vector<double> time_s;
      std::vector<PressureTrace> traces;
      ClosedFormLog(c, 100.0, noise_pa, &time_s, &traces);
      auto result = EstimateTravelTime(time_s, traces);
      ASSERT_TRUE(result.ok()) << result.status().message();
      std::printf("c %.0f, noise %.0f Pa: estimated %.2f +- %.2f m/s, %d of %zu pairs\n", c,
                  noise_pa, result->wave_speed_mps, result->wave_speed_uncertainty_mps,
                  result->pairs_used, result->pairs.size());
      const double error = std::fabs(result->wave_speed_mps - c);
      EXPECT_LT(error, (noise_pa > 0.0 ? 0.01 : 0.002) * c) << c << " " << noise_pa;
      EXPECT_LT(error, 3.0 * result->wave_speed_uncertainty_mps) << c << " " << noise_pa;
      EXPECT_GE(result->pairs_used, 10);  // four fronts: few pairs stand 5 sigma above chance
      if (noise_pa > 0.0) continue;
      for (const PairDelay& pair : result->pairs) {
        if (pair.first == "PT1" && pair.second == "PT10") {
          EXPECT_TRUE(pair.used);
          EXPECT_NEAR(pair.delay_s, kLengthM / c, 0.001 * kLengthM / c);
          EXPECT_NEAR(pair.delay_up_s, kLengthM / c, 0.001 * kLengthM / c);
          EXPECT_NEAR(pair.delay_down_s, kLengthM / c, 0.001 * kLengthM / c);
        }
      }
    }
  }
}

TEST(TravelTime, RefusesWhatItCannotTime) {
  std::vector<double> time_s;
  std::vector<PressureTrace> traces;
  ClosedFormLog(1173.0, 100.0, 0.0, &time_s, &traces);
  const std::vector<PressureTrace> two(traces.begin(), traces.begin() + 2);
  auto result = EstimateTravelTime(time_s, two);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("three"), std::string::npos);
  std::vector<PressureTrace> flat = traces;
  for (PressureTrace& trace : flat)
    std::fill(trace.pressure_pa.begin(), trace.pressure_pa.end(), 2e5);
  result = EstimateTravelTime(time_s, flat);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("does not change"), std::string::npos);
  TravelTimeOptions bad;
  bad.min_wave_speed_mps = 2000.0;
  bad.max_wave_speed_mps = 1000.0;
  EXPECT_FALSE(EstimateTravelTime(time_s, traces, bad).ok());
}

TEST(TravelTime, OneChokeMoveInAWindow) {
  // As the thesis read it (Table 8.3.1): one front, the window around it (at the lab's noise:
  // within 1 % and three standard errors).
  std::vector<double> time_s;
  std::vector<PressureTrace> traces;
  ClosedFormLog(1173.0, 100.0, 2400.0, &time_s, &traces);
  TravelTimeOptions options;
  options.window_begin_s = 8.0;
  options.window_end_s = 14.0;
  auto result = EstimateTravelTime(time_s, traces, options);
  ASSERT_TRUE(result.ok()) << result.status().message();
  EXPECT_NEAR(result->wave_speed_mps, 1173.0, 0.01 * 1173.0);
  EXPECT_LT(std::fabs(result->wave_speed_mps - 1173.0), 3.0 * result->wave_speed_uncertainty_mps);
  EXPECT_NEAR(result->duration_s, 6.0, 0.011);
}

// --- Lab-like logs ------------------------------------------------------------------------------

// A lab run: heave sine (0.2 Hz, 1 cm), 8 L/min, the choke stepped between 30 and 18 deg every
// 6 s at the actuator's rate (about 90 deg/s: 0.13 s per step, thesis 8.4).
testing::Scenario ChokeSteps() {
  testing::Scenario s;
  s.name = "choke steps";
  s.duration_s = 60.0;
  s.piston_m = [](double t) { return testing::Sine(t, 0.01, 0.2); };
  s.choke_deg = [](double t) {
    const double period = 6.0;
    const double phase = std::fmod(t, 2.0 * period);
    return phase < period ? testing::Ramp(phase, 3.0, 0.13, 30.0, 18.0)
                          : testing::Ramp(phase - period, 3.0, 0.13, 18.0, 30.0);
  };
  s.pump_lpm = [](double) { return 8.0; };
  return s;
}

TEST(TravelTimeAtLabNoise, RecoversTheWaveSpeedWithinTwoPercent) {
  // 3 wave speeds x 2 sampling rates x 3 seeds of the lab's noise: within 2 %.
  constexpr int kCells = 90;  // nodes at the transmitters (every 10 m)
  double worst = 0.0;
  for (double c : {950.0, 1173.0, 1300.0}) {
    RigParams params;
    params.wave_speed_mps = c;
    for (double rate : {100.0, 1000.0}) {
      const riglog::RigLog truth = testing::TruthLog(ChokeSteps(), params, rate, kCells);
      for (std::uint64_t seed : {1, 2, 3}) {
        const riglog::RigLog log = testing::LabNoise(truth, seed);
        auto result = EstimateTravelTime(log.time_s, PipeTransmitterTraces(log));
        ASSERT_TRUE(result.ok()) << result.status().message();
        const double error = result->wave_speed_mps / c - 1.0;
        worst = std::max(worst, std::fabs(error));
        std::printf("c %.0f m/s, %4.0f Hz, seed %d: %.1f +- %.1f m/s (%+.2f %%), %d of %zu pairs\n",
                    c, rate, static_cast<int>(seed), result->wave_speed_mps,
                    result->wave_speed_uncertainty_mps, 100.0 * error, result->pairs_used,
                    result->pairs.size());
        EXPECT_NEAR(result->wave_speed_mps, c, 0.02 * c)
            << "seed " << seed << ", " << rate << " Hz";
        EXPECT_GT(result->wave_speed_uncertainty_mps, 0.0);
      }
    }
  }
  std::printf("worst %.2f %%\n", 100.0 * worst);
}

TEST(TravelTimeAtLabNoise, EachChokeMoveOnItsOwn) {
  // The thesis's way (Table 8.3.1): one wave speed per choke move. The ten moves of the lab run
  // (every 6 s from 3 s, the 0.13 s ramp's middle at +0.065 s) are found within 0.05 s, and each
  // one's window [t - 1, t + 4] s gives c within 2 % at 1173 m/s, 100 Hz, the lab's noise.
  RigParams params;
  params.wave_speed_mps = 1173.0;
  const riglog::RigLog log =
      testing::LabNoise(testing::TruthLog(ChokeSteps(), params, 100.0, 90), 1);
  const std::vector<double> moves = FindChokeMoves(log.time_s, *log.Find(Channel::kChokePosition));
  ASSERT_EQ(moves.size(), 10u);
  for (std::size_t k = 0; k < moves.size(); ++k) {
    EXPECT_NEAR(moves[k], 3.065 + 6.0 * k, 0.05) << k;
  }
  const auto per_move = TravelTimePerMove(log.time_s, PipeTransmitterTraces(log), moves);
  ASSERT_EQ(per_move.size(), moves.size());
  for (const MoveTravelTime& move : per_move) {
    ASSERT_TRUE(move.status.ok()) << move.time_s << ": " << move.status.message();
    std::printf("move at %5.2f s: %.1f +- %.1f m/s, %d pairs\n", move.time_s,
                move.result.wave_speed_mps, move.result.wave_speed_uncertainty_mps,
                move.result.pairs_used);
    EXPECT_NEAR(move.result.wave_speed_mps, 1173.0, 0.02 * 1173.0) << move.time_s;
  }
}

TEST(TravelTimeAtLabNoise, HeaveAloneHasNoFrontToTime) {
  // A heave sine with the choke and pump held: above 3 Hz only the transmitters' noise. No pair's
  // peak stands 5 sigma above chance, and the log is refused rather than timed.
  testing::Scenario s;
  s.duration_s = 60.0;
  s.piston_m = [](double t) { return testing::Sine(t, 0.02, 0.2); };
  s.choke_deg = [](double) { return 25.0; };
  s.pump_lpm = [](double) { return 8.0; };
  const riglog::RigLog log = testing::LabNoise(testing::TruthLog(s), 1);
  TravelTimeOptions options;
  options.window_begin_s = 10.0;  // after the start-up's front has faded into the noise
  auto result = EstimateTravelTime(log.time_s, PipeTransmitterTraces(log), options);
  ASSERT_FALSE(result.ok()) << result->wave_speed_mps;
  EXPECT_NE(result.status().message().find("clear front"), std::string::npos)
      << result.status().message();
}

TEST(TravelTimeAtLabNoise, SynthLogsWithinTwoPercent) {
  // `mpdrig synth`'s logs (MakeSyntheticLog with the lab's noise): heave sines and a sweep to
  // 0.8 Hz, choke and pump steps of a few degrees and L/min over 0.5 s, a wave speed drawn within
  // +-10 % of 850 m/s; 120 s at 100 Hz and at 1 kHz, seeds 1-3: within 2 %.
  double worst = 0.0;
  for (double rate : {100.0, 1000.0}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      SyntheticLogOptions options;
      options.seed = seed;
      options.rate_hz = rate;
      options.sensor_noise = SensorNoise::Lab();
      auto made = MakeSyntheticLog(options);
      ASSERT_TRUE(made.ok()) << made.status().message();
      const double c = made->truth.wave_speed_mps;
      auto result = EstimateTravelTime(made->log.time_s, PipeTransmitterTraces(made->log));
      ASSERT_TRUE(result.ok()) << result.status().message();
      const double error = result->wave_speed_mps / c - 1.0;
      worst = std::max(worst, std::fabs(error));
      std::printf(
          "synth seed %d, %4.0f Hz: c %.1f m/s, estimated %.1f +- %.1f (%+.2f %%), %d pairs\n",
          static_cast<int>(seed), rate, c, result->wave_speed_mps,
          result->wave_speed_uncertainty_mps, 100.0 * error, result->pairs_used);
      EXPECT_NEAR(result->wave_speed_mps, c, 0.02 * c) << "seed " << seed << ", " << rate << " Hz";
    }
  }
  std::printf("worst %.2f %%\n", 100.0 * worst);
}

}  // namespace
}  // namespace mpdrig
