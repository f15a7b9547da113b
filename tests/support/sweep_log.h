// A sweep log of the simulator at the lab's sensor noise (thesis Table 4.1.1, SensorNoise::Lab(),
// as `mpdrig synth` adds it): what the rig records when the heave generator sweeps with the line
// held in one termination, for the empirical response and the resonances read from it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/frequency_response.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig::testing {

inline constexpr double kSweepTwoPi = 2.0 * std::numbers::pi;

// A logarithmic sweep from f0 to f1 over `period_s`, repeated: the phase of one sweep is
// 2 pi f0 T / ln(f1/f0) (e^{t ln(f1/f0) / T} - 1).
inline double Sweep(double t, double amplitude_m, double f0, double f1, double period_s) {
  const double tau = std::fmod(t, period_s);
  const double rate = std::log(f1 / f0) / period_s;
  const double phase = kSweepTwoPi * f0 * (std::exp(rate * tau) - 1.0) / rate;
  // Tapered over the first and last 2 s of each sweep, so the joins are smooth.
  const double taper = std::min({1.0, tau / 2.0, (period_s - tau) / 2.0});
  return amplitude_m * taper * std::sin(phase);
}

inline const SimulationOptions& SweepSimulation() {
  static const SimulationOptions options = [] {
    SimulationOptions o;
    o.cells = 60;
    o.model = PipeModel::kQuasiLinear;
    return o;
  }();
  return options;
}

// 400 s of sweeps 0.1 -> 1 Hz (100 s each), 5 mm, at 100 Hz, choke shut, pump off, 4 barg at the
// outlet; the lab's noise on every channel (seed `seed`).
inline riglog::RigLog MakeSweepLog(const RigParams& params, const ChokeSetting& choke,
                                   std::uint64_t seed) {
  const double rate_hz = 100.0, duration_s = 400.0;
  std::vector<double> times;
  for (int i = 0; i <= static_cast<int>(duration_s * rate_hz); ++i) times.push_back(i / rate_hz);
  InputSignals inputs;
  inputs.piston_position_m = [](double t) { return Sweep(t, 0.005, 0.1, 1.0, 100.0); };
  RigInputs held;
  held.choke_opening_frac = choke.opening_frac;
  held.pump_flow_m3ps = 0.0;
  held.outlet_pressure_pa = 5.0e5;
  inputs.rig = [held](double) { return held; };
  SimulationOptions options = SweepSimulation();
  options.choke_input = ChokeInput::kMeasured;
  RigParams rig = params;
  if (choke.kind == ChokeSetting::Kind::kClosed) {
    rig.choke_leak_m2 = 0.0;
    rig.choke_characteristic = {{0.0, 0.0}, {1.0, 0.0}};
  }
  auto run = Simulate(rig, options, inputs, times);
  EXPECT_TRUE(run.ok()) << run.status().message();
  riglog::RigLog log;
  log.time_s = times;
  if (!run.ok()) return log;
  SensorNoiseApplier noise(SensorNoise::Lab(), seed);
  for (Channel channel :
       {Channel::kPistonPosition, Channel::kP2, Channel::kPT1, Channel::kPT5, Channel::kC2}) {
    std::vector<double> values;
    for (RigSample sample : run->samples) values.push_back(sample[channel]);
    noise.MeasureColumn(channel, values);
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(channel), values).ok());
  }
  return log;
}

}  // namespace mpdrig::testing
