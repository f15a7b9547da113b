// Each effect changes the response the way its physics says it must, measured on the periodic
// response to a piston sine (complex amplitude of a channel at the drive frequency, over whole
// periods after the start-up transient has decayed).
#include <cmath>
#include <complex>
#include <numbers>

#include <gtest/gtest.h>

#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "tests/model/effects/sine_response.h"
#include "tests/model/rig_test_util.h"

namespace mpdrig {
namespace {

using Complex = std::complex<double>;

using testing::SineRun;

std::array<Complex, kChannelCount> Response(const RigParams& params, const SineRun& run) {
  return testing::SineResponse(params, run);
}

RigParams With(std::string_view spec) {
  RigParams params;
  const Status status = ApplyEffectSpec(&params, spec);
  EXPECT_TRUE(status.ok()) << status.message();
  return params;
}

double PhaseDeg(Complex z) { return std::arg(z) * 180.0 / std::numbers::pi; }
double WrapDeg(double d) { return std::remainder(d, 360.0); }

TEST(UnsteadyFriction, DampingGrowsWithFrequency) {
  // Open choke: resonances at c/4L = 0.236 Hz and 3c/4L = 0.708 Hz (9.3.2). The extra damping
  // k du/dt ~ k 2 pi f u lowers the higher peak by more than the lower one.
  const RigParams base;
  const RigParams with = With("unsteady_friction:k=0.05");
  const double c4l = base.wave_speed_mps / (4.0 * base.pipe_length_m);
  double reduction[2];
  for (int mode = 0; mode < 2; ++mode) {
    SineRun run;
    run.choke_deg = 90.0;
    run.freq_hz = (2 * mode + 1) * c4l;
    run.amplitude_m = 0.002;
    const double without = std::abs(Response(base, run)[Index(Channel::kPT1)]);
    const double with_effect = std::abs(Response(with, run)[Index(Channel::kPT1)]);
    reduction[mode] = with_effect / without;
    EXPECT_LT(reduction[mode], 1.0) << "mode " << mode;
  }
  // At a resonance the peak scales as 1/damping: the ratio must fall clearly with frequency.
  EXPECT_LT(reduction[1], reduction[0] - 0.05);
}

TEST(UnsteadyFriction, LeavesSteadyStateAlone) {
  // No acceleration, no velocity gradient: after a pump step has settled, every channel is the
  // base model's (the transient differs, the end state must not).
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(31.0, t < 1.0 ? 5.0 : 8.0, 0.0); };
  const RigSample base = testing::RunSteps(RigParams(), options, drive, 150.0).Sample();
  const RigSample with =
      testing::RunSteps(With("unsteady_friction:k=0.2"), options, drive, 150.0).Sample();
  for (Channel channel : {Channel::kPT1, Channel::kPT5, Channel::kC2, Channel::kP1}) {
    EXPECT_NEAR(with[channel], base[channel], 10.0) << riglog::ChannelName(channel);  // Pa
  }
  EXPECT_NEAR(with[Channel::kFT3], base[Channel::kFT3], 1e-9);
}

TEST(HelicalFriction, DampingGrowsWithAmplitude) {
  // S ~ |u|^(1/2) u: relative to the base model, a larger heave is damped more. Open-choke
  // resonance c/4L (9.3.2), where the response is friction-limited.
  const RigParams base;
  const RigParams with = With("helical_friction:scale=2");
  double ratio[2];
  const double amplitudes[2] = {0.002, 0.05};
  for (int i = 0; i < 2; ++i) {
    SineRun run;
    run.choke_deg = 90.0;
    run.outlet_barg = 10.0;
    run.freq_hz = base.wave_speed_mps / (4.0 * base.pipe_length_m);
    run.amplitude_m = amplitudes[i];
    ratio[i] = std::abs(Response(with, run)[Index(Channel::kPT1)]) /
               std::abs(Response(base, run)[Index(Channel::kPT1)]);
  }
  EXPECT_LT(ratio[0], 1.0) << ratio[0] << " " << ratio[1];
  EXPECT_LT(ratio[1], ratio[0] - 0.05);
}

TEST(ChokeInertia, AddsPhaseLagToChokeFlowGrowingWithFrequency) {
  const RigParams base;
  const RigParams with = With("choke_inertia:b1_per_m=2e6");
  double lag_deg[2];
  const double freqs[2] = {0.05, 0.3};
  for (int i = 0; i < 2; ++i) {
    SineRun run;
    run.freq_hz = freqs[i];
    const Complex ft3_base = Response(base, run)[Index(Channel::kFT3)];
    const Complex ft3_with = Response(with, run)[Index(Channel::kFT3)];
    lag_deg[i] = -WrapDeg(PhaseDeg(ft3_with) - PhaseDeg(ft3_base));
  }
  EXPECT_GT(lag_deg[0], 0.0);
  EXPECT_GT(lag_deg[1], lag_deg[0] + 5.0) << lag_deg[0] << " " << lag_deg[1];
}

TEST(ChokeInertia, SteadyFlowObeysTheOrificeEquation) {
  // b1 dq/dt vanishes in steady flow: (5.3.3) reduces to (5.3.2). After a pump step the
  // pressure settles where the steady orifice law puts it.
  RigParams params = With("choke_inertia:b1_per_m=2e6");
  SimulationOptions options;
  options.cells = 60;
  testing::Drive drive;
  drive.rig = [](double t) { return testing::Held(31.0, t < 1.0 ? 5.0 : 8.0, 0.0); };
  RigSimulator sim = testing::RunSteps(params, options, drive, 120.0);
  const RigSample s = sim.Sample();
  const double g = ChokeCharacteristic(params).FlowCoefficientM2(31.0 / 90.0);
  const double q = s[Channel::kFT3];
  const double dp = params.choke_density_kgpm3 * q * q / (g * g);
  EXPECT_NEAR(s[Channel::kC2] - s[Channel::kC1], dp, 2e-3 * dp);
  EXPECT_NEAR(q, units::LpmToM3ps(8.0), 1e-3 * units::LpmToM3ps(8.0));
}

TEST(SensorLag, PressuresLagByTheFirstOrderPhaseAndFlowsDoNot) {
  const double tau = 0.2;
  const RigParams base;
  const RigParams with = With("sensor_lag:time_constant_s=0.2");
  SineRun run;
  run.freq_hz = 0.3;
  const auto b = Response(base, run);
  const auto w = Response(with, run);
  const double w_rad = 2.0 * std::numbers::pi * run.freq_hz;
  const double expected_lag_deg = std::atan(w_rad * tau) * 180.0 / std::numbers::pi;
  const double expected_gain = 1.0 / std::sqrt(1.0 + w_rad * w_rad * tau * tau);
  for (Channel channel : {Channel::kPT1, Channel::kPT5, Channel::kC2, Channel::kP1}) {
    SCOPED_TRACE(riglog::ChannelName(channel));
    const Complex ratio = w[Index(channel)] / b[Index(channel)];
    // The exact discretisation of a lag over a step of dt ~ 18 ms: phase within 1 deg
    // (the sample-and-hold delay dt/2 is 1 deg at 0.3 Hz), gain within 1%.
    EXPECT_NEAR(-PhaseDeg(ratio), expected_lag_deg, 1.0);
    EXPECT_NEAR(std::abs(ratio), expected_gain, 0.01);
  }
  for (Channel channel : {Channel::kFT1, Channel::kFT3, Channel::kFT4}) {
    EXPECT_NEAR(std::abs(w[Index(channel)] - b[Index(channel)]), 0.0,
                1e-9 * std::abs(b[Index(channel)]));
  }
}

}  // namespace
}  // namespace mpdrig
