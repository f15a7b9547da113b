#include "model/observer/measurement_noise.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

namespace mpdrig::observer {

Status MeasurementNoise::Validate() const {
  auto bad = [](double v) { return !(std::isfinite(v) && v >= 0.0); };
  if (bad(outlet_pressure_pa) || bad(outlet_flow_m3ps)) {
    std::ostringstream out;
    out << "observer measurement noise must be finite and >= 0, got " << outlet_pressure_pa
        << " Pa, " << outlet_flow_m3ps << " m3/s";
    return Status::Error(out.str());
  }
  if (!(std::isfinite(sample_period_s) && sample_period_s > 0.0 && sample_period_s < 10.0)) {
    std::ostringstream out;
    out << "observer noise sample period must be in (0, 10) s, got " << sample_period_s;
    return Status::Error(out.str());
  }
  return Status::Ok();
}

namespace {
double Median(std::vector<double> v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}
}  // namespace

double RobustNoiseSigma(const std::vector<double>& values) {
  if (values.size() < 3) return 0.0;
  std::vector<double> d2(values.size() - 2);
  for (std::size_t k = 1; k + 1 < values.size(); ++k) {
    d2[k - 1] = std::fabs(values[k + 1] - 2.0 * values[k] + values[k - 1]);
  }
  double mean_abs = 0.0;
  for (double d : d2) mean_abs += d / d2.size();
  const double median = Median(std::move(d2));
  // A channel held between updates (a meter slower than the log) has mostly zero differences:
  // then the mean absolute difference, E|d2| = sqrt(2 / pi) sqrt(6) sigma for Gaussian noise.
  if (median == 0.0) return std::sqrt(M_PI / 2.0) * mean_abs / std::sqrt(6.0);
  return 1.4826 * median / std::sqrt(6.0);
}

Result<MeasurementNoise> EstimateTopsideNoise(const std::vector<double>& time_s,
                                              const std::vector<double>& outlet_pressure_pa,
                                              const std::vector<double>& outlet_flow_m3ps) {
  const std::size_t n = time_s.size();
  if (n < 3 || outlet_pressure_pa.size() != n || outlet_flow_m3ps.size() != n) {
    return Status::Error("noise estimate: need at least 3 topside samples of equal length");
  }
  std::vector<double> dt(n - 1);
  for (std::size_t k = 0; k + 1 < n; ++k) dt[k] = time_s[k + 1] - time_s[k];
  MeasurementNoise noise;
  noise.sample_period_s = Median(std::move(dt));
  noise.outlet_pressure_pa = RobustNoiseSigma(outlet_pressure_pa);
  noise.outlet_flow_m3ps = RobustNoiseSigma(outlet_flow_m3ps);
  MPDRIG_RETURN_IF_ERROR(noise.Validate());
  return noise;
}

Result<std::array<std::complex<double>, 2>> KalmanPoles(double omega_radps, double q, double r) {
  if (!(std::isfinite(omega_radps) && omega_radps > 0.0 && std::isfinite(q) && q > 0.0 &&
        std::isfinite(r) && r > 0.0)) {
    return Status::Error("Kalman gain: need omega, process and measurement noise > 0");
  }
  // Filter Riccati A P + P A' + Q - P C' R^-1 C P = 0 is the control Riccati of (A', C'):
  // Hamiltonian H = [A', -C'C/r; -Q, -A]; stable eigenvectors [X1; X2] give P = X2 X1^-1.
  // P = sqrt(q r) P' balances the equation: A P' + P' A' + g I - g P' C'C P' = 0, g = sqrt(q / r),
  // with the same closed loop A - g P' C'C (the raw q and r differ by many decades).
  const double g = std::sqrt(q / r);
  Eigen::Matrix2d a;
  a << 0.0, -omega_radps, omega_radps, 0.0;
  Eigen::RowVector2d c(0.0, 1.0);
  Eigen::Matrix4d h;
  h.topLeftCorner<2, 2>() = a.transpose();
  h.topRightCorner<2, 2>() = -g * c.transpose() * c;
  h.bottomLeftCorner<2, 2>() = -g * Eigen::Matrix2d::Identity();
  h.bottomRightCorner<2, 2>() = -a;
  Eigen::ComplexEigenSolver<Eigen::Matrix4d> eig(h);
  if (eig.info() != Eigen::Success) return Status::Error("Kalman gain: eigen solver failed");
  Eigen::Matrix<std::complex<double>, 4, 2> stable;
  int found = 0;
  for (int i = 0; i < 4 && found < 2; ++i) {
    if (eig.eigenvalues()(i).real() < 0.0) stable.col(found++) = eig.eigenvectors().col(i);
  }
  if (found != 2) return Status::Error("Kalman gain: the Hamiltonian has no stable subspace");
  const Eigen::Matrix2cd x1 = stable.topRows<2>();
  const Eigen::Matrix2cd x2 = stable.bottomRows<2>();
  const Eigen::Matrix2d p = (x2 * x1.inverse()).real();
  const Eigen::Vector2d l = g * p * c.transpose();
  const Eigen::Matrix2d closed = a - l * c;
  // Eigenvalues of a 2x2: tr/2 +- sqrt(tr^2/4 - det).
  const double half_tr = 0.5 * closed.trace();
  const std::complex<double> root =
      std::sqrt(std::complex<double>(half_tr * half_tr - closed.determinant(), 0.0));
  std::array<std::complex<double>, 2> poles{half_tr + root, half_tr - root};
  if (poles[0].imag() < 0.0) std::swap(poles[0], poles[1]);
  for (const std::complex<double>& p : poles) {
    if (!(std::isfinite(p.real()) && std::isfinite(p.imag()) && p.real() < 0.0)) {
      return Status::Error("Kalman gain: the filter is not stable (ill-conditioned noise levels)");
    }
  }
  return poles;
}

void ZeroLagFilter::Reset(double value) { x_ = z1_ = z2_ = out_ = value; }

double ZeroLagFilter::Step(double value, double dt_s, double tau_s) {
  if (!(tau_s > 0.0)) {
    Reset(value);
    return value;
  }
  // Tustin first-order low-pass: z_n = a z_{n-1} + b (x_n + x_{n-1}); its group delay at DC is
  // exactly tau, so 2 z1 - z2 has none.
  const double a = (2.0 * tau_s - dt_s) / (2.0 * tau_s + dt_s);
  const double b = dt_s / (2.0 * tau_s + dt_s);
  const double z1 = a * z1_ + b * (value + x_);
  const double z2 = a * z2_ + b * (z1 + z1_);
  x_ = value;
  z1_ = z1;
  z2_ = z2;
  out_ = 2.0 * z1 - z2;
  return out_;
}

}  // namespace mpdrig::observer
