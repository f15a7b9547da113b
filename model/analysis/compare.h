// Comparison of the model with a measured rig log: replay the log's inputs through the
// model, then measure how and where the model departs from every measured channel.
//
// Two ways in, one implementation of each metric (compare_accumulator.h):
//   CompareLog        streams the file twice, in memory that does not grow with its length (an
//                     hour at 1 kHz with all 16 channels: well under 200 MB, docs/compare.md,
//                     "Memory and speed"): pass 1 reads it for what the metrics need of the whole
//                     log up front (length, mean interval, each channel's mean, the inputs' means,
//                     the piston's dominant frequencies); pass 2 reads it again with the model
//                     replay in lock step (log_stream.h) and accumulates the metrics.
//   CompareTraces     the same two passes over a log in memory (LoadMeasuredLog, measured_log.h)
//                     and the model's traces on it (ReplayModel, log_replay.h: the same replay as
//                     pass 2, the same numbers). fit and diagnose call ReplayModel and
//                     CompareTraces many times on one log to fit and screen effects.
//
// Metrics per channel y (measured) and yhat (model), over the samples where y is measured:
//   NRMSE = ||y - yhat|| / ||y - mean(y)||, fit = 100 (1 - NRMSE) %  (System Identification);
//   rms = sqrt(mean((yhat - y)^2)), bias = mean(yhat - y)  (positive: the model reads high);
//   Spectral quantities use Welch's method: Hann-windowed segments of L samples, L = the whole
//     log up to CompareOptions::welch_segment_samples (2^17: 131 s at 1 kHz, 21.8 min at 100 Hz),
//     beyond that segments of that length overlapping by half (the last one ending at the last
//     sample), each with its own mean removed; DFT size M = the smallest 7-smooth number >= L.
//     A log of at most L samples is one segment: the plain periodogram of the whole log.
//   lag_s: the model's lag behind the measurement: the peak within +-max lag of the cross-
//     correlation of the Hann-windowed segments, summed over the segments (through the summed
//     cross-spectrum), divided by the window's own correlation,
//     r(k) ~ sum_segments sum_n w[n] y[n] w[n + k] yhat[n + k] / sum_n w[n] w[n + k],
//     refined by a parabola through the peak and its neighbours. Positive: the model is late
//     (yhat(t) ~ y(t - lag)); negative: the model leads. The window is at most L / 2.
//   bands: around the piston's dominant frequencies f0, 2 f0, 3 f0, ... and any further spectral
//     peak of the piston's Welch-averaged power spectrum: the segments' spectra Y, Yhat summed
//     over the band (+-3 bins, the Hann main lobe plus one bin) and over the segments:
//       magnitude_ratio = sqrt(sum |Yhat|^2 / sum |Y|^2)            (model / measurement)
//       phase_diff_deg  = arg(sum Yhat conj(Y))                     (model - measurement;
//                                                                    negative: model lags)
//       band_nrmse      = sqrt(sum |Yhat - Y|^2 / sum |Y|^2)        (the error in that band)
//       amplitudes      = 2 sqrt(sum |Y|^2 / (K M sum w^2)), K the segments, M the DFT size (a
//                         sinusoid's amplitude, by Parseval)
//   transfer functions piston -> PT1, C2: sum Y conj(U) / sum |U|^2 over the segments, at the
//     bins where the piston's averaged power is above a fraction of its largest (pooled in
//     log-spaced groups beyond transfer_points).
//   residual e = y - yhat as MATLAB's `resid`: normalised autocorrelation r_ee(k), k = 1..M, and
//     cross-correlation with each input u, r_eu(k) = sum_n e[n] u[n - k] / (N sigma_e sigma_u),
//     k = -M..M (k > 0: the input leads the residual), with the 99% band +-2.58/sqrt(N). White:
//     every r_ee(k) inside the band; independent of u: every r_eu(k) inside it. Exact lagged sums
//     over the whole log (running sums over a history of M samples).
// Spectral quantities (lag, bands, transfer functions) treat the log as uniformly sampled at its
// mean interval; gaps (unmeasured samples) are filled by linear interpolation within each
// segment (held at its ends) for them only; a segment without a measured sample is left out.
//
// Units: SI with absolute pressure (differences in Pa, m^3/s). The edges (JSON, HTML) convert to
// each channel's unit in the log.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/common/units.h"
#include "model/params/rig_params.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

struct CompareOptions {
  int residual_lags = 25;   // M, as MATLAB resid's default
  int max_harmonics = 3;    // f0, 2 f0, 3 f0
  int max_extra_peaks = 3;  // further piston peaks above extra_peak_fraction of the largest
  double extra_peak_fraction = 0.01;  // of the dominant peak's power
  int band_half_width_bins = 3;
  // Lag search window; 0: half the dominant period (the cross-correlation of a periodic signal
  // is periodic, so only that is unambiguous), at most 10 s, without dominant frequency 10 s.
  double max_lag_s = 0.0;
  int trace_columns = 1200;   // min/max envelope columns of the traces for plots
  double zoom_periods = 5.0;  // close-up window in dominant periods (10 s without one)
  int max_zoom_samples = 3000;
  int transfer_points = 300;  // at most this many points of the empirical transfer functions
  double transfer_min_power_fraction = 1.0e-4;  // of the piston's largest bin power
  // The piston velocity used by the residual analysis: smoothed over this window (and, in
  // CompareLog, the replay's piston when the inputs are not reconstructed).
  double piston_smoothing_s = 0.05;
  // CompareLog: replay reconstructed inputs (ReplayOptions::reconstruct_inputs). CompareTraces
  // follows the traces it is given (ModelTraces::inputs_reconstructed).
  bool reconstruct_inputs = true;
  // CompareLog: start the replay after a warm-up or from the measured pipe state where
  // ChooseReplayStart says so; false: from the steady state.
  bool choose_warmup = true;
  // CompareLog: correct the reconstructed choke and FT2 levels from the measured pressures
  // (EstimateInputLevels).
  bool estimate_levels = true;
  // Welch segment length (samples, >= 8): longer logs are averaged over segments this long.
  // Memory per compared channel is about 24 bytes times this (compare_accumulator.h): 3 MB.
  int welch_segment_samples = 1 << 17;
  // CompareLog: the reader's limits on the log's time axis (largest gap, smallest step).
  riglog::ReadOptions read;

  // residual_lags, trace_columns and band_half_width_bins >= 1, welch_segment_samples >= 8
  // (CompareTraces and CompareLog refuse options that fail it).
  [[nodiscard]] Status Validate() const;
};

struct BandMetrics {
  double freq_hz = 0.0;  // centre (piston peak or harmonic)
  double low_hz = 0.0, high_hz = 0.0;
  int harmonic = 0;                 // k of k f0; 0 for a further peak
  double measured_amplitude = 0.0;  // SI
  double model_amplitude = 0.0;
  double magnitude_ratio = 0.0;  // model / measured
  double phase_diff_deg = 0.0;   // model - measured, in (-180, 180]
  double band_nrmse = 0.0;
  double error_amplitude = 0.0;  // SI: amplitude of yhat - y in the band (band_nrmse * measured)
};

struct Correlation {
  std::string input;            // "piston_velocity", "piston_position", "choke_position"
  bool constant_input = false;  // zero variance: no correlation defined, nothing to explain
  std::vector<double> r;        // k = -M..M (index k + M)
  double max_abs = 0.0;
  bool independent = true;  // every |r| within the confidence band
};

struct ResidualAnalysis {
  int lags = 0;                          // M
  double confidence = 0.0;               // 2.58 / sqrt(N), 99%
  std::vector<double> autocorrelation;   // k = 0..M, r_ee(0) = 1
  double max_abs_autocorrelation = 0.0;  // over k = 1..M
  bool white = true;
  std::vector<Correlation> cross;
  bool independent_of_inputs = true;
};

// Per-pixel-column min/max of the traces, for plots of long logs (design: readable at 10 min of
// 100 Hz and at an hour of 1 kHz alike). Column c covers [t0 + c w, t0 + (c + 1) w).
struct TraceEnvelope {
  double t0_s = 0.0, t1_s = 0.0;
  std::vector<double> measured_min, measured_max, model_min, model_max, residual_min,
      residual_max;  // NaN where a column has no sample
};

// The raw samples of a short window (a few dominant periods, at most max_zoom_samples) centred on
// the largest |residual|, for a close look beside the envelope.
struct TraceWindow {
  std::vector<double> time_s, measured, model;  // SI; measured NaN where not measured
};

inline constexpr std::size_t kInputCloseUpSamples = 2000;
struct InputCloseUp {
  std::vector<double> time_s;
  std::array<std::vector<double>, 4> measured, replayed;
};

struct ChannelMetrics {
  Channel channel = Channel::kP1;
  riglog::Unit unit = riglog::Unit::kBarg;
  long samples = 0;          // measured samples used
  double nrmse = 0.0;        // NaN if the measurement is constant
  double fit_percent = 0.0;  // 100 (1 - nrmse)
  double rms_si = 0.0;
  double bias_si = 0.0;
  double measured_mean_si = 0.0;
  double measured_std_si = 0.0;
  double lag_s = 0.0;
  double lag_correlation = 0.0;  // normalised r at the peak (1: same shape)
  std::vector<BandMetrics> bands;
  ResidualAnalysis residual;
  TraceEnvelope envelope;
  TraceWindow zoom;
};

struct TransferPoint {
  double freq_hz = 0.0;
  std::complex<double> measured;  // SI per m of piston position
  std::complex<double> model;
};

struct TransferFunction {
  Channel output = Channel::kPT1;  // from piston_position
  std::vector<TransferPoint> points;
};

// One point of the error profile along the pipe (PT1..PT10 present in the log).
struct ProfilePoint {
  Channel channel = Channel::kPT1;
  double x_m = 0.0;
  double nrmse = 0.0, fit_percent = 0.0, rms_si = 0.0, bias_si = 0.0, lag_s = 0.0;
};

struct Comparison {
  std::string path;
  long samples = 0;
  double duration_s = 0.0;
  double sample_interval_s = 0.0;         // mean
  bool uniform_sampling = true;           // every interval within 1% of the mean
  double error = 0.0;                     // mean NRMSE over channels with a defined NRMSE
  std::vector<double> dominant_freqs_hz;  // the band centres
  double max_lag_s = 0.0;                 // the lag search window used
  std::vector<ChannelMetrics> channels;   // order of the log's compared channels
  std::vector<ProfilePoint> profile;      // x increasing
  std::vector<TransferFunction> transfer_functions;  // piston -> PT1 and -> C2 when present
  std::optional<RangeEvent> first_range_event;
  long spectrum_segments = 1;       // Welch segments K
  double spectrum_segment_s = 0.0;  // their length, L times the mean interval
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;  // the log's, for the edges
  // The log's first kInputCloseUpSamples samples of each input (piston, choke, pump, outlet: SI,
  // absolute pressure), as measured and as the model was fed them.
  InputCloseUp input_close_up;
  // How the replayed inputs were reconstructed; absent when replayed as measured.
  std::optional<InputReconstruction> input_reconstruction;
  // The warm-up the replay started after, or the measured pipe state it started from; both
  // absent: from the steady state.
  std::optional<PeriodicWarmup> warmup;
  std::optional<PipeProfile> measured_start;

  const ChannelMetrics* Find(Channel channel) const;
};

// Metrics of `model` against `log` (model.values_si in the order of log.channels).
Result<Comparison> CompareTraces(const MeasuredLog& log, const ModelTraces& model,
                                 const CompareOptions& options = {},
                                 const CompareProgress& progress = {});

// The same numbers as LoadMeasuredLog + ReplayModel + CompareTraces, streaming the file twice
// (above) in bounded memory. Progress: ("read", fraction of the file) during pass 1, ("replay",
// fraction of the samples) during pass 2.
Result<Comparison> CompareLog(const std::string& path, const RigParams& params,
                              const SimulationOptions& sim_options,
                              const CompareOptions& options = {},
                              const CompareProgress& progress = {});

}  // namespace mpdrig
