// Comparison metrics (model/analysis/compare.h) on logs the model itself produced, with and
// without injected discrepancies: the metrics must point at exactly the injected sensor, lag or
// band. Logs are generated here with Simulate and RigLogWriter (no binary fixtures).
#include "model/analysis/compare.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "model/common/units.h"
#include "model/riglog/rig_log.h"
#include "model/riglog/rig_log_writer.h"
#include "model/sim/log_inputs.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;
using riglog::Channel;

constexpr double kRateHz = 100.0;
constexpr double kDurationS = 60.0;

fs::path TempDir() {
  const fs::path dir =
      fs::temp_directory_path() /
      ("mpdrig_compare_test_" +
       std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::create_directories(dir);
  return dir;
}

// The inputs of a lab run: piston `piston(t)` [m], choke 31 deg, pump 20 L/min, C1 0 barg.
riglog::RigLog InputLog(const std::function<double(double)>& piston) {
  riglog::RigLog log;
  const long count = std::lround(kDurationS * kRateHz);
  for (long i = 0; i <= count; ++i) log.time_s.push_back(i / kRateHz);
  std::vector<double> position, choke, pump, outlet;
  for (double t : log.time_s) {
    position.push_back(piston(t));
    choke.push_back(units::ChokeDegToFrac(31.0));
    pump.push_back(units::LpmToM3ps(20.0));
    outlet.push_back(log.atmospheric_pressure_pa);
  }
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kPistonPosition), position).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kChokePosition), choke).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kFT2), pump).ok());
  EXPECT_TRUE(log.AddColumn(riglog::LabColumn(Channel::kC1), outlet).ok());
  return log;
}

double Sine(double t, double amp_m, double freq_hz) {
  return amp_m * std::sin(2.0 * std::numbers::pi * freq_hz * t);
}

SimulationOptions ReplayOptionsFor() {
  SimulationOptions options;
  options.choke_input = ChokeInput::kMeasured;
  return options;
}

// The model's channels for the log's inputs at `times` (Simulate, as `mpdrig simulate --inputs`).
std::vector<RigSample> SimulateLog(const riglog::RigLog& inputs, const RigParams& params,
                                   const std::vector<double>& times) {
  auto signals = SignalsFromLog(inputs, "inputs", ReplayOptions{}.piston_smoothing_s);
  EXPECT_TRUE(signals.ok()) << signals.status().message();
  auto run = Simulate(params, ReplayOptionsFor(), *signals, times);
  EXPECT_TRUE(run.ok()) << run.status().message();
  return run.ok() ? run->samples : std::vector<RigSample>{};
}

// A "measured" log: the inputs plus every compared channel of `samples`, after `inject` may
// change a channel's SI values; written with RigLogWriter in the lab's units.
std::string WriteMeasuredLog(
    const riglog::RigLog& inputs, const std::vector<RigSample>& samples, const std::string& name,
    const std::function<void(Channel, std::vector<double>*)>& inject = {}) {
  riglog::RigLog log = inputs;
  for (Channel channel : ComparedChannels()) {
    std::vector<double> values;
    for (const RigSample& sample : samples) values.push_back(sample[channel]);
    if (inject) inject(channel, &values);
    EXPECT_TRUE(log.AddColumn(riglog::LabColumn(channel), values).ok());
  }
  const std::string path = (TempDir() / name).string();
  const Status written = riglog::WriteRigLog(log, path);
  EXPECT_TRUE(written.ok()) << written.message();
  return path;
}

Result<Comparison> Compare(const std::string& path, const RigParams& params = {}) {
  return CompareLog(path, params, SimulationOptions{});
}

const std::function<double(double)> kPistonSine = [](double t) { return Sine(t, 0.05, 0.2); };

TEST(CompareTest, ReplayGivesExactlyWhatSimulateGives) {
  const riglog::RigLog inputs = InputLog(kPistonSine);
  const std::vector<RigSample> samples = SimulateLog(inputs, RigParams{}, inputs.time_s);
  const std::string path = WriteMeasuredLog(inputs, samples, "self.csv");
  auto log = LoadMeasuredLog(path);
  ASSERT_TRUE(log.ok()) << log.status().message();
  ASSERT_EQ(log->channels.size(), ComparedChannels().size());
  auto model = ReplayModel(*log, RigParams{}, SimulationOptions{});
  ASSERT_TRUE(model.ok()) << model.status().message();
  // Same stepping and interpolation as Simulate(), so the same doubles (no tolerance). The inputs
  // went through the file in lab units (m, deg, lpm, barg); the writer's shortest round-trip
  // text gives them back exactly for m, lpm-to-SI may differ by one ulp: compare with the run
  // on the inputs read back from the file.
  auto read_back = riglog::ReadRigLog(path);
  ASSERT_TRUE(read_back.ok());
  const std::vector<RigSample> expected = SimulateLog(*read_back, RigParams{}, read_back->time_s);
  for (std::size_t c = 0; c < log->channels.size(); ++c) {
    for (std::size_t i = 0; i < expected.size(); i += 97) {
      ASSERT_EQ(model->values_si[c][i], expected[i][log->channels[c].channel])
          << riglog::ChannelName(log->channels[c].channel) << " sample " << i;
    }
  }
}

TEST(CompareTest, SelfComparisonFitsHundredPercent) {
  const riglog::RigLog inputs = InputLog(kPistonSine);
  const std::string path =
      WriteMeasuredLog(inputs, SimulateLog(inputs, RigParams{}, inputs.time_s), "self.csv");
  auto comparison = Compare(path);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  ASSERT_EQ(comparison->channels.size(), ComparedChannels().size());
  // The only difference is the rig log's text round trip of the measured values (shortest
  // round-trip digits in barg/lpm) and of the inputs: relative 1e-16 of ~5e5 Pa, i.e. 1e-10 Pa,
  // against variations of 1e3..1e5 Pa. 1e-6 of NRMSE leaves four orders of margin.
  for (const ChannelMetrics& channel : comparison->channels) {
    SCOPED_TRACE(std::string(riglog::ChannelName(channel.channel)));
    EXPECT_NEAR(channel.fit_percent, 100.0, 1e-4);
    EXPECT_LT(channel.nrmse, 1e-6);
    EXPECT_LT(channel.rms_si, 1e-6 * channel.measured_std_si);
    EXPECT_NEAR(channel.lag_s, 0.0, 1e-3 * comparison->sample_interval_s);
    EXPECT_TRUE(channel.residual.white);
    for (const BandMetrics& band : channel.bands) {
      EXPECT_NEAR(band.magnitude_ratio, 1.0, 1e-6);
      EXPECT_NEAR(band.phase_diff_deg, 0.0, 1e-4);
    }
  }
  EXPECT_LT(comparison->error, 1e-6);
  // The piston's dominant frequency is the sine's (bin 1/60 Hz wide; the parabola does better).
  ASSERT_FALSE(comparison->dominant_freqs_hz.empty());
  EXPECT_NEAR(comparison->dominant_freqs_hz.front(), 0.2, 0.2 / kDurationS);
  // Empirical transfer functions piston -> PT1 and -> C2 agree to round-off.
  ASSERT_EQ(comparison->transfer_functions.size(), 2u);
  for (const TransferFunction& tf : comparison->transfer_functions) {
    ASSERT_FALSE(tf.points.empty());
    for (const TransferPoint& point : tf.points) {
      EXPECT_LT(std::abs(point.model - point.measured), 1e-6 * std::abs(point.measured));
    }
  }
}

TEST(CompareTest, BiasOnOneSensorShowsOnThatSensorOnly) {
  const riglog::RigLog inputs = InputLog(kPistonSine);
  constexpr double kOffsetPa = 0.05e5;  // PT4 reads 0.05 bar high
  const std::string path =
      WriteMeasuredLog(inputs, SimulateLog(inputs, RigParams{}, inputs.time_s), "bias.csv",
                       [](Channel channel, std::vector<double>* values) {
                         if (channel == Channel::kPT4)
                           for (double& v : *values) v += kOffsetPa;
                       });
  auto comparison = Compare(path);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  const ChannelMetrics* pt4 = comparison->Find(Channel::kPT4);
  ASSERT_NE(pt4, nullptr);
  // bias = mean(model - measured): the model reads low by the offset. Round-off as above.
  EXPECT_NEAR(pt4->bias_si, -kOffsetPa, 1e-6 * kOffsetPa);
  EXPECT_NEAR(pt4->rms_si, kOffsetPa, 1e-6 * kOffsetPa);
  // A constant offset has no dynamics: lag, bands and the residual's shape are untouched.
  EXPECT_NEAR(pt4->lag_s, 0.0, 1e-3 * comparison->sample_interval_s);
  for (const BandMetrics& band : pt4->bands) EXPECT_NEAR(band.magnitude_ratio, 1.0, 1e-6);
  // Along the pipe the error stands out at PT4's place, x = 300 m.
  ASSERT_EQ(comparison->profile.size(), 10u);
  const auto worst_point = std::max_element(
      comparison->profile.begin(), comparison->profile.end(),
      [](const ProfilePoint& a, const ProfilePoint& b) { return a.rms_si < b.rms_si; });
  EXPECT_EQ(worst_point->channel, Channel::kPT4);
  EXPECT_EQ(worst_point->x_m, 300.0);
  for (const ChannelMetrics& channel : comparison->channels) {
    if (channel.channel == Channel::kPT4) continue;
    SCOPED_TRACE(std::string(riglog::ChannelName(channel.channel)));
    EXPECT_LT(std::abs(channel.bias_si), 1e-6 * kOffsetPa);
    EXPECT_LT(channel.nrmse, pt4->nrmse * 1e-3);
  }
}

TEST(CompareTest, SensorDelayShowsAsLagOnThatSensor) {
  const riglog::RigLog inputs = InputLog(kPistonSine);
  // PT6 reads the pressure 0.153 s late (15.3 samples: the parabola must find the fraction).
  constexpr double kDelayS = 0.153;
  // The same run 0.153 s later: the inputs' time stamps moved by the delay (held before), the
  // outputs taken at the log's times, so the result is the first run at t - delay.
  riglog::RigLog late_inputs = inputs;
  for (double& t : late_inputs.time_s) t += kDelayS;
  const std::vector<RigSample> delayed = SimulateLog(late_inputs, RigParams{}, inputs.time_s);
  const std::string path =
      WriteMeasuredLog(inputs, SimulateLog(inputs, RigParams{}, inputs.time_s), "lag.csv",
                       [&](Channel channel, std::vector<double>* values) {
                         if (channel != Channel::kPT6) return;
                         for (std::size_t i = 0; i < values->size(); ++i)
                           (*values)[i] = delayed[i][Channel::kPT6];
                       });
  auto comparison = Compare(path);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  const ChannelMetrics* pt6 = comparison->Find(Channel::kPT6);
  ASSERT_NE(pt6, nullptr);
  // The measurement is late, so the model leads: lag_s = -delay. A parabola through the peak of
  // the correlation of a 0.2 Hz sine sampled at 100 Hz is off by far less than a tenth of a
  // sample (1 ms); the delayed run's solver grid is offset by a fraction of its 5 ms step, which
  // its linear interpolation to the output times turns into much less than that.
  EXPECT_NEAR(pt6->lag_s, -kDelayS, 1e-3);
  // In the fundamental band the phase says the same: model minus measured is
  // +360 f delay = +11 deg (the model is ahead).
  ASSERT_FALSE(pt6->bands.empty());
  EXPECT_EQ(pt6->bands.front().harmonic, 1);
  EXPECT_NEAR(pt6->bands.front().phase_diff_deg, 360.0 * 0.2 * kDelayS, 0.5);
  for (const ChannelMetrics& channel : comparison->channels) {
    if (channel.channel == Channel::kPT6) continue;
    SCOPED_TRACE(std::string(riglog::ChannelName(channel.channel)));
    EXPECT_NEAR(channel.lag_s, 0.0, 1e-3 * comparison->sample_interval_s);
  }
}

TEST(CompareTest, WrongWaveSpeedShowsInTheBandNearResonance) {
  // Two piston tones: 0.05 Hz (quasi-static, far below the first resonance c/4L = 0.24 Hz) and
  // 0.5 Hz (near the closed-end resonance c/2L = 0.47 Hz). The "rig" has c = 1000 m/s, the model
  // the tuned 850 m/s: the resonances move, so the error belongs to the 0.5 Hz band.
  const riglog::RigLog inputs =
      InputLog([](double t) { return Sine(t, 0.05, 0.05) + Sine(t, 0.01, 0.5); });
  RigParams rig;
  rig.wave_speed_mps = 1000.0;
  const std::string path =
      WriteMeasuredLog(inputs, SimulateLog(inputs, rig, inputs.time_s), "wave_speed.csv");
  auto comparison = Compare(path);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  const ChannelMetrics* pt1 = comparison->Find(Channel::kPT1);
  ASSERT_NE(pt1, nullptr);
  const auto worst = std::max_element(
      pt1->bands.begin(), pt1->bands.end(),
      [](const BandMetrics& a, const BandMetrics& b) { return a.band_nrmse < b.band_nrmse; });
  ASSERT_NE(worst, pt1->bands.end());
  EXPECT_NEAR(worst->freq_hz, 0.5, 0.5 / kDurationS);
  const auto low = std::find_if(pt1->bands.begin(), pt1->bands.end(),
                                [](const BandMetrics& b) { return b.harmonic == 1; });
  ASSERT_NE(low, pt1->bands.end());
  EXPECT_NEAR(low->freq_hz, 0.05, 0.05 / 10);
  EXPECT_LT(low->band_nrmse, 0.5 * worst->band_nrmse);
  // The error amplitude (what the report's summary ranks by) points there too: the model at
  // 850 m/s resonates near 0.47 Hz, the rig at 1000 m/s near 0.56 Hz, so the 0.5 Hz response
  // differs by tens of kPa while the quasi-static 0.05 Hz one differs by a few kPa.
  const auto worst_amplitude = std::max_element(pt1->bands.begin(), pt1->bands.end(),
                                                [](const BandMetrics& a, const BandMetrics& b) {
                                                  return a.error_amplitude < b.error_amplitude;
                                                });
  EXPECT_EQ(worst_amplitude, worst);
  EXPECT_GT(worst->error_amplitude, 3.0 * low->error_amplitude);
  // The residual still holds what the piston explains.
  EXPECT_FALSE(pt1->residual.independent_of_inputs);
}

// CompareTraces on synthetic traces (no file, no simulation: how issue 4 calls it), against
// closed forms. y = A sin(w t) over 12 whole periods; yhat = g A sin(w t + phi).
TEST(CompareTest, SyntheticTracesMatchClosedForms) {
  constexpr double kFreqHz = 0.2, kAmplitudePa = 2.0e4, kGain = 0.8, kPhaseRad = 0.3;
  constexpr int kSamples = 6000;  // 60 s at 100 Hz: 12 periods, 0.2 Hz exactly on DFT bin 12
  const double w = 2.0 * std::numbers::pi * kFreqHz;
  MeasuredLog log;
  log.path = "synthetic";
  MeasuredChannel pt1{Channel::kPT1, riglog::Unit::kBarg, {}};
  ModelTraces model;
  model.values_si.resize(1);
  std::mt19937 random(12345);
  std::normal_distribution<double> noise(0.0, 100.0);
  MeasuredChannel pt2{Channel::kPT2, riglog::Unit::kBarg, {}};
  model.values_si.resize(2);
  for (int i = 0; i < kSamples; ++i) {
    const double t = i / kRateHz;
    log.inputs.time_s.push_back(t);
    log.inputs.piston_position_m.push_back(0.05 * std::sin(w * t));
    log.inputs.choke_opening_frac.push_back(0.3);
    log.inputs.pump_flow_m3ps.push_back(0.0);
    log.inputs.outlet_pressure_pa.push_back(units::kStandardAtmospherePa);
    pt1.values_si.push_back(3.0e5 + kAmplitudePa * std::sin(w * t));
    model.values_si[0].push_back(3.0e5 + kGain * kAmplitudePa * std::sin(w * t + kPhaseRad));
    // PT2: the model plus white noise, so the residual is white and independent of the inputs.
    model.values_si[1].push_back(3.0e5 + kAmplitudePa * std::sin(w * t));
    pt2.values_si.push_back(model.values_si[1].back() + noise(random));
  }
  log.channels = {pt1, pt2};
  auto comparison = CompareTraces(log, model);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  const ChannelMetrics& sine = comparison->channels[0];
  // Over whole periods: ||yhat - y|| / ||y - mean y|| = |g e^{i phi} - 1|; the sampled sums
  // equal the integrals to round-off for whole periods, so 1e-9 relative.
  const double nrmse = std::abs(std::polar(kGain, kPhaseRad) - 1.0);
  EXPECT_NEAR(sine.nrmse, nrmse, 1e-9 * nrmse);
  EXPECT_NEAR(sine.fit_percent, 100.0 * (1.0 - nrmse), 1e-7);
  EXPECT_NEAR(sine.rms_si, kAmplitudePa * nrmse / std::sqrt(2.0), 1e-9 * kAmplitudePa);
  EXPECT_NEAR(sine.bias_si, 0.0, 1e-9 * kAmplitudePa);
  // yhat(t) = g y(t + phi/w): the model leads by phi/w = 0.239 s. The windowed correlation
  // (compare.h) of two sines peaks there up to an edge term of order (T/D)^3 = 1e-4 samples; the
  // parabola through three samples of a cosine at 0.0126 rad per sample adds ~1e-5 samples. 0.1 ms
  // is a hundredth of a sample. (The plain unbiased correlation is off by a whole sample here.)
  EXPECT_NEAR(sine.lag_s, -kPhaseRad / w, 1e-4);
  ASSERT_FALSE(sine.bands.empty());
  const BandMetrics& band = sine.bands.front();
  EXPECT_EQ(band.harmonic, 1);
  EXPECT_NEAR(band.freq_hz, kFreqHz, 1e-6);  // on a bin: the parabola through a symmetric peak
  // The same window and frequency in both spectra: ratio and phase are exact up to the few
  // 1e-4 of Hann side-lobe power outside +-3 bins that the -f image adds.
  EXPECT_NEAR(band.magnitude_ratio, kGain, 1e-4);
  EXPECT_NEAR(band.phase_diff_deg, kPhaseRad * 180.0 / std::numbers::pi, 0.01);
  EXPECT_NEAR(band.measured_amplitude, kAmplitudePa, 2e-3 * kAmplitudePa);
  EXPECT_NEAR(band.model_amplitude, kGain * kAmplitudePa, 2e-3 * kAmplitudePa);
  // A sinusoidal residual is neither white nor independent of the sinusoidal piston.
  EXPECT_FALSE(sine.residual.white);
  EXPECT_FALSE(sine.residual.independent_of_inputs);
  // Constant choke: no correlation is defined, so it cannot make the residual "dependent".
  ASSERT_EQ(sine.residual.cross.size(), 3u);
  EXPECT_TRUE(sine.residual.cross[2].constant_input);

  // White noise: each r(k) ~ N(0, 1/N); |r| > 2 x the 99% band (5.2 sigma) has probability
  // ~2e-7 per lag, so this bound cannot flake whatever the seed.
  const ChannelMetrics& noisy = comparison->channels[1];
  EXPECT_LT(noisy.residual.max_abs_autocorrelation, 2.0 * noisy.residual.confidence);
  for (const Correlation& cross : noisy.residual.cross) {
    if (!cross.constant_input) {
      EXPECT_LT(cross.max_abs, 2.0 * noisy.residual.confidence);
    }
  }
  EXPECT_NEAR(noisy.residual.confidence, 2.58 / std::sqrt(kSamples), 1e-12);
  // The envelope holds the exact extremes: column c of 1200 covers 5 samples.
  const TraceEnvelope& env = sine.envelope;
  ASSERT_EQ(env.measured_max.size(), 1200u);
  EXPECT_NEAR(*std::max_element(env.measured_max.begin(), env.measured_max.end()),
              *std::max_element(pt1.values_si.begin(), pt1.values_si.end()), 0.0);
  EXPECT_NEAR(env.measured_min[0],
              std::min({pt1.values_si[0], pt1.values_si[1], pt1.values_si[2], pt1.values_si[3],
                        pt1.values_si[4]}),
              0.0);
}

TEST(CompareTest, LogWithoutChokeIsRefusedWithFileAndLine) {
  const std::string path = (TempDir() / "no_choke.csv").string();
  std::ofstream(path) << "# rig-log: 1\ntime_s,piston_position_m,PT1_barg\n0,0,1\n0.01,0,1\n";
  auto comparison = Compare(path);
  ASSERT_FALSE(comparison.ok());
  EXPECT_NE(comparison.status().message().find(path + ":2:1:"), std::string::npos)
      << comparison.status().message();
  EXPECT_NE(comparison.status().message().find("choke_position"), std::string::npos);
}

TEST(CompareTest, NonIncreasingTimeAndUnknownUnitAreRefusedWithPosition) {
  const std::string time_path = (TempDir() / "time.csv").string();
  std::ofstream(time_path) << "time_s,piston_position_m,choke_position_deg,PT1_barg\n"
                              "0,0,31,1\n0.01,0,31,1\n0.01,0,31,1\n";
  auto time = Compare(time_path);
  ASSERT_FALSE(time.ok());
  EXPECT_NE(time.status().message().find(time_path + ":4:1:"), std::string::npos)
      << time.status().message();
  const std::string unit_path = (TempDir() / "unit.csv").string();
  std::ofstream(unit_path) << "time_s,piston_position_m,choke_position_deg,PT1_psi\n0,0,31,1\n";
  auto unit = Compare(unit_path);
  ASSERT_FALSE(unit.ok());
  EXPECT_NE(unit.status().message().find(unit_path + ":1:"), std::string::npos)
      << unit.status().message();
  EXPECT_NE(unit.status().message().find("psi"), std::string::npos);
}

TEST(CompareTest, UnmeasuredInputSampleIsRefusedWithLine) {
  const std::string path = (TempDir() / "gap.csv").string();
  std::ofstream(path) << "time_s,piston_position_m,choke_position_deg,PT1_barg\n"
                         "0,0,31,1\n0.01,,31,1\n0.02,0,31,1\n0.03,0,31,1\n";
  auto comparison = Compare(path);
  ASSERT_FALSE(comparison.ok());
  EXPECT_NE(comparison.status().message().find(path + ":3:"), std::string::npos)
      << comparison.status().message();
}

}  // namespace
}  // namespace mpdrig
