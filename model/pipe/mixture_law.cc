#include "model/pipe/mixture_law.h"

#include <algorithm>
#include <cmath>

#include "model/common/status.h"

namespace mpdrig {
namespace {

constexpr double kLowestPressurePa = 1.0;
constexpr double kHighestPressurePa = 1.0e9;
constexpr int kIntervals = 8192;

}  // namespace

MixtureLaw::MixtureLaw(const PipeLaw& law, double density_kgpm3, double k_pa,
                       const std::function<double(double)>& extra_compressibility_per_pa)
    : model_(law.model()),
      c_(law.wave_speed_mps()),
      density_(density_kgpm3),
      k_(k_pa),
      extra_(extra_compressibility_per_pa),
      x_lo_(std::log(kLowestPressurePa)),
      step_((std::log(kHighestPressurePa) - std::log(kLowestPressurePa)) / kIntervals),
      w_(kIntervals + 1),
      slope_(kIntervals + 1) {
  // W(x_0) = 0; each interval by 3-point Gauss-Legendre (exact for degree 5: the integrand is
  // smooth in ln p, so the error per interval is ~ step^7).
  const double g = std::sqrt(0.6);
  w_[0] = 0.0;
  slope_[0] = Slope(x_lo_);
  for (int j = 0; j < kIntervals; ++j) {
    const double mid = x_lo_ + (j + 0.5) * step_;
    const double half = 0.5 * step_;
    const double integral =
        half * (5.0 * Slope(mid - g * half) + 8.0 * Slope(mid) + 5.0 * Slope(mid + g * half)) / 9.0;
    w_[j + 1] = w_[j] + integral;
    slope_[j + 1] = Slope(x_lo_ + (j + 1) * step_);
  }
  // The same origin as the model's invariants: W(p) = PressureTerm(p) where C_x = 0 (at p_bar
  // when nothing is added), so alpha and beta read the same as the base law's at rest.
  const double p_bar = law.PressureFromDifference(0.0);
  const double offset = law.PressureTerm(p_bar) - W(p_bar);
  for (double& w : w_) w += offset;
}

double MixtureLaw::LiquidDensity(double pressure_pa) const {
  // (5.2.1): rho = (k + p) / c^2 for the quasi-linear model; rho_ref for the linear one.
  return model_ == PipeModel::kLinear ? density_ : (k_ + pressure_pa) / (c_ * c_);
}

double MixtureLaw::Slope(double x) const {
  const double p = std::exp(x);
  const double rho = LiquidDensity(p);
  const double extra = extra_(p);
  MPDRIG_CHECK(extra >= 0.0 && "an extension may only add compressibility (slow the waves)");
  const double compressibility = 1.0 / (rho * c_ * c_) + extra;
  return p * std::sqrt(compressibility / rho);
}

double MixtureLaw::Interpolate(int j, double x, double* slope) const {
  // Cubic Hermite on [x_j, x_j+1] with the node values and slopes.
  const double t = (x - (x_lo_ + j * step_)) / step_;
  const double t2 = t * t;
  const double t3 = t2 * t;
  const double h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
  const double h10 = t3 - 2.0 * t2 + t;
  const double h01 = -2.0 * t3 + 3.0 * t2;
  const double h11 = t3 - t2;
  if (slope != nullptr) {
    const double d00 = (6.0 * t2 - 6.0 * t) / step_;
    const double d10 = 3.0 * t2 - 4.0 * t + 1.0;
    const double d01 = (-6.0 * t2 + 6.0 * t) / step_;
    const double d11 = 3.0 * t2 - 2.0 * t;
    *slope = d00 * w_[j] + d10 * slope_[j] + d01 * w_[j + 1] + d11 * slope_[j + 1];
  }
  return h00 * w_[j] + h10 * step_ * slope_[j] + h01 * w_[j + 1] + h11 * step_ * slope_[j + 1];
}

double MixtureLaw::W(double pressure_pa) const {
  const double x = std::log(std::max(pressure_pa, 1e-300));
  const double s = (x - x_lo_) / step_;
  if (s <= 0.0) return w_[0] + slope_[0] * (x - x_lo_);
  if (s >= kIntervals)
    return w_[kIntervals] + slope_[kIntervals] * (x - x_lo_ - kIntervals * step_);
  return Interpolate(std::min(static_cast<int>(s), kIntervals - 1), x, nullptr);
}

double MixtureLaw::WAndWaveSpeed(double pressure_pa, double* wave_speed_mps) const {
  const double p = std::max(pressure_pa, 1e-300);
  return WAndWaveSpeedAtLog(p, std::log(p), wave_speed_mps);
}

double MixtureLaw::WAndWaveSpeedAtLog(double pressure_pa, double log_pressure,
                                      double* wave_speed_mps) const {
  const double p = std::max(pressure_pa, 1e-300);
  const double x = log_pressure;
  const double s = (x - x_lo_) / step_;
  if (s <= 0.0 || s >= kIntervals) {
    *wave_speed_mps = WaveSpeed(p);
    return W(p);
  }
  double slope = 0.0;
  const double w = Interpolate(std::min(static_cast<int>(s), kIntervals - 1), x, &slope);
  *wave_speed_mps = p / (LiquidDensity(p) * slope);  // c = 1 / (rho dW/dp), dW/dp = slope / p
  return w;
}

double MixtureLaw::DW(double pressure_pa) const {
  const double p = std::max(pressure_pa, 1e-300);
  return Slope(std::log(p)) / p;
}

double MixtureLaw::WaveSpeed(double pressure_pa) const {
  return 1.0 / (LiquidDensity(pressure_pa) * DW(pressure_pa));
}

double MixtureLaw::Pressure(double w, double guess_pa) const {
  double log_pressure = 0.0;
  return PressureAndLog(w, guess_pa > 0.0 ? std::log(guess_pa) : kNoGuess, &log_pressure);
}

double MixtureLaw::PressureAndLog(double w, double guess_log_pressure, double* log_pressure) const {
  // Outside the table: the linear continuation inverts in closed form.
  if (w <= w_[0]) {
    *log_pressure = x_lo_ + (w - w_[0]) / slope_[0];
    return std::exp(*log_pressure);
  }
  if (w >= w_[kIntervals]) {
    *log_pressure = x_lo_ + kIntervals * step_ + (w - w_[kIntervals]) / slope_[kIntervals];
    return std::exp(*log_pressure);
  }
  // The interval: the guess's or its neighbour's (a solver step moves a node's pressure by a
  // fraction of an interval), else bisect the monotonic node values.
  int j = -1;
  if (std::isfinite(guess_log_pressure)) {
    const double s = (guess_log_pressure - x_lo_) / step_;
    if (s >= 0.0 && s < kIntervals) {
      const int k = static_cast<int>(s);
      if (w < w_[k]) {
        if (k > 0 && w_[k - 1] <= w) j = k - 1;
      } else if (w <= w_[k + 1]) {
        j = k;
      } else if (k + 1 < kIntervals && w <= w_[k + 2]) {
        j = k + 1;
      }
    }
  }
  if (j < 0) {
    j = static_cast<int>(std::upper_bound(w_.begin(), w_.end(), w) - w_.begin()) - 1;
    j = std::clamp(j, 0, kIntervals - 1);
  }
  // Start from the inverse's cubic Hermite on [W_j, W_j+1] (x(W) with dx/dW = 1 / slope at the
  // nodes): it differs from the inverse of W's cubic by O(step^4), about 1e-13 in ln p. Newton
  // on W's cubic then gains the square: from an error e the next is (W''/(2 W')) e^2, and
  // W''/W' = d ln(dW/dx)/dx is O(1) in ln p (1 where the liquid dominates, ~0 where the gas
  // does), so once a step is below 1e-8 the error left is below 1e-16, the round-off of x: one
  // step from this start, against three or four from a linear one. Kept inside the interval.
  double lo = x_lo_ + j * step_;
  double hi = lo + step_;
  const double dw = w_[j + 1] - w_[j];
  double x = lo + step_ * (w - w_[j]) / dw;
  if (slope_[j] > 0.0 && slope_[j + 1] > 0.0) {
    const double t = (w - w_[j]) / dw;
    const double t2 = t * t;
    const double t3 = t2 * t;
    const double hermite = (2.0 * t3 - 3.0 * t2 + 1.0) * lo + (t3 - 2.0 * t2 + t) * dw / slope_[j] +
                           (-2.0 * t3 + 3.0 * t2) * hi + (t3 - t2) * dw / slope_[j + 1];
    if (hermite >= lo && hermite <= hi) x = hermite;
  }
  for (int iteration = 0; iteration < 30; ++iteration) {
    double slope = 0.0;
    const double f = Interpolate(j, x, &slope) - w;
    if (f > 0.0) {
      hi = x;
    } else {
      lo = x;
    }
    double next = slope > 0.0 ? x - f / slope : lo - 1.0;
    const bool newton = next >= lo && next <= hi;  // else bisect (far from the root only)
    if (!newton) next = 0.5 * (lo + hi);
    if ((newton && std::fabs(next - x) <= 1e-8) || next == x) {
      x = next;
      break;
    }
    x = next;
  }
  *log_pressure = x;
  return std::exp(x);
}

}  // namespace mpdrig
