// The comparison's metrics (compare.h) computed in two passes over a log's rows, in memory that
// does not grow with the log's length. Both the streaming CompareLog and the in-memory
// CompareTraces feed these: one implementation of each metric.
//
//   LogScanner (pass 1): the rows without the model: length, times, each channel's count and
//     mean, the inputs' means and ranges, the smoothed piston's Welch power spectrum.
//   ComparisonAccumulator (pass 2): the rows with the model, in the same order: running sums
//     (NRMSE, RMS, bias), Welch band and transfer-function sums and the averaged cross-spectrum
//     for the lag, lagged residual sums (a history of M samples), envelopes and the close-up.
//
// Memory, per compared channel: two rings of one Welch segment (y and yhat; at most
// CompareOptions::welch_segment_samples each), the summed cross-spectrum for the lag (about as
// many complex numbers over 2), 2 M + 1 lagged sums per input, the envelope and the close-up.
#pragma once

#include <array>
#include <complex>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/analysis/compare.h"
#include "model/analysis/log_stream.h"
#include "model/signal/spectrum.h"

namespace mpdrig {

// The three inputs the residual is correlated with (compare.h).
inline constexpr std::size_t kResidualInputCount = 3;
inline constexpr std::array<const char*, kResidualInputCount> kResidualInputNames = {
    "piston_velocity", "piston_position", "choke_position"};

// What pass 1 learns of the whole log.
struct LogSummary {
  struct ChannelSummary {
    Channel channel = Channel::kP1;
    riglog::Unit unit = riglog::Unit::kBarg;
    std::size_t source_index = 0;  // in the rows' measured_si
    long count = 0;                // measured samples
    double mean_si = 0.0;          // over them
    bool has_gaps = false;         // count < samples
  };
  long samples = 0;
  double t0_s = 0.0, t1_s = 0.0;
  double sample_interval_s = 0.0;        // mean
  bool uniform_sampling = true;          // every interval within 1 % of the mean
  std::vector<ChannelSummary> channels;  // those with a measured sample, source order
  // Welch: segment length, DFT size, segment count, bin width; the smoothed piston's windowed
  // power |U_k|^2 summed over the segments, k = 0 .. fft_size / 2.
  std::size_t segment_length = 0, fft_size = 0, segments = 0;
  double df_hz = 0.0;
  std::vector<double> piston_power;
  std::array<double, kResidualInputCount> input_mean{};
  std::array<bool, kResidualInputCount> input_constant{};
};

class LogScanner {
 public:
  LogScanner(std::vector<SourceChannel> channels, const CompareOptions& options);
  void Add(const PipelineSample& sample);
  // Errors (fewer than 4 samples, no measured channel) name `path`.
  Result<LogSummary> Finish(const std::string& path);

 private:
  void AddPistonSegment(std::size_t length);

  std::vector<SourceChannel> source_channels_;
  std::vector<long> counts_;
  std::vector<double> sums_;
  long samples_ = 0;
  double t0_ = 0.0, t_last_ = 0.0;
  double min_interval_ = 0.0, max_interval_ = 0.0;
  std::array<double, kResidualInputCount> input_sum_{}, input_min_{}, input_max_{};
  WelchSegmenter segmenter_;
  SampleRing piston_ring_;
  std::vector<double> piston_power_;
  std::size_t segment_length_ = 0, segments_ = 0;
  std::vector<double> scratch_, window_;
  std::vector<std::complex<double>> spectrum_;
  std::unique_ptr<RealFft> fft_;
};

class ComparisonAccumulator {
 public:
  ComparisonAccumulator(const LogSummary& summary, const CompareOptions& options);
  ~ComparisonAccumulator();
  ComparisonAccumulator(const ComparisonAccumulator&) = delete;
  ComparisonAccumulator& operator=(const ComparisonAccumulator&) = delete;

  // Rows in the order pass 1 saw them; `model_si` has one value per summary channel.
  void Add(const PipelineSample& sample, const double* model_si);
  // The metrics; `path` and the range event go into the result as they are.
  Result<Comparison> Finish(const std::string& path,
                            const std::optional<RangeEvent>& first_range_event);

 private:
  struct ChannelState;
  // The lagged residual sums that involve the mask (1 measured, 0 not), j = 0..M and per input
  // k = -M..M, stored as ChannelState's.
  struct MaskSums {
    std::vector<double> dm, md, mm;
    std::array<std::vector<double>, kResidualInputCount> mu;
  };
  void InitChannel(ChannelState* state, const LogSummary::ChannelSummary& summary,
                   std::size_t transfer_groups) const;
  // Add's steps.
  void AddInputCloseUp(const LogRow& row);
  std::array<double, kResidualInputCount> AddResidualInputs(const PipelineSample& sample);
  void AddToZoomRing(ChannelState* s, long n, double time_s, double y, double yhat) const;
  void AddLaggedSums(ChannelState* s, double y, double yhat,
                     const std::array<double, kResidualInputCount>& u) const;
  void AddSegment(std::size_t length);
  void TakeSnapshot(ChannelState* s, long last) const;
  // Finish's steps.
  Comparison LogMetrics(const std::string& path,
                        const std::optional<RangeEvent>& first_range_event) const;
  ChannelMetrics SampleMetrics(const ChannelState& s) const;
  void CalcLag(const ChannelState& s, ChannelMetrics* metrics) const;
  std::vector<BandMetrics> CalcBands(const ChannelState& s) const;
  TransferFunction CalcTransferFunction(const ChannelState& s) const;
  MaskSums CalcMaskSums(const ChannelState& s) const;
  ResidualAnalysis CalcResidualAnalysis(const ChannelState& s, const ChannelMetrics& metrics) const;
  TraceWindow Zoom(ChannelState* s) const;

  const LogSummary& summary_;
  CompareOptions options_;
  long added_ = 0;
  InputCloseUp input_close_up_;
  // Shared by the channels.
  std::vector<std::pair<double, int>> band_centres_;  // frequency, harmonic (0: further peak)
  double max_lag_s_ = 0.0;
  std::size_t max_lag_ = 0, lag_fft_size_ = 0;
  std::vector<double> window_;
  double window_power_ = 0.0;
  std::vector<double> window_correlation_;  // W(k), k = -max_lag..max_lag
  double zoom_span_s_ = 10.0;
  std::vector<std::size_t> excited_bins_;   // transfer functions: piston bins with power
  std::vector<std::size_t> excited_group_;  // their log-spaced group
  WelchSegmenter segmenter_;
  SampleRing piston_ring_;
  std::vector<double> piston_segment_;
  std::unique_ptr<RealFft> fft_, lag_fft_;  // sizes M and P
  // Residual inputs (mean removed): the last M + 1 values, newest first, and their sums.
  class History;
  std::vector<History> input_history_;
  std::array<double, kResidualInputCount> input_sum_{}, input_square_sum_{};
  std::array<std::vector<double>, kResidualInputCount> input_head_;  // first M values
  std::vector<ChannelState> channels_;
};

}  // namespace mpdrig
