// The compare metric on a time window: per channel y (measured) and yhat (model), over the
// samples of the window where y is measured,
//   ss_res = sum (yhat - y)^2,   ss_tot = sum (y - mean(y))^2,   NRMSE = sqrt(ss_res / ss_tot)
// (compare.h: NRMSE = ||y - yhat|| / ||y - mean(y)||). compare's accumulator, fit's cost report
// and diagnose's scores all take their NRMSE from here, so a "mean NRMSE" means one thing.
#pragma once

#include <limits>
#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"

namespace mpdrig {

// NRMSE from the two sums; NaN where the measurement is constant (no variation to explain).
double Nrmse(double ss_res, double ss_tot);

// Whether a measurement that spreads by `std_si` (its standard deviation) about `mean_si` is
// constant: its spread is rounding, not variation. Relative to its level, 1e-9 (a double carries
// 16 digits, a lab log 4-6; rounding in the model's arithmetic or a conversion is far below
// 1e-9, the coarsest variation a log's digits can show far above), and, for a level near 0,
// 1e-12 of the quantity's physical span (riglog::PhysicalRangeOf: 2e-4 Pa of pressure,
// 2e-13 m^3/s of flow). A constant channel has no variation to explain: its NRMSE is
// undefined (NaN), and it is left out of an error averaged over channels.
bool IsConstantSpread(Channel channel, double mean_si, double std_si);

struct WindowSums {
  double ss_res = 0.0;
  double ss_tot = 0.0;
  long count = 0;         // measured samples in the window
  bool constant = false;  // the measurement is constant there (IsConstantSpread): NRMSE NaN
  double nrmse() const {
    return constant ? std::numeric_limits<double>::quiet_NaN() : Nrmse(ss_res, ss_tot);
  }
};

// Each channel's mean over the measured samples of [begin_s, end_s] (0 where there is none).
std::vector<double> WindowMeans(const MeasuredLog& log, double begin_s, double end_s);

// The sums of every channel of `log` over [begin_s, end_s] (both ends included). ss_tot is taken
// about `means` when given (e.g. a whole window's means, for blocks of it), else about each
// channel's own mean over the window.
std::vector<WindowSums> ChannelWindowSums(const MeasuredLog& log, const ModelTraces& model,
                                          double begin_s, double end_s,
                                          const std::vector<double>* means = nullptr);

// Mean NRMSE over the channels with a defined NRMSE, on [begin_s, end_s]: compare's `error`
// restricted to the window. NaN if no channel has one.
double WindowError(const MeasuredLog& log, const ModelTraces& model, double begin_s, double end_s);

// The log's own side of WindowError on [begin_s, end_s]: each channel's ss_tot, count and
// constancy, which no model changes. A search that scores many replays on one window measures it
// once (WindowErrorAccumulator's second constructor) instead of once a replay.
struct WindowReference {
  double begin_s = 0.0, end_s = 0.0;
  std::size_t samples = 0;       // the log's, as a check that it is used with the same log
  std::vector<WindowSums> sums;  // ss_res 0
};
WindowReference MeasureWindow(const MeasuredLog& log, double begin_s, double end_s);

// WindowError as a replay goes on, sample by sample in time order, with a bound below the final
// error at every sample: each ss_res is a sum of squares in time order, so its partial sum (the
// same additions, in the same order) never exceeds the final one, and ss_tot is the log's own.
// A search can stop a replay whose bound has passed the errors that matter (diagnose's scans):
// its error would have been larger. Error() after the last sample is WindowError's, to the bit.
// (The bound assumes that every channel defined now stays so: a model value that turns NaN later
// drops its channel from WindowError's mean, which may then fall below the bound.)
class WindowErrorAccumulator {
 public:
  WindowErrorAccumulator(const MeasuredLog& log, double begin_s, double end_s);
  // `reference`: MeasureWindow of this log (its measured channels as they are now).
  WindowErrorAccumulator(const MeasuredLog& log, const WindowReference& reference);
  // Sample n of the log: the model's value of each of the log's channels, in their order.
  void Add(std::size_t n, const double* model_values);
  double LowerBound() const;  // <= Error() at the end; NaN while no channel is defined
  double Error() const;       // WindowError's value over the samples added

 private:
  const MeasuredLog& log_;
  double begin_s_, end_s_;
  std::vector<WindowSums> sums_;  // ss_tot, count, constant from the log; ss_res accumulates
};

}  // namespace mpdrig
