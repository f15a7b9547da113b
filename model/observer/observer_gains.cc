#include "model/observer/observer_gains.h"

#include <cmath>
#include <sstream>

namespace mpdrig::observer {

Status ObserverOptions::Validate() const {
  if (cells < 2 || cells > 20000) {
    return Status::Error("observer cells must be in [2, 20000], got " + std::to_string(cells));
  }
  if (!(std::isnan(friction_f1_per_s) ||
        (std::isfinite(friction_f1_per_s) && friction_f1_per_s >= 0.0 &&
         friction_f1_per_s <= 100.0))) {
    std::ostringstream out;
    out << "observer friction_f1_per_s must be in [0, 100] 1/s, got " << friction_f1_per_s;
    return Status::Error(out.str());
  }
  if (!(std::isfinite(disturbance_hz) && disturbance_hz > 0.0 && disturbance_hz < 1e3)) {
    std::ostringstream out;
    out << "disturbance frequency must be in (0, 1000) Hz, got " << disturbance_hz;
    return Status::Error(out.str());
  }
  if (!(std::isfinite(pole.real()) && std::isfinite(pole.imag()) && pole.real() < 0.0)) {
    std::ostringstream out;
    out << "observer poles must have a negative real part, got " << pole.real() << " +- "
        << std::fabs(pole.imag()) << "i";
    return Status::Error(out.str());
  }
  MPDRIG_RETURN_IF_ERROR(noise.Validate());
  if (!(std::isfinite(heave_stroke_m) && heave_stroke_m > 0.0 &&
        std::isfinite(heave_drift_per_period) && heave_drift_per_period > 0.0)) {
    return Status::Error("observer heave_stroke_m and heave_drift_per_period must be > 0");
  }
  if (!(prefilter_error >= 0.0 && prefilter_error < 0.5)) {
    return Status::Error("observer prefilter_error must be in [0, 0.5)");
  }
  if (!(retune_fraction >= 0.0 && retune_fraction < 1.0)) {
    return Status::Error("observer retune_fraction must be in [0, 1)");
  }
  return Status::Ok();
}

double EquivalentLinearFriction(double f1_per_s, double f2_per_m, double velocity_amplitude_mps) {
  return f1_per_s + 8.0 / (3.0 * M_PI) * f2_per_m * std::fabs(velocity_amplitude_mps);
}

ObserverCoordinates ObserverCoordinates::Create(const RigParams& params, double friction_f1_per_s) {
  ObserverCoordinates c;
  c.length_m = params.pipe_length_m;
  c.wave_speed_mps = params.wave_speed_mps;
  c.density_kgpm3 = params.density_kgpm3;
  c.area_m2 = params.PipeAreaM2();
  c.gravity_slope_mps2 = params.gravity_mps2 * params.SinInclination();
  c.friction_f1_per_s = friction_f1_per_s;
  c.sigma = 0.5 * friction_f1_per_s * c.length_m / c.wave_speed_mps;
  c.epsilon_per_s = c.wave_speed_mps / c.length_m;
  c.impedance_m3ps_per_pa = c.area_m2 / (c.density_kgpm3 * c.wave_speed_mps);
  return c;
}

double ObserverCoordinates::C1(double x) const {
  return -0.5 * friction_f1_per_s * std::exp(2.0 * sigma * x);
}
double ObserverCoordinates::C2(double x) const {
  return -0.5 * friction_f1_per_s * std::exp(-2.0 * sigma * x);
}
double ObserverCoordinates::GravityFree(double x, double pressure_pa, double p_sp_pa) const {
  return pressure_pa + density_kgpm3 * gravity_slope_mps2 * x * length_m - p_sp_pa;
}
double ObserverCoordinates::UpWave(double x, double pressure_pa, double flow_m3ps,
                                   double p_sp_pa) const {
  return 0.5 * (flow_m3ps + impedance_m3ps_per_pa * GravityFree(x, pressure_pa, p_sp_pa)) *
         std::exp(sigma * x);
}
double ObserverCoordinates::DownWave(double x, double pressure_pa, double flow_m3ps,
                                     double p_sp_pa) const {
  return 0.5 * (flow_m3ps - impedance_m3ps_per_pa * GravityFree(x, pressure_pa, p_sp_pa)) *
         std::exp(-sigma * x);
}
double ObserverCoordinates::Pressure(double x, double u, double v, double p_sp_pa) const {
  const double big_p = (u * std::exp(-sigma * x) - v * std::exp(sigma * x)) / impedance_m3ps_per_pa;
  return big_p + p_sp_pa - density_kgpm3 * gravity_slope_mps2 * x * length_m;
}
double ObserverCoordinates::Flow(double x, double u, double v) const {
  return u * std::exp(-sigma * x) + v * std::exp(sigma * x);
}

Result<NoiseDesign> DesignForNoise(const RigParams& params, const ObserverOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  NoiseDesign design;
  design.poles = {options.pole, std::conj(options.pole)};
  const std::complex<double> nan(std::nan(""), std::nan(""));
  design.kalman = {nan, nan};
  if (options.gain_design == GainDesign::kPoles || options.noise.IsZero()) return design;
  const double f1 =
      std::isnan(options.friction_f1_per_s) ? params.friction_f1_per_s : options.friction_f1_per_s;
  const ObserverCoordinates co = ObserverCoordinates::Create(params, f1);
  const double omega = 2.0 * M_PI * options.disturbance_hz;
  // In units of X [m/s]: the injected error measures C X = -(A_d - A_d2) X2.
  const double area = params.PistonDisplacementAreaM2();
  const double k = co.impedance_m3ps_per_pa;
  const double sq = options.noise.outlet_flow_m3ps, sp = options.noise.outlet_pressure_pa;
  const double var_y = 0.25 * std::exp(2.0 * co.sigma) * (sq * sq + k * k * sp * sp);
  const double r = var_y * options.noise.sample_period_s / (area * area);
  const double v = options.heave_stroke_m * omega;
  const double drift = options.heave_drift_per_period * v;
  const double q = drift * drift * options.disturbance_hz;
  // The Kalman filter's faster pole is close to -sqrt(q / r): far beyond the thesis's the noise is
  // negligible and the Riccati equation ill-conditioned (the Hamiltonian spans many decades).
  if (r == 0.0 || std::sqrt(q / r) > 10.0 * std::abs(options.pole)) return design;
  auto kalman = KalmanPoles(omega, q, r);
  if (!kalman.ok()) return kalman.status();
  design.kalman = *kalman;
  if (std::max(std::abs((*kalman)[0]), std::abs((*kalman)[1])) < std::abs(options.pole)) {
    design.poles = *kalman;
    design.prefilter_tau_s = std::sqrt(options.prefilter_error) / omega;
  }
  return design;
}

Result<ObserverGains> ObserverGains::Compute(const RigParams& params,
                                             const ObserverOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  const double f1 =
      std::isnan(options.friction_f1_per_s) ? params.friction_f1_per_s : options.friction_f1_per_s;
  const ObserverCoordinates coordinates = ObserverCoordinates::Create(params, f1);
  auto kernel = KernelSolution::Solve(coordinates.sigma, options.cells);
  if (!kernel.ok()) return kernel.status();
  return Compute(params, options, *kernel);
}

Result<ObserverGains> ObserverGains::Compute(const RigParams& params,
                                             const ObserverOptions& options,
                                             const KernelSolution& kernel) {
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  ObserverGains g;
  const double f1 =
      std::isnan(options.friction_f1_per_s) ? params.friction_f1_per_s : options.friction_f1_per_s;
  g.coordinates = ObserverCoordinates::Create(params, f1);
  if (kernel.cells() != options.cells || std::fabs(kernel.sigma() - g.coordinates.sigma) > 1e-12) {
    return Status::Error("kernel solution does not match the observer's grid or friction");
  }
  auto design = DesignForNoise(params, options);
  if (!design.ok()) return design.status();
  g.design = *design;
  auto disturbance = SinusoidDisturbance::CreateWithPoles(
      options.disturbance_hz, params.PistonDisplacementAreaM2(), g.design.poles);
  if (!disturbance.ok()) return disturbance.status();
  g.disturbance = *disturbance;
  const double travel_s = params.pipe_length_m / params.wave_speed_mps;
  g.delay_s = travel_s;  // a = h(0)
  g.disturbance_gain = g.disturbance.Exp(g.delay_s) * g.disturbance.l;

  const int m = options.cells;
  const double h = 1.0 / m;
  const double eps = g.coordinates.epsilon_per_s;
  std::vector<double> gx(m + 1);  // g(xi) = C exp(A h(xi)) L
  for (int j = 0; j <= m; ++j) {
    gx[j] = g.disturbance.c * g.disturbance.Exp((1.0 - j * h) * travel_s) * g.disturbance.l;
  }
  g.x.resize(m + 1);
  g.p1.resize(m + 1);
  g.p2.resize(m + 1);
  g.p1_without_kernel = gx;
  for (int i = 0; i <= m; ++i) {
    g.x[i] = i * h;
    double int_uu = 0.0, int_vu = 0.0;  // trapezoid over xi_j, j = i..m
    for (int j = i; j <= m; ++j) {
      const double w = (j == i || j == m) ? 0.5 * h : h;
      int_uu += w * kernel.Puu(i, j) * gx[j];
      int_vu += w * kernel.Pvu(i, j) * gx[j];
    }
    if (i == m) int_uu = int_vu = 0.0;
    g.p1[i] = gx[i] - eps * kernel.Puu(i, m) - int_uu;  // (10.1.16)
    g.p2[i] = 0.0 - eps * kernel.Pvu(i, m) - int_vu;    // (10.1.17)
    if (!options.use_kernel) {
      g.p1[i] = gx[i];
      g.p2[i] = 0.0;
    }
  }
  return g;
}

}  // namespace mpdrig::observer
