// The pipe at rest and its wave fronts, for every model and scheme:
// hydrostatic profile (6.5.3), Joukowsky's pressure jump rho c du, travel time L/c, and the
// doubling of a pressure wave at a closed end. And the characteristics scheme's vectorised
// interior against its formula written out node by node.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "model/pipe/characteristics_solver.h"
#include "model/sim/rig_simulator.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

using testing::AllVariants;
using testing::Drive;
using testing::Held;
using testing::RunSteps;
using testing::Variant;

class PipePhysics : public ::testing::TestWithParam<Variant> {
 protected:
  SimulationOptions Options(int cells = kDefaultCells) const {
    SimulationOptions options;
    options.model = GetParam().model;
    options.scheme = GetParam().scheme;
    options.cells = cells;
    options.choke_input = ChokeInput::kMeasured;
    return options;
  }
};

TEST_P(PipePhysics, RestStateIsHydrostaticAndStays) {
  const RigParams params;
  Drive drive;
  drive.rig = [](double) { return Held(0.0, 0.0, 3.0); };  // no flow anywhere
  const RigSimulator sim = RunSteps(params, Options(), drive, 10.0);
  const double p_l = 3e5 + params.atmospheric_pressure_pa;  // Held(.., 3 barg)
  const double c = params.wave_speed_mps;
  const double gs = params.gravity_mps2 * params.SinInclination();
  for (int k = 0; k < 10; ++k) {
    const double x = 100.0 * k;
    const double expected =
        GetParam().model == PipeModel::kQuasiLinear
            ? (params.QuasiLinearK() + p_l) * std::exp(gs * (900.0 - x) / (c * c)) -
                  params.QuasiLinearK()  // (6.5.3)
            : p_l + params.density_kgpm3 * gs * (900.0 - x);
    // The rest state is an exact discrete steady state of both schemes: after 10 s it may differ
    // from the closed form only by round-off (1e-9 of 5 bar).
    EXPECT_NEAR(sim.PressureAtPa(x), expected, 5e-4) << "x = " << x;
  }
  // 2.3 m of water column between PT1 and PT10: rho g h = 22.5 kPa, where the quasi-linear
  // model's water is denser at 4 bar by (p - p_ref)/c^2 (5.2.1), +9.7 Pa here.
  const double p_mean = 0.5 * (sim.PressureAtPa(0.0) + sim.PressureAtPa(900.0));
  const double rho = GetParam().model == PipeModel::kQuasiLinear
                         ? params.density_kgpm3 + (p_mean - params.reference_pressure_pa) / (c * c)
                         : params.density_kgpm3;
  EXPECT_NEAR(sim.PressureAtPa(0.0) - sim.PressureAtPa(900.0), rho * params.gravity_mps2 * 2.3,
              0.01);
}

TEST_P(PipePhysics, PistonStepTravelsUpThePipeInLOverC) {
  // A velocity step of the piston at t0 (closed choke, no friction): Joukowsky's jump
  // dp = rho c du at the inlet at once; at x = L after L/c; doubled there by the closed end.
  RigParams params;
  params.friction_f1_per_s = 0.0;
  params.friction_f2_per_m = 0.0;
  params.choke_leak_m2 = 0.0;
  const double v_d = 0.02;  // m/s, piston moving up
  const double t0 = 0.2;
  Drive drive;
  drive.piston_position_m = [&](double t) { return t > t0 ? v_d * (t - t0) : 0.0; };
  drive.rig = [](double) { return Held(0.0, 0.0, 3.0); };  // tight choke: leak removed above

  const SimulationOptions options = Options(400);
  std::vector<double> time, inlet, outlet;
  RunSteps(params, options, drive, t0 + 1.5 * params.pipe_length_m / params.wave_speed_mps,
           [&](const RigSimulator& sim) {
             time.push_back(sim.time_s());
             inlet.push_back(sim.PressureAtPa(0.0));
             outlet.push_back(sim.PressureAtPa(params.pipe_length_m));
           });
  const double du = -v_d * params.PistonDisplacementAreaM2() / params.PipeAreaM2();  // (5.4.1)
  const double joukowsky = params.density_kgpm3 * params.wave_speed_mps * du;        // negative
  const double travel = params.pipe_length_m / params.wave_speed_mps;
  const double dt = time[1] - time[0];

  // Inlet: the full jump within two steps of t0, held until the reflection returns at 2L/c.
  auto at = [&](const std::vector<double>& v, double t) {
    return v[static_cast<std::size_t>(std::lround(t / dt))];
  };
  EXPECT_NEAR(at(inlet, t0 + 0.5 * travel) - inlet[0], joukowsky, 0.01 * std::fabs(joukowsky));
  // Outlet: crosses half of its final (doubled) jump at t0 + L/c, within two steps.
  double arrival = -1.0;
  for (std::size_t i = 0; i < time.size(); ++i) {
    if (outlet[i] - outlet[0] < joukowsky) {  // half of 2 * joukowsky (both negative)
      arrival = time[i];
      break;
    }
  }
  ASSERT_GT(arrival, 0.0) << "the wave never reached x = L";
  // Characteristics: transport is exact, the front lands within the grid's two steps. Method of
  // lines: the upwind differences smear the front over several cells; 1% of L/c.
  const double tolerance =
      GetParam().scheme == PipeScheme::kCharacteristics ? 2.0 * dt : 0.01 * travel;
  EXPECT_NEAR(arrival, t0 + travel, tolerance);
  EXPECT_NEAR(at(outlet, t0 + 1.4 * travel) - outlet[0], 2.0 * joukowsky,
              0.02 * std::fabs(joukowsky));
}

// The interior nodes of the characteristics scheme (characteristics_solver.cc, StepInterior)
// against the scheme as the header states it, one node at a time: the feet of both
// characteristics interpolated on the upwind side (clamped at the end nodes), the friction at a
// foot with the neighbouring node's velocity, the trapezoidal rule with the new point's friction
// linearised as (f1 + f2 |u_old|) u_P. Strong waves of both signs (u/c up to 2e-3, so both
// sides of every foot are used), strong quadratic friction, grids whose sizes leave every
// remainder of the eight-wide loops, both models. The two differ by the order of the operations
// only: round-off, 1e-12 of the invariants' scale. The range check's minimum is the nodes'.
TEST(CharacteristicsInterior, IsTheSchemeNodeByNode) {
  RigParams params;
  params.friction_f2_per_m = 0.5;  // strong, so the |u| terms matter
  for (PipeModel model : {PipeModel::kQuasiLinear, PipeModel::kLinear}) {
    for (int cells : {2, 3, 9, 16, 37, 200}) {
      const PipeConfig config = PipeConfig::FromParams(params, model, cells);
      CharacteristicsSolver solver(config, 4e5);
      solver.SetRestState(4e5);
      const double h = solver.time_step_s();
      const double c = config.wave_speed_mps;
      const double scale = c * 0.01;  // |alpha|, |beta| of a few bar, in m/s
      double largest_error = 0.0;
      for (int step = 0; step < 400; ++step) {
        const std::vector<double> a = solver.alpha();
        const std::vector<double> b = solver.beta();
        const double t = (step + 1) * h;
        PipeStepInputs inputs;
        inputs.end.inlet_velocity_mps = 2.0 * std::sin(2.0 * M_PI * 3.0 * t);  // +-2 m/s
        inputs.end.choke = {1e-5, 0.0, 1e5};
        inputs.start = inputs.end;
        RangeViolation violation;
        ASSERT_TRUE(solver.Step(inputs, &violation).ok());
        const auto u = [&](int i) { return 0.5 * (a[i] + b[i]); };
        const auto f = [&](double v) { return config.Friction(v); };
        double smallest = solver.alpha()[0] - solver.beta()[0];
        for (int i = 1; i < cells; ++i) {
          double alpha_foot = a[i - 1], beta_foot = b[i + 1];
          if (model == PipeModel::kQuasiLinear) {
            const double theta_a = u(i - 1) / c;  // foot at x_(i-1) - theta dx
            const int ja = theta_a >= 0.0 ? std::max(i - 2, 0) : i;
            alpha_foot = (1.0 - std::fabs(theta_a)) * a[i - 1] + std::fabs(theta_a) * a[ja];
            const double theta_b = u(i + 1) / c;  // foot at x_(i+1) - theta dx
            const int jb = theta_b >= 0.0 ? i : std::min(i + 2, cells);
            beta_foot = (1.0 - std::fabs(theta_b)) * b[i + 1] + std::fabs(theta_b) * b[jb];
          }
          const double lambda =
              config.friction_f1_per_s + config.friction_f2_per_m * std::fabs(u(i));
          const double gs = config.gravity_slope_mps2;
          const double u_p =
              (alpha_foot + beta_foot - 0.5 * h * (f(u(i - 1)) + f(u(i + 1))) - 2.0 * h * gs) /
              (2.0 + h * lambda);
          const double alpha_p = alpha_foot - 0.5 * h * (f(u(i - 1)) + lambda * u_p) - h * gs;
          const double beta_p = beta_foot - 0.5 * h * (f(u(i + 1)) + lambda * u_p) - h * gs;
          largest_error = std::max({largest_error, std::fabs(solver.alpha()[i] - alpha_p),
                                    std::fabs(solver.beta()[i] - beta_p)});
          smallest = std::min(smallest, solver.alpha()[i] - solver.beta()[i]);
        }
        smallest = std::min(smallest, solver.alpha()[cells] - solver.beta()[cells]);
        EXPECT_EQ(violation.occurred, smallest <= solver.law().ZeroPressureDifference());
      }
      EXPECT_LT(largest_error, 1e-12 * scale) << "N = " << cells;
      // The waves were strong: |u| / c reached 1e-3, so the feet moved.
      double largest_velocity = 0.0;
      for (int i = 0; i <= cells; ++i) {
        largest_velocity =
            std::max(largest_velocity, std::fabs(0.5 * (solver.alpha()[i] + solver.beta()[i])));
      }
      EXPECT_GT(largest_velocity, 0.1) << "N = " << cells;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllSchemes, PipePhysics, ::testing::ValuesIn(AllVariants()),
                         testing::VariantName);

}  // namespace
}  // namespace mpdrig
