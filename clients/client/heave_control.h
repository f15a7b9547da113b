// Blocks of a controller that holds the rig's bottom-hole pressure (BHP) against heave with the
// choke, for clients/bhp_controller.cc and clients/examples/hello_controller.cc (and a student's
// own): the heave canceller, the set point learnt with the choke left alone, and the measure of
// the heave's swing. They take numbers, not the rig: time and signals are arguments, the
// transport is the client library's (control_loop.h).
//
// Why PI feedback alone is not enough on this rig: the choke acts on the bottom through the
// 900 m pipe, l/c = 1.06 s of transport delay plus the 0.1 s actuator lag, which is 40-90 degrees
// of phase at a 0.1-0.2 Hz heave, before the pipe's own resonance at c/4l = 0.24 Hz (thesis 9.3).
// Measured (bench/bhp_attenuation.sh: 0.1 m heave at 0.1 Hz, 5 L/min through a 31 deg choke,
// lockstep, lab noise; docs/service.md): PT1's periodic RMS 0.259 bar with the choke fixed,
// 0.263 bar under PI (Kp 0.1 deg/bar, Ki 0.05 deg/(bar s)): no better; 0.011 bar with the PI and
// this canceller (22.9x; 22-26x over 0.1-0.2 Hz).
//
// HeaveCanceller: adaptive feed-forward cancellation on the observer's heave phasor. The observer
// (thesis 10) publishes the heave as a rotating phasor: X = (X1, X2) of the disturbance model
// (10.2.8)-(10.2.11) with v_d = X2 and x_d = -X1/omega (mpdrig_estimate's
// piston_velocity_est_mps, piston_position_est_m and disturbance_frequency_hz), so
//   z = v_d^ + j omega x_d^ = |z| exp(j (omega t + phi))       [m/s]
// and the heave's effect on the BHP in steady state is Re{D z} for some complex D [bar/(m/s)],
// while a choke motion Re{theta z} [deg] adds Re{G(j omega) theta z}. The feed-forward gain theta
// is adapted until the oscillation at omega vanishes (a gradient step on the demodulated error
// W = 2 e conj(z)/|z|^2 = D + G theta, e = BHP - set point [bar]):
//   theta' = -gamma W / G^,   G^ = -g exp(-j omega tau)
// with a rough plant model G^: g the static choke gain [bar/deg] and tau the delay from the choke
// to the bottom (l/c plus the actuator lag plus the pipe's phase). It converges while the phase
// of G^ is within 90 degrees of the true G(j omega); the defaults are within about 20 degrees on
// the lab rig at 0.1-0.2 Hz for 5-20 L/min of pump flow and a 30-45 degree choke, and converge in
// about 20 s (1/gamma = 5 s per e-fold, slowed by the pipe's delay). What it leaves is mostly the
// second harmonic (the choke's and the friction's quadratic terms).
#pragma once

#include <complex>
#include <limits>
#include <optional>
#include <utility>

#include "clients/client/rig_client.h"

namespace mpdrig::client {

class HeaveCanceller {
 public:
  struct Options {
    double adapt_per_s = 0.2;  // gamma; above about 0.4 it outruns the pipe's delay, oscillating
    double choke_gain_bar_per_deg =
        0.7;               // g: BHP drop per degree of opening, about 2 dp/G dG/dtheta
    double delay_s = 1.3;  // tau: l/c + actuator lag + the pipe's phase
  };

  HeaveCanceller() = default;
  explicit HeaveCanceller(const Options& options) : o_(options) {}

  // The heave phasor z = v_d^ + j omega x_d^ [m/s] of an estimate.
  static std::complex<double> Phasor(const Estimate& e);

  // One sample: the BHP error e = BHP - set point [bar], the heave phasor z [m/s] and its
  // frequency [Hz], the time since the last sample [s]. Adapts theta and returns the feed-forward
  // Re{theta z} [deg of choke opening, added to the PI's]; 0 while the heave is unknown
  // (frequency <= 0 or |z| <= 1e-4 m/s: no adaptation then).
  double Update(double error_bar, std::complex<double> z, double frequency_hz, double dt_s);
  double Update(double error_bar, const Estimate& estimate, double dt_s) {
    return Update(error_bar, Phasor(estimate), estimate.disturbance_frequency_hz, dt_s);
  }

  std::complex<double> theta() const { return theta_; }

 private:
  Options o_;
  std::complex<double> theta_{0.0, 0.0};  // [deg/(m/s)]
};

// A set point where the BHP sits without the heave, learnt with the choke left as the rig has
// it: ignore the first settle_s and two heave periods (the heave's start-up transient; the
// observer's, which converges in about two periods: measured at the lab's noise, 0.1 Hz,
// BHP_est - PT1 averaged -0.027 bar over 10-20 s, -0.002 over 20-30 s), then average the BHP and
// the choke's position over learn_s rounded to whole heave periods (a part period biases the mean
// by up to the heave's amplitude over pi periods). The choke's mean is where a PI's integrator
// starts (one noisy reading, 0.1 deg at the lab, moves the held BHP by up to 0.07 bar).
class SetpointLearner {
 public:
  struct Options {
    double settle_s = 10.0;
    double learn_s = 10.0;
  };

  SetpointLearner() = default;
  explicit SetpointLearner(const Options& options) : o_(options) {}

  // One sample: time [s], BHP [barg], choke position [deg], the heave's frequency [Hz] (<= 0:
  // unknown, learn_s as it is). True once learnt (from this sample on; later calls change
  // nothing).
  bool Add(double t_s, double bhp_barg, double choke_deg, double frequency_hz);

  bool learnt() const { return setpoint_barg_.has_value(); }
  double setpoint_barg() const {
    return setpoint_barg_.value_or(std::numeric_limits<double>::quiet_NaN());
  }
  double choke_deg() const { return choke_deg_.value_or(std::numeric_limits<double>::quiet_NaN()); }

 private:
  static constexpr double kSettlePeriods = 2.0;

  Options o_;
  std::optional<double> first_t_s_, learn_start_s_, learn_end_s_;
  double sum_ = 0.0, choke_sum_ = 0.0;
  long n_ = 0;
  std::optional<double> setpoint_barg_, choke_deg_;
};

// A signal's periodic part at the heave frequency f over a window, robust to the sensors' noise
// (half the peak-to-peak swing is not: the lab's 0.024 bar of PT1 noise alone reads about
// 0.07 bar). Least squares of y(t) = c0 + sum_k (a_k cos(k w t) + b_k sin(k w t)), k = 1..3,
// w = 2 pi f, over the window's samples: the fundamental's amplitude |a_1 + j b_1| and the RMS
// of the fitted periodic part, sqrt(sum_k (a_k^2 + b_k^2) / 2), which counts the harmonics the
// choke's and the friction's quadratic terms make. White noise of sigma adds about
// sigma sqrt(2 / N) to an amplitude (0.0008 bar over 20 s at 100 Hz at the lab's noise).
class HeaveFit {
 public:
  static constexpr int kHarmonics = 3;
  static constexpr int kTerms = 1 + 2 * kHarmonics;

  // One sample; the window's first frequency > 0 is the one fitted (a commanded sine's own, or
  // the observer's lock); samples without a frequency are left out.
  void Add(double t_s, double y, double frequency_hz);

  // {fundamental amplitude, RMS of the periodic part}; NaN without a frequency or enough samples
  // (4 per fitted term), or when the fit is singular (a window much shorter than a period).
  std::pair<double, double> Amplitudes() const;
  long samples() const { return n_; }
  double frequency_hz() const { return frequency_hz_; }

 private:
  void Basis(double t_s, double* basis) const;
  bool Solve(double* x) const;

  double frequency_hz_ = 0.0;
  double normal_[kTerms][kTerms] = {};
  double right_[kTerms] = {};
  long n_ = 0;
};

}  // namespace mpdrig::client
