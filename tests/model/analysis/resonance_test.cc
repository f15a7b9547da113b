// The rig's terminations and their first resonances (termination.h, resonance.h): the analytic
// response with effects against closed forms of the lossless pipe, and the simulated resonance
// against the analytic one.
#include "model/analysis/resonance.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

constexpr double kPi = std::numbers::pi;

// Nearly lossless: the closed forms of (9.3.2) and (9.3.4) hold to the scan's refinement.
RigParams Lossless(double wave_speed_mps) {
  RigParams params;
  params.wave_speed_mps = wave_speed_mps;
  params.friction_f1_per_s = 1e-6;
  return params;
}

RigParams With(RigParams params, const std::string& spec) {
  const Status applied = ApplyEffectSpec(&params, spec);
  EXPECT_TRUE(applied.ok()) << applied.message();
  return params;
}

double Analytic(const RigParams& params, Termination termination) {
  ResonanceOptions options;
  options.method = ResponseMethod::kAnalytic;
  auto resonance = FirstResonance(params, termination, options);
  EXPECT_TRUE(resonance.ok()) << resonance.status().message();
  return resonance.ok() ? resonance->freq_hz : NAN;
}

// The root of an increasing g on (lo, hi) by bisection.
template <typename G>
double Root(G g, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (g(mid) < 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double PipeCompliance(const RigParams& p) {
  return p.PipeAreaM2() * p.pipe_length_m / (p.density_kgpm3 * p.wave_speed_mps * p.wave_speed_mps);
}

// The simulated response the comparisons use: the linear model (9.2.13 is linear), 60 cells.
ResonanceOptions SimulatedOptions() {
  ResonanceOptions options;
  options.simulation.cells = 60;
  options.simulation.model = PipeModel::kLinear;
  options.method = ResponseMethod::kSimulated;
  return options;
}

// Relative tolerance of the closed forms: f1 = 1e-6 /s moves a peak by far less.
constexpr double kClosedFormTolerance = 1e-5;

TEST(Termination, NamesRoundTripAndAnUnknownOneListsTheValidOnes) {
  for (const TerminationInfo& info : TerminationTable()) {
    auto parsed = ParseTermination(info.name);
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, info.termination);
    EXPECT_EQ(TerminationName(info.termination), info.name);
  }
  auto bad = ParseTermination("choke_closed");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("choke-closed, choke-open, closed-at-pipe-end"),
            std::string::npos)
      << bad.status().message();
}

TEST(Termination, TheValveCutsOffTheTopsideEffectsOnly) {
  RigParams params = With(RigParams(), "topside_compliance");
  params = With(params, "hose_compliance");
  const TerminatedRig valve = ApplyTermination(params, Termination::kClosedAtPipeEnd);
  ASSERT_EQ(valve.params.effects.size(), 1u);
  EXPECT_EQ(valve.params.effects[0].name, "hose_compliance");
  EXPECT_EQ(valve.choke.kind, ChokeSetting::Kind::kClosed);
  EXPECT_EQ(valve.params.choke_leak_m2, 0.0);
  EXPECT_EQ(ApplyTermination(params, Termination::kChokeClosed).params.effects.size(), 2u);
  EXPECT_EQ(ApplyTermination(params, Termination::kChokeOpen).choke.kind,
            ChokeSetting::Kind::kOpen);
}

TEST(AnalyticResonance, BarePipeIsHalfWaveClosedAndQuarterWaveOpen) {
  // (9.3.4) closed: c/2L; (9.3.2) open: c/4L. At c = 1173 m/s: 0.6517 and 0.3258 Hz.
  const RigParams params = Lossless(1173.0);
  const double c2l = 1173.0 / (2.0 * params.pipe_length_m);
  EXPECT_NEAR(Analytic(params, Termination::kChokeClosed), c2l, kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kClosedAtPipeEnd), c2l, kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kChokeOpen), c2l / 2.0, kClosedFormTolerance * c2l);
}

TEST(AnalyticResonance, TopsideComplianceSolvesTanThetaIsMinusRTheta) {
  // Behind a closed choke the tubes end the pipe in C: tan(theta) = -r theta, r = C / C_pipe;
  // the valve cuts them off (c/2L) and the open choke holds the outlet (c/4L).
  const RigParams base = Lossless(1173.0);
  const RigParams params = With(base, "topside_compliance:compliance_m3_per_pa=1.0e-10");
  const double r = 1.0e-10 / PipeCompliance(base);
  const double theta = Root([r](double t) { return std::tan(t) + r * t; }, kPi / 2 + 1e-12, kPi);
  const double c2l = 1173.0 / (2.0 * base.pipe_length_m);
  EXPECT_NEAR(Analytic(params, Termination::kChokeClosed), theta / kPi * c2l,
              kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kClosedAtPipeEnd), c2l, kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kChokeOpen), c2l / 2.0, kClosedFormTolerance * c2l);
}

TEST(AnalyticResonance, HoseComplianceLowersBothEndsAndKeepsTheRatioAboveTwo) {
  // At the inlet: closed outlet tan(theta) = -r theta, open theta tan(theta) = 1/r.
  const RigParams base = Lossless(1173.0);
  const RigParams params = With(base, "hose_compliance:compliance_m3_per_pa=5.0e-11");
  const double r = 5.0e-11 / PipeCompliance(base);
  const double closed = Root([r](double t) { return std::tan(t) + r * t; }, kPi / 2 + 1e-12, kPi);
  const double open =
      Root([r](double t) { return t * std::tan(t) - 1.0 / r; }, 1e-9, kPi / 2 - 1e-12);
  const double c2l = 1173.0 / (2.0 * base.pipe_length_m);
  const double f_closed = Analytic(params, Termination::kChokeClosed);
  const double f_open = Analytic(params, Termination::kChokeOpen);
  EXPECT_NEAR(f_closed, closed / kPi * c2l, kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kClosedAtPipeEnd), f_closed, 1e-9);
  EXPECT_NEAR(f_open, open / kPi * c2l, kClosedFormTolerance * c2l);
  EXPECT_GT(f_closed / f_open, 2.0);
  std::printf("hose C = 5e-11 (r %.3f): closed %.4f Hz, open %.4f Hz, ratio %.3f\n", r, f_closed,
              f_open, f_closed / f_open);
}

TEST(AnalyticResonance, GasEntrainmentIsAUniformWaveSpeedAtTheMeanPressure) {
  // 1/(rho c_m^2) = 1/(rho c^2) + eps/(n p) - eps/K at p_m: both resonances move by c_m / c, the
  // ratio stays 2.
  const RigParams base = Lossless(1173.0);
  const RigParams params = With(base, "gas_entrainment:void_fraction=1e-3");
  ResonanceOptions options;
  const double p_m = MeanLinePressurePa(base, options.simulated.outlet_pressure_pa);
  const double rho = base.density_kgpm3, k = rho * 1173.0 * 1173.0;
  const double eps = 1e-3 * 101325.0 / p_m;
  const double c_m = 1.0 / std::sqrt(rho * (1.0 / k + eps / p_m - eps / k));
  const double c2l = c_m / (2.0 * base.pipe_length_m);
  const double f_closed = Analytic(params, Termination::kChokeClosed);
  EXPECT_NEAR(f_closed, c2l, kClosedFormTolerance * c2l);
  EXPECT_NEAR(f_closed / Analytic(params, Termination::kChokeOpen), 2.0, 1e-4);
}

TEST(SimulatedResonance, AgreesWithTheAnalyticOneWithTheTubes) {
  // The simulator (linear model, 60 cells) with the tuned friction, scanned and refined by a
  // parabola, against (9.2.13) with k = 1/(i w C / A): within 0.5 % (the grid's dispersion and
  // the parabola).
  RigParams params = With(RigParams(), "topside_compliance:compliance_m3_per_pa=3.2e-11");
  params.friction_f2_per_m = 0.0;
  const ResonanceOptions options = SimulatedOptions();
  auto simulated = FirstResonance(params, Termination::kChokeClosed, options);
  ASSERT_TRUE(simulated.ok()) << simulated.status().message();
  const double analytic = Analytic(params, Termination::kChokeClosed);
  EXPECT_NEAR(simulated->freq_hz, analytic, 0.005 * analytic);
  EXPECT_EQ(simulated->method, ResponseMethod::kSimulated);
  std::printf("closed choke with the tubes: simulated %.4f Hz (%d frequencies), analytic %.4f Hz\n",
              simulated->freq_hz, simulated->simulations, analytic);
}

TEST(AnalyticResonance, AnIdealCompartmentIsOneCapacitanceAtTheInlet) {
  // piston_compressibility without the clearance's inertance and friction: its two volumes are
  // one capacitance (V_p + V_b)/K at the inlet, so the closed outlet resonates where
  // tan(theta) = -r theta and the open one where theta tan(theta) = 1/r, r = C / C_pipe.
  RigParams base = Lossless(1173.0);
  base.piston_friction_fd1_pa_s_per_m = 0.0;
  const RigParams params = With(base,
                                "piston_compressibility:bulk_modulus_pa=2e7,inertance_kg_per_m4=0,"
                                "volume_above_m3=6e-4,volume_below_m3=7e-4");
  const double r = (6e-4 + 7e-4) / 2e7 / PipeCompliance(base);
  const double closed = Root([r](double t) { return std::tan(t) + r * t; }, kPi / 2 + 1e-12, kPi);
  const double open =
      Root([r](double t) { return t * std::tan(t) - 1.0 / r; }, 1e-9, kPi / 2 - 1e-12);
  const double c2l = 1173.0 / (2.0 * base.pipe_length_m);
  EXPECT_NEAR(Analytic(params, Termination::kChokeClosed), closed / kPi * c2l,
              kClosedFormTolerance * c2l);
  EXPECT_NEAR(Analytic(params, Termination::kChokeOpen), open / kPi * c2l,
              kClosedFormTolerance * c2l);
}

TEST(SimulatedResonance, AgreesWithTheAnalyticOneWithACompressibleCompartment) {
  // The full three-state compartment (inertance and clearance friction of Table 8.1.1) with a
  // little trapped air (K = 2e7 Pa): the simulator's implicit compartment against the linearised
  // 2x2 system, within 0.5 % as for the tubes, in both choke terminations.
  RigParams params = With(RigParams(), "piston_compressibility:bulk_modulus_pa=2e7");
  params.friction_f2_per_m = 0.0;
  ResonanceOptions options = SimulatedOptions();
  options.simulated.amplitude_m = 2.5e-4;
  for (Termination termination : {Termination::kChokeClosed, Termination::kChokeOpen}) {
    auto simulated = FirstResonance(params, termination, options);
    ASSERT_TRUE(simulated.ok()) << simulated.status().message();
    const double analytic = Analytic(params, termination);
    EXPECT_NEAR(simulated->freq_hz, analytic, 0.005 * analytic) << TerminationName(termination);
    EXPECT_LT(analytic, Analytic(RigParams(), termination));  // a compliance lowers it
    std::printf("%s with the compartment at K = 2e7 Pa: simulated %.4f Hz, analytic %.4f Hz\n",
                std::string(TerminationName(termination)).c_str(), simulated->freq_hz, analytic);
  }
}

TEST(SimulatedResonance, AnalyticIsRefusedForAnEffectItDoesNotHold) {
  const RigParams params = With(RigParams(), "sensor_lag");
  ResonanceOptions options;
  options.method = ResponseMethod::kAnalytic;
  auto refused = FirstResonance(params, Termination::kChokeClosed, options);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("sensor_lag"), std::string::npos);
  EXPECT_EQ(EffectsOutsideAnalytic(With(RigParams(), "topside_compliance")), "");
}

}  // namespace
}  // namespace mpdrig
