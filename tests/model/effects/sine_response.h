// The periodic response of the rig to a piston sine: complex amplitude of every channel at the
// drive frequency, over whole periods after the start-up transient has decayed. Shared by the
// effects' physics tests.
#pragma once

#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "model/sim/rig_simulator.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig::testing {

struct SineRun {
  double freq_hz = 0.2;
  double amplitude_m = 0.01;
  double choke_deg = 31.0;
  double pump_lpm = 5.0;
  double outlet_barg = 5.0;  // keeps absolute pressure well above zero at resonance
  int cells = 60;
  double settle_s = 60.0;  // f1/2 = 0.075/s: e^-4.5 of the start-up transient is left
  int periods = 4;
  PipeModel model = PipeModel::kQuasiLinear;
};

// Complex amplitude of each channel at the drive frequency (SI), relative to the piston
// position's.
inline std::array<std::complex<double>, kChannelCount> SineResponse(const RigParams& params,
                                                                    const SineRun& run) {
  using Complex = std::complex<double>;
  const double f = run.freq_hz;
  InputSignals inputs;
  inputs.piston_position_m = [&](double t) {
    return run.amplitude_m * std::sin(2.0 * std::numbers::pi * f * t);
  };
  inputs.rig = [&](double) { return Held(run.choke_deg, run.pump_lpm, run.outlet_barg); };
  const int per_period = 64;
  const double t_start = std::ceil(run.settle_s * f) / f;
  std::vector<double> times;
  times.push_back(0.0);
  for (int k = 0; k < run.periods * per_period; ++k) {
    times.push_back(t_start + k / (f * per_period));
  }
  SimulationOptions options;
  options.cells = run.cells;
  options.model = run.model;
  auto result = Simulate(params, options, inputs, times);
  EXPECT_TRUE(result.ok()) << result.status().message();
  std::array<Complex, kChannelCount> out{};
  if (!result.ok()) return out;
  const Complex piston(0.0, -run.amplitude_m / 2.0);  // A sin = (A/2i) e^{iwt} + c.c.
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    Complex sum = 0.0;
    for (std::size_t k = 1; k < times.size(); ++k) {
      sum += result->samples[k].values[c] *
             std::exp(Complex(0.0, -2.0 * std::numbers::pi * f * times[k]));
    }
    out[c] = sum / static_cast<double>(times.size() - 1) / piston;
  }
  return out;
}

}  // namespace mpdrig::testing
