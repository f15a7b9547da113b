// Coordinates and output-injection gains of the backstepping observer (thesis 10.1-10.2, after
// Aamo, "Disturbance rejection in 2x2 linear hyperbolic systems", IEEE TAC 2013).
//
// The linear pipe (thesis 7.0.1-7.0.2, 9.2.2-9.2.3) in volumetric flow q = A u_fluid [m^3/s] and
// the gravity-free pressure P = p + rho g sin(gamma) x_m - p_sp [Pa] (9.2.1):
//   P_t = -(rho c^2 / A) q_x,   q_t = -(A / rho) P_x - f1 q,    x_m in [0, l]
// Change of coordinates (10.2.1)-(10.2.2), x = x_m / l in [0, 1], k = A / (rho c):
//   u(x, t) = (1/2) (q + k P) exp( sigma x)    the wave travelling UP, towards the choke
//   v(x, t) = (1/2) (q - k P) exp(-sigma x)    the wave travelling DOWN, towards the heave gen.
// and, conversely, q = u exp(-sigma x) + v exp(sigma x), P = (u exp(-sigma x) - v exp(sigma x))/k.
// Then (10.1.1)-(10.1.4) hold with (10.2.3)-(10.2.7):
//   epsilon_1 = epsilon_2 = c / l [1/s],  c_1(x) = -(f1/2) exp(2 sigma x),
//   c_2(x) = -(f1/2) exp(-2 sigma x),     sigma = f1 l / (2 c)
// i.e. the thesis's F / rho is our linear friction f1 [1/s] (8.6.8); the quadratic friction f2 of
// the plant is not in the linear observer (it can be folded into an equivalent f1, see
// ObserverOptions). Boundaries in terms of the rig's channels:
//   x = 0 (heave generator): u(0) = q v(0) + C X,  q = -1: u + v = q(0) = FT4 = -(A_d - A_d2) v_d
//   x = 1 (choke): v(1, t) = U(t) = (1/2)(FT1 - k P(l)) exp(-sigma)     (10.1.4), from C2 and FT1
//   measured output y(t) = u(1, t) = (1/2)(FT1 + k P(l)) exp(sigma)      (injected error y - u^)
// with P(l) = C2 + rho g sin(gamma) l - p_sp and FT1 = A u_fluid(l) (or FT3 - FT2). The set point
// p_sp is any constant (the model is linear); the observer uses the first measured C2.
//
// Gains (10.1.16)-(10.1.17), with g(xi) = C exp(A h(xi)) L and h(xi) = (1 - xi) l / c:
//   p1(x) = g(x) - epsilon P^uu(x, 1) - int_x^1 P^uu(x, xi) g(xi) dxi     [1/s]
//   p2(x) =      - epsilon P^vu(x, 1) - int_x^1 P^vu(x, xi) g(xi) dxi     [1/s]
// (trapezoidal rule on the kernel grid), and the disturbance injection exp(A a) L with
// a = h(0) = l / c, the travel time of the up-going wave (10.1.5).
#pragma once

#include <complex>
#include <limits>
#include <vector>

#include "model/common/status.h"
#include "model/observer/disturbance_model.h"
#include "model/observer/kernel.h"
#include "model/observer/measurement_noise.h"
#include "model/params/rig_params.h"

namespace mpdrig::observer {

// How the disturbance gain L is chosen (measurement_noise.h).
enum class GainDesign {
  kPoles,  // L places the poles of A - L C at `pole` (thesis 10.3); no prefilter
  kNoise,  // L is the steady-state Kalman gain for `noise`, never faster than `pole`, and C2,
           // FT1 are prefiltered when the noise limits the design; zero noise: as kPoles
};

struct ObserverOptions {
  int cells = 200;                         // grid of the observer's pipe and of the kernels
  double disturbance_hz = 0.2;             // omega / 2 pi in (10.2.10)
  std::complex<double> pole{-40.0, 20.0};  // poles of A - L C [rad/s]: pole and its conjugate
  GainDesign gain_design = GainDesign::kNoise;
  MeasurementNoise noise;  // of C2 and FT1; zero (the default): the thesis's poles exactly
  // Process noise of the heave model for kNoise: the velocity amplitude V = heave_stroke_m *
  // omega may drift by heave_drift_per_period of itself per heave period.
  double heave_stroke_m = 0.1;
  double heave_drift_per_period = 0.01;
  // kNoise prefilter: the largest relative error it may cause at the heave frequency. 2 %: over
  // the scenarios measured (0.1-0.33 Hz, 0.02-0.1 m strokes, chokes 30-70 deg, lab noise) the
  // budget that fitted the true BHP best lay between 1 and 4 %; the more noise relative to the
  // BHP swing, the larger. 2 % costs at most 2 points of fit where the noise is small.
  double prefilter_error = 0.02;
  // Linear friction used by the observer [1/s]; NaN: the rig's friction_f1_per_s. The plant's
  // quadratic term f2 u|u| can be represented by the describing-function equivalent
  // f1 + 8 f2 U / (3 pi) for a velocity amplitude U (EquivalentLinearFriction).
  double friction_f1_per_s = std::numeric_limits<double>::quiet_NaN();
  // Beyond the thesis: also run the plant's quadratic friction f2 u|u| (8.6.8, the rig's
  // friction_f2_per_m) inside the observer's copy of the pipe, as a nonlinear source on the
  // estimate. The gains stay those of the linear design (f1). With the thesis's f2 = 0.63 1/m and
  // 0.1 m piston strokes, f2 u|u| is comparable to f1 u, and leaving it out is the observer's
  // largest error on simulated data (docs/observer.md, "Accuracy on simulated data").
  bool quadratic_friction = false;
  // false: the thesis's approximation of 10.3, p1 = C exp(A h(x)) L and p2 = 0 (no kernels).
  // For tests and comparison only.
  bool use_kernel = true;
  // Beyond the thesis: estimate the heave frequency online (FrequencyTracker on the measured
  // up-going wave y) starting from disturbance_hz, and retune the gains whenever the estimate
  // moves by more than retune_fraction.
  bool track_frequency = false;
  double retune_fraction = 0.005;

  Status Validate() const;
};

// f1 + (8 / 3 pi) f2 U: the linear friction that dissipates the same energy per period as
// f1 u + f2 u|u| for u = U sin(w t) (describing function).
double EquivalentLinearFriction(double f1_per_s, double f2_per_m, double velocity_amplitude_mps);

struct ObserverCoordinates {
  double length_m = 0.0;               // l
  double wave_speed_mps = 0.0;         // c
  double density_kgpm3 = 0.0;          // rho
  double area_m2 = 0.0;                // A
  double gravity_slope_mps2 = 0.0;     // g sin(gamma)
  double friction_f1_per_s = 0.0;      // f1 = F / rho
  double sigma = 0.0;                  // (10.2.7)
  double epsilon_per_s = 0.0;          // c / l (10.2.3)
  double impedance_m3ps_per_pa = 0.0;  // k = A / (rho c)

  static ObserverCoordinates Create(const RigParams& params, double friction_f1_per_s);
  double C1(double x) const;  // (10.2.4)
  double C2(double x) const;  // (10.2.5)
  // P = p + rho g sin(gamma) x_m - p_sp at normalised x, from an absolute pressure.
  double GravityFree(double x, double pressure_pa, double p_sp_pa) const;
  double UpWave(double x, double pressure_pa, double flow_m3ps, double p_sp_pa) const;    // u
  double DownWave(double x, double pressure_pa, double flow_m3ps, double p_sp_pa) const;  // v
  double Pressure(double x, double u, double v, double p_sp_pa) const;  // absolute [Pa]
  double Flow(double x, double u, double v) const;                      // [m^3/s]
};

// What GainDesign::kNoise chooses (or kPoles: `pole` and no prefilter).
struct NoiseDesign {
  std::array<std::complex<double>, 2> poles;   // of A - L C in use [rad/s]
  std::array<std::complex<double>, 2> kalman;  // the Kalman filter's (NaN: kPoles, no noise)
  double prefilter_tau_s = 0.0;  // tau of the zero-lag prefilter on C2 and FT1; 0: none
};
Result<NoiseDesign> DesignForNoise(const RigParams& params, const ObserverOptions& options);

struct ObserverGains {
  ObserverCoordinates coordinates;
  NoiseDesign design;
  SinusoidDisturbance disturbance;
  double delay_s = 0.0;                   // a = l / c in (10.1.5)
  Eigen::Vector2d disturbance_gain;       // exp(A a) L
  std::vector<double> x;                  // normalised node positions i / cells
  std::vector<double> p1;                 // (10.1.16) [1/s]
  std::vector<double> p2;                 // (10.1.17) [1/s]
  std::vector<double> p1_without_kernel;  // C exp(A h(x)) L: the thesis's approximation (10.3)

  static Result<ObserverGains> Compute(const RigParams& params, const ObserverOptions& options);
  // The same, from a kernel solution already at hand (sigma and cells must match).
  static Result<ObserverGains> Compute(const RigParams& params, const ObserverOptions& options,
                                       const KernelSolution& kernel);
};

}  // namespace mpdrig::observer
