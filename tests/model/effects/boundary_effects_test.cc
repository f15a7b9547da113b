// The boundary effects (pump_curve, hose_compliance, topside_compliance, piston_compressibility)
// change the response the way their physics says: closed-form fixed points, mass balances of the
// added volumes, and the linearised transfer functions of the added states measured on the periodic
// response to a piston sine.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>

#include <gtest/gtest.h>

#include "model/boundary/choke.h"
#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "tests/model/effects/sine_response.h"
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

// Small amplitude on the linear model: the linearised closed forms below hold.
struct SineRun : testing::SineRun {
  SineRun() {
    freq_hz = 0.15;
    amplitude_m = 0.002;
    model = PipeModel::kLinear;
  }
};

// With linear pipe and piston friction (the closed forms below are linear).
std::array<Complex, kChannelCount> Response(RigParams params, const SineRun& run) {
  params.friction_f2_per_m = 0.0;
  params.piston_friction_fd2_pa_s2_per_m2 = 0.0;
  return testing::SineResponse(params, run);
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
    EXPECT_LT(q, in.pump_flow_m3ps * 0.99);      // the curve matters at this pressure
    EXPECT_NEAR(s[Channel::kFT2], q, 1e-6 * q);  // the model's FT2 is the delivered flow
    EXPECT_NEAR(s[Channel::kFT3], q, 1e-4 * q);
    EXPECT_NEAR(s[Channel::kC2], p_c, 2e-4 * (p_c - in.outlet_pressure_pa));
  }
  const double rise_with = with.Sample()[Channel::kC2] - before.Sample()[Channel::kC2];
  const double rise_base =
      base.Sample()[Channel::kC2] -
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

// --- hose_compliance ----------------------------------------------------------------------------

TEST(HoseCompliance, MassBalanceOfTheHose) {
  // C dp(0)/dt = q_0 - A u(0), summed over the steps (implicit Euler: exact up to the solver's
  // tolerance): C (P2(T) - P2(0)) = sum dt (q_0 - FT4).
  const double compliance = 5e-11;
  const RigParams params = With("hose_compliance:compliance_m3_per_pa=5e-11");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.piston_position_m = [](double t) {
    return 0.02 * std::sin(2.0 * std::numbers::pi * 0.3 * t);
  };
  drive.rig = [](double t) { return testing::Held(t < 3.0 ? 31.0 : 20.0, 5.0, 3.0); };
  const double dt = TimeStep(params, options.cells);
  double p_start = 0.0, p_end = 0.0, net_inflow = 0.0;
  bool first = true;
  testing::RunSteps(params, options, drive, 10.0, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    if (first) {
      p_start = s[Channel::kP2];
      first = false;
      return;
    }
    const double t = sim.time_s();
    const double v_d =
        (drive.piston_position_m(t + 0.5 * dt) - drive.piston_position_m(t - 0.5 * dt)) / dt;
    const double q_0 = -v_d * params.PistonDisplacementAreaM2();
    net_inflow += dt * (q_0 - s[Channel::kFT4]);
    p_end = s[Channel::kP2];
  });
  EXPECT_GT(std::fabs(p_end - p_start), 1e4);  // the choke step moved the hose pressure
  EXPECT_NEAR(compliance * (p_end - p_start), net_inflow,
              1e-9 * compliance * std::fabs(p_end - p_start) + 1e-16);
}

TEST(HoseCompliance, InletFlowFollowsTheCapacitanceAgainstThePipesInputImpedance) {
  // The pipe's input impedance Z_in = P2/FT4 belongs to the pipe and choke, not to the inlet:
  // measure it on the rigid inlet and predict the hose's FT4/q_0 = 1 / (1 + i w C Z_in).
  const double compliance = 1e-10;
  SineRun run;
  const RigParams base;
  const auto b = Response(base, run);
  const auto h = Response(With("hose_compliance:compliance_m3_per_pa=1e-10"), run);
  const double w = 2.0 * std::numbers::pi * run.freq_hz;
  const Complex q_0 = -kI * w * base.PistonDisplacementAreaM2();  // per metre of piston position
  EXPECT_NEAR(std::abs(b[Index(Channel::kFT4)] / q_0 - 1.0), 0.0, 2e-3);  // rigid: FT4 = q_0
  const Complex z_in = b[Index(Channel::kP2)] / b[Index(Channel::kFT4)];
  const Complex predicted = 1.0 / (1.0 + EulerIw(w, TimeStep(base, run.cells)) * compliance * z_in);
  const Complex measured = h[Index(Channel::kFT4)] / q_0;
  EXPECT_LT(std::abs(measured), 0.95);  // the hose matters at this compliance
  EXPECT_NEAR(std::abs(measured), std::abs(predicted), 0.01 * std::abs(predicted));
  EXPECT_NEAR(PhaseDeg(measured), PhaseDeg(predicted), 1.0);
  EXPECT_LT(PhaseDeg(measured), -3.0);  // a lag behind the piston
}

// The frequency [in units of `unit_hz`] of the largest PT1 response in [from, to], scanned at
// steps of 0.01 and refined by a parabola through the largest three.
double PeakFactor(const RigParams& params, SineRun run, double unit_hz, double from, double to) {
  std::vector<double> factors, gains;
  for (double f = from; f <= to + 1e-9; f += 0.01) {
    run.freq_hz = f * unit_hz;
    factors.push_back(f);
    gains.push_back(std::abs(Response(params, run)[Index(Channel::kPT1)]));
  }
  const std::size_t k = std::max_element(gains.begin(), gains.end()) - gains.begin();
  EXPECT_TRUE(k > 0 && k + 1 < gains.size()) << "peak at the end of the scan";
  if (k == 0 || k + 1 == gains.size()) return factors[k];
  const double curvature = gains[k - 1] - 2.0 * gains[k] + gains[k + 1];
  return factors[k] + 0.01 * 0.5 * (gains[k - 1] - gains[k + 1]) / curvature;
}

TEST(HoseCompliance, LowersTheOpenChokeResonance) {
  // Open outlet (no flow through the choke: its linearised impedance is zero): the pipe seen
  // from the inlet is Z_in = i Z_c tan(w L / c), Z_c = rho c / A, first resonance c/4L (9.3.2).
  // The hose in parallel with it,
  //   P2 / q_0 = 1 / (i w C - i cot(w L / c) / Z_c),
  // peaks where cot(theta) = theta (c / L) C Z_c, theta = w L / c: below c/4L (theta < pi/2).
  // Friction moves both peaks a little; their ratio is the closed form's theta / (pi/2).
  const double compliance = 3e-11;
  const RigParams base;
  const RigParams hose = With("hose_compliance:compliance_m3_per_pa=3e-11");
  const double c = base.wave_speed_mps, length = base.pipe_length_m;
  const double z_c = base.density_kgpm3 * c / base.PipeAreaM2();
  double lo = 1e-9, hi = 0.5 * std::numbers::pi;  // cot(theta) - x theta decreases on (0, pi/2)
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (1.0 / std::tan(mid) - mid * c / length * compliance * z_c > 0.0 ? lo : hi) = mid;
  }
  const double predicted = 0.5 * (lo + hi) / (0.5 * std::numbers::pi);  // in units of c/4L
  SineRun run;
  run.choke_deg = 90.0;
  run.pump_lpm = 0.0;
  const double c4l = c / (4.0 * length);
  const double peak_base = PeakFactor(base, run, c4l, 0.9, 1.15);
  const double peak_hose = PeakFactor(hose, run, c4l, 0.75, 1.0);
  EXPECT_LT(predicted, 0.92);
  EXPECT_NEAR(peak_hose / peak_base, predicted, 0.01) << peak_base << " " << peak_hose;
}

TEST(HoseCompliance, LeavesPressureBelowTheBhaAlgebraic) {
  // With the piston at rest P1 - P2 = rho g h (5.4.2) at every step, also during a choke step.
  const RigParams params = With("hose_compliance:compliance_m3_per_pa=1e-10");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(t < 1.0 ? 40.0 : 31.0, 10.0, 2.0); };
  const double rho_g_h = params.density_kgpm3 * params.gravity_mps2 * params.compartment_height_m;
  double worst = 0.0;
  testing::RunSteps(params, options, drive, 5.0, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    worst = std::max(worst, std::fabs(s[Channel::kP1] - s[Channel::kP2] - rho_g_h));
  });
  EXPECT_LT(worst, 1e-6);
}

// --- topside_compliance -------------------------------------------------------------------------

TEST(TopsideCompliance, MassBalanceOfTheTubesAndTheOrificeAtTheChoke) {
  // C dp(L)/dt = A u(L) + q_b - q_c, summed over the steps (implicit Euler: exact up to the
  // solver's tolerance): C (C2(T) - C2(0)) = sum dt (FT1 + FT2 - FT3). And the choke flow FT3 is
  // the orifice's (5.3.2) for C2 - C1 at every step.
  const double compliance = 2e-10;
  const RigParams params = With("topside_compliance:compliance_m3_per_pa=2e-10");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.piston_position_m = [](double t) {
    return 0.02 * std::sin(2.0 * std::numbers::pi * 0.3 * t);
  };
  drive.rig = [](double t) { return testing::Held(t < 3.0 ? 31.0 : 20.0, 5.0, 3.0); };
  const double dt = TimeStep(params, options.cells);
  const ChokeCharacteristic characteristic(params);
  double p_start = 0.0, p_end = 0.0, net_inflow = 0.0, worst_orifice = 0.0, largest_lag = 0.0;
  bool first = true;
  testing::RunSteps(params, options, drive, 10.0, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    const double g = characteristic.FlowCoefficientM2(s[Channel::kChokePosition]);
    const double dp = s[Channel::kC2] - s[Channel::kC1];
    const double orifice =
        g * std::copysign(std::sqrt(std::fabs(dp) / params.choke_density_kgpm3), dp);
    worst_orifice = std::max(worst_orifice, std::fabs(s[Channel::kFT3] - orifice));
    largest_lag =
        std::max(largest_lag, std::fabs(s[Channel::kFT1] + s[Channel::kFT2] - s[Channel::kFT3]));
    if (first) {
      p_start = s[Channel::kC2];
      first = false;
      return;
    }
    net_inflow += dt * (s[Channel::kFT1] + s[Channel::kFT2] - s[Channel::kFT3]);
    p_end = s[Channel::kC2];
  });
  EXPECT_GT(std::fabs(p_end - p_start), 1e4);  // the choke step moved the tubes' pressure
  EXPECT_NEAR(compliance * (p_end - p_start), net_inflow,
              1e-9 * compliance * std::fabs(p_end - p_start) + 1e-16);
  EXPECT_LT(worst_orifice, 1e-9 * units::LpmToM3ps(5.0));
  EXPECT_GT(largest_lag, 0.01 * units::LpmToM3ps(5.0));  // FT3 is not FT1 + FT2
}

TEST(TopsideCompliance, ZeroComplianceIsTheThesisOutlet) {
  // C = 0: q_c = q_b + A u(L) (5.3.1), every channel as without the effect.
  const RigParams params = With("topside_compliance:compliance_m3_per_pa=0");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.piston_position_m = [](double t) {
    return 0.02 * std::sin(2.0 * std::numbers::pi * 0.3 * t);
  };
  drive.rig = [](double t) { return testing::Held(t < 3.0 ? 31.0 : 20.0, 5.0, 3.0); };
  const RigSample with = testing::RunSteps(params, options, drive, 8.0).Sample();
  const RigSample base = testing::RunSteps(RigParams(), options, drive, 8.0).Sample();
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    EXPECT_NEAR(with.values[c], base.values[c], 1e-7 * (std::fabs(base.values[c]) + 1e-6)) << c;
  }
}

// The first root in (pi/2, pi) of tan(theta) = -r theta (the closed pipe ending in a
// capacitance, the effect's header); tan(theta) + r theta increases there.
double ClosedTopsideTheta(double r) {
  double lo = 0.5 * std::numbers::pi + 1e-12, hi = std::numbers::pi;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::tan(mid) + r * mid < 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// (9.2.13) times s with friction f1 and the outlet impedance of a tight choke behind the tubes,
// k = A / (i w C) (complex: AnalyticBhpPerPistonPosition takes a real k).
double ClosedTopsideGain(const RigParams& params, double compliance, double freq_hz) {
  const double c = params.wave_speed_mps, rho = params.density_kgpm3;
  const double area = params.PipeAreaM2(), length = params.pipe_length_m;
  const Complex s(0.0, 2.0 * std::numbers::pi * freq_hz);
  const Complex kappa = std::sqrt(s * (s + params.friction_f1_per_s)) / c;
  const Complex z = rho * c * c * kappa / s;
  const Complex sh = std::sinh(kappa * length), ch = std::cosh(kappa * length);
  const Complex k = area / (compliance * s);
  const Complex ratio = compliance > 0.0 ? z * (z * sh + k * ch) / (z * ch + k * sh) : z * ch / sh;
  return std::abs(ratio * s);
}

TEST(TopsideCompliance, LowersTheClosedChokeResonanceAsTanThetaIsMinusRTheta) {
  // Tight choke (no leak), no pump flow: the pipe closed at the piston end resonates at c/2L
  // (9.3.4); behind the tubes it ends in C: tan(theta) = -r theta, theta = w L / c,
  // r = C / C_pipe, C_pipe = A L / (rho c^2). At the default C (r = 0.33 at c = 850 m/s) the
  // peak falls to 0.784 c/2L. Friction moves both peaks a little; their ratio is the closed
  // form's theta / pi (tolerance 0.003 c/2L; measured 0.7846 against 0.7842), and each peak lies
  // within 0.2 % of the analytic response's with friction (the same (9.2.13) with
  // k = A / (i w C); measured 0.7849 against 0.7847).
  const double compliance = 8.2e-11;
  RigParams base;
  base.choke_leak_m2 = 0.0;
  RigParams topside = With(base, "topside_compliance:compliance_m3_per_pa=8.2e-11");
  const double c = base.wave_speed_mps, length = base.pipe_length_m;
  const double c_pipe = base.PipeAreaM2() * length / (base.density_kgpm3 * c * c);
  const double r = compliance / c_pipe;
  const double predicted = ClosedTopsideTheta(r) / std::numbers::pi;    // in units of c/2L
  EXPECT_NEAR(ClosedTopsideTheta(1e-9) / std::numbers::pi, 1.0, 1e-6);  // C -> 0: c/2L
  SineRun run;
  run.choke_deg = 0.0;
  run.pump_lpm = 0.0;
  const double c2l = c / (2.0 * length);
  const double peak_base = PeakFactor(base, run, c2l, 0.9, 1.1);
  const double peak_topside = PeakFactor(topside, run, c2l, 0.7, 0.87);
  EXPECT_LT(predicted, 0.8);
  EXPECT_NEAR(peak_topside / peak_base, predicted, 0.003) << peak_base << " " << peak_topside;
  // The analytic responses' peaks, on a fine scan: with the tubes, and without (C -> 0: c/2L
  // moved by friction alone).
  const auto analytic_peak = [&](double c_m3_per_pa, double from, double to) {
    double best_f = 0.0, best_gain = 0.0;
    for (double f = from; f <= to; f += 1e-4) {
      const double gain = ClosedTopsideGain(base, c_m3_per_pa, f * c2l);
      if (gain > best_gain) best_gain = gain, best_f = f;
    }
    return best_f;
  };
  const double analytic_topside = analytic_peak(compliance, 0.7, 0.87);
  const double analytic_base = analytic_peak(0.0, 0.9, 1.1);
  EXPECT_NEAR(peak_topside, analytic_topside, 0.002 * analytic_topside);
  EXPECT_NEAR(peak_base, analytic_base, 0.002 * analytic_base);
  EXPECT_NEAR(analytic_base, 1.0, 0.002);
  std::printf(
      "closed choke: r %.3f, tan(theta) = -r theta gives %.4f c/2L; simulated %.4f / %.4f = %.4f; "
      "analytic with friction %.4f / %.4f\n",
      r, predicted, peak_topside, peak_base, peak_topside / peak_base, analytic_topside,
      analytic_base);
}

TEST(TopsideCompliance, LeavesTheOpenChokeResonanceAlone) {
  // Wide-open choke, no pump flow: the outlet is held at p_0 (its linearised impedance is zero),
  // the tubes beside it see no pressure change, and c/4L (9.3.2) stays where it was: the rig's
  // 0.25 Hz open against 0.44 Hz closed (a ratio of 1.76, not 2) is what the tubes can explain.
  // Tolerance 0.3 % of c/4L at the default C.
  const RigParams base;
  const RigParams topside = With("topside_compliance");
  SineRun run;
  run.choke_deg = 90.0;
  run.pump_lpm = 0.0;
  const double c4l = base.wave_speed_mps / (4.0 * base.pipe_length_m);
  const double peak_base = PeakFactor(base, run, c4l, 0.9, 1.1);
  const double peak_topside = PeakFactor(topside, run, c4l, 0.9, 1.1);
  EXPECT_NEAR(peak_topside, peak_base, 0.003) << peak_base << " " << peak_topside;
  std::printf("open choke: %.4f c/4L without, %.4f with the tubes\n", peak_base, peak_topside);
}

TEST(TopsideCompliance, ChokeInertiaAndTheTubesBothCloseTheOutlet) {
  // One closure per pipe end: the two are refused together, saying so.
  RigParams params = With("topside_compliance");
  params = With(params, "choke_inertia");
  SimulationOptions options;
  options.cells = 30;
  auto created = RigSimulator::Create(params, options, testing::Held(31.0, 5.0, 2.0), 0.0);
  ASSERT_FALSE(created.ok());
  EXPECT_NE(created.status().message().find("outlet"), std::string::npos)
      << created.status().message();
}

// --- piston_compressibility ----------------------------------------------------------------------

constexpr double kVolumeAboveM3 = 6.28e-4;  // the effect's defaults (Table 8.1.1)
constexpr double kVolumeBelowM3 = 7.02e-4;
constexpr double kInertanceKgPerM4 = 3.27e6;
constexpr double kBhaDiameterM = 0.0409;

TEST(PistonCompressibility, LeavesTheSteadyStateAlone) {
  // At rest the three states reduce to (5.4.1)-(5.4.2): after a pump step has settled every
  // channel is the rigid model's, and P1 - P2 = rho g h.
  const RigParams params = With("piston_compressibility:bulk_modulus_pa=5e6");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(31.0, t < 1.0 ? 5.0 : 8.0, 2.0); };
  const RigSample base = testing::RunSteps(RigParams(), options, drive, 150.0).Sample();
  const RigSample with = testing::RunSteps(params, options, drive, 150.0).Sample();
  for (Channel channel : {Channel::kP1, Channel::kP2, Channel::kPT1, Channel::kPT5, Channel::kC2}) {
    EXPECT_NEAR(with[channel], base[channel], 5.0) << riglog::ChannelName(channel);  // Pa
  }
  EXPECT_NEAR(with[Channel::kFT4], 0.0, 1e-10);
  EXPECT_NEAR(with[Channel::kFT3], base[Channel::kFT3], 1e-9);
}

TEST(PistonCompressibility, MassBalanceOfTheCompartment) {
  // (5.4.3) + (5.4.4): (V_p dp_p + V_b dp_b) / K = (q_0 - A u(0)) dt, the clearance flow
  // cancels; implicit Euler keeps it exactly. P2 = p_p and P1 = p_b are the effect's states.
  const double k = 5e6;
  const RigParams params = With("piston_compressibility:bulk_modulus_pa=5e6");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.piston_position_m = [](double t) {
    return 0.02 * std::sin(2.0 * std::numbers::pi * 0.3 * t);
  };
  drive.rig = [](double t) { return testing::Held(t < 3.0 ? 31.0 : 20.0, 5.0, 3.0); };
  const double dt = TimeStep(params, options.cells);
  double stored_start = 0.0, stored_end = 0.0, net_inflow = 0.0;
  bool first = true;
  testing::RunSteps(params, options, drive, 10.0, [&](const RigSimulator& sim) {
    const RigSample s = sim.Sample();
    const double stored = (kVolumeAboveM3 * s[Channel::kP2] + kVolumeBelowM3 * s[Channel::kP1]) / k;
    if (first) {
      stored_start = stored;
      first = false;
      return;
    }
    const double t = sim.time_s();
    const double v_d =
        (drive.piston_position_m(t + 0.5 * dt) - drive.piston_position_m(t - 0.5 * dt)) / dt;
    net_inflow += dt * (-v_d * params.PistonDisplacementAreaM2() - s[Channel::kFT4]);
    stored_end = stored;
  });
  EXPECT_GT(std::fabs(stored_end - stored_start), 1e-6);
  EXPECT_NEAR(stored_end - stored_start, net_inflow, 1e-8 * std::fabs(stored_end - stored_start));
}

TEST(PistonCompressibility, StiffCompartmentIsTheRigidModel) {
  // The thesis's finding (5.4.1, 11.3): with the compartment's liquid stiff, the inlet flow and
  // the pressures are those of (5.4.1)-(5.4.2).
  SineRun run;
  run.freq_hz = 0.2;
  const auto b = Response(RigParams(), run);
  const auto w = Response(With("piston_compressibility:bulk_modulus_pa=2.2e9"), run);
  for (Channel channel : {Channel::kFT4, Channel::kP1, Channel::kP2, Channel::kPT5, Channel::kC2}) {
    const Complex ratio = w[Index(channel)] / b[Index(channel)];
    EXPECT_NEAR(std::abs(ratio - 1.0), 0.0, 0.01) << riglog::ChannelName(channel);
  }
  // P1 - P2 is (5.4.2) plus the clearance liquid's inertia: (r_1 + i w M) (A_b - A_d2) v_d
  // (8.2.1 written for the clearance flow; the compression term i w C_b P1 is 1e-4 of it here).
  const double w_rad = 2.0 * std::numbers::pi * run.freq_hz;
  const Complex velocity = kI * w_rad;
  const Complex drop_base = b[Index(Channel::kP1)] - b[Index(Channel::kP2)];
  const Complex drop_with = w[Index(Channel::kP1)] - w[Index(Channel::kP2)];
  const RigParams rig;
  EXPECT_NEAR(std::abs(drop_base / (rig.piston_friction_fd1_pa_s_per_m * velocity) - 1.0), 0.0,
              1e-3);
  const double face_below =
      0.25 * std::numbers::pi *
      (kBhaDiameterM * kBhaDiameterM - rig.lower_rod_diameter_m * rig.lower_rod_diameter_m);
  const Complex predicted = drop_base - kI * w_rad * kInertanceKgPerM4 * face_below * velocity;
  EXPECT_NEAR(std::abs(drop_with / predicted - 1.0), 0.0, 0.01);
}

TEST(PistonCompressibility, SoftCompartmentLagsTheInletFlowAndCouplesP1ToPressure) {
  // Linearised (5.4.3)-(5.4.5) at the drive frequency, with V the piston velocity, Z_in = P2/FT4
  // the pipe's input impedance (from the rigid run) and C_x = V_x / K:
  //   (5.4.4)-(5.4.5): P1 - P2 = (r_1 + i w M) Q,  Q = -(A_b - A_d2) V - i w C_b P1,
  //   (5.4.3): i w C_p P2 = Q + (A_b - A_d) V - P2 / Z_in,
  // solved for P2 and FT4 = P2 / Z_in with i w as implicit Euler sees it. At low frequency it is
  // FT4 / q_0 ~ 1 / (1 + i w (C_p + C_b) Z_in): a capacitance like hose_compliance's.
  const double k = 5e6;
  SineRun run;
  const RigParams base;
  const auto b = Response(base, run);
  const auto c = Response(With("piston_compressibility:bulk_modulus_pa=5e6"), run);
  const double w = 2.0 * std::numbers::pi * run.freq_hz;
  const Complex velocity = kI * w;  // per metre of piston position
  const Complex q_0 = -velocity * base.PistonDisplacementAreaM2();

  const Complex z_in = b[Index(Channel::kP2)] / b[Index(Channel::kFT4)];
  const Complex s = EulerIw(w, TimeStep(base, run.cells));
  const double bha = 0.25 * std::numbers::pi * kBhaDiameterM * kBhaDiameterM;
  const double face_above =
      bha - 0.25 * std::numbers::pi * base.upper_rod_diameter_m * base.upper_rod_diameter_m;
  const double face_below =
      bha - 0.25 * std::numbers::pi * base.lower_rod_diameter_m * base.lower_rod_diameter_m;
  const double c_p = kVolumeAboveM3 / k, c_b = kVolumeBelowM3 / k;
  const double r_1 = -base.piston_friction_fd1_pa_s_per_m / face_below;
  const Complex z_gap = r_1 + s * kInertanceKgPerM4;
  const Complex fill = 1.0 + s * c_b * z_gap;
  const Complex p2 =
      (face_above - face_below / fill) * velocity / (s * c_p + 1.0 / z_in + s * c_b / fill);
  const Complex predicted_ft4 = p2 / z_in / q_0;
  const Complex measured_ft4 = c[Index(Channel::kFT4)] / q_0;
  EXPECT_LT(PhaseDeg(measured_ft4), -3.0);
  EXPECT_NEAR(std::abs(measured_ft4 - predicted_ft4), 0.0, 0.01 * std::abs(predicted_ft4));
  const Complex capacitance_only = 1.0 / (1.0 + s * (c_p + c_b) * z_in);
  EXPECT_NEAR(std::abs(measured_ft4 - capacitance_only), 0.0, 0.08 * std::abs(predicted_ft4));

  const Complex p1 = c[Index(Channel::kP1)];
  const Complex gap = -face_below * velocity - s * c_b * p1;
  const Complex predicted_drop = z_gap * gap;
  const Complex measured_drop = c[Index(Channel::kP1)] - c[Index(Channel::kP2)];
  const Complex rigid_drop = b[Index(Channel::kP1)] - b[Index(Channel::kP2)];
  // The pressure-driven part is visible against (5.4.2) and the linearised law holds.
  EXPECT_GT(std::abs(measured_drop - rigid_drop), 0.05 * std::abs(rigid_drop));
  EXPECT_NEAR(std::abs(measured_drop - predicted_drop), 0.0, 0.02 * std::abs(measured_drop));
}

TEST(PistonCompressibility, PressureBelowTheBhaAnswersAChokeStep) {
  // Piston at rest, choke closing: the rising pressure must fill the volume below the BHA
  // through the clearance, so P1 lags P2 (P1 - P2 < rho g h while P2 rises) and returns to
  // rho g h. The rigid model keeps P1 - P2 = rho g h throughout.
  const RigParams params = With("piston_compressibility:bulk_modulus_pa=5e6");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(t < 1.0 ? 40.0 : 31.0, 10.0, 2.0); };
  const double rho_g_h = params.density_kgpm3 * params.gravity_mps2 * params.compartment_height_m;
  double most_negative = 0.0;
  const RigSimulator sim =
      testing::RunSteps(params, options, drive, 120.0, [&](const RigSimulator& s) {
        const RigSample sample = s.Sample();
        most_negative =
            std::min(most_negative, sample[Channel::kP1] - sample[Channel::kP2] - rho_g_h);
      });
  EXPECT_LT(most_negative, -100.0);  // Pa
  const RigSample end = sim.Sample();
  EXPECT_NEAR(end[Channel::kP1] - end[Channel::kP2], rho_g_h, 1.0);
}

TEST(BoundaryEffects, PumpCurveCombinesAndTheInletHasOneClosure) {
  // pump_curve acts on the pump, hose_compliance on the inlet: they run together. The hose and
  // the compartment both close the inlet, and the pipe refuses two closures of one end.
  RigParams params = With("pump_curve");
  params = With(params, "hose_compliance");
  SimulationOptions options;
  options.cells = 30;
  testing::Drive drive;
  drive.rig = [](double) { return testing::Held(31.0, 5.0, 2.0); };
  testing::RunSteps(params, options, drive, 1.0);
  params = With(params, "piston_compressibility");
  auto created = RigSimulator::Create(params, options, drive.rig(0.0), 0.0);
  EXPECT_FALSE(created.ok());  // hose_compliance and piston_compressibility both close the inlet
}

}  // namespace
}  // namespace mpdrig
