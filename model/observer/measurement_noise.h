// Measurement noise of the observer's topside channels, and what the observer does with it
// (beyond the thesis, whose poles -40 +- 20i assume noise-free C2 and FT1).
//
// Noise model: white noise on C2 (standard deviation sigma_p [Pa]) and on the outlet flow FT1
// (sigma_q [m^3/s]), independent from one logged sample to the next, at the logging period dt
// [s]. Its two-sided spectral density is sigma^2 dt.
//
// Estimated from a record (RobustNoiseSigma): the second difference d2_k = s_{k+1} - 2 s_k +
// s_{k-1} of white noise has variance 6 sigma^2, and the heave (a few tenths of a Hz at 100 Hz
// logging) contributes almost nothing to it; the median of |d2| resists the rare large
// differences of steps and spikes:  sigma = 1.4826 median(|d2|) / sqrt(6).
//
// Two uses (ObserverOptions::gain_design == GainDesign::kNoise):
//  1. The disturbance gain L (10.2.8)-(10.2.11) becomes the steady-state Kalman gain of the
//     heave model  dX = A X dt + dw,  e = C X + n  (the injected error sees C X, thesis 10.1.5):
//       process noise  E[dw dw'] = q I dt,  q = (r V)^2 f  [(m/s)^2/s]: the heave velocity
//         amplitude V may drift by r = heave_drift_per_period of itself per period 1/f
//         (default 1 %: the heave generator runs steady sines; faster drift makes one Kalman
//         pole fast and lets more noise through, measured in tests/model/observer);
//         V = heave_stroke_m * omega, the lab's usual stroke (thesis 8.6.1) unless told;
//       measurement noise density  R = sigma_y^2 dt, sigma_y^2 = (1/4) e^{2 sigma}
//         (sigma_q^2 + k^2 sigma_p^2), the noise of y = u(1) = (1/2)(FT1 + k P(l)) e^{sigma}.
//     The poles of A - L C are those of the Kalman filter unless the faster one is faster than
//     the thesis's (|ObserverOptions::pole|): with negligible noise the thesis's design is kept
//     exactly. (As the noise vanishes one Kalman pole goes to -infinity, the other to -omega.)
//  2. The observer takes the outlet's down-going wave U = v(1) from C2 and FT1 as exact
//     (10.1.4); its noise reaches the BHP estimate with no filtering at all (BHP noise ~
//     sigma_q / k, 1/k = rho c / A). When the noise limits the design (the Kalman poles are
//     slower than the thesis's), C2 and FT1 are first smoothed by the zero-lag second-order
//     filter  F(s) = (1 + 2 tau s) / (1 + tau s)^2  (unit gain and no delay at DC; two
//     first-order Tustin low-passes z1, z2 in series, output 2 z1 - z2). The observer is linear,
//     so its estimate is F applied to the unfiltered one: the error at the heave frequency is
//     |1 - F(j omega)| <= (omega tau)^2 = prefilter_error, tau = sqrt(prefilter_error) / omega.
//     It passes 5 dt / (4 tau) of the white noise's variance (at 0.2 Hz, 100 Hz logging and
//     prefilter_error = 2 %: 11 %, i.e. 0.33 of its standard deviation).
#pragma once

#include <array>
#include <complex>
#include <vector>

#include "model/common/status.h"

namespace mpdrig::observer {

struct MeasurementNoise {
  double outlet_pressure_pa = 0.0;  // sigma_p on C2
  double outlet_flow_m3ps = 0.0;    // sigma_q on FT1 (or FT3 - FT2)
  double sample_period_s = 0.01;    // dt: the noise is white at this period (the logging rate)

  bool IsZero() const { return outlet_pressure_pa == 0.0 && outlet_flow_m3ps == 0.0; }
  Status Validate() const;
};

// sigma = 1.4826 median(|s_{k+1} - 2 s_k + s_{k-1}|) / sqrt(6); 0 for fewer than 3 values. If
// the median is 0 (a held or quantised channel), sqrt(pi / 2) mean(|d2|) / sqrt(6) instead.
double RobustNoiseSigma(const std::vector<double>& values);

// The noise of C2 and FT1 in a topside record (uniformly sampled; dt = median sample period).
Result<MeasurementNoise> EstimateTopsideNoise(const std::vector<double>& time_s,
                                              const std::vector<double>& outlet_pressure_pa,
                                              const std::vector<double>& outlet_flow_m3ps);

// Steady-state Kalman filter of dX = A X dt + dw (E dw dw' = q I dt), e = C_bar X + n (density
// r), A = [0 -omega; omega 0], C_bar = [0 1]: the eigenvalues of A - L C_bar, a conjugate pair
// (Im of the first >= 0) or two real ones (the slower first).
// Solves the filter Riccati equation A P + P A' + q I - P C_bar' C_bar P / r = 0 by the stable
// invariant subspace of its Hamiltonian.
Result<std::array<std::complex<double>, 2>> KalmanPoles(double omega_radps, double q, double r);

// F(s) = (1 + 2 tau s) / (1 + tau s)^2, Tustin-discretised per step; tau = 0 passes through.
class ZeroLagFilter {
 public:
  void Reset(double value);
  double Step(double value, double dt_s, double tau_s);
  double value() const { return out_; }

 private:
  double x_ = 0.0, z1_ = 0.0, z2_ = 0.0, out_ = 0.0;
};

}  // namespace mpdrig::observer
