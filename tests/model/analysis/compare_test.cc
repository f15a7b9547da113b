// Comparison metrics (model/analysis/compare.h) on logs the model itself produced, with and
// without injected discrepancies: the metrics must point at exactly the injected sensor, lag or
// band. Logs are generated here with Simulate and RigLogWriter (no binary fixtures).
#include "model/analysis/compare.h"
#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

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
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDurationS = 60.0;

fs::path TempDir() {
  const fs::path dir =
      fs::temp_directory_path() /
      ("mpdrig_compare_test_" +
       std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::create_directories(dir);
  return dir;
}

// The inputs of a lab run: piston `piston(t)` [m], choke 31 deg, pump 20 L/min (or
// pump_lpm(row)), C1 0 barg.
riglog::RigLog InputLog(const std::function<double(double)>& piston,
                        const std::function<double(std::size_t)>& pump_lpm = {}) {
  riglog::RigLog log;
  const long count = std::lround(kDurationS * kRateHz);
  for (long i = 0; i <= count; ++i) log.time_s.push_back(i / kRateHz);
  std::vector<double> position, choke, pump, outlet;
  for (double t : log.time_s) {
    position.push_back(piston(t));
    choke.push_back(units::ChokeDegToFrac(31.0));
    pump.push_back(units::LpmToM3ps(pump_lpm ? pump_lpm(pump.size()) : 20.0));
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
  auto signals = SignalsFromLog(inputs, "inputs", ReplayOptions{});
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

// A replay starts from the steady state of its inputs' mean over the first
// kInitialInputWindowS, so one noisy first sample moves the initial state by its share of the
// window only. Measured against a log whose pump flow is higher on every row: the initial C2 of
// the log with only its first row that high moves by 1/N of that (N rows in the window; the
// choke pressure is smooth in q, so linear to well under 10% for 2.5% of the flow), in both
// replays (compare's pipeline and Simulate on SignalsFromLog).
TEST(CompareTest, ReplayStartsFromTheMeanOfTheFirstInputs) {
  const riglog::RigLog clean = InputLog(kPistonSine);
  auto with_pump = [&](std::size_t rows, double lpm) {
    return InputLog(kPistonSine, [=](std::size_t row) { return row < rows ? lpm : 20.0; });
  };
  std::size_t window_rows = 0;
  while (clean.time_s[window_rows] <= clean.time_s[0] + kInitialInputWindowS) ++window_rows;
  ASSERT_GT(window_rows, 10u);
  const double spike_lpm = 20.5;
  auto initial_c2 = [&](const riglog::RigLog& inputs, bool pipeline) {
    if (!pipeline) return SimulateLog(inputs, RigParams{}, {0.0, 0.01}).front()[Channel::kC2];
    const std::vector<RigSample> samples = SimulateLog(clean, RigParams{}, clean.time_s);
    const std::string path = WriteMeasuredLog(inputs, samples, "first.csv");
    auto log = LoadMeasuredLog(path);
    EXPECT_TRUE(log.ok()) << log.status().message();
    auto model = ReplayModel(*log, RigParams{}, SimulationOptions{});
    EXPECT_TRUE(model.ok()) << model.status().message();
    for (std::size_t c = 0; c < log->channels.size(); ++c) {
      if (log->channels[c].channel == Channel::kC2) return model->values_si[c][0];
    }
    ADD_FAILURE() << "no C2";
    return 0.0;
  };
  for (bool pipeline : {true, false}) {
    SCOPED_TRACE(pipeline ? "compare's pipeline" : "Simulate on SignalsFromLog");
    const double base = initial_c2(with_pump(0, 20.0), pipeline);
    const double all = initial_c2(with_pump(clean.num_rows(), spike_lpm), pipeline) - base;
    const double first = initial_c2(with_pump(1, spike_lpm), pipeline) - base;
    ASSERT_GT(all, 1000.0);  // Pa: the higher flow's choke pressure
    EXPECT_NEAR(first * static_cast<double>(window_rows) / all, 1.0, 0.1)
        << "first row only: " << first << " Pa, every row: " << all << " Pa, " << window_rows
        << " rows in the window";
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

constexpr double kFreqHz = 0.2, kAmplitudePa = 2.0e4, kGain = 0.8, kPhaseRad = 0.3;
constexpr int kSynthSamples = 6000;  // 60 s at 100 Hz: 12 periods, 0.2 Hz exactly on DFT bin 12

// y = A sin(w t) over 12 whole periods (PT1) against yhat = g A sin(w t + phi); PT2 the model
// plus white noise.
struct Synthetic {
  MeasuredLog log;
  ModelTraces model;
};

Synthetic SyntheticSine() {
  const double w = 2.0 * std::numbers::pi * kFreqHz;
  Synthetic synthetic;
  MeasuredLog& log = synthetic.log;
  ModelTraces& model = synthetic.model;
  log.path = "synthetic";
  MeasuredChannel pt1{Channel::kPT1, riglog::Unit::kBarg, {}};
  std::mt19937 random(12345);
  std::normal_distribution<double> noise(0.0, 100.0);
  MeasuredChannel pt2{Channel::kPT2, riglog::Unit::kBarg, {}};
  model.values_si.resize(2);
  for (int i = 0; i < kSynthSamples; ++i) {
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
  return synthetic;
}

// CompareTraces on synthetic traces (no file, no simulation: how fit and diagnose call it), against
// closed forms.
TEST(CompareTest, SyntheticTracesMatchClosedForms) {
  const double w = 2.0 * std::numbers::pi * kFreqHz;
  constexpr int kSamples = kSynthSamples;
  const Synthetic synthetic = SyntheticSine();
  const MeasuredLog& log = synthetic.log;
  const ModelTraces& model = synthetic.model;
  const MeasuredChannel& pt1 = log.channels[0];
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

// ---- The streaming path (two passes over the file) and the in-memory path agree -------------

// NaN-aware exact equality: both paths feed the same accumulators the same doubles in the same
// order, so there is no tolerance.
void ExpectSameNumber(double a, double b, const std::string& what) {
  if (std::isnan(a) && std::isnan(b)) return;
  EXPECT_EQ(a, b) << what;
}

void ExpectSameNumbers(const std::vector<double>& a, const std::vector<double>& b,
                       const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) ExpectSameNumber(a[i], b[i], what);
}

void ExpectSameComparison(const Comparison& a, const Comparison& b) {
  EXPECT_EQ(a.samples, b.samples);
  ExpectSameNumber(a.duration_s, b.duration_s, "duration_s");
  ExpectSameNumber(a.sample_interval_s, b.sample_interval_s, "sample_interval_s");
  EXPECT_EQ(a.uniform_sampling, b.uniform_sampling);
  ExpectSameNumber(a.error, b.error, "error");
  ExpectSameNumbers(a.dominant_freqs_hz, b.dominant_freqs_hz, "dominant_freqs_hz");
  ExpectSameNumber(a.max_lag_s, b.max_lag_s, "max_lag_s");
  EXPECT_EQ(a.spectrum_segments, b.spectrum_segments);
  EXPECT_EQ(a.atmospheric_pressure_pa, b.atmospheric_pressure_pa);
  EXPECT_EQ(a.first_range_event.has_value(), b.first_range_event.has_value());
  ASSERT_EQ(a.channels.size(), b.channels.size());
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const ChannelMetrics& x = a.channels[c];
    const ChannelMetrics& y = b.channels[c];
    const std::string name(riglog::ChannelName(x.channel));
    SCOPED_TRACE(name);
    EXPECT_EQ(x.channel, y.channel);
    EXPECT_EQ(x.samples, y.samples);
    for (const auto& [p, q, what] :
         {std::tuple{x.nrmse, y.nrmse, "nrmse"}, std::tuple{x.rms_si, y.rms_si, "rms"},
          std::tuple{x.bias_si, y.bias_si, "bias"}, std::tuple{x.lag_s, y.lag_s, "lag"},
          std::tuple{x.lag_correlation, y.lag_correlation, "lag_correlation"},
          std::tuple{x.measured_mean_si, y.measured_mean_si, "mean"},
          std::tuple{x.measured_std_si, y.measured_std_si, "std"}}) {
      ExpectSameNumber(p, q, what);
    }
    ASSERT_EQ(x.bands.size(), y.bands.size());
    for (std::size_t i = 0; i < x.bands.size(); ++i) {
      ExpectSameNumber(x.bands[i].magnitude_ratio, y.bands[i].magnitude_ratio, "ratio");
      ExpectSameNumber(x.bands[i].phase_diff_deg, y.bands[i].phase_diff_deg, "phase");
      ExpectSameNumber(x.bands[i].band_nrmse, y.bands[i].band_nrmse, "band_nrmse");
      ExpectSameNumber(x.bands[i].measured_amplitude, y.bands[i].measured_amplitude, "amp");
    }
    ExpectSameNumbers(x.residual.autocorrelation, y.residual.autocorrelation, "autocorrelation");
    ASSERT_EQ(x.residual.cross.size(), y.residual.cross.size());
    for (std::size_t i = 0; i < x.residual.cross.size(); ++i) {
      ExpectSameNumbers(x.residual.cross[i].r, y.residual.cross[i].r, "cross");
    }
    ExpectSameNumbers(x.envelope.measured_min, y.envelope.measured_min, "envelope");
    ExpectSameNumbers(x.envelope.model_max, y.envelope.model_max, "envelope");
    ExpectSameNumbers(x.envelope.residual_max, y.envelope.residual_max, "envelope");
    ExpectSameNumbers(x.zoom.time_s, y.zoom.time_s, "zoom");
    ExpectSameNumbers(x.zoom.measured, y.zoom.measured, "zoom");
    ExpectSameNumbers(x.zoom.model, y.zoom.model, "zoom");
  }
  ASSERT_EQ(a.transfer_functions.size(), b.transfer_functions.size());
  for (std::size_t i = 0; i < a.transfer_functions.size(); ++i) {
    const auto& p = a.transfer_functions[i].points;
    const auto& q = b.transfer_functions[i].points;
    ASSERT_EQ(p.size(), q.size());
    for (std::size_t k = 0; k < p.size(); ++k) {
      EXPECT_EQ(p[k].freq_hz, q[k].freq_hz);
      EXPECT_EQ(p[k].measured, q[k].measured);
      EXPECT_EQ(p[k].model, q[k].model);
    }
  }
}

TEST(CompareTest, StreamingAndInMemoryPathsAgreeExactly) {
  // A rig with c = 1000 m/s against the default model, PT3 with gaps (single samples and a 5 s
  // stretch), PT4 with an offset: every metric has something to measure. FT2 is noisy (2 % of
  // 20 L/min, uniform from a fixed hash), so its reconstruction and level estimate run too.
  const riglog::RigLog inputs =
      InputLog([](double t) { return Sine(t, 0.05, 0.2) + Sine(t, 0.01, 0.5); },
               [](std::size_t i) {
                 const std::uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull;
                 const double u = static_cast<double>((h ^ (h >> 29)) % 1000003) / 1000003.0;
                 return 20.0 + 0.4 * std::sqrt(3.0) * (2.0 * u - 1.0);
               });
  RigParams rig;
  rig.wave_speed_mps = 1000.0;
  const std::string path =
      WriteMeasuredLog(inputs, SimulateLog(inputs, rig, inputs.time_s), "stream.csv",
                       [](Channel channel, std::vector<double>* values) {
                         if (channel == Channel::kPT3) {
                           for (std::size_t i = 0; i < values->size(); i += 7) (*values)[i] = kNaN;
                           for (std::size_t i = 2000; i < 2500; ++i) (*values)[i] = kNaN;
                         }
                         if (channel == Channel::kPT4)
                           for (double& v : *values) v += 0.05e5;
                       });
  CompareOptions whole_log;  // 6001 samples: one segment
  CompareOptions welch;      // 11 half-overlapping segments of 1000 samples
  welch.welch_segment_samples = 1000;
  welch.max_zoom_samples = 300;
  for (const CompareOptions& options : {whole_log, welch}) {
    SCOPED_TRACE(options.welch_segment_samples);
    auto streamed = CompareLog(path, RigParams{}, SimulationOptions{}, options);
    ASSERT_TRUE(streamed.ok()) << streamed.status().message();
    auto log = LoadMeasuredLog(path);
    ASSERT_TRUE(log.ok()) << log.status().message();
    ReplayOptions replay;
    replay.piston_smoothing_s = options.piston_smoothing_s;
    const Status prepared = PrepareLogReplay(&*log, RigParams{}, SimulationOptions{}, &replay);
    ASSERT_TRUE(prepared.ok()) << prepared.message();
    ASSERT_TRUE(streamed->input_reconstruction.has_value());
    EXPECT_TRUE(streamed->input_reconstruction->levels.applied());
    auto model = ReplayModel(*log, RigParams{}, SimulationOptions{}, replay);
    ASSERT_TRUE(model.ok()) << model.status().message();
    auto in_memory = CompareTraces(*log, *model, options);
    ASSERT_TRUE(in_memory.ok()) << in_memory.status().message();
    ExpectSameComparison(*streamed, *in_memory);
    // 6001 samples: segments start at 0, 500, .., 5000, and one more ends at the last sample.
    EXPECT_EQ(streamed->spectrum_segments, options.welch_segment_samples == 1000 ? 12 : 1);
    const ChannelMetrics* pt3 = streamed->Find(Channel::kPT3);
    ASSERT_NE(pt3, nullptr);
    EXPECT_EQ(pt3->samples, 6001 - 858 - 428);  // every 7th, and 428 more in [2000, 2500)
  }
}

// The residual's correlations against their definition (compare.h), summed directly: with and
// without gaps, with a residual mean far larger than its variation (the running sums are taken
// about the first residual, then corrected for the mean).
TEST(CompareTest, ResidualCorrelationsAreTheDirectSums) {
  constexpr int kSamples = 3000;
  constexpr int kLags = 25;
  MeasuredLog log;
  log.path = "residual";
  ModelTraces model;
  model.values_si.resize(2);
  MeasuredChannel gappy{Channel::kPT1, riglog::Unit::kBarg, {}};
  MeasuredChannel full{Channel::kPT2, riglog::Unit::kBarg, {}};
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 50.0);
  double ar = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double t = i / kRateHz;
    log.inputs.time_s.push_back(t);
    log.inputs.piston_position_m.push_back(0.05 * std::sin(2.0 * std::numbers::pi * 0.3 * t));
    log.inputs.choke_opening_frac.push_back(0.3 + 0.01 * std::sin(0.7 * t));
    log.inputs.pump_flow_m3ps.push_back(0.0);
    log.inputs.outlet_pressure_pa.push_back(units::kStandardAtmospherePa);
    ar = 0.8 * ar + noise(random);  // coloured residual
    const double y = 3.0e5 + 1.0e4 * std::sin(2.0 * std::numbers::pi * 0.3 * t);
    model.values_si[0].push_back(y - 2.0e5 + ar);  // residual mean 2e5 Pa, variation ~100 Pa
    model.values_si[1].push_back(y - 2.0e5 - ar + 300.0 * std::sin(1.9 * t));
    const bool gap = (i % 11 == 3) || (i > 1200 && i < 1400);
    gappy.values_si.push_back(gap ? kNaN : y);
    full.values_si.push_back(y);
  }
  log.channels = {gappy, full};
  auto comparison = CompareTraces(log, model);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();

  // The inputs as compare.h defines them: the smoothed piston position, its centred difference,
  // the choke; each with its mean removed.
  const std::vector<double> position = SmoothedPistonPosition(log.inputs, 0.05);
  std::vector<double> velocity(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const int a = std::max(0, i - 1), b = std::min(kSamples - 1, i + 1);
    velocity[i] = (position[b] - position[a]) / (log.inputs.time_s[b] - log.inputs.time_s[a]);
  }
  auto centred = [](std::vector<double> x) {
    double mean = 0.0;
    for (double v : x) mean += v;
    mean /= static_cast<double>(x.size());
    for (double& v : x) v -= mean;
    return x;
  };
  const std::vector<std::vector<double>> inputs = {centred(velocity), centred(position),
                                                   centred(log.inputs.choke_opening_frac)};
  for (std::size_t c = 0; c < 2; ++c) {
    SCOPED_TRACE(c);
    const std::vector<double>& y = log.channels[c].values_si;
    std::vector<double> e(kSamples, 0.0);
    double mean = 0.0;
    int count = 0;
    for (int i = 0; i < kSamples; ++i) {
      if (std::isfinite(y[i])) mean += y[i] - model.values_si[c][i], ++count;
    }
    mean /= count;
    for (int i = 0; i < kSamples; ++i) {
      if (std::isfinite(y[i])) e[i] = y[i] - model.values_si[c][i] - mean;
    }
    auto correlate = [&](const std::vector<double>& u, int k) {
      double sum = 0.0, ee = 0.0, uu = 0.0;
      for (int i = 0; i < kSamples; ++i) {
        ee += e[i] * e[i], uu += u[i] * u[i];
        if (i - k >= 0 && i - k < kSamples) sum += e[i] * u[i - k];
      }
      return sum / std::sqrt(ee * uu);
    };
    const ResidualAnalysis& residual = comparison->channels[c].residual;
    ASSERT_EQ(residual.autocorrelation.size(), kLags + 1u);
    // The sums are of order N sigma^2 ~ 3e7 Pa^2 and agree to round-off: 1e-10 relative.
    for (int k = 0; k <= kLags; ++k) {
      EXPECT_NEAR(residual.autocorrelation[k], correlate(e, k), 1e-10) << "k = " << k;
    }
    EXPECT_FALSE(residual.white);  // AR(1), 0.8
    ASSERT_EQ(residual.cross.size(), 3u);
    for (std::size_t u = 0; u < 3; ++u) {
      ASSERT_EQ(residual.cross[u].r.size(), 2u * kLags + 1u);
      for (int k = -kLags; k <= kLags; ++k) {
        EXPECT_NEAR(residual.cross[u].r[k + kLags], correlate(inputs[u], k), 1e-10)
            << residual.cross[u].input << " k = " << k;
      }
    }
  }
}

// Welch segments (a long log's estimator) on the synthetic sine: the closed forms still hold.
TEST(CompareTest, WelchSegmentsKeepTheClosedForms) {
  const Synthetic synthetic = SyntheticSine();
  CompareOptions options;
  // 2000 samples (20 s, 4 periods; 0.2 Hz on bin 4 of 0.05 Hz): segments at 0, 1000, .., 4000.
  options.welch_segment_samples = 2000;
  auto comparison = CompareTraces(synthetic.log, synthetic.model, options);
  ASSERT_TRUE(comparison.ok()) << comparison.status().message();
  EXPECT_EQ(comparison->spectrum_segments, 5);
  EXPECT_NEAR(comparison->spectrum_segment_s, 20.0, 1e-9);
  const ChannelMetrics& sine = comparison->channels[0];
  const double w = 2.0 * std::numbers::pi * kFreqHz;
  // The time-domain metrics do not depend on the segments.
  const double nrmse = std::abs(std::polar(kGain, kPhaseRad) - 1.0);
  EXPECT_NEAR(sine.nrmse, nrmse, 1e-9 * nrmse);
  // Each segment holds 4 whole periods of both sines, so every segment's windowed correlation
  // and spectra see the same shapes: the averages keep the single periodogram's accuracy
  // (measured: lag 8e-8 s, ratio 4e-8, phase 1e-5 deg, amplitudes 3e-7 relative; the -f image,
  // now 8 bins away instead of 24, is what is left). Bounds with 10-100x margin.
  EXPECT_NEAR(sine.lag_s, -kPhaseRad / w, 1e-6);
  ASSERT_FALSE(sine.bands.empty());
  const BandMetrics& band = sine.bands.front();
  EXPECT_EQ(band.harmonic, 1);
  EXPECT_NEAR(band.freq_hz, kFreqHz, 1e-6);
  EXPECT_NEAR(band.magnitude_ratio, kGain, 1e-6);
  EXPECT_NEAR(band.phase_diff_deg, kPhaseRad * 180.0 / std::numbers::pi, 1e-4);
  EXPECT_NEAR(band.measured_amplitude, kAmplitudePa, 1e-5 * kAmplitudePa);
  EXPECT_NEAR(band.model_amplitude, kGain * kAmplitudePa, 1e-5 * kAmplitudePa);
  // White noise stays white.
  const ChannelMetrics& noisy = comparison->channels[1];
  EXPECT_LT(noisy.residual.max_abs_autocorrelation, 2.0 * noisy.residual.confidence);
}

// The close-up, kept in a bounded buffer while streaming, against its definition (compare.h):
// the window of zoom_periods dominant periods centred on the first largest |residual|, moved
// inside the log, trimmed to max_zoom_samples around it.
TEST(CompareTest, CloseUpIsTheWindowAroundTheLargestError) {
  constexpr int kSamples = 20000;  // 200 s at 100 Hz; piston 0.2 Hz: 5 periods = 25 s
  auto reference = [](const std::vector<double>& time, const std::vector<double>& y,
                      const std::vector<double>& yhat, double span_s, std::size_t max_count) {
    std::size_t worst = 0;
    double worst_abs = -1.0;
    for (std::size_t i = 0; i < time.size(); ++i) {
      const double e = std::abs(y[i] - yhat[i]);
      if (e > worst_abs) worst_abs = e, worst = i;
    }
    double lo = time[worst] - 0.5 * span_s, hi = time[worst] + 0.5 * span_s;
    if (lo < time.front()) hi += time.front() - lo, lo = time.front();
    if (hi > time.back()) lo -= hi - time.back(), hi = time.back();
    auto first =
        static_cast<std::size_t>(std::lower_bound(time.begin(), time.end(), lo) - time.begin());
    auto last =
        static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), hi) - time.begin());
    if (last - first > max_count) {
      first = std::clamp(worst, first + max_count / 2, last - max_count / 2) - max_count / 2;
      last = first + max_count;
    }
    return std::vector<double>(time.begin() + first, time.begin() + last);
  };
  // Where the largest error is: mid-log, near either end, and a growing error (a new largest
  // one at every sample, the worst case for the buffer).
  const std::vector<std::function<double(int)>> errors = {
      [](int i) { return i == 12345 ? 900.0 : 10.0 * std::sin(i * 0.37); },
      [](int i) { return i == 30 ? 900.0 : 10.0 * std::sin(i * 0.37); },
      [](int i) { return i == kSamples - 10 ? -900.0 : 10.0 * std::sin(i * 0.37); },
      [](int i) { return 0.01 * i; },
  };
  for (int max_zoom : {300, 5000}) {  // trimmed, and the whole 25 s window (2500 samples)
    for (std::size_t which = 0; which < errors.size(); ++which) {
      SCOPED_TRACE(std::to_string(max_zoom) + " samples, case " + std::to_string(which));
      MeasuredLog log;
      log.path = "zoom";
      ModelTraces model;
      model.values_si.resize(1);
      MeasuredChannel pt1{Channel::kPT1, riglog::Unit::kBarg, {}};
      for (int i = 0; i < kSamples; ++i) {
        const double t = i / kRateHz;
        log.inputs.time_s.push_back(t);
        log.inputs.piston_position_m.push_back(0.05 * std::sin(2.0 * std::numbers::pi * 0.2 * t));
        log.inputs.choke_opening_frac.push_back(0.3);
        log.inputs.pump_flow_m3ps.push_back(0.0);
        log.inputs.outlet_pressure_pa.push_back(units::kStandardAtmospherePa);
        pt1.values_si.push_back(3.0e5 + 1.0e4 * std::sin(2.0 * std::numbers::pi * 0.2 * t));
        model.values_si[0].push_back(pt1.values_si.back() + errors[which](i));
      }
      log.channels = {pt1};
      CompareOptions options;
      options.max_zoom_samples = max_zoom;
      options.welch_segment_samples = 4096;
      auto comparison = CompareTraces(log, model, options);
      ASSERT_TRUE(comparison.ok()) << comparison.status().message();
      ASSERT_EQ(comparison->dominant_freqs_hz.size(), 3u);
      const double span_s = options.zoom_periods / comparison->dominant_freqs_hz.front();
      const TraceWindow& zoom = comparison->channels[0].zoom;
      EXPECT_EQ(zoom.time_s, reference(log.inputs.time_s, pt1.values_si, model.values_si[0], span_s,
                                       static_cast<std::size_t>(max_zoom)));
      ASSERT_EQ(zoom.measured.size(), zoom.time_s.size());
      const auto first = static_cast<std::size_t>(std::lround(zoom.time_s.front() * kRateHz));
      EXPECT_EQ(zoom.measured.front(), pt1.values_si[first]);
      EXPECT_EQ(zoom.model.back(), model.values_si[0][first + zoom.model.size() - 1]);
    }
  }
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

// Options are checked before the log is read: each bad field is refused by Validate, and by
// CompareLog with the same message, before it would look at the (missing) file.
TEST(CompareTest, BadOptionsAreRefusedUpFront) {
  EXPECT_TRUE(CompareOptions{}.Validate().ok());
  // Each bad field is named, with its value.
  const std::vector<std::pair<std::function<void(CompareOptions*)>, std::string>> breaks = {
      {[](CompareOptions* o) { o->residual_lags = 0; }, "residual_lags = 0 must be >= 1"},
      {[](CompareOptions* o) { o->trace_columns = 0; }, "trace_columns = 0 must be >= 1"},
      {[](CompareOptions* o) { o->band_half_width_bins = -1; },
       "band_half_width_bins = -1 must be >= 1"},
      {[](CompareOptions* o) { o->welch_segment_samples = 7; },
       "welch_segment_samples = 7 must be >= 8"},
  };
  for (const auto& [make_bad, says] : breaks) {
    SCOPED_TRACE(says);
    CompareOptions options;
    make_bad(&options);
    const Status status = options.Validate();
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message(), "compare options: " + says);
    auto comparison =
        CompareLog((TempDir() / "absent.csv").string(), RigParams{}, SimulationOptions{}, options);
    ASSERT_FALSE(comparison.ok());
    EXPECT_EQ(comparison.status().message(), status.message());
  }
}

}  // namespace
}  // namespace mpdrig
