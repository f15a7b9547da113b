// Lab-like test logs from scripted inputs: a scenario (piston, choke and pump as functions of
// time) run through the model with given parameters gives the noise-free truth, every compared
// channel and the inputs, at 100 Hz; LabNoise gives it the lab's sensor noise (thesis Table
// 4.1.1). Shared by the replay tests (tests/model/analysis) and the fit tests
// (tests/model/identification).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/measured_log.h"
#include "model/common/units.h"
#include "model/riglog/rig_log.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig::testing {

inline constexpr double kScenarioRateHz = 100.0;
inline constexpr int kScenarioCells = 50;

// A lab run as scripted inputs, in lab units (m, deg, L/min).
struct Scenario {
  std::string name;
  double duration_s = 60.0;
  double cut_s = 0.0;  // the log starts here (a recording joining a running rig)
  std::function<double(double)> piston_m;
  std::function<double(double)> choke_deg;
  std::function<double(double)> pump_lpm;
};

inline double Sine(double t, double amp, double freq_hz) {
  return amp * std::sin(2.0 * std::numbers::pi * freq_hz * t);
}

// A ramp from a to b over [t0, t0 + rise].
inline double Ramp(double t, double t0, double rise, double a, double b) {
  if (t <= t0) return a;
  if (t >= t0 + rise) return b;
  return a + (b - a) * (t - t0) / rise;
}

// The replay's options: the scenario's grid, the choke as measured.
inline SimulationOptions ScenarioReplayOptions() {
  SimulationOptions options;
  options.cells = kScenarioCells;
  options.choke_input = ChokeInput::kMeasured;
  return options;
}

// The truth (noise-free, every compared channel and the inputs) from t = 0, cut at cut_s, at
// `rate_hz` on a grid of `cells` (the scenario's 100 Hz and 50 cells unless told).
inline riglog::RigLog TruthLog(const Scenario& s, const RigParams& params = RigParams{},
                               double rate_hz = kScenarioRateHz, int cells = kScenarioCells) {
  InputSignals signals;
  signals.piston_position_m = s.piston_m;
  signals.rig = [&](double t) {
    RigInputs in;
    in.choke_opening_frac = units::ChokeDegToFrac(s.choke_deg(t));
    in.pump_flow_m3ps = units::LpmToM3ps(s.pump_lpm(t));
    in.outlet_pressure_pa = units::kStandardAtmospherePa;
    return in;
  };
  std::vector<double> times;
  for (long i = 0; i <= std::lround(s.duration_s * rate_hz); ++i) times.push_back(i / rate_hz);
  SimulationOptions options = ScenarioReplayOptions();
  options.cells = cells;
  auto run = Simulate(params, options, signals, times);
  EXPECT_TRUE(run.ok()) << run.status().message();
  riglog::RigLog log;
  std::vector<std::vector<double>> columns(4 + ComparedChannels().size());
  if (!run.ok()) return log;
  for (const RigSample& sample : run->samples) {
    if (sample.time_s < s.cut_s - 1e-9) continue;
    log.time_s.push_back(sample.time_s);
    columns[0].push_back(sample[Channel::kPistonPosition]);
    columns[1].push_back(sample[Channel::kChokePosition]);
    columns[2].push_back(sample[Channel::kFT2]);
    columns[3].push_back(sample[Channel::kC1]);
    for (std::size_t c = 0; c < ComparedChannels().size(); ++c) {
      columns[4 + c].push_back(sample[ComparedChannels()[c]]);
    }
  }
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kPistonPosition), columns[0]).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kChokePosition), columns[1]).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kFT2), columns[2]).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kC1), columns[3]).ok());
  for (std::size_t c = 0; c < ComparedChannels().size(); ++c) {
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(ComparedChannels()[c]), columns[4 + c]).ok());
  }
  return log;
}

// The truth as the lab's sensors would log it (SensorNoise::Lab(), thesis Table 4.1.1: the
// project's one noise model, as `mpdrig synth` and `simulate` apply it).
inline riglog::RigLog LabNoise(riglog::RigLog log, std::uint64_t seed) {
  SensorNoiseApplier noise(SensorNoise::Lab(), seed);
  for (std::size_t c = 0; c < log.columns.size(); ++c) {
    const auto channel = riglog::FindChannel(log.columns[c].channel);
    if (channel) noise.MeasureColumn(*channel, log.values_si[c]);
  }
  return log;
}

}  // namespace mpdrig::testing
