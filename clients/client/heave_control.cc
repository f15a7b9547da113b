#include "clients/client/heave_control.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mpdrig::client {

using Complex = std::complex<double>;

Complex HeaveCanceller::Phasor(const Estimate& e) {
  return Complex(e.piston_velocity_est_mps,
                 2.0 * std::numbers::pi * e.disturbance_frequency_hz * e.piston_position_est_m);
}

double HeaveCanceller::Update(double error_bar, Complex z, double frequency_hz, double dt_s) {
  if (!(frequency_hz > 0.0 && std::abs(z) > 1e-4)) return 0.0;
  const double omega = 2.0 * std::numbers::pi * frequency_hz;
  const Complex plant = -o_.choke_gain_bar_per_deg * std::exp(Complex(0.0, -omega * o_.delay_s));
  const Complex demodulated = 2.0 * error_bar * std::conj(z) / std::norm(z);
  theta_ -= o_.adapt_per_s * dt_s * demodulated / plant;
  return (theta_ * z).real();
}

bool SetpointLearner::Add(double t_s, double bhp_barg, double choke_deg, double frequency_hz) {
  if (learnt()) return true;
  if (!first_t_s_) first_t_s_ = t_s;
  const double settle_s =
      std::max(o_.settle_s, frequency_hz > 0.0 ? kSettlePeriods / frequency_hz : 0.0);
  if (!learn_start_s_ && t_s - *first_t_s_ < settle_s) return false;
  if (!learn_start_s_) {
    // The window: learn_s rounded to whole periods of the heave's frequency as it is now (the
    // estimate's: a commanded sine, or the tracker's lock after the settling), at least one.
    learn_start_s_ = t_s;
    learn_end_s_ = t_s + (frequency_hz > 0.0
                              ? std::max(1.0, std::round(o_.learn_s * frequency_hz)) / frequency_hz
                              : o_.learn_s);
  }
  // The samples in [start, end): the sample at the end belongs to the next period.
  if (t_s >= *learn_end_s_ - 1e-9) {
    const double n = static_cast<double>(n_);
    setpoint_barg_ = n_ > 0 ? sum_ / n : bhp_barg;
    choke_deg_ = n_ > 0 ? choke_sum_ / n : choke_deg;
    return true;
  }
  sum_ += bhp_barg;
  choke_sum_ += choke_deg;
  ++n_;
  return false;
}

void HeaveFit::Add(double t_s, double y, double frequency_hz) {
  if (!(frequency_hz > 0.0)) return;
  if (frequency_hz_ == 0.0) frequency_hz_ = frequency_hz;
  double basis[kTerms];
  Basis(t_s, basis);
  for (int i = 0; i < kTerms; ++i) {
    for (int j = 0; j < kTerms; ++j) normal_[i][j] += basis[i] * basis[j];
    right_[i] += basis[i] * y;
  }
  ++n_;
}

std::pair<double, double> HeaveFit::Amplitudes() const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (n_ < 4 * kTerms) return {nan, nan};
  double coefficients[kTerms];
  if (!Solve(coefficients)) return {nan, nan};
  double power = 0.0;
  for (int k = 1; k <= kHarmonics; ++k) {
    power += coefficients[2 * k - 1] * coefficients[2 * k - 1] +
             coefficients[2 * k] * coefficients[2 * k];
  }
  return {std::hypot(coefficients[1], coefficients[2]), std::sqrt(power / 2.0)};
}

void HeaveFit::Basis(double t_s, double* basis) const {
  const double omega = 2.0 * std::numbers::pi * frequency_hz_;
  basis[0] = 1.0;
  for (int k = 1; k <= kHarmonics; ++k) {
    basis[2 * k - 1] = std::cos(k * omega * t_s);
    basis[2 * k] = std::sin(k * omega * t_s);
  }
}

// Gaussian elimination with partial pivoting on the normal equations (7 x 7, well conditioned
// over a window of a period or more); false if singular. Written out so that a client needs
// nothing but the client library.
bool HeaveFit::Solve(double* x) const {
  double a[kTerms][kTerms + 1];
  for (int i = 0; i < kTerms; ++i) {
    for (int j = 0; j < kTerms; ++j) a[i][j] = normal_[i][j];
    a[i][kTerms] = right_[i];
  }
  for (int col = 0; col < kTerms; ++col) {
    int pivot = col;
    for (int row = col + 1; row < kTerms; ++row) {
      if (std::abs(a[row][col]) > std::abs(a[pivot][col])) pivot = row;
    }
    if (!(std::abs(a[pivot][col]) > 1e-9 * static_cast<double>(n_))) return false;
    std::swap(a[col], a[pivot]);
    for (int row = col + 1; row < kTerms; ++row) {
      const double factor = a[row][col] / a[col][col];
      for (int j = col; j <= kTerms; ++j) a[row][j] -= factor * a[col][j];
    }
  }
  for (int i = kTerms - 1; i >= 0; --i) {
    double sum = a[i][kTerms];
    for (int j = i + 1; j < kTerms; ++j) sum -= a[i][j] * x[j];
    x[i] = sum / a[i][i];
  }
  return true;
}

}  // namespace mpdrig::client
