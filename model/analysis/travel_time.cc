#include "model/analysis/travel_time.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <sstream>

#include "model/analysis/measured_log.h"
#include "model/riglog/channels.h"
#include "model/signal/spectrum.h"

namespace mpdrig {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kTaperShare = 0.05;   // Tukey taper on each end of the window: 5 %,
constexpr double kTaperMaxS = 0.25;    // at most 0.25 s (it reweights the fronts inside it)
constexpr double kSearchShare = 0.25;  // a pair's peak is sought within 25 % of the stack's lag
constexpr double kOutlierMads = 4.0;
constexpr double kStackStep = 0.0025;  // relative step of the stack's grid in c
constexpr double kFineStepS = 1e-3;    // the correlation's grid: at most 1 ms, 4-16 per sample

// Linear interpolation over NaN runs; leading and trailing NaN take the nearest measured value.
// Returns the number of measured samples.
std::size_t BridgeGaps(std::vector<double>* values, const std::vector<double>& time_s) {
  std::vector<double>& v = *values;
  std::size_t measured = 0, last = v.size();
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (std::isnan(v[i])) continue;
    ++measured;
    if (last == v.size()) {
      for (std::size_t k = 0; k < i; ++k) v[k] = v[i];
    } else if (i > last + 1) {
      for (std::size_t k = last + 1; k < i; ++k) {
        const double w = (time_s[k] - time_s[last]) / (time_s[i] - time_s[last]);
        v[k] = (1.0 - w) * v[last] + w * v[i];
      }
    }
    last = i;
  }
  if (last != v.size()) {
    for (std::size_t k = last + 1; k < v.size(); ++k) v[k] = v[last];
  }
  return measured;
}

// Samples `values` (at `time_s`) at t0 + k dt, k = 0..count-1, linearly.
std::vector<double> Resample(const std::vector<double>& time_s, const std::vector<double>& values,
                             double t0, double dt, std::size_t count) {
  std::vector<double> out(count);
  std::size_t j = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const double t = t0 + dt * static_cast<double>(k);
    while (j + 2 < time_s.size() && time_s[j + 1] < t) ++j;
    const double w = std::clamp((t - time_s[j]) / (time_s[j + 1] - time_s[j]), 0.0, 1.0);
    out[k] = (1.0 - w) * values[j] + w * values[j + 1];
  }
  return out;
}

// Centred-difference derivative, Tukey-tapered at both ends.
std::vector<double> TaperedDerivative(const std::vector<double>& p, double dt) {
  const std::size_t n = p.size();
  std::vector<double> d(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t lo = i == 0 ? 0 : i - 1, hi = i + 1 == n ? i : i + 1;
    d[i] = (p[hi] - p[lo]) / (dt * static_cast<double>(hi - lo));
  }
  const std::size_t taper = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::min(kTaperShare * n, kTaperMaxS / dt)));
  for (std::size_t i = 0; i < taper && i < n; ++i) {
    const double w = 0.5 * (1.0 - std::cos(std::numbers::pi * static_cast<double>(i) / taper));
    d[i] *= w;
    d[n - 1 - i] *= w;
  }
  return d;
}

// A pair's normalised cross-correlation at lags -max_lag..max_lag samples.
struct Correlation {
  std::vector<double> r;  // r[max_lag + m] at lag m dt
  int max_lag = 0;
  double dt = 0.0;
  double At(double lag_s) const {  // linear between samples; 0 outside
    const double m = lag_s / dt + max_lag;
    if (m < 0.0 || m > static_cast<double>(r.size() - 1)) return 0.0;
    const std::size_t k = std::min(static_cast<std::size_t>(m), r.size() - 2);
    const double w = m - static_cast<double>(k);
    return (1.0 - w) * r[k] + w * r[k + 1];
  }
  double Largest() const { return *std::max_element(r.begin(), r.end()); }
  double null_sigma = 0.0;  // r's standard deviation at any lag were the two independent
};

// The peak of r nearest `lag_s` (signed) within kSearchShare of it: the largest sample in the
// window, refined by a parabola; NaN if it lies on the window's edge (no local maximum there) or
// below `floor`.
// `outer_half_width_s`: how far from the peak, away from lag 0, r falls to half the peak's
// height (the side no other direct peak leans on): the front's width as this pair sees it.
double PeakNear(const Correlation& c, double lag_s, double floor, double* height,
                double* outer_half_width_s) {
  const double centre = lag_s / c.dt + c.max_lag;
  const double half = std::max(8.0, kSearchShare * std::fabs(lag_s) / c.dt);
  const long lo = std::max(1L, std::lround(centre - half));
  const long hi = std::min(static_cast<long>(c.r.size()) - 2, std::lround(centre + half));
  if (lo >= hi) return kNaN;
  long best = lo;
  for (long k = lo; k <= hi; ++k) {
    if (c.r[k] > c.r[best]) best = k;
  }
  if (best == lo || best == hi || c.r[best] < floor) return kNaN;
  const double left = c.r[best - 1], mid = c.r[best], right = c.r[best + 1];
  const double curvature = left - 2.0 * mid + right;
  const double shift = curvature < 0.0 ? 0.5 * (left - right) / curvature : 0.0;
  *height = mid;
  const long outward = lag_s >= 0.0 ? 1 : -1;
  long k = best;
  while (k > 0 && k + 1 < static_cast<long>(c.r.size()) && c.r[k] > 0.5 * mid) k += outward;
  *outer_half_width_s = static_cast<double>(std::labs(k - best)) * c.dt;
  return (static_cast<double>(best) + shift - c.max_lag) * c.dt;
}

struct Fit {
  double slowness = kNaN;
  double slowness_se = kNaN;
  double residual_rms = kNaN;
};

Fit FitThroughOrigin(const std::vector<PairDelay>& pairs) {
  double sdd = 0.0, sdt = 0.0;
  int n = 0;
  for (const PairDelay& p : pairs) {
    if (!p.used) continue;
    sdd += p.distance_m * p.distance_m;
    sdt += p.distance_m * p.delay_s;
    ++n;
  }
  Fit fit;
  if (n < 2 || sdd <= 0.0) return fit;
  fit.slowness = sdt / sdd;
  double sse = 0.0;
  for (const PairDelay& p : pairs) {
    if (p.used) sse += std::pow(p.delay_s - fit.slowness * p.distance_m, 2);
  }
  fit.residual_rms = std::sqrt(sse / n);
  fit.slowness_se = std::sqrt(sse / (n - 1) / sdd);
  return fit;
}

}  // namespace

Status TravelTimeOptions::Validate() const {
  std::ostringstream out;
  if (!(min_wave_speed_mps > 0.0 && std::isfinite(max_wave_speed_mps) &&
        max_wave_speed_mps > min_wave_speed_mps)) {
    out << "the wave speeds searched need 0 < min < max, got " << min_wave_speed_mps << " and "
        << max_wave_speed_mps << " m/s";
  } else if (!(band_low_hz >= 0.0 && band_high_hz > band_low_hz && std::isfinite(band_high_hz))) {
    out << "the band needs 0 <= low < high, got " << band_low_hz << " and " << band_high_hz
        << " Hz";
  } else if (!(min_peak >= 0.0 && min_peak < 1.0)) {
    out << "min_peak must lie in [0, 1), got " << min_peak;
  } else if (!(window_begin_s < window_end_s)) {
    out << "the window's begin must lie before its end";
  } else {
    return Status::Ok();
  }
  return Status::Error(out.str());
}

std::vector<PressureTrace> PipeTransmitterTraces(const riglog::RigLog& log) {
  std::vector<PressureTrace> traces;
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    const Channel channel = static_cast<Channel>(static_cast<int>(Channel::kPT1) + k);
    const std::vector<double>* values = log.Find(channel);
    if (values == nullptr) continue;
    traces.push_back({std::string(riglog::ChannelName(channel)), *PipePositionM(channel), *values});
  }
  return traces;
}

Result<TravelTimeResult> EstimateTravelTime(const std::vector<double>& time_s,
                                            const std::vector<PressureTrace>& traces,
                                            const TravelTimeOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  // The window's samples.
  std::size_t first = 0, end = 0;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    if (time_s[i] < options.window_begin_s) first = i + 1;
    if (time_s[i] <= options.window_end_s) end = i + 1;
  }
  if (end < first + 16) {
    return Status::Error("fewer than 16 samples in the window: nothing to correlate");
  }
  const std::vector<double> times(time_s.begin() + first, time_s.begin() + end);
  const std::size_t n = times.size();
  const double dt = (times.back() - times.front()) / static_cast<double>(n - 1);

  // Transmitters with enough samples, ordered along the pipe.
  struct Series {
    std::string name;
    double x;
    std::vector<std::complex<double>> spectrum;
    double energy;
  };
  std::vector<PressureTrace> usable;
  for (const PressureTrace& trace : traces) {
    if (trace.pressure_pa.size() != time_s.size()) {
      return Status::Error(trace.name + " has " + std::to_string(trace.pressure_pa.size()) +
                           " samples for " + std::to_string(time_s.size()) + " time stamps");
    }
    PressureTrace cut{
        trace.name, trace.position_m,
        std::vector<double>(trace.pressure_pa.begin() + first, trace.pressure_pa.begin() + end)};
    if (2 * BridgeGaps(&cut.pressure_pa, times) < n) continue;
    usable.push_back(std::move(cut));
  }
  std::sort(usable.begin(), usable.end(), [](const PressureTrace& a, const PressureTrace& b) {
    return a.position_m < b.position_m;
  });
  if (usable.size() < 3) {
    return Status::Error("needs at least three pipe transmitters measured in the window (found " +
                         std::to_string(usable.size()) + ")");
  }
  for (std::size_t k = 1; k < usable.size(); ++k) {
    if (!(usable[k].position_m > usable[k - 1].position_m)) {
      return Status::Error(usable[k - 1].name + " and " + usable[k].name + " sit at one place");
    }
  }
  const double span_m = usable.back().position_m - usable.front().position_m;
  const int max_lag = static_cast<int>(std::ceil(span_m / options.min_wave_speed_mps / dt)) + 2;

  TravelTimeResult result;
  result.sample_rate_hz = 1.0 / dt;
  result.duration_s = times.back() - times.front();
  result.band_low_hz = options.band_low_hz;
  result.band_high_hz = std::min(options.band_high_hz, 0.4 * 0.5 / dt);
  if (!(result.band_high_hz > result.band_low_hz)) {
    return Status::Error("the sampling rate leaves no band above the low edge");
  }

  // Spectra of the tapered derivatives, with the band weight's square root on each.
  const std::size_t size = FastFftSize(n + static_cast<std::size_t>(max_lag) + 1);
  RealFft fft(size);
  std::vector<double> weight(size / 2 + 1);
  const double f_lo4 = std::pow(result.band_low_hz, 4);
  for (std::size_t k = 0; k < weight.size(); ++k) {
    const double f = static_cast<double>(k) / (static_cast<double>(size) * dt);
    const double f4 = f * f * f * f;
    const double w = (f4 + f_lo4 > 0.0 ? f4 / (f4 + f_lo4) : 1.0) *
                     std::exp(-std::pow(f / result.band_high_hz, 2));
    weight[k] = std::sqrt(w);
  }
  std::vector<Series> series;
  for (const PressureTrace& trace : usable) {
    const double t0 = times.front();
    std::vector<double> d = TaperedDerivative(Resample(times, trace.pressure_pa, t0, dt, n), dt);
    d.resize(size, 0.0);
    Series s{trace.name, trace.position_m, {}, 0.0};
    fft.Forward(d, &s.spectrum);
    for (std::size_t k = 0; k < s.spectrum.size(); ++k) {
      s.spectrum[k] *= weight[k];
      const double hermitian = (k == 0 || 2 * k == size) ? 1.0 : 2.0;
      s.energy += hermitian * std::norm(s.spectrum[k]);
    }
    if (!(s.energy > 0.0)) {
      return Status::Error(trace.name + " does not change in the window: no front to time");
    }
    result.transmitters.push_back(trace.name);
    series.push_back(std::move(s));
  }

  // Every pair's correlation, on a grid `upsample` times finer than the samples: the spectrum
  // zero-padded, i.e. band-limited interpolation, exact for the band-weighted correlation (its
  // weight is e^-4 at 2 f_hi <= 0.4 Nyquist), so the parabola at the peak is one of a fine grid.
  const std::size_t upsample =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(dt / kFineStepS)), 4, 16);
  const std::size_t fine_size = upsample * size;
  RealFft fine_fft(fine_size);
  const int fine_lag = max_lag * static_cast<int>(upsample);
  struct Pair {
    std::size_t i, j;
    double distance;
    Correlation c;
  };
  std::vector<Pair> pairs;
  std::vector<std::complex<double>> cross(fine_size / 2 + 1, 0.0);
  std::vector<double> lagged;
  for (std::size_t i = 0; i < series.size(); ++i) {
    for (std::size_t j = i + 1; j < series.size(); ++j) {
      for (std::size_t k = 0; k < series[i].spectrum.size(); ++k) {
        cross[k] = std::conj(series[i].spectrum[k]) * series[j].spectrum[k];
      }
      fine_fft.Inverse(cross, &lagged);
      Pair pair{i, j, series[j].x - series[i].x, {}};
      pair.c.max_lag = fine_lag;
      pair.c.dt = dt / static_cast<double>(upsample);
      pair.c.r.resize(2 * static_cast<std::size_t>(fine_lag) + 1);
      const double norm = std::sqrt(series[i].energy * series[j].energy);
      // Two independent series with these spectra: the normalised correlation at any lag has
      // variance sum S_i S_j / (sum S_i sum S_j) (each frequency an independent term).
      double product = 0.0;
      for (std::size_t k = 0; k < series[i].spectrum.size(); ++k) {
        const double hermitian = (k == 0 || 2 * k == size) ? 1.0 : 2.0;
        product += hermitian * std::norm(series[i].spectrum[k]) * std::norm(series[j].spectrum[k]);
      }
      pair.c.null_sigma = std::sqrt(product) / norm;
      for (int m = -fine_lag; m <= fine_lag; ++m) {
        const std::size_t index =
            m >= 0 ? static_cast<std::size_t>(m) : fine_size - static_cast<std::size_t>(-m);
        pair.c.r[static_cast<std::size_t>(m + fine_lag)] = lagged[index] / norm;
      }
      pairs.push_back(std::move(pair));
    }
  }

  // Delay-and-sum over a geometric grid in c, refined by a parabola in the slowness.
  std::vector<double> grid_s, stack;
  for (double c = options.min_wave_speed_mps; c <= options.max_wave_speed_mps;
       c *= 1.0 + kStackStep) {
    const double s = 1.0 / c;
    double sum = 0.0;
    for (const Pair& p : pairs) sum += p.c.At(s * p.distance) + p.c.At(-s * p.distance);
    grid_s.push_back(s);
    stack.push_back(sum);
  }
  const std::size_t best = std::max_element(stack.begin(), stack.end()) - stack.begin();
  double slowness = grid_s[best];
  if (best > 0 && best + 1 < stack.size()) {
    const double curvature = stack[best - 1] - 2.0 * stack[best] + stack[best + 1];
    if (curvature < 0.0) {
      const double shift = 0.5 * (stack[best - 1] - stack[best + 1]) / curvature;
      slowness = grid_s[best] + shift * (shift > 0.0 ? grid_s[best + 1] - grid_s[best]
                                                     : grid_s[best] - grid_s[best - 1]);
    }
  }
  result.stack_wave_speed_mps = 1.0 / slowness;

  // Each pair's peaks near the stack's lags, the fit, and once more around the fitted line.
  Fit fit;
  std::vector<double> widths;
  for (int pass = 0; pass < 2; ++pass) {
    result.pairs.clear();
    widths.clear();
    for (const Pair& p : pairs) {
      PairDelay delay;
      delay.first = series[p.i].name;
      delay.second = series[p.j].name;
      delay.distance_m = p.distance;
      const double lag = slowness * p.distance;
      const double floor = std::max(options.min_peak * std::max(p.c.Largest(), 0.0),
                                    options.min_peak_sigmas * p.c.null_sigma);
      double up_height = 0.0, down_height = 0.0, up_width = 0.0, down_width = 0.0;
      const double up = PeakNear(p.c, lag, floor, &up_height, &up_width);
      const double down = PeakNear(p.c, -lag, floor, &down_height, &down_width);
      const double width =
          std::max(std::isnan(up) ? 0.0 : up_width, std::isnan(down) ? 0.0 : down_width);
      delay.delay_up_s = up;
      delay.delay_down_s = -down;
      delay.peak_correlation = std::max(up_height, down_height);
      delay.peak_sigmas = delay.peak_correlation / p.c.null_sigma;
      if (!std::isnan(up) && !std::isnan(down)) {
        delay.delay_s = 0.5 * (up - down);
      } else if (!std::isnan(up)) {
        delay.delay_s = up;
      } else if (!std::isnan(down)) {
        delay.delay_s = -down;
      } else {
        delay.delay_s = kNaN;
        delay.note = "no peak near +-d/c";
      }
      if (!std::isnan(delay.delay_s)) widths.push_back(width);
      if (!std::isnan(delay.delay_s) && delay.delay_s < 2.0 * width) {
        delay.delay_s = kNaN;
        delay.note = "closer than the fronts are wide (d/c < 2 half widths of the peak)";
      }
      if (!std::isnan(delay.delay_s) && !(delay.delay_s > 0.0)) {
        delay.note = "peaks on the wrong sides";
        delay.delay_s = kNaN;
      }
      if (!std::isnan(delay.delay_s) &&
          (delay.distance_m / delay.delay_s < options.min_wave_speed_mps ||
           delay.distance_m / delay.delay_s > options.max_wave_speed_mps)) {
        delay.note = "delay outside the wave speeds searched";
      } else {
        delay.used = !std::isnan(delay.delay_s);
      }
      result.pairs.push_back(std::move(delay));
    }
    fit = FitThroughOrigin(result.pairs);
    if (std::isnan(fit.slowness)) break;
    // Outliers: beyond kOutlierMads (scaled) median absolute deviations of the residuals.
    std::vector<double> residuals;
    for (const PairDelay& p : result.pairs) {
      if (p.used) residuals.push_back(p.delay_s - fit.slowness * p.distance_m);
    }
    std::vector<double> sorted = residuals;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    for (double& r : sorted) r = std::fabs(r - median);
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double limit = kOutlierMads * 1.4826 * sorted[sorted.size() / 2];
    bool dropped = false;
    for (PairDelay& p : result.pairs) {
      if (p.used && limit > 0.0 &&
          std::fabs(p.delay_s - fit.slowness * p.distance_m - median) > limit) {
        p.used = false;
        p.note = "off the line (more than 4 MADs)";
        dropped = true;
      }
    }
    if (dropped) fit = FitThroughOrigin(result.pairs);
    if (std::isnan(fit.slowness)) break;
    slowness = fit.slowness;
  }
  result.pairs_used = static_cast<int>(std::count_if(result.pairs.begin(), result.pairs.end(),
                                                     [](const PairDelay& p) { return p.used; }));
  if (result.pairs_used < 3 || std::isnan(fit.slowness) || !(fit.slowness > 0.0)) {
    return Status::Error(
        "fewer than three pairs of transmitters show a clear front (" +
        std::to_string(result.pairs_used) +
        "): the log needs fast moves of the choke or the piston, or broadband excitation");
  }
  // The pairs share transmitters: only (transmitters - 1) delays are independent.
  const double dependence =
      std::sqrt(static_cast<double>(result.pairs_used) / static_cast<double>(series.size() - 1));
  result.wave_speed_mps = 1.0 / fit.slowness;
  result.wave_speed_uncertainty_mps =
      std::max(dependence, 1.0) * fit.slowness_se / (fit.slowness * fit.slowness);
  result.residual_rms_s = fit.residual_rms;
  std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
  result.front_width_s = widths[widths.size() / 2];
  return result;
}

std::vector<double> FindChokeMoves(const std::vector<double>& time_s,
                                   const std::vector<double>& opening_frac, double min_step_frac,
                                   double min_gap_s) {
  // Prefix sums over the measured samples, for window means in O(1).
  const std::size_t n = time_s.size();
  std::vector<double> sum(n + 1, 0.0), count(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const bool measured = i < opening_frac.size() && !std::isnan(opening_frac[i]);
    sum[i + 1] = sum[i] + (measured ? opening_frac[i] : 0.0);
    count[i + 1] = count[i] + (measured ? 1.0 : 0.0);
  }
  const auto index_at = [&](double t) {
    return static_cast<std::size_t>(std::lower_bound(time_s.begin(), time_s.end(), t) -
                                    time_s.begin());
  };
  const auto mean = [&](double t0, double t1) {
    const std::size_t a = index_at(t0), b = index_at(t1);
    const double c = count[b] - count[a];
    return c > 0.0 ? (sum[b] - sum[a]) / c : kNaN;
  };
  std::vector<double> step(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = time_s[i];
    if (t - 0.6 < time_s.front() || t + 0.6 > time_s.back()) continue;
    const double change = mean(t + 0.1, t + 0.6) - mean(t - 0.6, t - 0.1);
    step[i] = std::isnan(change) ? 0.0 : std::fabs(change);
  }
  std::vector<double> moves;
  std::size_t i = 0;
  while (i < n) {
    if (step[i] < min_step_frac) {
      ++i;
      continue;
    }
    // The largest step of this run of samples above the threshold.
    std::size_t best = i;
    for (; i < n && step[i] >= min_step_frac; ++i) {
      if (step[i] > step[best]) best = i;
    }
    if (moves.empty() || time_s[best] - moves.back() >= min_gap_s) moves.push_back(time_s[best]);
  }
  return moves;
}

std::vector<MoveTravelTime> TravelTimePerMove(const std::vector<double>& time_s,
                                              const std::vector<PressureTrace>& traces,
                                              const std::vector<double>& move_times_s,
                                              const TravelTimeOptions& options, double before_s,
                                              double after_s) {
  std::vector<MoveTravelTime> out;
  for (double t : move_times_s) {
    TravelTimeOptions window = options;
    window.window_begin_s = t - before_s;
    window.window_end_s = t + after_s;
    MoveTravelTime move;
    move.time_s = t;
    auto result = EstimateTravelTime(time_s, traces, window);
    if (result.ok()) {
      move.result = std::move(result).value();
    } else {
      move.status = result.status();
    }
    out.push_back(std::move(move));
  }
  return out;
}

}  // namespace mpdrig
