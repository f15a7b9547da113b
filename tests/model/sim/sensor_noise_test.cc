#include "model/sim/sensor_noise.h"

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/sim/rig_simulator.h"
#include "tests/support/statistics.h"

namespace mpdrig {
namespace {

// Sample standard deviation of n independent normal draws: its relative spread is
// 1 / sqrt(2 (n - 1)). With n = 20000 that is 0.5 %; 4 of those (2 %) is exceeded by chance in
// one run of 16000.
constexpr int kDraws = 20000;
constexpr double kSigmaTol = 4.0 / 200.0;  // 4 / sqrt(2 * 20000)

// The first two standard normal draws of PT1's stream for seed 1 (SensorNoiseApplier).
constexpr double kFirstPt1Draw = -1.2104715101518471;
constexpr double kSecondPt1Draw = 0.42423507264248295;

using teststats::SampleStdDev;

double Mean(const std::vector<double>& x) {
  double sum = 0.0;
  for (double v : x) sum += v;
  return sum / static_cast<double>(x.size());
}

// The noise alone: readings of a constant true value minus that value.
std::vector<double> Errors(SensorNoiseApplier* applier, Channel channel, double value) {
  std::vector<double> errors;
  for (int i = 0; i < kDraws; ++i) errors.push_back(applier->Measure(channel, value) - value);
  return errors;
}

SensorNoise Parsed(const std::string& text) {
  auto noise = ParseSensorNoise(text);
  EXPECT_TRUE(noise.ok()) << text << ": " << noise.status().message();
  return noise.ok() ? *noise : SensorNoise{};
}

std::string ErrorOf(const std::string& text) {
  auto noise = ParseSensorNoise(text);
  EXPECT_FALSE(noise.ok()) << "accepted " << text;
  return noise.ok() ? std::string() : noise.status().message();
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// --- the spec --------------------------------------------------------------------------------

TEST(SensorNoiseSpec, LabIsTable411) {
  const SensorNoise lab = SensorNoise::Lab();
  EXPECT_DOUBLE_EQ(lab.pressure_pa, 0.0015 * 16.0 * 1e5);  // 0.15 % of 16 bar
  EXPECT_DOUBLE_EQ(lab.flow_fraction, 0.02);
  EXPECT_DOUBLE_EQ(lab.flow_m3ps, 0.05e-3 / 60.0);
  EXPECT_DOUBLE_EQ(lab.piston_m, 0.5e-3);
  EXPECT_DOUBLE_EQ(lab.choke_deg, 0.1);
  EXPECT_TRUE(SensorNoise::None().IsNone());
  EXPECT_FALSE(lab.IsNone());
}

TEST(SensorNoiseSpec, ParsesPresetsAndTheTextForm) {
  EXPECT_EQ(Parsed("none"), SensorNoise::None());
  EXPECT_EQ(Parsed("lab"), SensorNoise::Lab());
  EXPECT_EQ(Parsed("LAB"), SensorNoise::Lab());
  EXPECT_EQ(Parsed("pressure=0.024bar,flow=2%+0.05lpm,piston=0.5mm,choke=0.1deg"),
            SensorNoise::Lab());
  const SensorNoise custom = Parsed(" pressure = 300Pa , flow=1e-6m3ps , piston=20um ");
  EXPECT_DOUBLE_EQ(custom.pressure_pa, 300.0);
  EXPECT_DOUBLE_EQ(custom.flow_fraction, 0.0);
  EXPECT_DOUBLE_EQ(custom.flow_m3ps, 1e-6);
  EXPECT_DOUBLE_EQ(custom.piston_m, 20e-6);
  EXPECT_DOUBLE_EQ(custom.choke_deg, 0.0);  // not given, no preset: off
  EXPECT_DOUBLE_EQ(Parsed("pressure=24mbar").pressure_pa, 2400.0);
  EXPECT_DOUBLE_EQ(Parsed("pressure=2.4kPa").pressure_pa, 2400.0);
  EXPECT_DOUBLE_EQ(Parsed("flow=1e+1%").flow_fraction, 0.1);  // the exponent's '+' is no term
  EXPECT_DOUBLE_EQ(Parsed("flow=0.05lpm+2%").flow_fraction, 0.02);
}

TEST(SensorNoiseSpec, APresetFirstThenChangesAndScale) {
  const SensorNoise quiet = Parsed("lab,pressure=0,scale=0.5");
  EXPECT_EQ(quiet.pressure_pa, 0.0);
  EXPECT_DOUBLE_EQ(quiet.flow_fraction, 0.01);
  EXPECT_DOUBLE_EQ(quiet.piston_m, 0.25e-3);
  EXPECT_DOUBLE_EQ(quiet.choke_deg, 0.05);
  EXPECT_DOUBLE_EQ(Parsed("lab,scale=2").pressure_pa, 4800.0);
}

TEST(SensorNoiseSpec, ToSpecReadsBack) {
  EXPECT_EQ(SensorNoise::None().ToSpec(), "none");
  EXPECT_EQ(SensorNoise::Lab().ToSpec(), "lab");
  const SensorNoise custom = Parsed("lab,choke=0.3deg");
  EXPECT_EQ(custom.ToSpec(), "pressure=0.024bar,flow=2%+0.05lpm,piston=0.5mm,choke=0.3deg");
  const SensorNoise back = Parsed(custom.ToSpec());
  EXPECT_DOUBLE_EQ(back.pressure_pa, custom.pressure_pa);
  EXPECT_DOUBLE_EQ(back.flow_fraction, custom.flow_fraction);
  EXPECT_DOUBLE_EQ(back.flow_m3ps, custom.flow_m3ps);
  EXPECT_DOUBLE_EQ(back.piston_m, custom.piston_m);
  EXPECT_DOUBLE_EQ(back.choke_deg, custom.choke_deg);
}

TEST(SensorNoiseSpec, ErrorsNameTheTokenAndListWhatIsValid) {
  std::string error = ErrorOf("pressure=0.024bar,presure=1bar");
  EXPECT_TRUE(Contains(error, "'presure'")) << error;
  EXPECT_TRUE(Contains(error, "pressure, flow, piston, choke, scale")) << error;
  error = ErrorOf("loud");
  EXPECT_TRUE(Contains(error, "'loud'") && Contains(error, "none, lab")) << error;
  error = ErrorOf("pressure=0.024psi");
  EXPECT_TRUE(Contains(error, "'pressure=0.024psi'") && Contains(error, "bar")) << error;
  error = ErrorOf("pressure=0.024");
  EXPECT_TRUE(Contains(error, "needs a unit")) << error;
  error = ErrorOf("flow=2%+0.05gpm");
  EXPECT_TRUE(Contains(error, "'flow=2%+0.05gpm'") && Contains(error, "lpm")) << error;
  error = ErrorOf("piston=-0.5mm");
  EXPECT_TRUE(Contains(error, "'piston=-0.5mm'") && Contains(error, "negative")) << error;
  error = ErrorOf("choke=nandeg");
  EXPECT_TRUE(Contains(error, "'choke=nandeg'")) << error;
  error = ErrorOf("choke=infdeg");
  EXPECT_TRUE(Contains(error, "'choke=infdeg'")) << error;
  error = ErrorOf("pressure=abc");
  EXPECT_TRUE(Contains(error, "'pressure=abc'") && Contains(error, "not a number")) << error;
  error = ErrorOf("pressure=1bar,lab");
  EXPECT_TRUE(Contains(error, "'lab'") && Contains(error, "first")) << error;
  error = ErrorOf("pressure=1bar,pressure=2bar");
  EXPECT_TRUE(Contains(error, "twice")) << error;
  error = ErrorOf("lab,scale=2x");
  EXPECT_TRUE(Contains(error, "'scale=2x'")) << error;
  EXPECT_TRUE(Contains(ErrorOf(""), "pressure, flow")) << ErrorOf("");
  EXPECT_TRUE(Contains(ErrorOf("lab,,pressure=0"), "empty")) << ErrorOf("lab,,pressure=0");
}

TEST(SensorNoiseSpec, ValidateRefusesNanAndNegative) {
  SensorNoise noise = SensorNoise::Lab();
  EXPECT_TRUE(noise.Validate().ok());
  noise.flow_m3ps = std::nan("");
  EXPECT_TRUE(Contains(noise.Validate().message(), "flow_m3ps")) << noise.Validate().message();
  noise = SensorNoise::Lab();
  noise.pressure_pa = -1.0;
  EXPECT_TRUE(Contains(noise.Validate().message(), "pressure_pa")) << noise.Validate().message();
}

// --- the applier -----------------------------------------------------------------------------

TEST(SensorNoiseApplier, StandardDeviationsAreTheSpecs) {
  SensorNoiseApplier applier(SensorNoise::Lab(), 7);
  const double pressure = 5e5;
  for (Channel channel : {Channel::kP1, Channel::kPT5, Channel::kC2}) {
    const std::vector<double> e = Errors(&applier, channel, pressure);
    EXPECT_NEAR(SampleStdDev(e), 2400.0, kSigmaTol * 2400.0) << riglog::ChannelName(channel);
    // The mean of the errors: sigma / sqrt(n) spread; 4 of those.
    EXPECT_NEAR(Mean(e), 0.0, 4.0 * 2400.0 / std::sqrt(kDraws));
  }
  const std::vector<double> piston = Errors(&applier, Channel::kPistonPosition, 0.05);
  EXPECT_NEAR(SampleStdDev(piston), 0.5e-3, kSigmaTol * 0.5e-3);
  const std::vector<double> choke = Errors(&applier, Channel::kChokePosition, 31.0 / 90.0);
  EXPECT_NEAR(SampleStdDev(choke), 0.1 / 90.0, kSigmaTol * 0.1 / 90.0);
}

TEST(SensorNoiseApplier, FlowNoiseScalesWithTheReading) {
  SensorNoiseApplier applier(SensorNoise::Lab(), 7);
  const double absolute = units::LpmToM3ps(0.05);
  for (double lpm : {0.0, 5.0, 30.0, -20.0}) {
    const double q = units::LpmToM3ps(lpm);
    const double expected = 0.02 * std::abs(q) + absolute;
    const std::vector<double> e = Errors(&applier, Channel::kFT1, q);
    EXPECT_NEAR(SampleStdDev(e), expected, kSigmaTol * expected) << lpm << " L/min";
  }
  // 30 L/min: 0.65 L/min, 13 times the floor at zero flow.
  EXPECT_NEAR(SensorNoise::Lab().SigmaFor(Channel::kFT3, units::LpmToM3ps(30.0)),
              units::LpmToM3ps(0.65), 1e-15);
}

TEST(SensorNoiseApplier, SameSeedSameNumbersOtherSeedOthers) {
  SensorNoiseApplier a(SensorNoise::Lab(), 11), b(SensorNoise::Lab(), 11),
      c(SensorNoise::Lab(), 12);
  int differ = 0;
  for (int i = 0; i < 100; ++i) {
    const double x = a.Measure(Channel::kPT1, 4e5);
    EXPECT_EQ(x, b.Measure(Channel::kPT1, 4e5));
    differ += x != c.Measure(Channel::kPT1, 4e5);
  }
  EXPECT_EQ(differ, 100);
}

// The streams are per channel: reading another channel in between changes nothing.
TEST(SensorNoiseApplier, ChannelsAreIndependentStreams) {
  SensorNoiseApplier alone(SensorNoise::Lab(), 3), mixed(SensorNoise::Lab(), 3);
  for (int i = 0; i < 100; ++i) {
    (void)mixed.Measure(Channel::kFT4, 1e-4);
    (void)mixed.Measure(Channel::kPT9, 3e5);
    EXPECT_EQ(alone.Measure(Channel::kC2, 3e5), mixed.Measure(Channel::kC2, 3e5)) << i;
  }
  // ...and two channels of one kind do not share numbers.
  SensorNoiseApplier d(SensorNoise::Lab(), 3);
  EXPECT_NE(d.Measure(Channel::kPT1, 3e5), d.Measure(Channel::kPT2, 3e5));
}

// The Gaussian is written out, so these are the numbers on any standard library: a change of the
// generator, the seeding or the transform shows here.
TEST(SensorNoiseApplier, KnownNumbersForASeed) {
  SensorNoiseApplier applier(SensorNoise::Lab(), 1);
  const double first = applier.Measure(Channel::kPT1, 0.0) / 2400.0;
  const double second = applier.Measure(Channel::kPT1, 0.0) / 2400.0;
  EXPECT_NEAR(first, kFirstPt1Draw, 1e-12);
  EXPECT_NEAR(second, kSecondPt1Draw, 1e-12);
}

TEST(SensorNoiseApplier, NoneChangesNothingBitwise) {
  SensorNoiseApplier applier(SensorNoise::None(), 5);
  RigSample sample;
  for (std::size_t i = 0; i < kChannelCount; ++i) sample.values[i] = 0.1 * i - 0.3;
  sample.values[Index(Channel::kFT1)] = -0.0;
  sample.values[Index(Channel::kPT3)] = std::nan("");
  sample.pressure_at_positions_pa = {1e5, 2e5};
  const RigSample before = sample;
  for (int k = 0; k < 10; ++k) applier.MeasureSample(&sample);
  EXPECT_EQ(std::memcmp(before.values.data(), sample.values.data(), sizeof sample.values), 0);
  EXPECT_EQ(before.pressure_at_positions_pa, sample.pressure_at_positions_pa);
}

TEST(SensorNoiseApplier, ASampleGetsNoiseOnItsSensorsOnly) {
  SensorNoiseApplier applier(SensorNoise::Lab(), 5);
  RigSample sample;
  sample.time_s = 1.5;
  for (std::size_t i = 0; i < kChannelCount; ++i) sample.values[i] = 2e5;
  sample.values[Index(Channel::kTime)] = 1.5;
  sample.values[Index(Channel::kPT3)] = std::nan("");
  sample.pressure_at_positions_pa = {1e5, 2e5};
  const RigSample before = sample;
  applier.MeasureSample(&sample);
  EXPECT_EQ(sample[Channel::kTime], 1.5);
  EXPECT_TRUE(std::isnan(sample[Channel::kPT3]));  // not measured stays not measured
  EXPECT_EQ(sample.pressure_at_positions_pa, before.pressure_at_positions_pa);
  for (Channel channel : {Channel::kP1, Channel::kFT2, Channel::kC1, Channel::kPistonPosition,
                          Channel::kChokePosition}) {
    EXPECT_NE(sample[channel], before[channel]) << riglog::ChannelName(channel);
  }
}

}  // namespace
}  // namespace mpdrig
