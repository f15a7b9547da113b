#include "model/analysis/window_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "model/common/status.h"
#include "model/riglog/channels.h"

namespace mpdrig {
namespace {

bool InWindow(double t, double begin_s, double end_s) { return t >= begin_s && t <= end_s; }

// The samples n with begin_s <= t[n] <= end_s, as [first, end) of the log's increasing times: the
// loops below visit those only, in the same order (the others they skipped anyway).
struct IndexRange {
  std::size_t first = 0, end = 0;
};
IndexRange WindowIndices(const std::vector<double>& t, double begin_s, double end_s) {
  const auto first = std::lower_bound(t.begin(), t.end(), begin_s);
  const auto end = std::upper_bound(first, t.end(), end_s);
  return {static_cast<std::size_t>(first - t.begin()), static_cast<std::size_t>(end - t.begin())};
}

}  // namespace

double Nrmse(double ss_res, double ss_tot) {
  return ss_tot > 0.0 ? std::sqrt(ss_res / ss_tot) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> WindowMeans(const MeasuredLog& log, double begin_s, double end_s) {
  const std::vector<double>& t = log.time_s();
  const IndexRange window = WindowIndices(t, begin_s, end_s);
  std::vector<double> means;
  for (const MeasuredChannel& channel : log.channels) {
    double sum = 0.0;
    long count = 0;
    for (std::size_t n = window.first; n < window.end; ++n) {
      if (std::isfinite(channel.values_si[n])) {
        sum += channel.values_si[n], ++count;
      }
    }
    means.push_back(count > 0 ? sum / count : 0.0);
  }
  return means;
}

std::vector<WindowSums> ChannelWindowSums(const MeasuredLog& log, const ModelTraces& model,
                                          double begin_s, double end_s,
                                          const std::vector<double>* means) {
  MPDRIG_CHECK(model.values_si.size() == log.channels.size());
  const std::vector<double> own_means =
      means != nullptr ? std::vector<double>() : WindowMeans(log, begin_s, end_s);
  const std::vector<double>& mean = means != nullptr ? *means : own_means;
  const IndexRange window = WindowIndices(log.time_s(), begin_s, end_s);
  std::vector<WindowSums> sums(log.channels.size());
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    const std::vector<double>& y = log.channels[c].values_si;
    const std::vector<double>& yhat = model.values_si[c];
    for (std::size_t n = window.first; n < window.end; ++n) {
      if (!std::isfinite(y[n])) continue;
      sums[c].ss_res += (yhat[n] - y[n]) * (yhat[n] - y[n]);
      sums[c].ss_tot += (y[n] - mean[c]) * (y[n] - mean[c]);
      ++sums[c].count;
    }
    if (sums[c].count > 0) {
      sums[c].constant = IsConstantSpread(log.channels[c].channel, mean[c],
                                          std::sqrt(sums[c].ss_tot / sums[c].count));
    }
  }
  return sums;
}

bool IsConstantSpread(Channel channel, double mean_si, double std_si) {
  const std::optional<riglog::PhysicalRange> range =
      riglog::PhysicalRangeOf(riglog::QuantityOf(channel));
  const double span = range ? range->max_si - range->min_si : 0.0;
  return !(std_si > 1e-9 * std::abs(mean_si) && std_si > 1e-12 * span);
}

double WindowError(const MeasuredLog& log, const ModelTraces& model, double begin_s, double end_s) {
  double total = 0.0;
  int count = 0;
  for (const WindowSums& sums : ChannelWindowSums(log, model, begin_s, end_s)) {
    const double nrmse = sums.nrmse();
    if (std::isfinite(nrmse)) total += nrmse, ++count;
  }
  return count > 0 ? total / count : std::numeric_limits<double>::quiet_NaN();
}

WindowReference MeasureWindow(const MeasuredLog& log, double begin_s, double end_s) {
  // ss_tot, counts and constancy as ChannelWindowSums takes them (the same loop, the same order).
  WindowReference reference;
  reference.begin_s = begin_s;
  reference.end_s = end_s;
  reference.samples = log.time_s().size();
  reference.sums.resize(log.channels.size());
  const std::vector<double> mean = WindowMeans(log, begin_s, end_s);
  const IndexRange window = WindowIndices(log.time_s(), begin_s, end_s);
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    const std::vector<double>& y = log.channels[c].values_si;
    WindowSums& sums = reference.sums[c];
    for (std::size_t n = window.first; n < window.end; ++n) {
      if (!std::isfinite(y[n])) continue;
      sums.ss_tot += (y[n] - mean[c]) * (y[n] - mean[c]);
      ++sums.count;
    }
    if (sums.count > 0) {
      sums.constant =
          IsConstantSpread(log.channels[c].channel, mean[c], std::sqrt(sums.ss_tot / sums.count));
    }
  }
  return reference;
}

WindowErrorAccumulator::WindowErrorAccumulator(const MeasuredLog& log, double begin_s, double end_s)
    : WindowErrorAccumulator(log, MeasureWindow(log, begin_s, end_s)) {}

WindowErrorAccumulator::WindowErrorAccumulator(const MeasuredLog& log,
                                               const WindowReference& reference)
    : log_(log), begin_s_(reference.begin_s), end_s_(reference.end_s), sums_(reference.sums) {
  MPDRIG_CHECK(reference.sums.size() == log.channels.size() &&
               reference.samples == log.time_s().size());
}

void WindowErrorAccumulator::Add(std::size_t n, const double* model_values) {
  if (!InWindow(log_.time_s()[n], begin_s_, end_s_)) return;
  for (std::size_t c = 0; c < sums_.size(); ++c) {
    const double y = log_.channels[c].values_si[n];
    if (!std::isfinite(y)) continue;
    sums_[c].ss_res += (model_values[c] - y) * (model_values[c] - y);
  }
}

double WindowErrorAccumulator::Error() const {
  double total = 0.0;
  int count = 0;
  for (const WindowSums& sums : sums_) {
    const double nrmse = sums.nrmse();
    if (std::isfinite(nrmse)) total += nrmse, ++count;
  }
  return count > 0 ? total / count : std::numeric_limits<double>::quiet_NaN();
}

double WindowErrorAccumulator::LowerBound() const { return Error(); }

}  // namespace mpdrig
