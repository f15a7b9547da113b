// What a model leaves unexplained in a log, and whether that is more than noise: the signature of
// the residual e = yhat - y of the best model diagnose found (the fitted base model, or it with the
// effects selected), so that where no effect of the catalogue explains the error the diagnosis can
// say so plainly and say what is left.
//
// Noise floor (the error a perfect model would have on this log), per channel c, two parts:
//   sensor:  sigma_c / std(y_c), sigma_c the white-noise level of the measurement from its second
//            differences (the median absolute deviation of y[n] - 2 y[n-1] + y[n-2], x 1.4826 for
//            a normal, / sqrt(6): robust to water-hammer fronts and cavity collapses), as
//            EstimateNoiseFloor;
//   inputs:  ||yhat' - yhat|| / ||y - mean(y)||, yhat' the same model replayed on the log's inputs
//            with fresh white noise of their own estimated levels added (log_inputs.h's plan) and
//            reconstructed again: the model sees noisy inputs, and a replay of one noise
//            realisation departs from the truth's by about as much as one replay departs from
//            another (linear in the noise).
//   floor_c = sqrt(sensor_c^2 + inputs_c^2); the floor is their mean over the channels, as the
//   error is (compare's mean NRMSE).
// What is left is above the noise when, beyond kMissesFactor times the floor, (a) its error on the
// scoring data (the mean over channels), or (b) one channel's error there (a fault of one sensor
// is diluted in the mean over 16 channels), or (c) its error in one regime over the whole log
// (a regime may last seconds; its residual normalised per sample, as its floor) is.
// Effect-free lab-noise logs gave ratios of 0.75-1.25 per channel and 0.99-1.1 for the mean
// (measured, docs/effects-and-diagnose.md): 2 leaves a margin of 1.6.
// Then, where no effect was selected (the best model is the fitted base model), the model misses
// something the catalogue does not hold (`misses`); where effects were selected, what is left may
// be that, or their fits stopping short of the truth (a pump curve named with its error down from
// 56 % to 7.7 % against a floor of 1.4 %, on a log with nothing else hidden): the summary says
// both.
//
// Signature, over the whole log (what is left, not a score), per channel:
//   nrmse, its floor, excess = sqrt(max(0, nrmse^2 - floor^2)) (what is not noise),
//   bias (mean of e) and steady share: the energy of e's mean over each part of the log (the
//   parts its regimes make; the whole log without) over the energy beyond the noise,
//   excess^2 ||y - mean(y)||^2, at most 1 (a steady offset against dynamics);
// per band of the residual's spectrum (periodogram of e - mean(e), zero-padded DFT, Parseval):
//   bands relative to the pipe's quarter-wave frequency f_q = c / 4L (the open choke's first
//   resonance): slow [0, f_q/3) (levels, drifts), heave and first modes [f_q/3, 2 f_q) (c/4L open,
//   c/2L closed), higher modes [2 f_q, 10 f_q), fast [10 f_q, f_s/2] (fronts, noise); the
//   error and the floor in each (white sensor noise spreads evenly over frequency, the replayed
//   input noise as its own spectrum says), and each band's share of the excess energy;
// along the pipe: the excess at PT1..PT10 (x = 0..900 m);
// per regime (regimes.h): the error over its samples, each channel's residual normalised by the
// channel's variation over the whole log (so regimes compare), its floor the same way, and its
// steady share (the regime's own mean residual over its energy beyond the noise).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/identification/regimes.h"

namespace mpdrig {

// "Far above the noise floor": the error more than twice the floor, i.e. what is not noise,
// sqrt(e^2 - floor^2), at least sqrt(3) = 1.7 times the noise.
inline constexpr double kMissesFactor = 2.0;
// A finding names channels whose excess is at least this share of the largest one's ...
inline constexpr double kLeadingShare = 0.5;
// ... a band or a regime that carries at least this share of the excess ...
inline constexpr double kBandShare = 0.25;
// ... a regime whose error beyond the noise is at least this many times the other state's of
// its input ...
inline constexpr double kRegimeContrast = 2.0;
// ... one transmitter whose excess is this many times any other transmitter's (a sensor, not the
// pipe: a wave or a leak moves its neighbours too) ...
inline constexpr double kSingleTransmitterFactor = 3.0;
// ... and a residual whose mean carries at least this share of its energy is steady.
inline constexpr double kSteadyShare = 0.5;

// How the noise floor is estimated (for the report).
inline constexpr const char* kNoiseFloorMethod =
    "per channel: the measurement's white noise from its second differences (median absolute "
    "deviation), and the inputs' noise replayed (the model replayed once more with fresh noise of "
    "the inputs' own estimated levels); floor = sqrt(sensor^2 + inputs^2), mean over channels";

struct ChannelResidual {
  Channel channel = Channel::kP1;
  std::optional<double> x_m;  // along the pipe (PT1..PT10)
  double nrmse = 0.0;         // whole log
  double sensor_floor = 0.0;
  double input_floor = 0.0;
  double floor = 0.0;      // sqrt(sensor^2 + input^2)
  double excess = 0.0;     // sqrt(max(0, nrmse^2 - floor^2))
  double bias_si = 0.0;    // mean of yhat - y (SI, differences)
  double bias_unit = 0.0;  // the same in the log's unit for the channel (a difference)
  double steady_share = 0.0;
  // On the scoring data: its error and floor there (over the window's own variation).
  double score_nrmse = std::numeric_limits<double>::quiet_NaN();
  double score_floor = std::numeric_limits<double>::quiet_NaN();
};

struct BandResidual {
  std::string name;  // "slow", "heave and first modes", "higher modes", "fast"
  double low_hz = 0.0, high_hz = 0.0;
  double error = 0.0;         // mean over channels of sqrt(band energy / ss_tot)
  double floor = 0.0;         // the same for the noise's expected band energy
  double excess_share = 0.0;  // of the excess energy summed over bands and channels
};

struct RegimeResidual {
  std::string regime;  // Regime::name
  std::string input;
  double duration_s = 0.0;
  double error = 0.0;  // mean over channels, residual over the whole log's variation per sample
  double floor = 0.0;
  double steady_share = 0.0;  // its own mean residual over its energy beyond the noise
  std::vector<std::pair<Channel, double>> channel_errors;
  // The pressures' mean residual there (yhat - y), in the log's unit of each (a difference).
  std::vector<std::pair<Channel, double>> channel_bias;
};

struct ResidualSignature {
  std::string model;  // "base model", "base model + sensor_lag"
  // On the scoring data: the model's error, the noise floor and its parts, and the decision.
  double error = 0.0;
  double noise_floor = 0.0;
  double sensor_floor = 0.0;
  double input_floor = 0.0;
  bool above_noise = false;          // any of (a)-(c) above
  bool misses = false;               // above_noise, and no effect selected
  std::vector<std::string> reasons;  // which, with their numbers
  // Over the whole log.
  double whole_error = 0.0;
  double whole_floor = 0.0;
  double steady_share = 0.0;  // of the energy beyond the noise, summed over channels
  double quarter_wave_hz = 0.0;
  std::vector<ChannelResidual> channels;  // the log's order
  std::vector<BandResidual> bands;
  std::vector<RegimeResidual> regimes;
  // Sentences: "channels: ...", "bands: ...", "along the pipe: ...", "steady or dynamic: ...",
  // "regimes: ...".
  std::vector<std::string> findings;
  // One paragraph: "the base model misses something the catalogue does not hold: ..." where
  // `misses`, "the base model + X still leaves more than noise: ..." where above_noise with
  // effects selected, else "what the ... leaves is noise: ...".
  std::string Summary() const;
};

struct ResidualInputs {
  const MeasuredLog* log = nullptr;
  const ModelTraces* model = nullptr;
  // The same model replayed with fresh input noise (WithFreshInputNoise); null: no input floor.
  const ModelTraces* input_noise = nullptr;
  double score_begin_s = 0.0, score_end_s = 0.0;
  const std::vector<Regime>* regimes = nullptr;
  double quarter_wave_hz = 0.0;  // c / 4L of the model
  std::string model_name;
  std::size_t selected_effects = 0;  // effects of the catalogue in the model
};

ResidualSignature DescribeResidual(const ResidualInputs& inputs);

// `log` with white noise of its inputs' estimated levels (log.reconstruction) added to the
// measured inputs, then reconstructed again with the same plan and levels: replayed, it departs
// from the replay of `log` as much as the inputs' noise moves the model. Deterministic for a seed.
MeasuredLog WithFreshInputNoise(const MeasuredLog& log, std::uint64_t seed);

// The white-noise standard deviation of a measured series from its second differences (above),
// about their median and over the samples measured three in a row (NaN where not measured);
// 0 for fewer than 3 such.
double MeasurementNoiseSigma(const std::vector<double>& y);

}  // namespace mpdrig
