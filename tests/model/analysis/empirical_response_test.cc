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

namespace mpdrig {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A logarithmic sweep from f0 to f1 over `period_s`, repeated: the phase of one sweep is
// 2 pi f0 T / ln(f1/f0) (e^{t ln(f1/f0) / T} - 1).
double Sweep(double t, double amplitude_m, double f0, double f1, double period_s) {
  const double tau = std::fmod(t, period_s);
  const double rate = std::log(f1 / f0) / period_s;
  const double phase = kTwoPi * f0 * (std::exp(rate * tau) - 1.0) / rate;
  // Tapered over the first and last 2 s of each sweep, so the joins are smooth.
  const double taper = std::min({1.0, tau / 2.0, (period_s - tau) / 2.0});
  return amplitude_m * taper * std::sin(phase);
}

struct SweepLog {
  riglog::RigLog log;
  double simulated_resonance_hz = 0.0;
};

const SimulationOptions& SweepSimulation() {
  static const SimulationOptions options = [] {
    SimulationOptions o;
    o.cells = 60;
    o.model = PipeModel::kQuasiLinear;
    return o;
  }();
  return options;
}

// 400 s of sweeps 0.1 -> 1 Hz (100 s each), 5 mm, at 100 Hz, choke shut, pump off, 4 barg at the
// outlet; the lab's noise on every channel (seed `seed`).
riglog::RigLog MakeSweepLog(const RigParams& params, const ChokeSetting& choke,
                            std::uint64_t seed) {
  const double rate_hz = 100.0, duration_s = 400.0;
  std::vector<double> times;
  for (int i = 0; i <= static_cast<int>(duration_s * rate_hz); ++i) times.push_back(i / rate_hz);
  InputSignals inputs;
  inputs.piston_position_m = [](double t) { return Sweep(t, 0.005, 0.1, 1.0, 100.0); };
  RigInputs held;
  held.choke_opening_frac = choke.opening_frac;
  held.pump_flow_m3ps = 0.0;
  held.outlet_pressure_pa = 5.0e5;
  inputs.rig = [held](double) { return held; };
  SimulationOptions options = SweepSimulation();
  options.choke_input = ChokeInput::kMeasured;
  RigParams rig = params;
  if (choke.kind == ChokeSetting::Kind::kClosed) {
    rig.choke_leak_m2 = 0.0;
    rig.choke_characteristic = {{0.0, 0.0}, {1.0, 0.0}};
  }
  auto run = Simulate(rig, options, inputs, times);
  EXPECT_TRUE(run.ok()) << run.status().message();
  riglog::RigLog log;
  log.time_s = times;
  if (!run.ok()) return log;
  SensorNoiseApplier noise(SensorNoise::Lab(), seed);
  for (Channel channel :
       {Channel::kPistonPosition, Channel::kP2, Channel::kPT1, Channel::kPT5, Channel::kC2}) {
    std::vector<double> values;
    for (RigSample sample : run->samples) values.push_back(sample[channel]);
    noise.MeasureColumn(channel, values);
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(channel), values).ok());
  }
  return log;
}

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
