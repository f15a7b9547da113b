// A virtual rig as the service runs it, without transport: commands in lab units, refusal of bad
// commands (counted, explained, the rig keeps its last valid command and keeps running), and the
// physics seen through sensor ticks.
#include "service/rig/rig_host.h"

#include <cmath>
#include <complex>
#include <limits>

#include <gtest/gtest.h>

#include "model/boundary/choke.h"
#include "model/common/units.h"

namespace mpdrig::service {
namespace {

constexpr double kRateHz = 100.0;

RigHost MakeRig(InitialCommands initial = {}) {
  auto rig = RigHost::Create("rig-1", RigParams(), SimulationOptions(), kRateHz, initial);
  EXPECT_TRUE(rig.ok()) << rig.status().message();
  return std::move(rig).value();
}

TEST(RigHost, BadCommandsAreRefusedCountedAndChangeNothing) {
  RigHost rig = MakeRig();
  RigHost twin = MakeRig();  // gets only the valid commands
  for (RigHost* r : {&rig, &twin}) {
    ASSERT_TRUE(r->SetPumpLpm(5.0).ok());
    ASSERT_TRUE(r->SetChokeDeg(31.0).ok());
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Bad {
    Status status;
    const char* names;
  };
  PistonCommandIn far;
  far.mode = PistonCommandIn::Mode::kPosition;
  far.position_m = 2.0;
  PistonCommandIn fast;
  fast.mode = PistonCommandIn::Mode::kSine;
  fast.amplitude_m = 0.1;
  fast.frequency_hz = nan;
  const Bad bad[] = {
      {rig.SetChokeDeg(nan), "choke opening"},      {rig.SetChokeDeg(95.0), "choke opening"},
      {rig.SetPumpLpm(-1.0), "pump flow"},          {rig.SetPumpLpm(inf), "pump flow"},
      {rig.SetOutletBarg(40.0), "outlet pressure"}, {rig.SetPiston(far), "piston position"},
      {rig.SetPiston(fast), "piston frequency"},
  };
  for (const Bad& b : bad) {
    EXPECT_FALSE(b.status.ok());
    EXPECT_NE(b.status.message().find(b.names), std::string::npos) << b.status.message();
  }
  EXPECT_EQ(rig.counters().rejected_commands, std::size(bad));
  EXPECT_NE(rig.counters().last_rejection.find("piston frequency"), std::string::npos);
  // The rig kept its valid commands: it runs exactly as its twin.
  for (int i = 0; i < 200; ++i) {
    auto a = rig.Tick();
    auto b = twin.Tick();
    ASSERT_TRUE(a.ok() && b.ok());
    ASSERT_EQ(a->values, b->values) << "tick " << i;
  }
  EXPECT_EQ(twin.counters().rejected_commands, 0u);
}

TEST(RigHost, ClosingTheChokeRaisesC2ToTheOrificeValue) {
  RigHost rig = MakeRig();
  ASSERT_TRUE(rig.SetPumpLpm(5.0).ok());
  ASSERT_TRUE(rig.SetChokeDeg(31.0).ok());
  double c2_before = 0.0;
  for (int i = 0; i < 100; ++i) c2_before = rig.Tick()->values[Index(Channel::kC2)];
  ASSERT_TRUE(rig.SetChokeDeg(28.0).ok());
  // 150 s: waves decay as e^(-f1 t/2) = e^-11; the pipe's compliance fills through the orifice
  // with tau = (2 rho q / G^2)(A L / (rho c^2)) = 7 s at 28 deg.
  RigSample last;
  for (int i = 0; i < 15000; ++i) last = *rig.Tick();
  const double g28 = ChokeCharacteristic(rig.params()).FlowCoefficientM2(28.0 / 90.0);
  const double q = units::LpmToM3ps(5.0);
  const double expected = rig.params().choke_density_kgpm3 * (q / g28) * (q / g28);
  EXPECT_GT(last[Channel::kC2], c2_before + 1e5) << "closing the choke must raise C2";
  // 0.5%: the actuator and the transients have long settled.
  EXPECT_NEAR(last[Channel::kC2] - last[Channel::kC1], expected, 5e-3 * expected);
  EXPECT_NEAR(last[Channel::kChokePosition], 28.0 / 90.0, 1e-9);
}

TEST(RigHost, PistonSineGivesTheModelsResponseAtThatFrequency) {
  // The rig's generated sine and a batch Simulate() with the same profile agree sample for
  // sample; PT1's spectrum peaks at the piston's frequency.
  RigHost rig = MakeRig({31.0, 5.0, 0.0});  // steady state with the pump on, as Simulate starts
  PistonCommandIn sine;
  sine.mode = PistonCommandIn::Mode::kSine;
  sine.amplitude_m = 0.1;
  sine.frequency_hz = 0.25;
  ASSERT_TRUE(rig.SetPiston(sine).ok());
  std::vector<double> times, pt1;
  for (int i = 1; i <= 4000; ++i) {
    auto s = rig.Tick();
    ASSERT_TRUE(s.ok());
    times.push_back(s->time_s);
    pt1.push_back((*s)[Channel::kPT1]);
  }
  InputSignals inputs;
  inputs.piston_position_m = [](double t) { return 0.1 * std::sin(2 * M_PI * 0.25 * t); };
  RigInputs held;
  held.choke_opening_frac = 31.0 / 90.0;
  held.pump_flow_m3ps = units::LpmToM3ps(5.0);
  inputs.rig = [held](double) { return held; };
  std::vector<double> batch_times = {0.0};
  batch_times.insert(batch_times.end(), times.begin(), times.end());
  auto batch = Simulate(RigParams(), SimulationOptions(), inputs, batch_times);
  ASSERT_TRUE(batch.ok());
  double worst = 0.0;
  for (std::size_t i = 0; i < pt1.size(); ++i) {
    worst = std::max(worst, std::fabs(pt1[i] - batch->samples[i + 1][Channel::kPT1]));
  }
  // The batch run differentiates the profile one-sidedly at its very end only.
  EXPECT_LT(worst, 50.0) << "Pa";

  auto amplitude_at = [&](double f) {
    std::complex<double> sum = 0.0;
    for (std::size_t i = 2000; i < pt1.size(); ++i) {
      sum += pt1[i] * std::exp(std::complex<double>(0.0, -2 * M_PI * f * times[i]));
    }
    return std::abs(sum);
  };
  const double at_drive = amplitude_at(0.25);
  for (double f : {0.1, 0.15, 0.2, 0.3, 0.35, 0.5}) EXPECT_GT(at_drive, 5.0 * amplitude_at(f)) << f;
}

// The pump flow and the outlet pressure are inputs: the next sample after a command shows them
// (what a command-to-sensor latency measurement relies on), even at 1 kHz, where a sample falls
// between simulator steps computed before the command (5.3 ms apart).
TEST(RigHost, PumpAndOutletCommandsShowInTheNextSample) {
  auto created =
      RigHost::Create("rig-1", RigParams(), SimulationOptions(), 1000.0, {31.0, 5.0, 0.0});
  ASSERT_TRUE(created.ok());
  RigHost& rig = *created;
  for (int i = 0; i < 7; ++i) {
    auto settled = rig.Tick();
    ASSERT_TRUE(settled.ok());
    ASSERT_TRUE(rig.SetPumpLpm(i % 2 == 0 ? 6.0 : 5.0).ok());
    ASSERT_TRUE(rig.SetOutletBarg(0.1 * i).ok());
    auto next = rig.Tick();
    ASSERT_TRUE(next.ok());
    EXPECT_DOUBLE_EQ(units::M3psToLpm((*next)[Channel::kFT2]), i % 2 == 0 ? 6.0 : 5.0) << i;
    EXPECT_NEAR(units::PaAbsToBarg((*next)[Channel::kC1], 101325.0), 0.1 * i, 1e-12) << i;
    EXPECT_DOUBLE_EQ((*next)[Channel::kFT3], (*next)[Channel::kFT1] + (*next)[Channel::kFT2]);
  }
}

}  // namespace
}  // namespace mpdrig::service
