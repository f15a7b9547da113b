#include "model/observer/disturbance_model.h"

#include <cmath>
#include <sstream>

namespace mpdrig::observer {

Eigen::Matrix2d SinusoidDisturbance::Exp(double t_s) const {
  const double phi = omega_radps * t_s;
  Eigen::Matrix2d r;
  r << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  return r;
}

Result<Eigen::Vector2d> PlacePoles2(const Eigen::Matrix2d& a, const Eigen::RowVector2d& c,
                                    double a1, double a0) {
  Eigen::Matrix2d obs;
  obs.row(0) = c;
  obs.row(1) = c * a;
  const double det = obs.determinant();
  const double scale = obs.norm() * obs.norm();
  if (!(std::fabs(det) > 1e-12 * scale)) {
    return Status::Error("the disturbance model is not observable from the outlet (det O = 0)");
  }
  // L = phi(A) O^{-1} e2, phi(s) = s^2 + a1 s + a0 (Ackermann, dual form).
  const Eigen::Matrix2d phi = a * a + a1 * a + a0 * Eigen::Matrix2d::Identity();
  return Eigen::Vector2d(phi * obs.inverse() * Eigen::Vector2d(0.0, 1.0));
}

Result<SinusoidDisturbance> SinusoidDisturbance::Create(double frequency_hz,
                                                        double displacement_area_m2,
                                                        std::complex<double> pole) {
  return CreateWithPoles(frequency_hz, displacement_area_m2, {pole, std::conj(pole)});
}

Result<SinusoidDisturbance> SinusoidDisturbance::CreateWithPoles(
    double frequency_hz, double displacement_area_m2,
    const std::array<std::complex<double>, 2>& poles) {
  if (!(std::isfinite(frequency_hz) && frequency_hz > 0.0 && frequency_hz < 1e3)) {
    std::ostringstream out;
    out << "disturbance frequency must be in (0, 1000) Hz, got " << frequency_hz;
    return Status::Error(out.str());
  }
  if (!(displacement_area_m2 > 0.0)) {
    return Status::Error("piston displacement area A_d - A_d2 must be positive");
  }
  const std::complex<double> sum = poles[0] + poles[1], product = poles[0] * poles[1];
  for (const std::complex<double>& pole : poles) {
    if (!(std::isfinite(pole.real()) && std::isfinite(pole.imag()) && pole.real() < 0.0)) {
      std::ostringstream out;
      out << "observer poles must have a negative real part, got " << pole.real() << " +- "
          << std::fabs(pole.imag()) << "i";
      return Status::Error(out.str());
    }
  }
  if (std::fabs(sum.imag()) > 1e-9 * std::abs(sum) ||
      std::fabs(product.imag()) > 1e-9 * std::abs(product)) {
    return Status::Error("observer poles must be a conjugate pair or both real");
  }
  SinusoidDisturbance d;
  d.omega_radps = 2.0 * M_PI * frequency_hz;
  d.a << 0.0, -d.omega_radps, d.omega_radps, 0.0;
  d.c_bar << 0.0, 1.0;
  d.c = -displacement_area_m2 * d.c_bar;
  // (s - p1)(s - p2) = s^2 - (p1 + p2) s + p1 p2
  auto l = PlacePoles2(d.a, d.c, -sum.real(), product.real());
  if (!l.ok()) return l.status();
  d.l = *l;
  return d;
}

}  // namespace mpdrig::observer
