#include "model/analysis/empirical_response.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "model/signal/spectrum.h"

namespace mpdrig {
namespace {

using Complex = std::complex<double>;

// Removes the least-squares line a + b n and applies the window.
void DetrendAndWindow(const std::vector<double>& window, std::vector<double>* x) {
  const std::size_t n = x->size();
  const double mid = 0.5 * static_cast<double>(n - 1);
  double mean = 0.0, sxy = 0.0, sxx = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean += (*x)[i];
  mean /= static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) - mid;
    sxy += t * ((*x)[i] - mean);
    sxx += t * t;
  }
  const double slope = sxx > 0.0 ? sxy / sxx : 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    (*x)[i] = ((*x)[i] - mean - slope * (static_cast<double>(i) - mid)) * window[i];
  }
}

// Fills NaNs by linear interpolation (the ends by the nearest value); false if all are NaN.
bool FillGaps(std::vector<double>* x) {
  const std::size_t n = x->size();
  std::size_t last = n;  // last finite index seen
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite((*x)[i])) continue;
    if (last == n) {
      for (std::size_t j = 0; j < i; ++j) (*x)[j] = (*x)[i];
    } else {
      for (std::size_t j = last + 1; j < i; ++j) {
        const double w = static_cast<double>(j - last) / static_cast<double>(i - last);
        (*x)[j] = (1.0 - w) * (*x)[last] + w * (*x)[i];
      }
    }
    last = i;
  }
  if (last == n) return false;
  for (std::size_t j = last + 1; j < n; ++j) (*x)[j] = (*x)[last];
  return true;
}

// Where |H|^2 crosses half the peak's on one side of index i (direction -1 or +1); NaN if never.
double HalfPowerCrossing(const std::vector<EmpiricalPoint>& points, std::size_t i, int direction) {
  const double half = points[i].magnitude / std::numbers::sqrt2;
  long j = static_cast<long>(i);
  while (true) {
    const long next = j + direction;
    if (next < 0 || next >= static_cast<long>(points.size())) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    if (points[next].magnitude > points[i].magnitude)
      return std::numeric_limits<double>::quiet_NaN();
    if (points[next].magnitude <= half) {
      const double m0 = points[j].magnitude, m1 = points[next].magnitude;
      const double w = (m0 - half) / (m0 - m1);
      return points[j].freq_hz + w * (points[next].freq_hz - points[j].freq_hz);
    }
    j = next;
  }
}

// The lowest magnitude between i and the next higher point in `direction` (or the end).
double Valley(const std::vector<EmpiricalPoint>& points, std::size_t i, int direction) {
  double lowest = points[i].magnitude;
  for (long j = static_cast<long>(i) + direction; j >= 0 && j < static_cast<long>(points.size());
       j += direction) {
    if (points[j].magnitude > points[i].magnitude) break;
    lowest = std::min(lowest, points[j].magnitude);
  }
  return lowest;
}

}  // namespace

Status EmpiricalResponseOptions::Validate() const {
  if (!(segment_s > 0.0) || !std::isfinite(segment_s)) {
    return Status::Error("segment length must be a positive number of seconds");
  }
  if (!(fmin_hz > 0.0) || !(fmax_hz > fmin_hz) || !std::isfinite(fmax_hz)) {
    return Status::Error("need 0 < fmin < fmax");
  }
  if (!(min_coherence >= 0.0 && min_coherence < 1.0)) {
    return Status::Error("minimum coherence must be in [0, 1)");
  }
  if (!(min_prominence >= 1.0) || !std::isfinite(min_prominence)) {
    return Status::Error("minimum prominence must be >= 1");
  }
  return Status::Ok();
}

std::vector<ResonancePeak> FindResonancePeaks(const std::vector<EmpiricalPoint>& points,
                                              int segments,
                                              const EmpiricalResponseOptions& options) {
  std::vector<ResonancePeak> peaks;
  for (std::size_t i = 1; i + 1 < points.size(); ++i) {
    const EmpiricalPoint& p = points[i];
    if (p.coherence < options.min_coherence) continue;
    if (p.input_power_fraction < options.min_input_power_fraction) continue;
    if (!(p.magnitude > points[i - 1].magnitude && p.magnitude >= points[i + 1].magnitude))
      continue;
    const double valley = std::max(Valley(points, i, -1), Valley(points, i, +1));
    if (!(p.magnitude >= options.min_prominence * valley)) continue;
    const double df = points[i + 1].freq_hz - p.freq_hz;
    const double y0 = std::log(points[i - 1].magnitude), y1 = std::log(p.magnitude),
                 y2 = std::log(points[i + 1].magnitude);
    const double curvature = y0 - 2.0 * y1 + y2;  // < 0 at a maximum
    ResonancePeak peak;
    peak.freq_hz = p.freq_hz;
    if (curvature < 0.0) {
      peak.freq_hz += std::clamp(0.5 * (y0 - y2) / curvature, -0.5, 0.5) * df;
    }
    const double gamma = std::sqrt(std::max(p.coherence, 1e-12));
    const double eps = std::sqrt(std::max(0.0, 1.0 - p.coherence)) /
                       (gamma * std::sqrt(2.0 * std::max(1, segments)));
    const double u_stat = curvature < 0.0 ? df * eps / (std::numbers::sqrt2 * -curvature) : df;
    peak.uncertainty_hz = std::sqrt(u_stat * u_stat + df * df / 12.0);
    peak.magnitude = p.magnitude;
    peak.coherence = p.coherence;
    peak.half_power_width_hz = HalfPowerCrossing(points, i, +1) - HalfPowerCrossing(points, i, -1);
    peaks.push_back(peak);
  }
  return peaks;
}

Result<EmpiricalResponse> EstimateEmpiricalResponse(const riglog::RigLog& log,
                                                    const EmpiricalResponseOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  const std::vector<double>* piston = log.Find(riglog::Channel::kPistonPosition);
  if (piston == nullptr) return Status::Error("the log has no piston_position column");
  const std::size_t rows = log.num_rows();
  if (rows < 16) return Status::Error("the log has fewer than 16 rows");
  const double interval = (log.time_s.back() - log.time_s.front()) / static_cast<double>(rows - 1);
  for (std::size_t i = 1; i < rows; ++i) {
    const double d = log.time_s[i] - log.time_s[i - 1];
    if (std::fabs(d - interval) > 0.01 * interval) {
      return Status::Error("the empirical response needs uniform sampling; the interval at t = " +
                           std::to_string(log.time_s[i - 1]) + " s is " + std::to_string(d) +
                           " s against a mean of " + std::to_string(interval) + " s");
    }
  }
  EmpiricalResponse result;
  result.sample_rate_hz = 1.0 / interval;
  const std::size_t length = std::min(
      rows, static_cast<std::size_t>(std::llround(options.segment_s * result.sample_rate_hz)));
  if (length < 16) return Status::Error("the Welch segment holds fewer than 16 samples");
  const std::size_t hop = length / 2;
  std::vector<std::size_t> starts;
  for (std::size_t start = 0; start + length <= rows; start += hop) starts.push_back(start);
  result.segment_s = static_cast<double>(length) * interval;
  result.df_hz = 1.0 / result.segment_s;
  result.segments = static_cast<int>(starts.size());

  const std::vector<double> window = HannWindow(length);
  RealFft fft(length);
  const std::size_t bins = length / 2 + 1;
  const auto k_lo =
      static_cast<std::size_t>(std::max(1.0, std::ceil(options.fmin_hz / result.df_hz)));
  const auto k_hi = std::min(bins - 1, static_cast<std::size_t>(options.fmax_hz / result.df_hz));

  // The piston's spectra, once per segment.
  std::vector<std::vector<Complex>> piston_spectra;
  std::vector<bool> piston_ok;
  std::vector<double> segment;
  for (std::size_t start : starts) {
    segment.assign(piston->begin() + start, piston->begin() + start + length);
    piston_ok.push_back(FillGaps(&segment));
    DetrendAndWindow(window, &segment);
    piston_spectra.emplace_back();
    fft.Forward(segment, &piston_spectra.back());
  }

  std::vector<Complex> spectrum;
  for (std::size_t column = 0; column < log.columns.size(); ++column) {
    const auto channel = riglog::FindChannel(log.columns[column].channel);
    if (!channel || riglog::QuantityOf(*channel) != riglog::Quantity::kPressure) continue;
    const std::vector<double>& values = log.values_si[column];
    std::vector<Complex> syx(bins, 0.0);
    std::vector<double> sxx(bins, 0.0), syy(bins, 0.0);
    int used = 0;
    for (std::size_t s = 0; s < starts.size(); ++s) {
      if (!piston_ok[s]) continue;
      segment.assign(values.begin() + starts[s], values.begin() + starts[s] + length);
      if (!FillGaps(&segment)) continue;
      DetrendAndWindow(window, &segment);
      fft.Forward(segment, &spectrum);
      const std::vector<Complex>& x = piston_spectra[s];
      for (std::size_t k = k_lo; k <= k_hi; ++k) {
        syx[k] += spectrum[k] * std::conj(x[k]);
        sxx[k] += std::norm(x[k]);
        syy[k] += std::norm(spectrum[k]);
      }
      ++used;
    }
    if (used == 0) continue;
    ChannelResponse response;
    response.channel = log.columns[column].channel;
    double previous_phase = 0.0;
    for (std::size_t k = k_lo; k <= k_hi; ++k) {
      if (!(sxx[k] > 0.0)) continue;
      EmpiricalPoint point;
      point.freq_hz = static_cast<double>(k) * result.df_hz;
      point.h = syx[k] / sxx[k];
      point.magnitude = std::abs(point.h);
      double phase = std::arg(point.h) * 180.0 / std::numbers::pi;
      if (!response.points.empty()) {
        while (phase - previous_phase > 180.0) phase -= 360.0;
        while (phase - previous_phase < -180.0) phase += 360.0;
      }
      previous_phase = phase;
      point.phase_deg = phase;
      point.coherence = syy[k] > 0.0 ? std::norm(syx[k]) / (sxx[k] * syy[k]) : 0.0;
      response.points.push_back(point);
    }
    double largest = 0.0;
    for (std::size_t k = k_lo; k <= k_hi; ++k) largest = std::max(largest, sxx[k]);
    for (EmpiricalPoint& point : response.points) {
      const auto k = static_cast<std::size_t>(std::llround(point.freq_hz / result.df_hz));
      point.input_power_fraction = largest > 0.0 ? sxx[k] / largest : 0.0;
    }
    response.peaks = FindResonancePeaks(response.points, used, options);
    result.channels.push_back(std::move(response));
  }
  if (result.channels.empty()) return Status::Error("the log has no pressure channel");
  return result;
}

}  // namespace mpdrig
