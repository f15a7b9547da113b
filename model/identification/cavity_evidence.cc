#include "model/identification/cavity_evidence.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace mpdrig {
namespace {

// The channels whose pressure can sit at the vapour pressure as the model computes it: the
// pipe's (P2 is the inlet's, C2 the outlet's). P1 adds the piston's drop (5.4.2).
bool CanHoldFloor(Channel channel) {
  return channel == Channel::kP2 || channel == Channel::kC2 ||
         (channel >= Channel::kPT1 && channel <= Channel::kPT10);
}

double Median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Noise sigma from second differences: d2 = n[k+1] - 2 n[k] + n[k-1] has variance 6 sigma^2;
// the median absolute value (0.6745 sigma for a normal) ignores the rises at collapses. At least
// 10 Pa: a noise-free log's second differences are the signal's curvature (b dt^2).
double NoiseSigma(const std::vector<double>& y) {
  std::vector<double> d2;
  for (std::size_t k = 1; k + 1 < y.size(); ++k) {
    const double d = y[k + 1] - 2.0 * y[k] + y[k - 1];
    if (std::isfinite(d)) d2.push_back(std::fabs(d));
  }
  const double sigma = Median(std::move(d2)) / 0.6745 / std::sqrt(6.0);
  return std::isfinite(sigma) ? std::max(sigma, 10.0) : 10.0;
}

// The holds of one channel at the level its low tail suggests (see the header).
std::optional<ChannelFloor> FindChannelFloor(const std::vector<double>& time_s,
                                             const MeasuredChannel& channel, std::size_t index) {
  const std::vector<double>& y = channel.values_si;
  std::vector<double> finite;
  for (double v : y) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  if (finite.size() < 20 || time_s.size() != y.size()) return std::nullopt;
  ChannelFloor floor;
  floor.channel = channel.channel;
  floor.index = index;
  floor.noise_pa = NoiseSigma(y);
  const double sigma = floor.noise_pa;
  std::vector<double> sorted = finite;
  const auto quantile_at =
      sorted.begin() + static_cast<std::ptrdiff_t>(kLowQuantile * (sorted.size() - 1));
  std::nth_element(sorted.begin(), quantile_at, sorted.end());
  const double low = *quantile_at;
  floor.low_pa = low;
  if (low > kMaxFloorPa) return floor;  // no holds: its low tail only
  // The level: the median of the samples near the low tail (a floor's samples scatter about it
  // by the noise; the quantile sits in the floor's lower tail).
  std::vector<double> near;
  for (double v : finite) {
    if (v <= low + 4.0 * sigma) near.push_back(v);
  }
  const double level = Median(std::move(near));
  // Centred running mean over kSmoothingSamples (NaN where a sample is missing).
  const int half = kSmoothingSamples / 2;
  const std::size_t n = y.size();
  std::vector<double> smooth(n, std::nan(""));
  for (std::size_t k = half; k + half < n; ++k) {
    double sum = 0.0;
    for (int j = -half; j <= half; ++j) sum += y[k + j];
    smooth[k] = sum / kSmoothingSamples;
  }
  const double band = kLevelBand * sigma / std::sqrt(static_cast<double>(kSmoothingSamples));
  const double dt = (time_s.back() - time_s.front()) / static_cast<double>(n - 1);
  const std::size_t window = std::max<std::size_t>(1, std::lround(kCollapseWindowS / dt));
  std::size_t k = 0;
  while (k < n) {
    if (!(std::fabs(smooth[k] - level) <= band)) {
      ++k;
      continue;
    }
    std::size_t end = k;
    while (end < n && std::fabs(smooth[end] - level) <= band) ++end;
    // [k, end): the run. A hold: long enough, and a steep rise right after it.
    if (time_s[end - 1] - time_s[k] >= kMinHoldS && end < n) {
      double peak = -INFINITY, sum = 0.0;
      for (std::size_t j = end; j < std::min(n, end + window); ++j) peak = std::max(peak, y[j]);
      for (std::size_t j = k; j < end; ++j) sum += y[j];
      const double hold_level = sum / static_cast<double>(end - k);
      if (peak - hold_level >= kMinCollapseRise * sigma) {
        floor.holds.push_back({time_s[k], time_s[end - 1], hold_level, peak - hold_level});
        for (std::size_t j = k; j < end; ++j) floor.samples.push_back(j);
      }
    }
    k = end;
  }
  if (floor.holds.empty()) return floor;
  double sum = 0.0;
  for (std::size_t j : floor.samples) sum += y[j];
  floor.level_pa = sum / static_cast<double>(floor.samples.size());
  return floor;
}

}  // namespace

CavityEvidence FindPressureFloors(const MeasuredLog& log) {
  CavityEvidence evidence;
  std::vector<ChannelFloor> found;
  std::vector<double> levels;
  std::vector<std::pair<double, double>> lows;  // each channel's low tail and noise sigma
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    if (!CanHoldFloor(log.channels[c].channel)) continue;
    auto floor = FindChannelFloor(log.time_s(), log.channels[c], c);
    if (!floor) continue;
    lows.emplace_back(floor->low_pa, floor->noise_pa);
    if (floor->holds.empty()) continue;
    for (const PressureHold& hold : floor->holds) levels.push_back(hold.level_pa);
    found.push_back(std::move(*floor));
  }
  if (levels.empty()) return evidence;
  // One level for the liquid: the median of the holds'; a channel's floor counts where its level
  // agrees within kLevelBand of its noise sigma.
  evidence.level_pa = Median(levels);
  // Nothing in the liquid goes below the vapour pressure: a channel whose low tail lies below
  // the level (beyond its noise) says the holds are not at a floor of the liquid's.
  for (const auto& [low, sigma] : lows) {
    if (low < evidence.level_pa - kLevelBand * sigma) return CavityEvidence{};
  }
  for (ChannelFloor& floor : found) {
    if (std::fabs(floor.level_pa - evidence.level_pa) > kLevelBand * floor.noise_pa) continue;
    evidence.holds += static_cast<int>(floor.holds.size());
    evidence.floors.push_back(std::move(floor));
  }
  return evidence;
}

double FloorError(const MeasuredLog& log, const CavityEvidence& evidence,
                  const ModelTraces& model) {
  double sum = 0.0;
  int used = 0;
  for (const ChannelFloor& floor : evidence.floors) {
    if (floor.index >= model.values_si.size()) continue;
    const std::vector<double>& y = log.channels[floor.index].values_si;
    const std::vector<double>& m = model.values_si[floor.index];
    double mean = 0.0, squares = 0.0;
    int count = 0;
    for (double v : y) {
      if (std::isfinite(v)) mean += v, ++count;
    }
    if (count < 2) continue;
    mean /= count;
    for (double v : y) {
      if (std::isfinite(v)) squares += (v - mean) * (v - mean);
    }
    const double deviation = std::sqrt(squares / count);
    double residual = 0.0;
    int on_floor = 0;
    for (std::size_t k : floor.samples) {
      if (k >= m.size() || !std::isfinite(m[k]) || !std::isfinite(y[k])) continue;
      residual += (m[k] - y[k]) * (m[k] - y[k]);
      ++on_floor;
    }
    if (on_floor == 0 || !(deviation > 0.0)) continue;
    sum += std::sqrt(residual / on_floor) / deviation;
    ++used;
  }
  return used > 0 ? sum / used : 0.0;
}

double ErrorWithFloors(double error, int channel_count, const CavityEvidence& evidence,
                       double floor_error) {
  if (!evidence.present()) return error;
  const double floors = static_cast<double>(evidence.floors.size());
  return (error * channel_count + floor_error * floors) / (channel_count + floors);
}

}  // namespace mpdrig
