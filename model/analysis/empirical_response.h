// The empirical frequency response of a measured log, from the piston position x to every
// pressure channel y (P1 P2 PT1..PT10 C1 C2), with its coherence, and the resonance peaks in it:
// the rig's own measurement of the thesis's Fig. 9.1.2 from a sweep or multi-tone log.
//
// Welch (1967) with Hann-windowed segments of `segment_s`, 50 % overlap, each segment's mean and
// linear trend removed:
//   H(f) = S_yx(f) / S_xx(f),   gamma^2(f) = |S_yx|^2 / (S_xx S_yy),
// S_yx = sum over segments of Y conj(X) (the H1 estimator: noise on y averages out, noise on x
// biases |H| low by S_nn / S_xx, small where the piston moves). compare's transfer_functions
// (compare.h) are the same ratio pooled over log-spaced groups of bins, without coherence.
//
// Peaks: local maxima of |H| among the bins with gamma^2 >= min_coherence where the piston has
// at least min_input_power_fraction of its largest power, standing at least
// `min_prominence` above the lowest coherent point between them and the next higher one on each
// side. Frequency: the vertex of a parabola through log |H| at the bin and its neighbours.
// Uncertainty: the random error of |H| (Bendat & Piersol, Random Data, 9.3:
// eps = sqrt(1 - gamma^2) / (|gamma| sqrt(2 n_d)), n_d the segments) moved through the vertex,
//   u_stat = df eps / (sqrt(2) |y_- - 2 y_0 + y_+|)    (y = log |H| at the three bins),
// combined with the grid's df / sqrt(12) (what the parabola may miss between bins):
//   u = sqrt(u_stat^2 + df^2 / 12).
// The half-power width (where |H|^2 falls to half the peak's) is reported beside it.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/rig_log.h"

namespace mpdrig {

struct EmpiricalResponseOptions {
  double segment_s = 100.0;  // Welch segment; df = 1 / segment_s. A shorter log: one segment.
  double fmin_hz = 0.02;
  double fmax_hz = 2.0;
  double min_coherence = 0.5;  // gamma^2 of a point a peak may stand on
  // |H| ratio of a peak over the higher of the valleys beside it. A resonance of the rig stands
  // 10-100 times above them; 1.5 let the weakly excited plateau below a sweep's start through
  // (a closed pipe's static gain, 1.6 above the next wiggle, at gamma^2 0.65).
  double min_prominence = 2.0;
  // A peak stands only where the piston moves: its power in the bin at least this fraction of
  // its largest in [fmin, fmax] (below, the coherence of noise with noise can reach 0.6 by chance
  // over a few segments).
  double min_input_power_fraction = 0.01;

  // 0 < fmin < fmax, segment_s > 0, min_coherence in [0, 1), min_prominence >= 1.
  [[nodiscard]] Status Validate() const;
};

struct EmpiricalPoint {
  double freq_hz = 0.0;
  std::complex<double> h;             // SI: Pa per m of piston position
  double magnitude = 0.0;             // |h|
  double phase_deg = 0.0;             // unwrapped along the frequencies
  double coherence = 0.0;             // gamma^2
  double input_power_fraction = 0.0;  // the piston's power here over its largest in the range
};

struct ResonancePeak {
  double freq_hz = 0.0;
  double uncertainty_hz = 0.0;
  double magnitude = 0.0;
  double coherence = 0.0;
  double half_power_width_hz = 0.0;  // NaN where |H|^2 does not fall to half on both sides
};

struct ChannelResponse {
  std::string channel;  // "PT1"
  std::vector<EmpiricalPoint> points;
  std::vector<ResonancePeak> peaks;  // in frequency order
};

struct EmpiricalResponse {
  double sample_rate_hz = 0.0;
  double segment_s = 0.0;  // as used
  int segments = 0;
  double df_hz = 0.0;
  std::vector<ChannelResponse> channels;  // the pressure channels the log has, in file order
};

// Needs a piston_position column, uniform sampling (every interval within 1 % of the mean) and
// at least one pressure channel; a NaN in a channel inside a segment is filled by linear
// interpolation between its neighbours (a segment with nothing measured is skipped).
Result<EmpiricalResponse> EstimateEmpiricalResponse(const riglog::RigLog& log,
                                                    const EmpiricalResponseOptions& options = {});

// The peaks of one channel's points (the rules above), given the segments averaged.
std::vector<ResonancePeak> FindResonancePeaks(const std::vector<EmpiricalPoint>& points,
                                              int segments,
                                              const EmpiricalResponseOptions& options);

}  // namespace mpdrig
