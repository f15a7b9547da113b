// RigSimulator and Simulate(): outputs at requested pipe positions (thesis 6.8), time handling,
// and refusal of bad inputs.
#include "model/sim/rig_simulator.h"

#include <cmath>

#include <gtest/gtest.h>

#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

using testing::Held;

InputSignals SineDrive() {
  InputSignals inputs;
  inputs.piston_position_m = [](double t) { return 0.1 * std::sin(2 * M_PI * 0.2 * t); };
  inputs.rig = [](double) { return Held(31.0, 5.0, 0.0); };
  return inputs;
}

TEST(RigSimulator, PressureAtRequestedPositionsMatchesTheTransmitters) {
  const RigParams params;
  SimulationOptions options;
  options.model = PipeModel::kLinear;
  options.pressure_positions_m = {0.0, 450.0, 900.0};
  std::vector<double> times;
  for (int i = 0; i <= 300; ++i) times.push_back(0.01 * i);
  auto run = Simulate(params, options, SineDrive(), times);
  ASSERT_TRUE(run.ok()) << run.status().message();
  for (const RigSample& s : run->samples) {
    ASSERT_EQ(s.pressure_at_positions_pa.size(), 3u);
    EXPECT_DOUBLE_EQ(s.pressure_at_positions_pa[0], s[Channel::kPT1]);
    EXPECT_DOUBLE_EQ(s.pressure_at_positions_pa[2], s[Channel::kC2]);
  }
  // At rest (t = 0) the linear model's profile is a straight hydrostatic line: p(450 m) is the
  // mean of PT5 (400 m) and PT6 (500 m).
  const RigSample& rest = run->samples.front();
  EXPECT_NEAR(rest.pressure_at_positions_pa[1], 0.5 * (rest[Channel::kPT5] + rest[Channel::kPT6]),
              1e-6);
}

TEST(RigSimulator, RefusesPositionsOutsideThePipe) {
  const RigParams params;
  for (double x : {-1.0, 900.5, std::nan("")}) {
    SimulationOptions options;
    options.pressure_positions_m = {x};
    auto sim = RigSimulator::Create(params, options, Held(31.0, 5.0, 0.0));
    ASSERT_FALSE(sim.ok()) << x;
    EXPECT_NE(sim.status().message().find("outside the pipe"), std::string::npos);
  }
}

TEST(RigSimulator, NonFiniteStepInputIsRefusedAndNamesTheTime) {
  const RigParams params;
  auto sim = RigSimulator::Create(params, SimulationOptions(), Held(31.0, 5.0, 0.0));
  ASSERT_TRUE(sim.ok());
  StepInputs in;
  in.rig = Held(31.0, 5.0, 0.0);
  in.piston_velocity_mps = NAN;
  const Status status = sim->Step(in);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("t = 0"), std::string::npos) << status.message();
  // The refused step changed nothing: the rig still steps on from where it was.
  in.piston_velocity_mps = 0.0;
  EXPECT_TRUE(sim->Step(in).ok());
  EXPECT_NEAR(sim->time_s(), sim->time_step_s(), 1e-15);
}

TEST(RigSimulator, LeavingTheRangeIsAModelRangeErrorWithTimeAndPlace) {
  // A large fast piston stroke against an open outlet pulls the inlet below zero absolute.
  const RigParams params;
  InputSignals inputs;
  inputs.piston_position_m = [](double t) { return 0.3 * std::sin(2 * M_PI * 0.5 * t); };
  inputs.rig = [](double) { return Held(31.0, 0.0, 0.0); };
  const std::vector<double> times = {0.0, 5.0};
  auto run = Simulate(params, SimulationOptions(), inputs, times);
  ASSERT_FALSE(run.ok());
  EXPECT_EQ(run.status().code(), Status::Code::kModelRange);
  EXPECT_NE(run.status().message().find("x = "), std::string::npos);
  EXPECT_NE(run.status().message().find("t = "), std::string::npos);

  SimulationOptions keep_going;
  keep_going.stop_on_range_violation = false;
  auto continued = Simulate(params, keep_going, inputs, times);
  ASSERT_TRUE(continued.ok());
  ASSERT_TRUE(continued->first_range_event.has_value());
  EXPECT_LT(continued->first_range_event->pressure_pa, 0.0);
}

}  // namespace
}  // namespace mpdrig

namespace mpdrig {
namespace {

// A natural cubic spline through the profile's points: exact at the points, and exact for a
// straight line between them (its second derivatives vanish).
TEST(PipeProfile, SplineHitsThePointsAndKeepsAStraightLine) {
  const std::vector<double> line = {1.0, 3.0, 5.0, 7.0, 9.0};
  const std::vector<double> nodes = PipeProfile::AtNodes(line, 8);
  ASSERT_EQ(nodes.size(), 9u);
  for (int i = 0; i <= 8; ++i) EXPECT_NEAR(nodes[i], 1.0 + i, 1e-12);
  const std::vector<double> bumpy = {0.0, 2.0, -1.0, 4.0, 0.5, 3.0};
  const std::vector<double> at = PipeProfile::AtNodes(bumpy, 25);  // 5 nodes per interval
  for (std::size_t k = 0; k < bumpy.size(); ++k) EXPECT_NEAR(at[5 * k], bumpy[k], 1e-12);
}

// The pipe's state carried over as a profile through every node (cells + 1 points) is the same
// state: a run started from it follows the run it was taken from to rounding.
TEST(PipeProfile, AStateTakenAsAProfileContinuesTheSameRun) {
  const RigParams params;
  SimulationOptions options;
  options.cells = 40;
  const InputSignals drive = SineDrive();
  auto first = RigSimulator::Create(params, options, drive.rig(0.0), 0.0);
  ASSERT_TRUE(first.ok());
  const auto step = [&](RigSimulator* sim) {
    const double t_b = sim->next_step_end_s(), dt = sim->time_step_s();
    StepInputs in;
    in.piston_position_m = drive.piston_position_m(t_b);
    in.piston_velocity_mps =
        (drive.piston_position_m(t_b + 0.5 * dt) - drive.piston_position_m(t_b - 0.5 * dt)) / dt;
    in.rig = drive.rig(t_b);
    return sim->Step(in);
  };
  while (first->time_s() < 7.3) ASSERT_TRUE(step(&*first).ok());
  PipeProfile profile;
  for (int i = 0; i <= options.cells; ++i) {
    const double x = params.pipe_length_m * i / options.cells;
    profile.pressure_pa.push_back(first->PressureAtPa(x));
    profile.velocity_mps.push_back(first->pipe().VelocityAt(x));
  }
  auto second = RigSimulator::Create(params, options, drive.rig(0.0),
                                     drive.piston_position_m(first->time_s()), first->time_s());
  ASSERT_TRUE(second.ok());
  ASSERT_TRUE(second->SetPipeProfile(profile).ok());
  for (int k = 0; k < 500; ++k) {
    ASSERT_TRUE(step(&*first).ok());
    ASSERT_TRUE(step(&*second).ok());
    for (Channel c : {Channel::kPT1, Channel::kPT5, Channel::kC2}) {
      // 1e-3 Pa (1e-8 of the pressure): the invariants' round trip through p and u rounds.
      ASSERT_NEAR(second->Sample()[c], first->Sample()[c], 1e-3) << k;
    }
  }
  auto fresh = RigSimulator::Create(params, options, drive.rig(0.0), 0.0);
  ASSERT_TRUE(fresh.ok());
  PipeProfile bad = profile;
  bad.velocity_mps[3] = std::nan("");
  EXPECT_FALSE(fresh->SetPipeProfile(bad).ok());
  bad.pressure_pa.resize(1);
  EXPECT_FALSE(fresh->SetPipeProfile(bad).ok());
}

}  // namespace
}  // namespace mpdrig
