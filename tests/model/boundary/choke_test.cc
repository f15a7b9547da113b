// The choke: characteristic (Table 8.4.1 with the leak of 9.4.1), actuator (8.4), and the outlet
// boundary solve of the orifice equation (5.3.2) in both flow directions (6.6.1-6.6.2).
#include "model/boundary/choke.h"

#include <cmath>

#include <gtest/gtest.h>

#include "model/params/rig_params.h"

namespace mpdrig {
namespace {

TEST(ChokeCharacteristic, InterpolatesTableAndFloorsAtLeak) {
  const RigParams params;
  const ChokeCharacteristic g(params);
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(31.0 / 90.0), 4.5e-6);
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(1.0), 1.03e-4);
  // Halfway between 31 and 40 deg: the mean of 4.5e-6 and 1.19e-5 (linear interpolation).
  EXPECT_NEAR(g.FlowCoefficientM2(35.5 / 90.0), 0.5 * (4.5e-6 + 1.19e-5), 1e-15);
  // The table's zeros (0 and 15 deg) and its small values are replaced by the leak (9.4).
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(0.0), 6e-7);
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(15.0 / 90.0), 6e-7);
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(20.0 / 90.0), 6e-7);  // table 2.2e-7 < leak
  EXPECT_DOUBLE_EQ(g.FlowCoefficientM2(25.0 / 90.0), 8e-7);
}

TEST(ChokeActuator, RateLimitGivesAboutOneSecondFullStroke) {
  // Section 8.4: 0 -> 90 deg takes about 1 s. With the rate limit of 1 /s and a 0.1 s lag, the
  // opening reaches 99% between 0.99 s and 1.5 s.
  const RigParams params;
  const ChokeActuator actuator(params);
  const double dt = 1e-3;
  double opening = 0.0;
  double t = 0.0;
  while (opening < 0.99 && t < 10.0) {
    opening = actuator.Advance(opening, 1.0, dt);
    t += dt;
  }
  EXPECT_GE(t, 0.99);
  EXPECT_LE(t, 1.5);
}

TEST(ChokeActuator, SmallStepFollowsFirstOrderLag) {
  // Away from the rate limit the lag is exact: e(t) = e0 exp(-t / T).
  const RigParams params;
  const ChokeActuator actuator(params);
  double opening = 0.5;
  const double reference = 0.51;
  for (int i = 0; i < 100; ++i) opening = actuator.Advance(opening, reference, 1e-3);
  EXPECT_NEAR(reference - opening, 0.01 * std::exp(-0.1 / params.choke_time_constant_s), 1e-12);
}

class ChokeBoundaryTest : public ::testing::TestWithParam<PipeModel> {};

TEST_P(ChokeBoundaryTest, SolutionSatisfiesOrificeEquationInBothDirections) {
  const RigParams params;
  const double area = params.PipeAreaM2();
  const double rho_l = params.choke_density_kgpm3;
  const PipeLaw law(GetParam(), params.wave_speed_mps, params.density_kgpm3, params.QuasiLinearK(),
                    5e5);
  const ChokeBoundary choke(area, rho_l);
  const ChokeBoundaryInputs in{4.5e-6, 8.3e-5, 4e5};
  // Arriving invariants from well below to well above the outlet pressure: reverse, zero and
  // forward choke flow.
  int reverse = 0, forward = 0;
  for (double alpha = -1.0; alpha <= 1.0; alpha += 0.05) {
    const double u = choke.SolveOutletVelocity(law, alpha, in);
    const double q_c = in.pump_flow_m3ps + area * u;  // (5.3.1)
    const double p_c = law.PressureFromAlpha(alpha, u);
    const double orifice =
        rho_l * q_c * std::fabs(q_c) / (in.flow_coefficient_m2 * in.flow_coefficient_m2);
    // (5.3.2) with the sign of the flow; tolerance: round-off on pressures of 1e5..1e6 Pa.
    EXPECT_NEAR(p_c - in.outlet_pressure_pa, orifice, 1e-6 * (1.0 + std::fabs(orifice)))
        << "alpha " << alpha;
    // Reverse flow exactly when the choke inlet is below its outlet (6.6.2).
    EXPECT_EQ(q_c < 0.0, p_c < in.outlet_pressure_pa);
    reverse += q_c < 0.0;
    forward += q_c > 0.0;
  }
  EXPECT_GT(reverse, 5);
  EXPECT_GT(forward, 5);
}

TEST_P(ChokeBoundaryTest, TightChokeSendsPumpFlowDownThePipe) {
  const RigParams params;
  const PipeLaw law(GetParam(), params.wave_speed_mps, params.density_kgpm3, params.QuasiLinearK(),
                    5e5);
  const ChokeBoundary choke(params.PipeAreaM2(), params.choke_density_kgpm3);
  const double u = choke.SolveOutletVelocity(law, 0.3, {0.0, 8.3e-5, 1e5});
  EXPECT_DOUBLE_EQ(u, -8.3e-5 / params.PipeAreaM2());
}

INSTANTIATE_TEST_SUITE_P(Models, ChokeBoundaryTest,
                         ::testing::Values(PipeModel::kQuasiLinear, PipeModel::kLinear),
                         [](const auto& info) {
                           return info.param == PipeModel::kLinear ? "Linear" : "QuasiLinear";
                         });

}  // namespace
}  // namespace mpdrig
