// MakeSyntheticLog's sensor noise: the C++ default stays the quiet noise the identification tests
// were tuned on; SyntheticLogOptions::sensor_noise puts the lab's (or any) on the same run, and
// truth_log is that run without noise.
#include "model/identification/synthetic_log.h"

#include <cmath>
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

}  // namespace
}  // namespace mpdrig
