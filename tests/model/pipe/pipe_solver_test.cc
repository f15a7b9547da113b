// The pipe at rest and its wave fronts, for every model and scheme:
// hydrostatic profile (6.5.3), Joukowsky's pressure jump rho c du, travel time L/c, and the
// doubling of a pressure wave at a closed end.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

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

INSTANTIATE_TEST_SUITE_P(AllSchemes, PipePhysics, ::testing::ValuesIn(AllVariants()),
                         testing::VariantName);

}  // namespace
}  // namespace mpdrig
