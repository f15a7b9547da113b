// The empirical frequency response of a log (empirical_response.h): a swept-sine log of the
// simulator at the lab's sensor noise (thesis Table 4.1.1, SensorNoise::Lab(), as `mpdrig synth`
// adds it) gives back the simulated resonance; the peak finder on a known response.
#include "model/analysis/empirical_response.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "model/analysis/resonance.h"
#include "model/sim/rig_simulator.h"
#include "model/sim/sensor_noise.h"
#include "tests/support/sweep_log.h"

namespace mpdrig {
namespace {

using testing::MakeSweepLog;
using testing::SweepSimulation;

const ChannelResponse* Find(const EmpiricalResponse& response, const std::string& channel) {
  for (const ChannelResponse& c : response.channels) {
    if (c.channel == channel) return &c;
  }
  return nullptr;
}

// The tolerance of the first resonance from a 400 s sweep log at the lab's noise, against the
// simulated response's (which runs each frequency to its steady state): 0.004 Hz, a quarter of
// the frequency step of 100 s segments; and the error within 3 reported uncertainties.
constexpr double kSweepResonanceToleranceHz = 0.004;

TEST(EmpiricalResponse, SweepLogAtLabNoiseRecoversTheSimulatedResonance) {
  RigParams params;
  ApplyEffectSpec(&params, "topside_compliance:compliance_m3_per_pa=3.2e-11");
  ResonanceOptions reference;
  reference.method = ResponseMethod::kSimulated;
  reference.simulation = SweepSimulation();
  auto simulated = FirstResonance(params, Termination::kChokeClosed, reference);
  ASSERT_TRUE(simulated.ok()) << simulated.status().message();
  for (std::uint64_t seed : {1, 2, 3}) {
    const riglog::RigLog log = MakeSweepLog(params, ChokeSetting::Closed(), seed);
    auto response = EstimateEmpiricalResponse(log);
    ASSERT_TRUE(response.ok()) << response.status().message();
    EXPECT_EQ(response->segments, 7);
    const ChannelResponse* pt1 = Find(*response, "PT1");
    ASSERT_NE(pt1, nullptr);
    ASSERT_FALSE(pt1->peaks.empty());
    const ResonancePeak& first = pt1->peaks.front();
    EXPECT_NEAR(first.freq_hz, simulated->freq_hz, kSweepResonanceToleranceHz) << "seed " << seed;
    EXPECT_LT(std::fabs(first.freq_hz - simulated->freq_hz), 3.0 * first.uncertainty_hz)
        << "seed " << seed;
    EXPECT_GT(first.coherence, 0.7);
    std::printf(
        "seed %d: PT1 first peak %.4f +- %.4f Hz (gamma^2 %.3f, half-power width %.4f Hz); "
        "simulated %.4f Hz\n",
        static_cast<int>(seed), first.freq_hz, first.uncertainty_hz, first.coherence,
        first.half_power_width_hz, simulated->freq_hz);
  }
}

TEST(EmpiricalResponse, OpenChokeSweepFindsTheQuarterWave) {
  const RigParams params;
  ResonanceOptions reference;
  reference.method = ResponseMethod::kSimulated;
  reference.simulation = SweepSimulation();
  auto simulated = FirstResonance(params, Termination::kChokeOpen, reference);
  ASSERT_TRUE(simulated.ok()) << simulated.status().message();
  const riglog::RigLog log = MakeSweepLog(params, ChokeSetting::Open(), 4);
  auto response = EstimateEmpiricalResponse(log);
  ASSERT_TRUE(response.ok()) << response.status().message();
  const ChannelResponse* pt1 = Find(*response, "PT1");
  ASSERT_NE(pt1, nullptr);
  ASSERT_FALSE(pt1->peaks.empty());
  EXPECT_NEAR(pt1->peaks.front().freq_hz, simulated->freq_hz, kSweepResonanceToleranceHz);
  std::printf("open choke: PT1 first peak %.4f +- %.4f Hz; simulated %.4f Hz\n",
              pt1->peaks.front().freq_hz, pt1->peaks.front().uncertainty_hz, simulated->freq_hz);
}

TEST(EmpiricalResponse, RefusesALogWithoutPistonOrWithUnevenSampling) {
  riglog::RigLog log;
  log.time_s = {0.0, 0.01, 0.02};
  ASSERT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kPT1), {1e5, 1e5, 1e5}).ok());
  auto refused = EstimateEmpiricalResponse(log);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("piston_position"), std::string::npos);
  riglog::RigLog uneven;
  for (int i = 0; i < 100; ++i) uneven.time_s.push_back(i * 0.01 + (i > 50 ? 0.005 : 0.0));
  ASSERT_TRUE(
      uneven.AddColumn(riglog::LabColumn(Channel::kPistonPosition), std::vector<double>(100, 0.0))
          .ok());
  ASSERT_TRUE(
      uneven.AddColumn(riglog::LabColumn(Channel::kPT1), std::vector<double>(100, 1e5)).ok());
  auto refused_uneven = EstimateEmpiricalResponse(uneven);
  ASSERT_FALSE(refused_uneven.ok());
  EXPECT_NE(refused_uneven.status().message().find("uniform"), std::string::npos);
}

TEST(ResonancePeaks, ALorentzianPeakIsFoundBetweenBins) {
  // |H| = 1 / |1 - (f/f0)^2 + i f/(Q f0)| sampled every 0.01 Hz, f0 = 0.4437 Hz, Q = 20: the
  // parabola through log |H| finds f0 within a tenth of a bin; one coherent point only.
  std::vector<EmpiricalPoint> points;
  for (int k = 1; k <= 100; ++k) {
    const double f = 0.01 * k, f0 = 0.4437, q = 20.0;
    EmpiricalPoint p;
    p.freq_hz = f;
    p.magnitude = 1.0 / std::abs(std::complex<double>(1.0 - f * f / (f0 * f0), f / (q * f0)));
    p.coherence = 0.99;
    p.input_power_fraction = 1.0;
    points.push_back(p);
  }
  EmpiricalResponseOptions options;
  const auto peaks = FindResonancePeaks(points, 7, options);
  ASSERT_EQ(peaks.size(), 1u);
  EXPECT_NEAR(peaks[0].freq_hz, 0.4437, 0.001);
  EXPECT_NEAR(peaks[0].half_power_width_hz, 0.4437 / 20.0, 0.004);  // linear between bins
  EXPECT_GT(peaks[0].uncertainty_hz, 0.01 / std::sqrt(12.0) - 1e-12);
  for (EmpiricalPoint& p : points) p.coherence = 0.4;  // below min_coherence: no peak
  EXPECT_TRUE(FindResonancePeaks(points, 7, options).empty());
}

}  // namespace
}  // namespace mpdrig
