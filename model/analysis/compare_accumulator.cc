#include "model/analysis/compare_accumulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>
#include <utility>

#include "model/analysis/window_error.h"

namespace mpdrig {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kConfidence99 = 2.58;  // two-sided 99% quantile of the standard normal
constexpr double kMaxLagCapS = 10.0;

// Linear interpolation over NaN gaps (ends held), for the spectral quantities only. At least one
// value must be finite.
void FillGaps(std::vector<double>* values) {
  std::vector<double>& out = *values;
  const std::size_t n = out.size();
  std::size_t first = 0;
  while (first < n && !std::isfinite(out[first])) ++first;
  MPDRIG_CHECK(first < n);
  for (std::size_t i = 0; i < first; ++i) out[i] = out[first];
  std::size_t last = first;
  for (std::size_t i = first + 1; i < n; ++i) {
    if (!std::isfinite(out[i])) continue;
    for (std::size_t j = last + 1; j < i; ++j) {
      const double w = static_cast<double>(j - last) / static_cast<double>(i - last);
      out[j] = (1.0 - w) * out[last] + w * out[i];
    }
    last = i;
  }
  for (std::size_t i = last + 1; i < n; ++i) out[i] = out[last];
}

// x <- (x - mean(x)) w, the Hann-windowed segment with its mean removed.
void RemoveMeanAndWindow(const std::vector<double>& window, std::vector<double>* x) {
  const double mean = std::accumulate(x->begin(), x->end(), 0.0) / static_cast<double>(x->size());
  for (double& v : *x) v -= mean;
  for (std::size_t i = 0; i < x->size(); ++i) (*x)[i] *= window[i];
}

double WrapDeg(double deg) {
  double wrapped = std::remainder(deg, 360.0);
  if (wrapped <= -180.0) wrapped += 360.0;
  return wrapped;
}

// Parabolic vertex offset in (-0.5, 0.5) bins through (-1, a), (0, b), (1, c).
double ParabolicOffset(double a, double b, double c) {
  const double denominator = a - 2.0 * b + c;
  if (!(std::abs(denominator) > 0.0)) return 0.0;
  return std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5);
}

struct Peak {
  double freq_hz;
  double power;
};

// The piston's dominant frequencies from its (averaged) power spectrum: the largest peak f0, its
// harmonics up to max_harmonics, and further local maxima above extra_peak_fraction of the
// largest power, away from those bands.
std::vector<std::pair<double, int>> DominantFrequencies(const std::vector<double>& power,
                                                        double df_hz,
                                                        const CompareOptions& options) {
  std::vector<std::pair<double, int>> bands;
  const std::size_t bins = power.size();
  if (bins < 8) return bands;
  // Skip the bins next to DC: the Hann window leaks the remaining trend there.
  const std::size_t first = 2;
  std::size_t peak = first;
  for (std::size_t k = first; k + 1 < bins; ++k) {
    if (power[k] > power[peak]) peak = k;
  }
  if (!(power[peak] > 0.0)) return bands;
  auto refine = [&](std::size_t k) {
    const double offset = ParabolicOffset(std::log(power[k - 1] + 1e-300), std::log(power[k]),
                                          std::log(power[k + 1] + 1e-300));
    return (static_cast<double>(k) + offset) * df_hz;
  };
  const double f0 = refine(peak);
  const double nyquist = (bins - 1) * df_hz;
  const double half_width = options.band_half_width_bins * df_hz;
  for (int h = 1; h <= options.max_harmonics; ++h) {
    if (h * f0 + half_width < nyquist) bands.emplace_back(h * f0, h);
  }
  std::vector<Peak> extra;
  for (std::size_t k = first; k + 1 < bins; ++k) {
    if (power[k] >= options.extra_peak_fraction * power[peak] && power[k] > power[k - 1] &&
        power[k] >= power[k + 1]) {
      extra.push_back({refine(k), power[k]});
    }
  }
  std::sort(extra.begin(), extra.end(),
            [](const Peak& a, const Peak& b) { return a.power > b.power; });
  int added = 0;
  for (const Peak& candidate : extra) {
    if (added >= options.max_extra_peaks) break;
    const bool taken = std::any_of(bands.begin(), bands.end(), [&](const auto& band) {
      return std::abs(band.first - candidate.freq_hz) <= 2.0 * half_width;
    });
    if (taken) continue;
    bands.emplace_back(candidate.freq_hz, 0);
    ++added;
  }
  std::sort(bands.begin(), bands.end());
  return bands;
}

// The window's autocorrelation W(k) = sum_n w[n] w[n + k], |k| <= max_lag (index k + max_lag).
std::vector<double> WindowCorrelation(const std::vector<double>& window, std::size_t max_lag,
                                      RealFft* fft) {
  const std::size_t fft_size = fft->size();
  std::vector<std::complex<double>> spectrum;
  fft->Forward(window, &spectrum);
  for (auto& value : spectrum) value = std::norm(value);
  std::vector<double> raw;
  fft->Inverse(spectrum, &raw);
  std::vector<double> correlation;
  for (long k = -static_cast<long>(max_lag); k <= static_cast<long>(max_lag); ++k) {
    const std::size_t index =
        k >= 0 ? static_cast<std::size_t>(k) : fft_size - static_cast<std::size_t>(-k);
    correlation.push_back(raw[index] / static_cast<double>(fft_size));
  }
  return correlation;
}

// Transfer functions: the bins where the piston has power; beyond transfer_points of them,
// log-spaced groups of bins pooled as sum(Y conj U) / sum |U|^2 (a smoothed ETFE). `groups` holds
// each bin's group, numbered from 0 in frequency order.
void PlanTransferPoints(const std::vector<double>& power, const CompareOptions& options,
                        std::vector<std::size_t>* bins, std::vector<std::size_t>* groups) {
  double max_power = 0.0;
  for (std::size_t k = 2; k < power.size(); ++k) max_power = std::max(max_power, power[k]);
  for (std::size_t k = 2; k < power.size(); ++k) {
    if (power[k] >= options.transfer_min_power_fraction * max_power && max_power > 0.0) {
      bins->push_back(k);
    }
  }
  if (bins->empty()) return;
  const std::size_t max_points = static_cast<std::size_t>(std::max(1, options.transfer_points));
  const double lo = std::log(static_cast<double>(bins->front()));
  const double hi = std::log(static_cast<double>(bins->back()) + 1.0);
  auto group_of = [&](std::size_t k) {
    if (bins->size() <= max_points) return k;  // every excited bin is a point
    return static_cast<std::size_t>((std::log(static_cast<double>(k)) - lo) / (hi - lo) *
                                    static_cast<double>(max_points));
  };
  std::size_t point = 0;
  std::size_t current = group_of(bins->front());
  for (std::size_t k : *bins) {
    if (group_of(k) != current) current = group_of(k), ++point;
    groups->push_back(point);
  }
}

void UpdateRange(double value, double* lo, double* hi) {
  if (!std::isfinite(value)) return;
  if (!(*lo <= value)) *lo = value;
  if (!(*hi >= value)) *hi = value;
}

// y[j] += a x[j], j < n: the lagged sums' inner loop (vectorised by the compiler).
void Axpy(std::size_t n, double a, const double* x, double* y) {
  for (std::size_t j = 0; j < n; ++j) y[j] += a * x[j];
}

// Pass 2's rings: the last segment (AddSegment copies exactly summary.segment_length samples).
std::size_t RingCapacity(const LogSummary& summary) {
  return std::max<std::size_t>(1, summary.segment_length);
}

}  // namespace

// ---- Pass 1 -----------------------------------------------------------------------------------

LogScanner::LogScanner(std::vector<SourceChannel> channels, const CompareOptions& options)
    : source_channels_(std::move(channels)),
      counts_(source_channels_.size(), 0),
      sums_(source_channels_.size(), 0.0),
      segmenter_(static_cast<std::size_t>(std::max(8, options.welch_segment_samples))),
      piston_ring_(segmenter_.max_length()) {}

void LogScanner::Add(const PipelineSample& sample) {
  const LogRow& row = *sample.row;
  if (samples_ == 0) {
    t0_ = row.time_s;
  } else {
    const double interval = row.time_s - t_last_;
    if (samples_ == 1 || interval < min_interval_) min_interval_ = interval;
    if (samples_ == 1 || interval > max_interval_) max_interval_ = interval;
  }
  t_last_ = row.time_s;
  for (std::size_t c = 0; c < source_channels_.size(); ++c) {
    const double y = row.measured_si[c];
    if (std::isfinite(y)) sums_[c] += y, ++counts_[c];
  }
  const std::array<double, kResidualInputCount> inputs = {
      sample.piston_velocity_mps, sample.piston_position_m, row.choke_opening_frac};
  for (std::size_t u = 0; u < kResidualInputCount; ++u) {
    input_sum_[u] += inputs[u];
    if (samples_ == 0 || inputs[u] < input_min_[u]) input_min_[u] = inputs[u];
    if (samples_ == 0 || inputs[u] > input_max_[u]) input_max_[u] = inputs[u];
  }
  ++samples_;
  piston_ring_.Push(sample.piston_position_m);
  if (auto length = segmenter_.Push()) AddPistonSegment(*length);
}

void LogScanner::AddPistonSegment(std::size_t length) {
  if (segments_ == 0) {
    segment_length_ = length;
    window_ = HannWindow(length);
    fft_ = std::make_unique<RealFft>(FastFftSize(length));
    piston_power_.assign(fft_->size() / 2 + 1, 0.0);
  }
  MPDRIG_CHECK(length == segment_length_);
  piston_ring_.CopyLast(length, &scratch_);
  RemoveMeanAndWindow(window_, &scratch_);
  fft_->Forward(scratch_, &spectrum_);
  for (std::size_t k = 0; k < spectrum_.size(); ++k) piston_power_[k] += std::norm(spectrum_[k]);
  ++segments_;
}

Result<LogSummary> LogScanner::Finish(const std::string& path) {
  if (samples_ < 4) return Status::Error(path + ": needs at least 4 samples to compare");
  if (auto length = segmenter_.Finish()) AddPistonSegment(*length);
  LogSummary summary;
  summary.samples = samples_;
  summary.t0_s = t0_;
  summary.t1_s = t_last_;
  const double dt = (t_last_ - t0_) / static_cast<double>(samples_ - 1);
  summary.sample_interval_s = dt;
  // |interval - dt| is largest at the smallest or the largest interval.
  summary.uniform_sampling =
      !(std::abs(max_interval_ - dt) > 0.01 * dt) && !(std::abs(min_interval_ - dt) > 0.01 * dt);
  for (std::size_t c = 0; c < source_channels_.size(); ++c) {
    if (counts_[c] == 0) continue;
    summary.channels.push_back({source_channels_[c].channel, source_channels_[c].unit, c,
                                counts_[c], sums_[c] / static_cast<double>(counts_[c]),
                                counts_[c] < samples_});
  }
  if (summary.channels.empty()) {
    return Status::Error(path +
                         ": no measured channel to compare (P1 P2 PT1..PT10 C2 FT1 FT3 FT4)");
  }
  summary.segment_length = segment_length_;
  summary.fft_size = FastFftSize(segment_length_);
  summary.segments = segments_;
  summary.df_hz = 1.0 / (static_cast<double>(summary.fft_size) * dt);
  summary.piston_power = std::move(piston_power_);
  for (std::size_t u = 0; u < kResidualInputCount; ++u) {
    const double mean = input_sum_[u] / static_cast<double>(samples_);
    summary.input_mean[u] = mean;
    // x - mean is monotone in x, so these are the extremes of the mean-removed input.
    const double lo = input_min_[u] - mean, hi = input_max_[u] - mean;
    summary.input_constant[u] = !(hi - lo > 1e-12 * std::max(1.0, std::abs(hi)));
  }
  return summary;
}

// ---- Pass 2 -----------------------------------------------------------------------------------

// The last `length` values of a stream, newest first, contiguous: data()[j] is the value j
// samples ago (0 before the stream's start). Written backwards into a buffer with room for
// kSlack pushes before the window is moved back to its end.
class ComparisonAccumulator::History {
 public:
  explicit History(std::size_t length)
      : length_(length), buffer_(2 * length + kSlack, 0.0), position_(length + kSlack) {}
  void Push(double value) {
    if (position_ == 0) {  // move the newest length - 1 values to the end (no overlap)
      std::copy(buffer_.begin(), buffer_.begin() + static_cast<long>(length_ - 1),
                buffer_.end() - static_cast<long>(length_ - 1));
      position_ = buffer_.size() - (length_ - 1);
    }
    buffer_[--position_] = value;
  }
  const double* data() const { return buffer_.data() + position_; }

 private:
  static constexpr std::size_t kSlack = 4096;
  std::size_t length_;
  std::vector<double> buffer_;
  std::size_t position_;
};

struct ComparisonAccumulator::ChannelState {
  const LogSummary::ChannelSummary* summary = nullptr;
  // Scalar sums over the measured samples.
  double sse = 0.0, sst = 0.0, sum_e = 0.0;
  TraceEnvelope envelope;
  // Close-up: the last 2 B + 1 samples (B = max_zoom_samples), the largest |residual| so far,
  // and a copy of the samples within B of it, taken B samples after it (or at the end).
  std::vector<double> ring_time, ring_measured, ring_model;
  long worst = -1;
  double worst_abs = -1.0;
  bool snapshot_due = false;
  long snapshot_start = 0;
  TraceWindow snapshot;
  // Residual d = y - yhat, shifted by its first value (conditioning of the sums), 0 where y is
  // not measured, and the mask m (1 measured, 0 not): lagged sums, j = 0..M
  //   dd[j] = sum d_n d_{n-j}; with gaps also dm = sum d_n m_{n-j}, md = sum m_n d_{n-j},
  //   mm = sum m_n m_{n-j}; per input u (mean removed), k = -M..M (index k + M):
  //   du[k] = sum d_n u_{n-k}; with gaps mu[k] = sum m_n u_{n-k}; stored as [k = 0..M, then
  //   k = 0..-M] so that every update is a contiguous axpy.
  // Without gaps the mask sums follow from the first and last M values (Finish).
  double shift = 0.0;
  bool shifted = false;
  double sum_shifted = 0.0;
  std::vector<double> head;  // first M shifted residuals
  std::unique_ptr<History> residual_history, mask_history;
  std::vector<double> dd, dm, md, mm;
  std::array<std::vector<double>, kResidualInputCount> du, mu;
  // Welch sums.
  std::unique_ptr<SampleRing> measured_ring, model_ring;
  std::size_t segments = 0;
  std::vector<double> band_power_measured, band_power_model, band_power_error;
  std::vector<std::complex<double>> band_cross;
  bool transfer = false;  // PT1, C2
  std::vector<std::complex<double>> transfer_measured, transfer_model;
  std::vector<double> transfer_power, transfer_freq_power;
  std::vector<std::complex<double>> lag_cross;  // sum conj(A) B over the segments
  double lag_aa = 0.0, lag_bb = 0.0;
};

ComparisonAccumulator::ComparisonAccumulator(const LogSummary& summary,
                                             const CompareOptions& options)
    : summary_(summary),
      options_(options),
      segmenter_(static_cast<std::size_t>(std::max(8, options.welch_segment_samples))),
      // Pass 2 knows the segments' length: its rings hold one segment, not the longest one
      // (2^17 doubles each, 2 per channel: 30 MB to clear for a 40 s log of 15 channels).
      piston_ring_(RingCapacity(summary)) {
  const double dt = summary.sample_interval_s;
  const std::size_t length = summary.segment_length;
  band_centres_ = DominantFrequencies(summary.piston_power, summary.df_hz, options);
  max_lag_s_ = options.max_lag_s;
  if (!(max_lag_s_ > 0.0)) {
    max_lag_s_ = kMaxLagCapS;
    for (const auto& band : band_centres_) {
      if (band.second == 1) max_lag_s_ = std::min(max_lag_s_, 0.5 / band.first);
    }
  }
  max_lag_ =
      std::min(length / 2, static_cast<std::size_t>(std::max(1.0, std::floor(max_lag_s_ / dt))));
  lag_fft_size_ = FastFftSize(length + max_lag_ + 1);
  window_ = HannWindow(length);
  window_power_ = std::inner_product(window_.begin(), window_.end(), window_.begin(), 0.0);
  fft_ = std::make_unique<RealFft>(summary.fft_size);
  lag_fft_ = std::make_unique<RealFft>(lag_fft_size_);
  window_correlation_ = WindowCorrelation(window_, max_lag_, lag_fft_.get());
  for (const auto& band : band_centres_) {
    if (band.second == 1) zoom_span_s_ = options.zoom_periods / band.first;
  }

  PlanTransferPoints(summary.piston_power, options, &excited_bins_, &excited_group_);
  const std::size_t transfer_groups = excited_group_.empty() ? 0 : excited_group_.back() + 1;
  const std::size_t lags = static_cast<std::size_t>(options.residual_lags);
  for (std::size_t u = 0; u < kResidualInputCount; ++u) input_history_.emplace_back(lags + 1);
  channels_.resize(summary.channels.size());
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    InitChannel(&channels_[c], summary.channels[c], transfer_groups);
  }
}

// Every sum and buffer of one channel, empty; the mask's lagged sums only where it has gaps,
// the transfer function's only for PT1 and C2.
void ComparisonAccumulator::InitChannel(ChannelState* state,
                                        const LogSummary::ChannelSummary& summary,
                                        std::size_t transfer_groups) const {
  const std::size_t lags = static_cast<std::size_t>(options_.residual_lags);
  const std::size_t zoom_ring =
      2 * static_cast<std::size_t>(std::max(2, options_.max_zoom_samples)) + 1;
  const std::size_t columns = static_cast<std::size_t>(std::max(1, options_.trace_columns));
  state->summary = &summary;
  TraceEnvelope& env = state->envelope;
  env.t0_s = summary_.t0_s;
  env.t1_s = summary_.t1_s;
  for (auto* v : {&env.measured_min, &env.model_min, &env.residual_min}) v->assign(columns, kNaN);
  for (auto* v : {&env.measured_max, &env.model_max, &env.residual_max}) v->assign(columns, kNaN);
  state->ring_time.assign(zoom_ring, kNaN);
  state->ring_measured.assign(zoom_ring, kNaN);
  state->ring_model.assign(zoom_ring, kNaN);
  state->residual_history = std::make_unique<History>(lags + 1);
  state->dd.assign(lags + 1, 0.0);
  if (summary.has_gaps) {
    state->mask_history = std::make_unique<History>(lags + 1);
    state->dm.assign(lags + 1, 0.0);
    state->md.assign(lags + 1, 0.0);
    state->mm.assign(lags + 1, 0.0);
  }
  for (std::size_t u = 0; u < kResidualInputCount; ++u) {
    state->du[u].assign(2 * lags + 2, 0.0);
    if (summary.has_gaps) state->mu[u].assign(2 * lags + 2, 0.0);
  }
  state->measured_ring = std::make_unique<SampleRing>(RingCapacity(summary_));
  state->model_ring = std::make_unique<SampleRing>(RingCapacity(summary_));
  for (auto* v :
       {&state->band_power_measured, &state->band_power_model, &state->band_power_error}) {
    v->assign(band_centres_.size(), 0.0);
  }
  state->band_cross.assign(band_centres_.size(), 0.0);
  state->transfer = summary.channel == Channel::kPT1 || summary.channel == Channel::kC2;
  if (state->transfer) {
    state->transfer_measured.assign(transfer_groups, 0.0);
    state->transfer_model.assign(transfer_groups, 0.0);
    state->transfer_power.assign(transfer_groups, 0.0);
    state->transfer_freq_power.assign(transfer_groups, 0.0);
  }
  state->lag_cross.assign(lag_fft_size_ / 2 + 1, 0.0);
}

ComparisonAccumulator::~ComparisonAccumulator() = default;

void ComparisonAccumulator::Add(const PipelineSample& sample, const double* model_si) {
  const LogRow& row = *sample.row;
  const long n = added_++;
  AddInputCloseUp(row);
  const std::array<double, kResidualInputCount> u = AddResidualInputs(sample);
  const double span = summary_.t1_s - summary_.t0_s;
  const std::size_t columns = static_cast<std::size_t>(std::max(1, options_.trace_columns));
  std::size_t column =
      span > 0.0 ? static_cast<std::size_t>((row.time_s - summary_.t0_s) / span * columns) : 0;
  column = std::min(column, columns - 1);
  for (std::size_t c = 0; c < channels_.size(); ++c) {
    ChannelState& s = channels_[c];
    const double y = row.measured_si[s.summary->source_index];
    const double yhat = model_si[c];
    if (std::isfinite(y)) {
      const double e = yhat - y;
      s.sse += e * e;
      s.sum_e += e;
      s.sst += (y - s.summary->mean_si) * (y - s.summary->mean_si);
    }
    UpdateRange(y, &s.envelope.measured_min[column], &s.envelope.measured_max[column]);
    UpdateRange(yhat, &s.envelope.model_min[column], &s.envelope.model_max[column]);
    UpdateRange(y - yhat, &s.envelope.residual_min[column], &s.envelope.residual_max[column]);
    AddToZoomRing(&s, n, row.time_s, y, yhat);
    AddLaggedSums(&s, y, yhat, u);
    s.measured_ring->Push(y);
    s.model_ring->Push(yhat);
  }
  piston_ring_.Push(sample.piston_position_m);
  if (auto length = segmenter_.Push()) AddSegment(*length);
}

// The log's first kInputCloseUpSamples inputs, as measured and as replayed.
void ComparisonAccumulator::AddInputCloseUp(const LogRow& row) {
  if (input_close_up_.time_s.size() >= kInputCloseUpSamples) return;
  input_close_up_.time_s.push_back(row.time_s);
  const std::array<double, 4> replayed = {row.piston_position_m, row.choke_opening_frac,
                                          row.pump_flow_m3ps, row.outlet_pressure_pa};
  for (std::size_t k = 0; k < 4; ++k) {
    input_close_up_.measured[k].push_back(row.measured_inputs[k]);
    input_close_up_.replayed[k].push_back(replayed[k]);
  }
}

// The residual inputs of this sample, mean removed, into their sums and histories.
std::array<double, kResidualInputCount> ComparisonAccumulator::AddResidualInputs(
    const PipelineSample& sample) {
  const std::size_t lags = static_cast<std::size_t>(options_.residual_lags);
  const std::array<double, kResidualInputCount> raw = {
      sample.piston_velocity_mps, sample.piston_position_m, sample.row->choke_opening_frac};
  std::array<double, kResidualInputCount> u{};
  for (std::size_t i = 0; i < kResidualInputCount; ++i) {
    u[i] = raw[i] - summary_.input_mean[i];
    input_sum_[i] += u[i];
    input_square_sum_[i] += u[i] * u[i];
    if (input_head_[i].size() < lags) input_head_[i].push_back(u[i]);
    input_history_[i].Push(u[i]);
  }
  return u;
}

// Sample n into the channel's ring of the last 2 B + 1 samples; the largest |residual| so far,
// and its snapshot B samples after it.
void ComparisonAccumulator::AddToZoomRing(ChannelState* s, long n, double time_s, double y,
                                          double yhat) const {
  const long zoom_half = static_cast<long>(std::max(2, options_.max_zoom_samples));
  const std::size_t ring_size = static_cast<std::size_t>(2 * zoom_half + 1);
  const std::size_t ring_slot = static_cast<std::size_t>(n) % ring_size;
  s->ring_time[ring_slot] = time_s;
  s->ring_measured[ring_slot] = y;
  s->ring_model[ring_slot] = yhat;
  const double abs_error = std::abs(y - yhat);
  if (std::isfinite(abs_error) && abs_error > s->worst_abs) {
    s->worst_abs = abs_error, s->worst = n, s->snapshot_due = true;
  }
  if (s->snapshot_due && n == s->worst + zoom_half) TakeSnapshot(s, n);
}

// The lagged residual sums (ChannelState) with this sample's shifted residual d, its mask m and
// the residual inputs u.
void ComparisonAccumulator::AddLaggedSums(ChannelState* s, double y, double yhat,
                                          const std::array<double, kResidualInputCount>& u) const {
  const std::size_t lags = static_cast<std::size_t>(options_.residual_lags);
  const bool measured = std::isfinite(y);
  double d = 0.0;
  if (measured) {
    if (!s->shifted) s->shift = y - yhat, s->shifted = true;
    d = (y - yhat) - s->shift;
    s->sum_shifted += d;
  }
  const double m = measured ? 1.0 : 0.0;
  if (s->head.size() < lags) s->head.push_back(d);
  s->residual_history->Push(d);
  const double* dh = s->residual_history->data();
  Axpy(lags + 1, d, dh, s->dd.data());
  const double* mh = nullptr;
  if (s->mask_history) {
    s->mask_history->Push(m);
    mh = s->mask_history->data();
    Axpy(lags + 1, d, mh, s->dm.data());
    Axpy(lags + 1, m, dh, s->md.data());
    Axpy(lags + 1, m, mh, s->mm.data());
  }
  for (std::size_t i = 0; i < kResidualInputCount; ++i) {
    const double* uh = input_history_[i].data();
    double* du = s->du[i].data();
    // k = j >= 0: d_n u_{n-j}; k = -j <= 0: d_{n-j} u_n.
    Axpy(lags + 1, d, uh, du);
    Axpy(lags + 1, u[i], dh, du + lags + 1);
    if (mh != nullptr) {
      double* mu = s->mu[i].data();
      Axpy(lags + 1, m, uh, mu);
      Axpy(lags + 1, u[i], mh, mu + lags + 1);
    }
  }
}

void ComparisonAccumulator::AddSegment(std::size_t length) {
  MPDRIG_CHECK(length == summary_.segment_length);
  const double df_hz = summary_.df_hz;
  std::vector<std::complex<double>> piston, y, yhat;
  if (!excited_bins_.empty()) {
    piston_ring_.CopyLast(length, &piston_segment_);
    RemoveMeanAndWindow(window_, &piston_segment_);
    fft_->Forward(piston_segment_, &piston);
  }
  std::vector<double> a, b;
  for (ChannelState& s : channels_) {
    s.measured_ring->CopyLast(length, &a);
    if (std::none_of(a.begin(), a.end(), [](double v) { return std::isfinite(v); })) continue;
    FillGaps(&a);
    s.model_ring->CopyLast(length, &b);
    RemoveMeanAndWindow(window_, &a);
    RemoveMeanAndWindow(window_, &b);
    ++s.segments;
    {
      fft_->Forward(a, &y);
      fft_->Forward(b, &yhat);
      for (std::size_t i = 0; i < band_centres_.size(); ++i) {
        const double centre = band_centres_[i].first;
        const double low = std::max(0.0, centre - options_.band_half_width_bins * df_hz);
        const double high = centre + options_.band_half_width_bins * df_hz;
        const auto k_lo = static_cast<std::size_t>(std::ceil(low / df_hz));
        const auto k_hi =
            std::min(y.size() - 1, static_cast<std::size_t>(std::floor(high / df_hz)));
        for (std::size_t k = k_lo; k <= k_hi; ++k) {
          s.band_power_measured[i] += std::norm(y[k]);
          s.band_power_model[i] += std::norm(yhat[k]);
          s.band_power_error[i] += std::norm(yhat[k] - y[k]);
          s.band_cross[i] += yhat[k] * std::conj(y[k]);
        }
      }
      if (s.transfer) {
        for (std::size_t i = 0; i < excited_bins_.size(); ++i) {
          const std::size_t k = excited_bins_[i];
          const std::size_t g = excited_group_[i];
          const double power = std::norm(piston[k]);
          s.transfer_measured[g] += y[k] * std::conj(piston[k]);
          s.transfer_model[g] += yhat[k] * std::conj(piston[k]);
          s.transfer_power[g] += power;
          s.transfer_freq_power[g] += power * static_cast<double>(k) * df_hz;
        }
      }
    }
    s.lag_aa += std::inner_product(a.begin(), a.end(), a.begin(), 0.0);
    s.lag_bb += std::inner_product(b.begin(), b.end(), b.begin(), 0.0);
    lag_fft_->Forward(a, &y);
    lag_fft_->Forward(b, &yhat);
    for (std::size_t k = 0; k < y.size(); ++k) s.lag_cross[k] += std::conj(y[k]) * yhat[k];
  }
}

// Copies samples max(0, worst - B) .. last (at most 2 B + 1, all in the ring).
void ComparisonAccumulator::TakeSnapshot(ChannelState* s, long last) const {
  const long zoom_half = static_cast<long>(std::max(2, options_.max_zoom_samples));
  const std::size_t ring_size = s->ring_time.size();
  s->snapshot_start = std::max(0L, s->worst - zoom_half);
  s->snapshot.time_s.clear(), s->snapshot.measured.clear(), s->snapshot.model.clear();
  for (long i = s->snapshot_start; i <= last; ++i) {
    const std::size_t slot = static_cast<std::size_t>(i) % ring_size;
    s->snapshot.time_s.push_back(s->ring_time[slot]);
    s->snapshot.measured.push_back(s->ring_measured[slot]);
    s->snapshot.model.push_back(s->ring_model[slot]);
  }
  s->snapshot_due = false;
}

// The window [t_w - span/2, t_w + span/2] around the largest |residual| at t_w, moved inside the
// log, then trimmed to max_zoom_samples around it. Everything it can hold lies within B samples
// of the worst one, which the snapshot holds. Where the window reaches beyond the snapshot, it
// is longer than B, so it is trimmed, and the trimmed window depends only on its other end.
TraceWindow ComparisonAccumulator::Zoom(ChannelState* s) const {
  TraceWindow window;
  if (s->worst < 0) return window;
  if (s->snapshot_due) TakeSnapshot(s, summary_.samples - 1);
  const std::vector<double>& time = s->snapshot.time_s;
  const long start = s->snapshot_start;
  const double t_w = time[static_cast<std::size_t>(s->worst - start)];
  double lo = t_w - 0.5 * zoom_span_s_;
  double hi = t_w + 0.5 * zoom_span_s_;
  if (lo < summary_.t0_s) hi += summary_.t0_s - lo, lo = summary_.t0_s;
  if (hi > summary_.t1_s) lo -= hi - summary_.t1_s, hi = summary_.t1_s;
  long first = start + (std::lower_bound(time.begin(), time.end(), lo) - time.begin());
  long last = start + (std::upper_bound(time.begin(), time.end(), hi) - time.begin());
  const long max_count = std::max(2, options_.max_zoom_samples);
  if (last - first > max_count) {
    first = std::clamp(s->worst, first + max_count / 2, last - max_count / 2) - max_count / 2;
    last = first + max_count;
  }
  const auto from = static_cast<long>(first - start), to = static_cast<long>(last - start);
  window.time_s.assign(time.begin() + from, time.begin() + to);
  window.measured.assign(s->snapshot.measured.begin() + from, s->snapshot.measured.begin() + to);
  window.model.assign(s->snapshot.model.begin() + from, s->snapshot.model.begin() + to);
  return window;
}

Result<Comparison> ComparisonAccumulator::Finish(
    const std::string& path, const std::optional<RangeEvent>& first_range_event) {
  if (added_ != summary_.samples) {
    return Status::Error(path + ": " + std::to_string(added_) + " samples on the second pass, " +
                         std::to_string(summary_.samples) + " on the first (did the file change?)");
  }
  if (auto length = segmenter_.Finish()) AddSegment(*length);
  Comparison result = LogMetrics(path, first_range_event);
  double error_sum = 0.0;
  int error_count = 0;
  for (ChannelState& s : channels_) {
    ChannelMetrics metrics = SampleMetrics(s);
    if (std::isfinite(metrics.nrmse)) error_sum += metrics.nrmse, ++error_count;
    // A constant measurement (NaN NRMSE) has no lag to find: its correlation would be rounding.
    if (std::isfinite(metrics.nrmse)) {
      CalcLag(s, &metrics);
    } else {
      metrics.lag_s = metrics.lag_correlation = std::numeric_limits<double>::quiet_NaN();
    }
    metrics.bands = CalcBands(s);
    if (s.transfer) result.transfer_functions.push_back(CalcTransferFunction(s));
    metrics.residual = CalcResidualAnalysis(s, metrics);
    if (auto x_m = PipePositionM(metrics.channel)) {
      result.profile.push_back({metrics.channel, *x_m, metrics.nrmse, metrics.fit_percent,
                                metrics.rms_si, metrics.bias_si, metrics.lag_s});
    }
    metrics.envelope = std::move(s.envelope);
    metrics.zoom = Zoom(&s);
    result.channels.push_back(std::move(metrics));
  }
  result.error = error_count > 0 ? error_sum / error_count : kNaN;
  return result;
}

// What the whole log's comparison says before its channels.
Comparison ComparisonAccumulator::LogMetrics(
    const std::string& path, const std::optional<RangeEvent>& first_range_event) const {
  const double dt = summary_.sample_interval_s;
  Comparison result;
  result.path = path;
  result.samples = summary_.samples;
  result.input_close_up = input_close_up_;
  result.duration_s = summary_.t1_s - summary_.t0_s;
  result.sample_interval_s = dt;
  result.uniform_sampling = summary_.uniform_sampling;
  result.first_range_event = first_range_event;
  result.spectrum_segments = static_cast<long>(summary_.segments);
  result.spectrum_segment_s = static_cast<double>(summary_.segment_length) * dt;
  for (const auto& band : band_centres_) result.dominant_freqs_hz.push_back(band.first);
  result.max_lag_s = max_lag_s_;
  return result;
}

// NRMSE, fit, rms, bias and the measurement's mean and spread from the scalar sums.
ChannelMetrics ComparisonAccumulator::SampleMetrics(const ChannelState& s) const {
  const LogSummary::ChannelSummary& channel = *s.summary;
  ChannelMetrics metrics;
  metrics.channel = channel.channel;
  metrics.unit = channel.unit;
  const auto count = static_cast<double>(channel.count);
  metrics.samples = channel.count;
  metrics.measured_mean_si = channel.mean_si;
  metrics.measured_std_si = std::sqrt(s.sst / count);
  metrics.rms_si = std::sqrt(s.sse / count);
  metrics.bias_si = s.sum_e / count;
  // A constant measurement (within rounding: IsConstantSpread) has no variation to explain:
  // NRMSE undefined (NaN), the channel left out of the mean error. Dividing by a spread of
  // rounding gave "error 2e+10" on a log of identical rows.
  metrics.nrmse = IsConstantSpread(channel.channel, channel.mean_si, metrics.measured_std_si)
                      ? std::numeric_limits<double>::quiet_NaN()
                      : Nrmse(s.sse, s.sst);
  metrics.fit_percent = 100.0 * (1.0 - metrics.nrmse);
  return metrics;
}

// Lag: the averaged cross-correlation sum_segments sum_n a[n] b[n + k] (FFTW's inverse leaves out
// 1/size; negative k at index size + k; no wrap-around: size >= L + max_lag + 1), normalised and
// with the window's own correlation W(k) divided out. Left at 0 where either side is flat.
void ComparisonAccumulator::CalcLag(const ChannelState& s, ChannelMetrics* metrics) const {
  const double norm = std::sqrt(s.lag_aa * s.lag_bb);
  if (!(norm > 0.0)) return;
  const std::size_t size = lag_fft_size_;
  std::vector<double> raw;
  lag_fft_->Inverse(s.lag_cross, &raw);
  const long max_lag = static_cast<long>(max_lag_);
  const double w0 = window_correlation_[max_lag_];
  auto r = [&](long k) {
    const std::size_t index =
        k >= 0 ? static_cast<std::size_t>(k) : size - static_cast<std::size_t>(-k);
    return raw[index] / static_cast<double>(size) / norm * w0 /
           window_correlation_[static_cast<std::size_t>(k + max_lag)];
  };
  const long limit = std::min(max_lag, static_cast<long>(summary_.segment_length) - 2);
  long best = 0;
  for (long k = -limit; k <= limit; ++k) {
    if (r(k) > r(best)) best = k;
  }
  double offset = 0.0;
  if (best > -limit && best < limit) offset = ParabolicOffset(r(best - 1), r(best), r(best + 1));
  metrics->lag_s = (static_cast<double>(best) + offset) * summary_.sample_interval_s;
  metrics->lag_correlation = r(best);
}

// The bands, averaged over the segments this channel was measured in.
std::vector<BandMetrics> ComparisonAccumulator::CalcBands(const ChannelState& s) const {
  const double amplitude_scale =
      2.0 / std::sqrt(static_cast<double>(summary_.fft_size) * window_power_);
  const double segments = static_cast<double>(std::max<std::size_t>(1, s.segments));
  std::vector<BandMetrics> bands;
  for (std::size_t i = 0; i < band_centres_.size(); ++i) {
    const auto& [centre, harmonic] = band_centres_[i];
    BandMetrics band;
    band.freq_hz = centre;
    band.harmonic = harmonic;
    band.low_hz = std::max(0.0, centre - options_.band_half_width_bins * summary_.df_hz);
    band.high_hz = centre + options_.band_half_width_bins * summary_.df_hz;
    const double power_y = s.band_power_measured[i];
    const double power_model = s.band_power_model[i];
    const double power_error = s.band_power_error[i];
    // Parseval: a sinusoid A cos puts size (A/2)^2 sum w^2 into the positive-frequency bins.
    band.measured_amplitude = amplitude_scale * std::sqrt(power_y / segments);
    band.model_amplitude = amplitude_scale * std::sqrt(power_model / segments);
    band.magnitude_ratio = power_y > 0.0 ? std::sqrt(power_model / power_y) : kNaN;
    band.phase_diff_deg = WrapDeg(std::arg(s.band_cross[i]) * 180.0 / std::numbers::pi);
    band.band_nrmse = power_y > 0.0 ? std::sqrt(power_error / power_y) : kNaN;
    band.error_amplitude = amplitude_scale * std::sqrt(power_error / segments);
    bands.push_back(band);
  }
  return bands;
}

// The empirical transfer function from the piston, one point per group of excited bins.
TransferFunction ComparisonAccumulator::CalcTransferFunction(const ChannelState& s) const {
  TransferFunction tf;
  tf.output = s.summary->channel;
  for (std::size_t g = 0; g < s.transfer_power.size(); ++g) {
    const double power = s.transfer_power[g];
    if (!(power > 0.0)) continue;
    tf.points.push_back({s.transfer_freq_power[g] / power, s.transfer_measured[g] / power,
                         s.transfer_model[g] / power});
  }
  return tf;
}

// The lagged sums with the mask m: the channel's own where it has gaps; without gaps (m = 1)
// sums of all but the first or last j values of the shifted residual and of the inputs.
ComparisonAccumulator::MaskSums ComparisonAccumulator::CalcMaskSums(const ChannelState& s) const {
  MaskSums sums{s.dm, s.md, s.mm, s.mu};
  if (s.summary->has_gaps) return sums;
  const long n = summary_.samples;
  const std::size_t lags = static_cast<std::size_t>(options_.residual_lags);
  const std::size_t history = std::min<std::size_t>(lags, static_cast<std::size_t>(n));
  const double* tail = s.residual_history->data();  // newest first
  sums.dm.assign(lags + 1, 0.0), sums.md.assign(lags + 1, 0.0), sums.mm.assign(lags + 1, 0.0);
  double head_sum = 0.0, tail_sum = 0.0;
  for (std::size_t j = 0; j <= lags; ++j) {
    if (j > 0 && j <= history) head_sum += s.head[j - 1], tail_sum += tail[j - 1];
    sums.dm[j] = j < static_cast<std::size_t>(n) ? s.sum_shifted - head_sum : 0.0;
    sums.md[j] = j < static_cast<std::size_t>(n) ? s.sum_shifted - tail_sum : 0.0;
    sums.mm[j] =
        j < static_cast<std::size_t>(n) ? static_cast<double>(n - static_cast<long>(j)) : 0.0;
  }
  for (std::size_t i = 0; i < kResidualInputCount; ++i) {
    const double* input_tail = input_history_[i].data();
    sums.mu[i].assign(2 * lags + 2, 0.0);
    double head = 0.0, tail_u = 0.0;
    for (std::size_t j = 0; j <= lags; ++j) {
      if (j > 0 && j <= history) head += input_head_[i][j - 1], tail_u += input_tail[j - 1];
      if (j >= static_cast<std::size_t>(n)) continue;
      sums.mu[i][j] = input_sum_[i] - tail_u;           // k = j: u_0 .. u_{N-1-j}
      sums.mu[i][lags + 1 + j] = input_sum_[i] - head;  // k = -j: u_j .. u_{N-1}
    }
  }
  return sums;
}

// Residual e = m (d - c), c the mean of the shifted residual over the measured samples:
//   sum e_n e_{n-j} = dd - c (dm + md) + c^2 mm,  sum e_n u_{n-k} = du - c mu,
// normalised, against the 99% band.
ResidualAnalysis ComparisonAccumulator::CalcResidualAnalysis(const ChannelState& s,
                                                             const ChannelMetrics& metrics) const {
  const std::size_t lags = static_cast<std::size_t>(options_.residual_lags);
  const double confidence = kConfidence99 / std::sqrt(static_cast<double>(summary_.samples));
  const MaskSums mask = CalcMaskSums(s);
  const double c = -metrics.bias_si - s.shift;
  std::vector<double> ee(lags + 1);
  for (std::size_t j = 0; j <= lags; ++j) {
    ee[j] = s.dd[j] - c * (mask.dm[j] + mask.md[j]) + c * c * mask.mm[j];
  }
  ResidualAnalysis analysis;
  analysis.lags = options_.residual_lags;
  analysis.confidence = confidence;
  for (std::size_t j = 0; j <= lags; ++j) {
    analysis.autocorrelation.push_back(ee[0] > 0.0 ? ee[j] / ee[0] : 0.0);
  }
  for (std::size_t k = 1; k < analysis.autocorrelation.size(); ++k) {
    analysis.max_abs_autocorrelation =
        std::max(analysis.max_abs_autocorrelation, std::abs(analysis.autocorrelation[k]));
  }
  // A residual at round-off level (rms below 1e-9 of the measured signal's rms) is the text
  // round trip of the log's numbers, not dynamics: a perfect model, white and independent of
  // the inputs by definition.
  const double measured_rms = std::hypot(metrics.measured_mean_si, metrics.measured_std_si);
  const bool round_off = metrics.rms_si <= 1e-9 * measured_rms;
  analysis.white = round_off || analysis.max_abs_autocorrelation <= confidence;
  for (std::size_t i = 0; i < kResidualInputCount; ++i) {
    Correlation correlation;
    correlation.input = kResidualInputNames[i];
    correlation.constant_input = summary_.input_constant[i];
    if (!correlation.constant_input) {
      const double scale = std::sqrt(std::max(0.0, ee[0]) * input_square_sum_[i]);
      for (long k = -static_cast<long>(lags); k <= static_cast<long>(lags); ++k) {
        const std::size_t index =
            k >= 0 ? static_cast<std::size_t>(k) : lags + 1 + static_cast<std::size_t>(-k);
        correlation.r.push_back(scale > 0.0 ? (s.du[i][index] - c * mask.mu[i][index]) / scale
                                            : 0.0);
      }
      for (double r : correlation.r) {
        correlation.max_abs = std::max(correlation.max_abs, std::abs(r));
      }
      correlation.independent = round_off || correlation.max_abs <= confidence;
    }
    analysis.independent_of_inputs = analysis.independent_of_inputs && correlation.independent;
    analysis.cross.push_back(std::move(correlation));
  }
  return analysis;
}

}  // namespace mpdrig
