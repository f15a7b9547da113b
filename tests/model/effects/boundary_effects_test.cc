// The boundary effects (pump_curve, hose_compliance, piston_compressibility) change the response
// the way their physics says: closed-form fixed points, mass balances of the added volumes, and
// the linearised transfer functions of the added states measured on the periodic response to a
// piston sine.
#include <cmath>
#include <complex>
#include <numbers>

#include <gtest/gtest.h>

#include "model/boundary/choke.h"
#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

using Complex = std::complex<double>;
constexpr Complex kI(0.0, 1.0);

RigParams With(RigParams params, std::string_view spec) {
  const Status status = ApplyEffectSpec(&params, spec);
  EXPECT_TRUE(status.ok()) << status.message();
  return params;
}
RigParams With(std::string_view spec) { return With(RigParams(), spec); }

double PhaseDeg(Complex z) { return std::arg(z) * 180.0 / std::numbers::pi; }

struct SineRun {
  double freq_hz = 0.15;
  double amplitude_m = 0.002;  // small: the linearised closed forms hold
  double choke_deg = 31.0;
  double pump_lpm = 5.0;
  double outlet_barg = 5.0;
  int cells = 60;
  double settle_s = 60.0;  // f1/2 = 0.075/s: e^-4.5 of the start-up transient is left
  int periods = 4;
};

// Complex amplitude of each channel at the drive frequency (SI), relative to the piston
// position's, on the linear model with linear pipe and piston friction (the closed forms below
// are linear).
std::array<Complex, kChannelCount> Response(RigParams params, const SineRun& run) {
  params.friction_f2_per_m = 0.0;
  params.piston_friction_fd2_pa_s2_per_m2 = 0.0;
  const double f = run.freq_hz;
  InputSignals inputs;
  inputs.piston_position_m = [&](double t) {
    return run.amplitude_m * std::sin(2.0 * std::numbers::pi * f * t);
  };
  inputs.rig = [&](double) { return testing::Held(run.choke_deg, run.pump_lpm, run.outlet_barg); };
  const int per_period = 64;
  const double t_start = std::ceil(run.settle_s * f) / f;
  std::vector<double> times;
  times.push_back(0.0);
  for (int k = 0; k < run.periods * per_period; ++k) times.push_back(t_start + k / (f * per_period));
  SimulationOptions options;
  options.cells = run.cells;
  options.model = PipeModel::kLinear;
  auto result = Simulate(params, options, inputs, times);
  EXPECT_TRUE(result.ok()) << result.status().message();
  std::array<Complex, kChannelCount> out{};
  if (!result.ok()) return out;
  const Complex piston(0.0, -run.amplitude_m / 2.0);  // A sin = (A/2i) e^{iwt} + c.c.
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    Complex sum = 0.0;
    for (std::size_t k = 1; k < times.size(); ++k) {
      const double t = times[k];
      sum += result->samples[k].values[c] * std::exp(Complex(0.0, -2.0 * std::numbers::pi * f * t));
    }
    out[c] = sum / static_cast<double>(times.size() - 1) / piston;
  }
  return out;
}

// The time step of a run with `cells` cells (characteristics scheme: dt = dx / c).
double TimeStep(const RigParams& params, int cells) {
  return params.pipe_length_m / cells / params.wave_speed_mps;
}

// i w as implicit Euler sees it: (1 - e^{-i w dt}) / dt.
Complex EulerIw(double w, double dt) { return (1.0 - std::exp(Complex(0.0, -w * dt))) / dt; }

// --- pump_curve ---------------------------------------------------------------------------------

// (8.5.1) normalised, as the effect's header writes it (defaults a, b, c; p_ref = 0 gauge).
double PumpCurveFlow(double q_cmd, double scale, double choke_pressure_pa) {
  const double a = -2.4050e-6, b = -2.5070e-6, c = 4.7967e-4;
  const double gauge = choke_pressure_pa - units::kStandardAtmospherePa;
  return q_cmd * (1.0 + scale * (a / c) * (std::exp(-b * gauge) - 1.0));
}

// Steady state of pump + choke with the pipe at rest: q_c = q_b and (5.3.2),
//   q = q_b(p_c(q)),  p_c(q) = p_0 + rho q^2 / G^2,
// q - q_b(p_c(q)) increases with q: bisection.
double SteadyPumpFlow(const RigParams& params, double q_cmd, double scale, double g_m2,
                      double outlet_pa) {
  const auto choke_pressure = [&](double q) {
    return outlet_pa + params.choke_density_kgpm3 * q * q / (g_m2 * g_m2);
  };
  double lo = 0.0, hi = 2.0 * q_cmd;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (mid - PumpCurveFlow(q_cmd, scale, choke_pressure(mid)) > 0.0 ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(PumpCurve, SteadyChokePressureAfterAChokeStepIsTheOrificeFixedPoint) {
  // Choke 40 -> 31 deg with the piston at rest: C2 settles where the orifice law (5.3.2) meets
  // the pump curve, q_b(p_c) < q_cmd, so C2 rises less than with the thesis's constant pump.
  const double scale = 2.0;
  const RigParams params = With("pump_curve:scale=2");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(t < 1.0 ? 40.0 : 31.0, 10.0, 1.0); };
  const RigSimulator before = testing::RunSteps(params, options, drive, 0.5);
  const RigSimulator with = testing::RunSteps(params, options, drive, 150.0);
  const RigSimulator base = testing::RunSteps(RigParams(), options, drive, 150.0);

  const RigInputs start = drive.rig(0.0), end = drive.rig(10.0);
  const ChokeCharacteristic characteristic(params);
  for (const auto& [sim, in] : {std::pair{&before, start}, std::pair{&with, end}}) {
    const double g = characteristic.FlowCoefficientM2(in.choke_opening_frac);
    const double q = SteadyPumpFlow(params, in.pump_flow_m3ps, scale, g, in.outlet_pressure_pa);
    const double p_c = in.outlet_pressure_pa + params.choke_density_kgpm3 * q * q / (g * g);
    const RigSample s = sim->Sample();
    EXPECT_LT(q, in.pump_flow_m3ps * 0.99);  // the curve matters at this pressure
    EXPECT_NEAR(s[Channel::kFT2], q, 1e-6 * q);  // the model's FT2 is the delivered flow
    EXPECT_NEAR(s[Channel::kFT3], q, 1e-4 * q);
    EXPECT_NEAR(s[Channel::kC2], p_c, 2e-4 * (p_c - in.outlet_pressure_pa));
  }
  const double rise_with = with.Sample()[Channel::kC2] - before.Sample()[Channel::kC2];
  const double rise_base = base.Sample()[Channel::kC2] -
                           testing::RunSteps(RigParams(), options, drive, 0.5).Sample()[Channel::kC2];
  EXPECT_LT(rise_with, 0.9 * rise_base) << rise_with << " " << rise_base;
}

TEST(PumpCurve, CommandIsTheFlowAtTheReferencePressure) {
  // Wide-open choke and outlet at p_ref: the pump delivers its command.
  const RigParams params = With("pump_curve:scale=5,reference_pressure_pa=2e5");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double) { return testing::Held(90.0, 1e-3, 2.0); };  // tiny flow: p_c ~ p_0
  const RigSample s = testing::RunSteps(params, options, drive, 1.0).Sample();
  EXPECT_NEAR(s[Channel::kFT2], units::LpmToM3ps(1e-3), 1e-9 * units::LpmToM3ps(1e-3));
}

}  // namespace
}  // namespace mpdrig
