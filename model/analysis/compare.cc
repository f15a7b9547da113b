#include "model/analysis/compare.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <sstream>
#include <utility>

#include "model/analysis/spectrum.h"
#include "model/riglog/rig_log.h"
#include "model/riglog/rig_log_reader.h"

namespace mpdrig {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kConfidence99 = 2.58;  // two-sided 99% quantile of the standard normal
constexpr double kMaxLagCapS = 10.0;

void Report(const CompareProgress& progress, std::string_view stage, double fraction) {
  if (progress) progress(stage, fraction);
}

// Linear interpolation over NaN gaps (ends held), for the spectral quantities only.
std::vector<double> FillGaps(const std::vector<double>& values) {
  std::vector<double> out = values;
  const std::size_t n = out.size();
  std::size_t first = 0;
  while (first < n && !std::isfinite(out[first])) ++first;
  if (first == n) return std::vector<double>(n, 0.0);
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
  return out;
}

double Mean(const std::vector<double>& x) {
  if (x.empty()) return 0.0;
  // Kahan-free two-pass is enough: a mean of up to ~1e7 samples loses ~1e-9 relative.
  return std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

std::vector<double> MinusMean(std::vector<double> x) {
  const double mean = Mean(x);
  for (double& v : x) v -= mean;
  return x;
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

// ---- Reading ----------------------------------------------------------------------------------

// A column of unknown length read in fixed-size chunks: no vector doubling (which would hold up to
// twice every column while reading), and one contiguous copy per column at the end.
class ChunkedColumn {
 public:
  void Push(double value) {
    if (chunks_.empty() || chunks_.back().size() == kChunk) {
      chunks_.emplace_back();
      chunks_.back().reserve(kChunk);
    }
    chunks_.back().push_back(value);
  }
  std::vector<double> Release() {
    std::size_t total = 0;
    for (const auto& chunk : chunks_) total += chunk.size();
    std::vector<double> out;
    out.reserve(total);
    for (auto& chunk : chunks_) {
      out.insert(out.end(), chunk.begin(), chunk.end());
      std::vector<double>().swap(chunk);
    }
    chunks_.clear();
    return out;
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;
  std::vector<std::vector<double>> chunks_;
};

struct ColumnSlots {
  std::optional<std::size_t> piston, choke, pump, outlet;
  std::vector<std::pair<Channel, std::size_t>> compared;  // channel, reader column
};

}  // namespace

std::vector<Channel> ComparedChannels() {
  std::vector<Channel> channels = {Channel::kP1, Channel::kP2};
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    channels.push_back(static_cast<Channel>(static_cast<int>(Channel::kPT1) + k));
  }
  channels.insert(channels.end(), {Channel::kC2, Channel::kFT1, Channel::kFT3, Channel::kFT4});
  return channels;
}

std::optional<double> PipePositionM(Channel channel) {
  constexpr double kSpacingM = 100.0;
  const int k = static_cast<int>(channel) - static_cast<int>(Channel::kPT1);
  if (k < 0 || k >= kPipeTransmitterCount) return std::nullopt;
  return kSpacingM * k;
}

const ChannelMetrics* Comparison::Find(Channel channel) const {
  for (const ChannelMetrics& metrics : channels) {
    if (metrics.channel == channel) return &metrics;
  }
  return nullptr;
}

namespace {

Status CheckMeasuredLog(MeasuredLog* log) {
  if (log->inputs.time_s.size() < 4) {
    return Status::Error(log->path + ": needs at least 4 samples to compare");
  }
  // Keep only channels with at least one measured sample.
  std::erase_if(log->channels, [](const MeasuredChannel& channel) {
    return std::none_of(channel.values_si.begin(), channel.values_si.end(),
                        [](double v) { return std::isfinite(v); });
  });
  if (log->channels.empty()) {
    return Status::Error(log->path +
                         ": no measured channel to compare (P1 P2 PT1..PT10 C2 FT1 FT3 FT4)");
  }
  const std::vector<Channel> order = ComparedChannels();
  auto rank = [&](Channel channel) { return std::find(order.begin(), order.end(), channel); };
  std::sort(log->channels.begin(), log->channels.end(),
            [&](const MeasuredChannel& a, const MeasuredChannel& b) {
              return rank(a.channel) < rank(b.channel);
            });
  return Status::Ok();
}

}  // namespace

Result<MeasuredLog> LoadMeasuredLog(const std::string& path, const CompareProgress& progress) {
  auto opened = riglog::RigLogReader::Open(path);
  if (!opened.ok()) return opened.status();
  riglog::RigLogReader& reader = *opened;
  MeasuredLog log;
  log.path = path;
  log.metadata = reader.metadata();
  log.atmospheric_pressure_pa = reader.atmospheric_pressure_pa();
  const std::vector<riglog::ColumnSpec>& columns = reader.columns();
  const std::int64_t header_line = reader.line_number();
  ColumnSlots slots;
  slots.piston = reader.FindColumn("piston_position");
  slots.choke = reader.FindColumn("choke_position");
  slots.pump = reader.FindColumn("FT2");
  slots.outlet = reader.FindColumn("C1");
  for (const auto& [slot, name] :
       {std::pair{slots.piston, "piston_position"}, std::pair{slots.choke, "choke_position"}}) {
    if (!slot) {
      return Status::Error(path + ":" + std::to_string(header_line) +
                           ":1: required input column '" + name +
                           "_<unit>' is missing from the header");
    }
  }
  for (Channel channel : ComparedChannels()) {
    if (auto column = reader.FindColumn(riglog::ChannelName(channel))) {
      slots.compared.emplace_back(channel, *column);
      log.channels.push_back({channel, columns[*column].unit, {}});
    }
  }
  const double atmosphere = log.atmospheric_pressure_pa;
  // time, the four inputs, then the compared channels
  std::vector<ChunkedColumn> columns_read(5 + slots.compared.size());
  std::vector<double> row;
  double next_report_s = 0.0;
  while (true) {
    auto more = reader.Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    // Inputs must be measured on every row: the model cannot run on a gap.
    for (const auto& [slot, required] :
         {std::pair{slots.piston, true}, std::pair{slots.choke, true}, std::pair{slots.pump, false},
          std::pair{slots.outlet, false}}) {
      if (slot && !std::isfinite(row[*slot])) {
        std::ostringstream out;
        out << path << ":" << reader.line_number() << ": input column " << columns[*slot].name
            << " (column " << *slot + 1 << ") is not measured (empty or nan); the model needs "
            << (required ? "every" : "every (or no)") << " input sample";
        return Status::Error(out.str());
      }
    }
    columns_read[0].Push(row[reader.time_index()]);
    columns_read[1].Push(row[*slots.piston]);
    columns_read[2].Push(row[*slots.choke]);
    columns_read[3].Push(slots.pump ? row[*slots.pump] : 0.0);
    columns_read[4].Push(slots.outlet ? row[*slots.outlet] : atmosphere);
    for (std::size_t i = 0; i < slots.compared.size(); ++i) {
      columns_read[5 + i].Push(row[slots.compared[i].second]);
    }
    // The file's length is unknown while streaming: report every 100k samples.
    if (static_cast<double>(reader.samples_read()) >= next_report_s) {
      Report(progress, "read", -static_cast<double>(reader.samples_read()));
      next_report_s += 100000.0;
    }
  }
  log.inputs.time_s = columns_read[0].Release();
  log.inputs.piston_position_m = columns_read[1].Release();
  log.inputs.choke_opening_frac = columns_read[2].Release();
  log.inputs.pump_flow_m3ps = columns_read[3].Release();
  log.inputs.outlet_pressure_pa = columns_read[4].Release();
  for (std::size_t i = 0; i < slots.compared.size(); ++i) {
    log.channels[i].values_si = columns_read[5 + i].Release();
  }
  MPDRIG_RETURN_IF_ERROR(CheckMeasuredLog(&log));
  return log;
}

Result<MeasuredLog> MeasuredLogFromRigLog(const riglog::RigLog& rig_log, const std::string& path) {
  MeasuredLog log;
  log.path = path;
  log.metadata = rig_log.metadata;
  log.atmospheric_pressure_pa = rig_log.atmospheric_pressure_pa;
  auto inputs = InputColumnsFromLog(rig_log, path);
  if (!inputs.ok()) return inputs.status();
  log.inputs = std::move(inputs).value();
  for (Channel channel : ComparedChannels()) {
    if (auto column = rig_log.FindColumn(riglog::ChannelName(channel))) {
      log.channels.push_back({channel, rig_log.columns[*column].unit, rig_log.values_si[*column]});
    }
  }
  MPDRIG_RETURN_IF_ERROR(CheckMeasuredLog(&log));
  return log;
}

// ---- Replay -----------------------------------------------------------------------------------

Result<ModelTraces> ReplayModel(const MeasuredLog& log, const RigParams& params,
                                const SimulationOptions& sim_options, const ReplayOptions& replay,
                                const CompareProgress& progress) {
  SimulationOptions options = sim_options;
  options.choke_input = ChokeInput::kMeasured;
  auto signals = SignalsFromColumns(log.inputs, log.path, replay.piston_smoothing_s);
  if (!signals.ok()) return signals.status();
  const std::vector<double>& times = log.time_s();
  // Keep only the compared channels of each sample.
  ModelTraces traces;
  traces.values_si.assign(log.channels.size(), {});
  for (auto& values : traces.values_si) values.reserve(times.size());
  auto summary = SimulateEach(
      params, options, *signals, times,
      [&](const RigSample& sample) {
        for (std::size_t i = 0; i < log.channels.size(); ++i) {
          traces.values_si[i].push_back(sample.values[Index(log.channels[i].channel)]);
        }
      },
      [&progress](double fraction) { Report(progress, "simulate", fraction); });
  if (!summary.ok()) return summary.status();
  traces.time_step_s = summary->time_step_s;
  traces.steps = summary->steps;
  traces.first_range_event = summary->first_range_event;
  return traces;
}

// ---- Metrics ----------------------------------------------------------------------------------

namespace {

// Spectra of one series, Hann-windowed, mean removed.
struct Spectra {
  std::size_t n = 0;
  std::size_t fft_size = 0;
  double window_power = 0.0;  // sum w^2
  std::vector<double> window;
};

std::vector<std::complex<double>> WindowedSpectrum(const std::vector<double>& x,
                                                   const Spectra& setup) {
  std::vector<double> windowed = MinusMean(x);
  for (std::size_t i = 0; i < windowed.size(); ++i) windowed[i] *= setup.window[i];
  return RealDft(windowed, setup.fft_size);
}

struct Peak {
  double freq_hz;
  double power;
};

// The piston's dominant frequencies: the largest peak f0, its harmonics up to max_harmonics, and
// further local maxima above extra_peak_fraction of the largest power, away from those bands.
std::vector<std::pair<double, int>> DominantFrequencies(
    const std::vector<std::complex<double>>& piston, double df_hz, const CompareOptions& options) {
  std::vector<std::pair<double, int>> bands;
  const std::size_t bins = piston.size();
  if (bins < 8) return bands;
  std::vector<double> power(bins);
  for (std::size_t k = 0; k < bins; ++k) power[k] = std::norm(piston[k]);
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

// The Hann window's autocorrelation W(k) = sum_n w[n] w[n + k], |k| <= max_lag (index k +
// max_lag), which CrossCorrelationLag divides out.
struct LagSetup {
  std::size_t n = 0, max_lag = 0, fft_size = 0;
  const std::vector<double>* window = nullptr;
  std::vector<double> window_correlation;
};

LagSetup MakeLagSetup(const std::vector<double>& window, std::size_t max_lag) {
  LagSetup setup;
  setup.n = window.size();
  setup.max_lag = max_lag;
  setup.fft_size = FastFftSize(setup.n + max_lag + 1);
  setup.window = &window;
  std::vector<std::complex<double>> spectrum = RealDft(window, setup.fft_size);
  for (auto& value : spectrum) value = std::norm(value);
  const std::vector<double> raw = InverseRealDft(spectrum, setup.fft_size);
  for (long k = -static_cast<long>(max_lag); k <= static_cast<long>(max_lag); ++k) {
    const std::size_t index =
        k >= 0 ? static_cast<std::size_t>(k) : setup.fft_size - static_cast<std::size_t>(-k);
    setup.window_correlation.push_back(raw[index] / static_cast<double>(setup.fft_size));
  }
  return setup;
}

// The lag [s] of yhat behind y and the normalised correlation at the peak. Both series, mean
// removed, are Hann-windowed in their own time, correlated (FFT), and the window's own
// correlation W(k) is divided out:
//   r(k) = sum_n a[n] b[n + k] / W(k) * W(0) / sqrt(sum a^2 sum b^2),  a = w y, b = w yhat.
// Why the window: without it the correlation of a slow sine over a finite record carries an
// edge term (the partial period at the ends) that moves the peak by about T^2 / (4 pi^2 D)
// (T the period, D the record: 10 ms for 0.2 Hz over a minute); the Hann taper makes that term
// decay like (T / D)^3. Dividing by W(k) removes the taper's own pull towards k = 0.
std::pair<double, double> CrossCorrelationLag(const std::vector<double>& y,
                                              const std::vector<double>& yhat,
                                              const LagSetup& setup, double dt_s) {
  const std::size_t n = y.size();
  MPDRIG_CHECK(n == setup.n && yhat.size() == n);
  std::vector<double> a = MinusMean(y);
  std::vector<double> b = MinusMean(yhat);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] *= (*setup.window)[i];
    b[i] *= (*setup.window)[i];
  }
  const double norm = std::sqrt(std::inner_product(a.begin(), a.end(), a.begin(), 0.0) *
                                std::inner_product(b.begin(), b.end(), b.begin(), 0.0));
  if (!(norm > 0.0)) return {0.0, 0.0};
  const std::size_t size = setup.fft_size;
  std::vector<std::complex<double>> spectrum = RealDft(a, size);
  std::vector<double>().swap(a);
  {
    const std::vector<std::complex<double>> model = RealDft(b, size);
    for (std::size_t k = 0; k < spectrum.size(); ++k)
      spectrum[k] = std::conj(spectrum[k]) * model[k];
  }
  std::vector<double>().swap(b);
  const std::vector<double> raw = InverseRealDft(spectrum, size);
  const long max_lag = static_cast<long>(setup.max_lag);
  const double w0 = setup.window_correlation[setup.max_lag];
  // FFTW leaves out the 1/size of the inverse: raw[k] = size * sum_n a[n] b[n + k], with
  // negative k at index size + k (no wrap-around: size >= n + max_lag + 1).
  auto r = [&](long k) {
    const std::size_t index =
        k >= 0 ? static_cast<std::size_t>(k) : size - static_cast<std::size_t>(-k);
    return raw[index] / static_cast<double>(size) / norm * w0 /
           setup.window_correlation[static_cast<std::size_t>(k + max_lag)];
  };
  const long limit = std::min(max_lag, static_cast<long>(n) - 2);
  long best = 0;
  for (long k = -limit; k <= limit; ++k) {
    if (r(k) > r(best)) best = k;
  }
  double offset = 0.0;
  if (best > -limit && best < limit) offset = ParabolicOffset(r(best - 1), r(best), r(best + 1));
  return {(static_cast<double>(best) + offset) * dt_s, r(best)};
}

// sum_n e[n] u[n - k] / (N sigma_e sigma_u), both with mean removed; k in [-M, M].
std::vector<double> Correlate(const std::vector<double>& e, const std::vector<double>& u, int lags,
                              bool symmetric) {
  const long n = static_cast<long>(e.size());
  const double ee = std::inner_product(e.begin(), e.end(), e.begin(), 0.0);
  const double uu = std::inner_product(u.begin(), u.end(), u.begin(), 0.0);
  const double scale = std::sqrt(ee * uu);
  std::vector<double> r;
  for (long k = symmetric ? -lags : 0; k <= lags; ++k) {
    double sum = 0.0;
    const long lo = std::max(0L, k), hi = std::min(n, n + k);
    for (long i = lo; i < hi; ++i) sum += e[i] * u[i - k];
    r.push_back(scale > 0.0 ? sum / scale : 0.0);
  }
  return r;
}

TraceEnvelope Envelope(const std::vector<double>& time_s, const std::vector<double>& measured,
                       const std::vector<double>& model, int columns) {
  TraceEnvelope env;
  env.t0_s = time_s.front();
  env.t1_s = time_s.back();
  const std::size_t count = static_cast<std::size_t>(std::max(1, columns));
  for (auto* v : {&env.measured_min, &env.model_min, &env.residual_min}) v->assign(count, kNaN);
  for (auto* v : {&env.measured_max, &env.model_max, &env.residual_max}) v->assign(count, kNaN);
  const double span = env.t1_s - env.t0_s;
  auto update = [](double value, double* lo, double* hi) {
    if (!std::isfinite(value)) return;
    if (!(*lo <= value)) *lo = value;
    if (!(*hi >= value)) *hi = value;
  };
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    std::size_t c =
        span > 0.0 ? static_cast<std::size_t>((time_s[i] - env.t0_s) / span * count) : 0;
    c = std::min(c, count - 1);
    update(measured[i], &env.measured_min[c], &env.measured_max[c]);
    update(model[i], &env.model_min[c], &env.model_max[c]);
    update(measured[i] - model[i], &env.residual_min[c], &env.residual_max[c]);
  }
  return env;
}

TraceWindow Zoom(const std::vector<double>& time_s, const std::vector<double>& measured,
                 const std::vector<double>& model, double span_s, int max_samples) {
  std::size_t worst = 0;
  double worst_abs = -1.0;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    const double e = std::abs(measured[i] - model[i]);
    if (std::isfinite(e) && e > worst_abs) worst_abs = e, worst = i;
  }
  // The window [t_w - span/2, t_w + span/2], moved inside the log, then trimmed to max_samples.
  double lo = time_s[worst] - 0.5 * span_s;
  double hi = time_s[worst] + 0.5 * span_s;
  if (lo < time_s.front()) hi += time_s.front() - lo, lo = time_s.front();
  if (hi > time_s.back()) lo -= hi - time_s.back(), hi = time_s.back();
  auto first =
      static_cast<std::size_t>(std::lower_bound(time_s.begin(), time_s.end(), lo) - time_s.begin());
  auto last =
      static_cast<std::size_t>(std::upper_bound(time_s.begin(), time_s.end(), hi) - time_s.begin());
  const auto max_count = static_cast<std::size_t>(std::max(2, max_samples));
  if (last - first > max_count) {
    first = std::clamp(worst, first + max_count / 2, last - max_count / 2) - max_count / 2;
    last = first + max_count;
  }
  TraceWindow window;
  window.time_s.assign(time_s.begin() + first, time_s.begin() + last);
  window.measured.assign(measured.begin() + first, measured.begin() + last);
  window.model.assign(model.begin() + first, model.begin() + last);
  return window;
}

// Empirical transfer function from the piston to one output: H = Y / U at the bins where the
// piston has power; if there are more than max_points, bins are pooled in log-spaced groups as
// sum(Y conj U) / sum |U|^2 (a smoothed ETFE).
std::vector<TransferPoint> TransferPoints(const std::vector<std::complex<double>>& piston,
                                          const std::vector<std::complex<double>>& measured,
                                          const std::vector<std::complex<double>>& model,
                                          double df_hz, const CompareOptions& options) {
  double max_power = 0.0;
  for (std::size_t k = 2; k < piston.size(); ++k)
    max_power = std::max(max_power, std::norm(piston[k]));
  std::vector<std::size_t> excited;
  for (std::size_t k = 2; k < piston.size(); ++k) {
    if (std::norm(piston[k]) >= options.transfer_min_power_fraction * max_power &&
        max_power > 0.0) {
      excited.push_back(k);
    }
  }
  std::vector<TransferPoint> points;
  if (excited.empty()) return points;
  const std::size_t max_points = static_cast<std::size_t>(std::max(1, options.transfer_points));
  // Group boundaries: log-spaced in bin index between the first and last excited bin.
  const double lo = std::log(static_cast<double>(excited.front()));
  const double hi = std::log(static_cast<double>(excited.back()) + 1.0);
  auto group_of = [&](std::size_t k) {
    if (excited.size() <= max_points) return k;  // every excited bin is a point
    return static_cast<std::size_t>((std::log(static_cast<double>(k)) - lo) / (hi - lo) *
                                    static_cast<double>(max_points));
  };
  std::size_t current = group_of(excited.front());
  std::complex<double> sum_measured = 0.0, sum_model = 0.0;
  double sum_power = 0.0, sum_freq_power = 0.0;
  auto flush = [&]() {
    if (sum_power > 0.0) {
      points.push_back(
          {sum_freq_power / sum_power, sum_measured / sum_power, sum_model / sum_power});
    }
    sum_measured = sum_model = 0.0;
    sum_power = sum_freq_power = 0.0;
  };
  for (std::size_t k : excited) {
    const std::size_t group = group_of(k);
    if (group != current) {
      flush();
      current = group;
    }
    const double power = std::norm(piston[k]);
    sum_measured += measured[k] * std::conj(piston[k]);
    sum_model += model[k] * std::conj(piston[k]);
    sum_power += power;
    sum_freq_power += power * static_cast<double>(k) * df_hz;
  }
  flush();
  return points;
}

}  // namespace

Result<Comparison> CompareTraces(const MeasuredLog& log, const ModelTraces& model,
                                 const CompareOptions& options, const CompareProgress& progress) {
  const std::vector<double>& time = log.time_s();
  const std::size_t n = time.size();
  if (model.values_si.size() != log.channels.size()) {
    return Status::Error("model traces: " + std::to_string(model.values_si.size()) +
                         " channels for " + std::to_string(log.channels.size()) + " measured");
  }
  for (const auto& values : model.values_si) {
    if (values.size() != n) return Status::Error("model traces: length differs from the log's");
  }
  if (n < 4) return Status::Error(log.path + ": needs at least 4 samples to compare");
  if (options.residual_lags < 1 || options.trace_columns < 1 || options.band_half_width_bins < 1) {
    return Status::Error(
        "compare options: residual_lags, trace_columns and band_half_width_bins "
        "must be >= 1");
  }

  Comparison result;
  result.path = log.path;
  result.samples = static_cast<long>(n);
  result.duration_s = time.back() - time.front();
  const double dt = result.duration_s / static_cast<double>(n - 1);
  result.sample_interval_s = dt;
  for (std::size_t i = 1; i < n; ++i) {
    if (std::abs(time[i] - time[i - 1] - dt) > 0.01 * dt) {
      result.uniform_sampling = false;
      break;
    }
  }
  result.first_range_event = model.first_range_event;

  // The piston spectrum (the model's smoothed position, as it was fed) and its peaks.
  Spectra setup;
  setup.n = n;
  setup.fft_size = FastFftSize(n);
  setup.window = HannWindow(n);
  setup.window_power =
      std::inner_product(setup.window.begin(), setup.window.end(), setup.window.begin(), 0.0);
  const double df_hz = 1.0 / (static_cast<double>(setup.fft_size) * dt);
  const std::vector<double> piston_position =
      SmoothedPistonPosition(log.inputs, options.piston_smoothing_s);
  const std::vector<std::complex<double>> piston_spectrum =
      WindowedSpectrum(piston_position, setup);
  const auto band_centres = DominantFrequencies(piston_spectrum, df_hz, options);
  for (const auto& band : band_centres) result.dominant_freqs_hz.push_back(band.first);
  double max_lag_s = options.max_lag_s;
  if (!(max_lag_s > 0.0)) {
    max_lag_s = kMaxLagCapS;
    for (const auto& band : band_centres) {
      if (band.second == 1) max_lag_s = std::min(max_lag_s, 0.5 / band.first);
    }
  }
  result.max_lag_s = max_lag_s;
  const std::size_t max_lag =
      std::min(n / 2, static_cast<std::size_t>(std::max(1.0, std::floor(max_lag_s / dt))));

  const LagSetup lag_setup = MakeLagSetup(setup.window, max_lag);

  // Inputs for the residual analysis, mean removed.
  std::vector<double> piston_velocity(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1 == n ? i : i + 1;
    piston_velocity[i] = (piston_position[b] - piston_position[a]) / (time[b] - time[a]);
  }
  const std::vector<std::pair<std::string, std::vector<double>>> inputs = {
      {"piston_velocity", MinusMean(piston_velocity)},
      {"piston_position", MinusMean(piston_position)},
      {"choke_position", MinusMean(log.inputs.choke_opening_frac)},
  };
  std::vector<bool> input_constant;
  for (const auto& input : inputs) {
    const auto [lo, hi] = std::minmax_element(input.second.begin(), input.second.end());
    input_constant.push_back(!(*hi - *lo > 1e-12 * std::max(1.0, std::abs(*hi))));
  }
  const double confidence = kConfidence99 / std::sqrt(static_cast<double>(n));
  double zoom_span_s = 10.0;
  for (const auto& band : band_centres) {
    if (band.second == 1) zoom_span_s = options.zoom_periods / band.first;
  }

  double error_sum = 0.0;
  int error_count = 0;
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    const MeasuredChannel& measured = log.channels[c];
    const std::vector<double>& y = measured.values_si;
    const std::vector<double>& yhat = model.values_si[c];
    ChannelMetrics metrics;
    metrics.channel = measured.channel;
    metrics.unit = measured.unit;

    // Scalar metrics over the measured samples.
    double sum_y = 0.0;
    long count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (std::isfinite(y[i])) sum_y += y[i], ++count;
    }
    const double mean_y = sum_y / static_cast<double>(count);
    double sse = 0.0, sst = 0.0, sum_e = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(y[i])) continue;
      const double e = yhat[i] - y[i];
      sse += e * e;
      sum_e += e;
      sst += (y[i] - mean_y) * (y[i] - mean_y);
    }
    metrics.samples = count;
    metrics.measured_mean_si = mean_y;
    metrics.measured_std_si = std::sqrt(sst / static_cast<double>(count));
    metrics.rms_si = std::sqrt(sse / static_cast<double>(count));
    metrics.bias_si = sum_e / static_cast<double>(count);
    // A constant measurement has no variation to explain: NRMSE undefined (NaN).
    metrics.nrmse = sst > 0.0 ? std::sqrt(sse / sst) : kNaN;
    metrics.fit_percent = 100.0 * (1.0 - metrics.nrmse);
    if (std::isfinite(metrics.nrmse)) error_sum += metrics.nrmse, ++error_count;

    // Lag, bands, transfer functions: gap-filled series.
    const std::vector<double> y_filled = FillGaps(y);
    const auto [lag_s, lag_r] = CrossCorrelationLag(y_filled, yhat, lag_setup, dt);
    metrics.lag_s = lag_s;
    metrics.lag_correlation = lag_r;
    const std::vector<std::complex<double>> spectrum_y = WindowedSpectrum(y_filled, setup);
    const std::vector<std::complex<double>> spectrum_model = WindowedSpectrum(yhat, setup);
    for (const auto& [centre, harmonic] : band_centres) {
      BandMetrics band;
      band.freq_hz = centre;
      band.harmonic = harmonic;
      band.low_hz = std::max(0.0, centre - options.band_half_width_bins * df_hz);
      band.high_hz = centre + options.band_half_width_bins * df_hz;
      double power_y = 0.0, power_model = 0.0, power_error = 0.0;
      std::complex<double> cross = 0.0;
      const auto k_lo = static_cast<std::size_t>(std::ceil(band.low_hz / df_hz));
      const auto k_hi = std::min(spectrum_y.size() - 1,
                                 static_cast<std::size_t>(std::floor(band.high_hz / df_hz)));
      for (std::size_t k = k_lo; k <= k_hi; ++k) {
        power_y += std::norm(spectrum_y[k]);
        power_model += std::norm(spectrum_model[k]);
        power_error += std::norm(spectrum_model[k] - spectrum_y[k]);
        cross += spectrum_model[k] * std::conj(spectrum_y[k]);
      }
      // Parseval: a sinusoid A cos puts size (A/2)^2 sum w^2 into the positive-frequency bins.
      const double amplitude_scale =
          2.0 / std::sqrt(static_cast<double>(setup.fft_size) * setup.window_power);
      band.measured_amplitude = amplitude_scale * std::sqrt(power_y);
      band.model_amplitude = amplitude_scale * std::sqrt(power_model);
      band.magnitude_ratio = power_y > 0.0 ? std::sqrt(power_model / power_y) : kNaN;
      band.phase_diff_deg = WrapDeg(std::arg(cross) * 180.0 / std::numbers::pi);
      band.band_nrmse = power_y > 0.0 ? std::sqrt(power_error / power_y) : kNaN;
      band.error_amplitude = amplitude_scale * std::sqrt(power_error);
      metrics.bands.push_back(band);
    }
    if (measured.channel == Channel::kPT1 || measured.channel == Channel::kC2) {
      result.transfer_functions.push_back(
          {measured.channel,
           TransferPoints(piston_spectrum, spectrum_y, spectrum_model, df_hz, options)});
    }

    // Residual analysis.
    std::vector<double> residual(n);
    for (std::size_t i = 0; i < n; ++i) {
      residual[i] = std::isfinite(y[i]) ? y[i] - yhat[i] : kNaN;
    }
    const double residual_mean = -metrics.bias_si;
    for (double& e : residual) e = std::isfinite(e) ? e - residual_mean : 0.0;
    ResidualAnalysis& analysis = metrics.residual;
    analysis.lags = options.residual_lags;
    analysis.confidence = confidence;
    analysis.autocorrelation = Correlate(residual, residual, options.residual_lags, false);
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
    for (std::size_t u = 0; u < inputs.size(); ++u) {
      Correlation correlation;
      correlation.input = inputs[u].first;
      correlation.constant_input = input_constant[u];
      if (!correlation.constant_input) {
        correlation.r = Correlate(residual, inputs[u].second, options.residual_lags, true);
        for (double r : correlation.r)
          correlation.max_abs = std::max(correlation.max_abs, std::abs(r));
        correlation.independent = round_off || correlation.max_abs <= confidence;
      }
      analysis.independent_of_inputs = analysis.independent_of_inputs && correlation.independent;
      analysis.cross.push_back(std::move(correlation));
    }

    if (auto x_m = PipePositionM(metrics.channel)) {
      result.profile.push_back({metrics.channel, *x_m, metrics.nrmse, metrics.fit_percent,
                                metrics.rms_si, metrics.bias_si, metrics.lag_s});
    }
    metrics.envelope = Envelope(time, y, yhat, options.trace_columns);
    metrics.zoom = Zoom(time, y, yhat, zoom_span_s, options.max_zoom_samples);
    result.channels.push_back(std::move(metrics));
    Report(progress, "analyse", static_cast<double>(c + 1) / log.channels.size());
  }
  result.error = error_count > 0 ? error_sum / error_count : kNaN;
  return result;
}

Result<Comparison> CompareLog(const std::string& path, const RigParams& params,
                              const SimulationOptions& sim_options, const CompareOptions& options,
                              const CompareProgress& progress) {
  auto log = LoadMeasuredLog(path, progress);
  if (!log.ok()) return log.status();
  ReplayOptions replay;
  replay.piston_smoothing_s = options.piston_smoothing_s;
  auto model = ReplayModel(*log, params, sim_options, replay, progress);
  if (!model.ok()) return model.status();
  return CompareTraces(*log, *model, options, progress);
}

}  // namespace mpdrig
