// MakeSyntheticLog's sensor noise: the C++ default stays the quiet noise the identification tests
// were tuned on; SyntheticLogOptions::sensor_noise puts the lab's (or any) on the same run, and
// truth_log is that run without noise. The irregular sea: never periodic, in the sea's band, the
// rest of the log as the lab series has it.
#include "model/identification/synthetic_log.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

// 20 s at 50 Hz: 1001 samples a channel, 14 pressure channels.
SyntheticLogOptions ShortRun() {
  SyntheticLogOptions options;
  options.seed = 2;
  options.duration_s = 20.0;
  options.rate_hz = 50.0;
  return options;
}

// Sample standard deviation of noisy - truth over every pressure column.
double PressureNoise(const SyntheticLog& made) {
  std::vector<double> e;
  for (std::size_t c = 0; c < made.log.columns.size(); ++c) {
    if (made.log.columns[c].quantity() != riglog::Quantity::kPressure) continue;
    for (std::size_t i = 0; i < made.log.num_rows(); ++i) {
      e.push_back(made.log.values_si[c][i] - made.truth_log.values_si[c][i]);
    }
  }
  double mean = 0.0;
  for (double v : e) mean += v;
  mean /= static_cast<double>(e.size());
  double sum = 0.0;
  for (double v : e) sum += (v - mean) * (v - mean);
  EXPECT_EQ(e.size(), 14u * 1001u);
  return std::sqrt(sum / static_cast<double>(e.size() - 1));
}

// The sample standard deviation of n normal draws spreads by 1 / sqrt(2 (n - 1)); 4 of those.
const double kTolerance = 4.0 / std::sqrt(2.0 * (14.0 * 1001.0 - 1.0));

TEST(SyntheticLogNoise, DefaultStaysQuietAndLabIsTheLabs) {
  auto quiet = MakeSyntheticLog(ShortRun());
  ASSERT_TRUE(quiet.ok()) << quiet.status().message();
  EXPECT_NEAR(PressureNoise(*quiet), 300.0, kTolerance * 300.0);

  SyntheticLogOptions lab_options = ShortRun();
  lab_options.sensor_noise = SensorNoise::Lab();
  auto lab = MakeSyntheticLog(lab_options);
  ASSERT_TRUE(lab.ok()) << lab.status().message();
  EXPECT_NEAR(PressureNoise(*lab), 2400.0, kTolerance * 2400.0);
  // The same run underneath: same truth, same parameters.
  EXPECT_EQ(lab->truth_log.values_si, quiet->truth_log.values_si);
  EXPECT_EQ(lab->description, quiet->description);
}

TEST(SyntheticLogNoise, NoneIsTheTruth) {
  SyntheticLogOptions options = ShortRun();
  options.sensor_noise = SensorNoise::None();
  auto made = MakeSyntheticLog(options);
  ASSERT_TRUE(made.ok()) << made.status().message();
  EXPECT_EQ(made->log.values_si, made->truth_log.values_si);
  EXPECT_EQ(made->log.columns, made->truth_log.columns);
  EXPECT_EQ(made->log.time_s, made->truth_log.time_s);
}

TEST(SyntheticLogNoise, RefusesAnInvalidNoise) {
  SyntheticLogOptions options = ShortRun();
  options.sensor_noise = SensorNoise::Lab();
  options.sensor_noise->choke_deg = std::nan("");
  auto made = MakeSyntheticLog(options);
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.status().message().find("choke_deg"), std::string::npos)
      << made.status().message();
}

// The column of `channel`'s samples (truth, SI).
std::vector<double> Column(const SyntheticLog& made, Channel channel) {
  const std::vector<double>* column = made.truth_log.Find(channel);
  if (column == nullptr) ADD_FAILURE() << "no column";
  return column != nullptr ? *column : std::vector<double>();
}

// Normalised autocorrelation of x (mean removed) at `lag` samples.
double Autocorrelation(const std::vector<double>& x, std::size_t lag) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double c0 = 0.0, c = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) c0 += (x[i] - mean) * (x[i] - mean);
  for (std::size_t i = 0; i + lag < x.size(); ++i) c += (x[i] - mean) * (x[i + lag] - mean);
  return c / c0;
}

TEST(SyntheticLogHeave, AnIrregularSeaNeverRepeatsAndKeepsTheRestOfTheLog) {
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    SyntheticLogOptions lab;
    lab.seed = seed;
    lab.duration_s = 200.0;
    lab.rate_hz = 10.0;
    SyntheticLogOptions sea = lab;
    sea.heave = SyntheticHeave::kIrregularSea;
    auto lab_log = MakeSyntheticLog(lab);
    auto sea_log = MakeSyntheticLog(sea);
    ASSERT_TRUE(lab_log.ok() && sea_log.ok());
    const std::vector<double> x = Column(*sea_log, Channel::kPistonPosition);
    // Never periodic: no lag from a wave period (5 s) to half the log brings the heave back onto
    // itself (a sum of incommensurate tones; the lab's sines repeat within a few periods).
    double best = -1.0;
    for (std::size_t lag = 50; lag < x.size() / 2; ++lag)
      best = std::max(best, Autocorrelation(x, lag));
    EXPECT_LT(best, 0.6);
    // In the sea's band: the heave's velocity and position give its mean frequency,
    // f = std(v) / (2 pi std(x)), between the band's ends (0.04-0.5 Hz) and near the peak.
    double vx = 0.0, vv = 0.0;
    for (std::size_t i = 1; i < x.size(); ++i) {
      const double v = (x[i] - x[i - 1]) * lab.rate_hz;
      vv += v * v;
      vx += x[i] * x[i];
    }
    const double mean_hz = std::sqrt(vv / vx) / (2.0 * std::numbers::pi);
    EXPECT_GT(mean_hz, 0.08);
    EXPECT_LT(mean_hz, 0.3);
    // Its size as the lab series': the standard deviation within a factor 1.5.
    const std::vector<double> y = Column(*lab_log, Channel::kPistonPosition);
    double sx = 0.0, sy = 0.0;
    for (double v : x) sx += v * v;
    for (double v : y) sy += v * v;
    EXPECT_NEAR(std::sqrt(sx / sy), 1.0, 0.5);
    // The rest of the log as the lab series: parameters, choke and pump.
    EXPECT_EQ(sea_log->truth.wave_speed_mps, lab_log->truth.wave_speed_mps);
    EXPECT_EQ(Column(*sea_log, Channel::kChokePosition), Column(*lab_log, Channel::kChokePosition));
    EXPECT_EQ(Column(*sea_log, Channel::kFT2), Column(*lab_log, Channel::kFT2));
  }
}

}  // namespace
}  // namespace mpdrig
