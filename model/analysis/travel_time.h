// The speed of pressure fronts along the pipe, from the transmitters' own records: how the thesis
// measured c = 1173 m/s (section 8.3.2, Table 8.3.1: the delay of the front after a fast choke or
// piston move, read by hand between the ends of the pipe), made automatic and extended to every
// pair of transmitters and to any broadband excitation.
//
// Model: in the lossless linear pipe (7.0.1-7.0.2) the pressure is two fronts travelling at +-c,
//   p(x, t) = F(t - x/c) + G(t + x/c),
// so two transmitters a distance d apart see each front delayed by d/c. Friction (f1 = 0.15/s)
// damps a front by e^{-f1 t/2}, 6 % over the pipe, but hardly delays it above f1/2pi = 0.02 Hz.
//
// Method, for every pair (i, j) of transmitters at x_i < x_j, d = x_j - x_i:
//   1. the time derivative of each pressure (centred differences; it takes away the hydrostatic
//      offsets and the slow pressure level, and weights the fronts' fast part), the window's ends
//      tapered (Tukey, 5 % or at most 0.25 s each side: a taper reweights the fronts
//      inside it, the later ones more, and so shifts their apparent delays);
//   2. the cross-correlation r_ij(tau) = sum_t p_i'(t) p_j'(t + tau) through FFTs, weighted by a
//      band W(f) = f^4/(f^4 + f_lo^4) exp(-(f/f_hi)^2): f_lo takes out the heave's standing waves
//      (a sine correlates at every lag), f_hi the transmitters' white noise (in the derivative its
//      power grows as f^2), normalised by sqrt(r_ii(0) r_jj(0));
//   3. a front going up the pipe (from the piston, or a choke's front reflected at the piston)
//      reaches x_i first and peaks r at tau = +d/c, one going down (from the choke) at -d/c.
//      First a stack over all pairs finds the slowness s = 1/c that maximises
//      sum_ij r_ij(+s d_ij) + r_ij(-s d_ij) (delay-and-sum: robust to the peaks of reflections,
//      which lie at +-(x_i + x_j)/c and +-(2L - x_i - x_j)/c, different for every pair). Then each
//      pair's peaks are sought near +-s d: the largest r within 25 % of the stack's lag, refined
//      by a parabola through three points (sub-sample), kept if it is a true local maximum and at
//      least `min_peak` of the pair's largest correlation and `min_peak_sigmas` standard
//      deviations of chance: two independent series with the pair's weighted spectra S_i, S_j
//      correlate at any lag with variance sum S_i S_j / (sum S_i sum S_j) (noise alone, or slow
//      sines, would otherwise give peaks wherever the search looks, and a fit that agrees with
//      its own search). The correlation is computed on a grid
//      of at most 1 ms (4-16 points a sample: the spectrum zero-padded, band-limited
//      interpolation), so the parabola's own error is far below a sample. The pair's delay is
//      (tau+ - tau-)/2 where both sides have a peak (a timing offset between the two channels
//      cancels), else the one side's |tau|. A pair whose two peaks merge (d/c shorter than the
//      fronts' width) has no local maximum there and is left out, saying so; so is a pair whose
//      delay is under two half widths of its peak (at half height, on the peak's outer flank):
//      its two peaks lean on each other's inner flanks and pull together.
//   4. the fit: delay = d / c over the pairs kept, least squares through the origin in the
//      slowness (the error is in the delay): s = sum d tau / sum d^2, c = 1/s. Pairs farther than
//      4 median absolute deviations from the line are dropped and the line refitted; then the
//      peaks are sought again around the fitted line (step 3) and the fit repeated once.
//      Uncertainty: the regression's standard error, sigma_s = sqrt(sum (tau - s d)^2 / (n - 1)
//      / sum d^2), times sqrt(n_pairs / (n_transmitters - 1)) because the pairs share transmitters
//      (only n_transmitters - 1 delays are independent), then sigma_c = sigma_s / s^2.
//
// Sampling: the log is put on a uniform grid at its mean step (linear interpolation; a lab log's
// jitter), gaps (NaN) in a channel are bridged linearly; a channel with fewer than half its
// samples measured is left out.
#pragma once

#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/rig_log.h"

namespace mpdrig {

struct TravelTimeOptions {
  double min_wave_speed_mps = 300.0;   // the lags searched: |tau| <= d / min_wave_speed
  double max_wave_speed_mps = 3000.0;  // and >= d / max_wave_speed (water alone: 1484 m/s)
  double band_low_hz = 3.0;            // f_lo of the band weight
  double band_high_hz = 10.0;          // f_hi, at most 0.4 times the Nyquist frequency
  double min_peak = 0.2;               // a peak counts from this share of the pair's largest
  double min_peak_sigmas = 5.0;        // and from this many sigma of r for unrelated series
  double window_begin_s = -1e300;      // only samples in [begin, end] (e.g. one choke move)
  double window_end_s = 1e300;
  Status Validate() const;
};

// One transmitter: its name (PT3), its place along the pipe [m] and its pressure [Pa].
struct PressureTrace {
  std::string name;
  double position_m = 0.0;
  std::vector<double> pressure_pa;  // one per time stamp, NaN where not measured
};

struct PairDelay {
  std::string first;  // the transmitter nearer the piston (x_i < x_j)
  std::string second;
  double distance_m = 0.0;
  double delay_s = 0.0;           // NaN when not resolved
  double delay_up_s = 0.0;        // tau+: fronts going up, from the piston; NaN if no peak
  double delay_down_s = 0.0;      // -tau-: fronts going down, from the choke; NaN if no peak
  double peak_correlation = 0.0;  // the larger of the two normalised peaks
  double peak_sigmas = 0.0;  // that peak in standard deviations of r between independent series
  bool used = false;         // in the fit
  std::string note;          // why not, if not
};

struct TravelTimeResult {
  double wave_speed_mps = 0.0;
  double wave_speed_uncertainty_mps = 0.0;  // one standard error
  double stack_wave_speed_mps = 0.0;        // step 3's delay-and-sum estimate
  double residual_rms_s = 0.0;              // of the fit's delays
  double front_width_s = 0.0;               // a correlation peak's half width at half height
  double sample_rate_hz = 0.0;
  double band_low_hz = 0.0;
  double band_high_hz = 0.0;              // as used (capped by the sampling rate)
  double duration_s = 0.0;                // of the window used
  std::vector<std::string> transmitters;  // those used, in order along the pipe
  std::vector<PairDelay> pairs;
  int pairs_used = 0;
};

// The estimate from traces on common time stamps (strictly increasing). Needs at least three
// transmitters at distinct places, and a fit from at least three pairs; else an error that says
// what is missing.
Result<TravelTimeResult> EstimateTravelTime(const std::vector<double>& time_s,
                                            const std::vector<PressureTrace>& traces,
                                            const TravelTimeOptions& options = {});

// The pipe's transmitters PT1..PT10 of a log at their places (0, 100, ..., 900 m,
// PipePositionM), those present.
std::vector<PressureTrace> PipeTransmitterTraces(const riglog::RigLog& log);

// --- One choke move at a time, as the thesis read them (Table 8.3.1) ----------------------------

// The times of the choke's moves: where the mean opening over [t + 0.1, t + 0.6] s differs from
// the mean over [t - 0.6, t - 0.1] s by at least `min_step_frac` (a local maximum of that step,
// so a move is found once, at its middle; the position feedback's noise averages out over the
// 0.5 s), at least `min_gap_s` after the previous one. NaN samples are skipped.
std::vector<double> FindChokeMoves(const std::vector<double>& time_s,
                                   const std::vector<double>& opening_frac,
                                   double min_step_frac = 2.0 / 90.0, double min_gap_s = 3.0);

struct MoveTravelTime {
  double time_s = 0.0;           // the move
  Status status = Status::Ok();  // the error where the window holds no clear front
  TravelTimeResult result;       // where status is ok
};

// EstimateTravelTime over [t - before_s, t + after_s] around each move (the other options as
// given): one wave speed per move, as the thesis's twelve.
std::vector<MoveTravelTime> TravelTimePerMove(const std::vector<double>& time_s,
                                              const std::vector<PressureTrace>& traces,
                                              const std::vector<double>& move_times_s,
                                              const TravelTimeOptions& options = {},
                                              double before_s = 1.0, double after_s = 4.0);

}  // namespace mpdrig
