// Errors in variables: the inputs of a measured log (piston position, choke position, pump flow,
// outlet pressure) are measurements, as noisy as the outputs (thesis Table 4.1.1: position
// ~0.5 mm, choke ~0.1 deg, turbine flow 2 % of reading, pressure 0.024 bar). Replayed as they are,
// their noise drives the pipe: FT2's noise alone enters at the choke as a white flow and comes
// back as pressure noise several times the transmitters' own. These are the building blocks that
// estimate each input's noise from the log itself and reconstruct the signal under it; the plan
// for a whole log lives in model/sim/log_inputs.h.
//
// Two kinds of input, two smoothers:
// - Band-limited (the piston: a heave, sines, sweeps): a local quadratic with tricube weights
//   over a fixed window, chosen as the longest that passes the highest frequency the piston
//   carries (found in its spectrum above the noise floor) with less than kBandGainTolerance
//   loss. One window for the whole log, so the position stays smooth and its derivative, the
//   piston velocity that drives the pipe, stays consistent with it.
// - Piecewise smooth (choke, pump flow, outlet pressure: levels with genuine steps): local linear
//   fits over windows that grow by doubling, from the left, the right and centred, each stopped
//   by the intersection-of-confidence-intervals rule (Goldenshluger & Nemirovski 1997; Katkovnik's
//   LPA-ICI) and fused by inverse variance. At a step the windows that cross it fail the rule and
//   the one-sided window on the step's far side carries the estimate, so the step stays sharp; on
//   a flat stretch the windows grow to their limit and average the noise away.
//
// Every output sample depends only on the samples within the smoother's half width of it, so a
// long log can be reconstructed in blocks with that much margin and give the same doubles.
#pragma once

#include <vector>

namespace mpdrig {

// A band counts as carried when its averaged power exceeds the white-noise floor this many times
// (20 dB: a component of a quarter of the noise's standard deviation over a 2-minute log).
inline constexpr double kBandDetectionRatio = 100.0;
// Largest gain loss of the band-limited smoother at the highest carried frequency.
inline constexpr double kBandGainTolerance = 1.0e-3;

// Standard deviation of the white noise on a series, from its second differences: white noise of
// variance s^2 gives d2 = e[i-1] - 2 e[i] + e[i+1] of variance 6 s^2, a smooth signal only
// (omega dt)^2 of its amplitude, a step two outliers; the median absolute value ignores both
// (1.4826 MAD = s for a Gaussian). 0 for fewer than 3 samples or a noise-free series.
double WhiteNoiseSigma(const std::vector<double>& values);

// The highest frequency [Hz] at which `values` (sampled every dt_s) carries power above
// kBandDetectionRatio times the floor of white noise of standard deviation `sigma`: Welch's
// averaged periodogram with a 4-term Blackman-Harris window (-92 dB side lobes, so a large slow
// heave does not leak into the bands above it), segments of about 40 s (a power of two of
// 4096..65536 samples), the whole series if shorter. 0 when no band
// does (a piston at rest).
double HighestSignalFrequencyHz(const std::vector<double>& values, double dt_s, double sigma);

// Half width [s] of the tricube local quadratic (SmoothBandLimited) that passes f_hz with a gain
// of 1 - kBandGainTolerance; +inf for f_hz <= 0.
double BandLimitedHalfWidthS(double f_hz);

// Local quadratic with tricube weights (1 - |tau/h|^3)^3 over |t_j - t_i| < half_width_s, at each
// sample's own time (non-uniform sampling allowed). Near the ends the window is one-sided. A
// quadratic passes unchanged. half_width_s <= 0 returns `values`.
std::vector<double> SmoothBandLimited(const std::vector<double>& time_s,
                                      const std::vector<double>& values, double half_width_s);

// Running sums of a series, for SmoothKeepingSteps's window sums in O(1): the sum of y and of
// (n - s) y over the samples of its segment before this one, segments of kSumSegmentSamples
// counted from the series' first sample (s the segment's first index), and at a segment's first
// sample the previous segment's totals. Built in order from the first sample, so a long series
// reconstructed in blocks carries them on and every window sum is the same double as over the
// whole series; segments keep the sums' magnitude, and so their rounding, bounded.
inline constexpr long kSumSegmentSamples = 65536;
struct RunningSum {
  double y = 0.0, ny = 0.0;            // within the segment, before this sample
  double prev_y = 0.0, prev_ny = 0.0;  // at a segment's first sample: the previous segment's
};
class RunningSums {
 public:
  // This sample's entry (the sums before it), then counts it.
  RunningSum Push(double y);
  // The entry a next sample would get.
  RunningSum Next() const;

 private:
  long count_ = 0;
  double y_ = 0.0, ny_ = 0.0;
};

struct StepKeepingOptions {
  double sigma = 0.0;  // the white noise's standard deviation; <= 0 returns the input
  // Windows of 2, 4, 8, ... samples on a side, up to this many.
  long max_half_width_samples = 0;
  // ICI threshold Gamma: windows grow while the intervals estimate +- Gamma std intersect.
  double threshold = 2.5;
};

// LPA-ICI (see the header comment) in the sample index: local linear fits over windows counted in
// samples (the log's sampling is near uniform), from the left, the right and centred. `sums` has
// one entry per value (RunningSums::Push) and one more after the last (RunningSums::Next);
// first_index is values[0]'s index in the series the sums were built over. Value i depends only
// on values within max_half_width_samples of it.
std::vector<double> SmoothKeepingSteps(const std::vector<double>& values,
                                       const std::vector<RunningSum>& sums, long first_index,
                                       const StepKeepingOptions& options);
// The same for a whole series (builds its sums).
std::vector<double> SmoothKeepingSteps(const std::vector<double>& values,
                                       const StepKeepingOptions& options);

}  // namespace mpdrig
