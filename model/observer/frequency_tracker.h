// Online estimate of the dominant heave frequency (beyond the thesis, which needs it given).
//
// A zero-crossing period meter on a topside signal s(t) (the observer feeds it the measured
// up-going wave y = u(1, t), which carries what arrives from the heave generator):
//   mean:       m' = (s - m) / tau                    (exponential, tau = mean_time_constant_s)
//   amplitude:  a' = (|s - m| - a) / tau               (mean absolute deviation)
//   an upward crossing of m, after s was below m - hysteresis * a, ends a period; the crossing
//   time is interpolated linearly between samples. The estimate is the number of periods over
//   their total duration, for the last `periods_averaged` periods whose frequency lies in
//   [min_hz, max_hz]. Until that many periods are seen the initial frequency is reported.
// It assumes one dominant oscillation: a choke moved at another frequency with a comparable
// pressure effect makes the crossings meaningless (then give the frequency).
#pragma once

#include <deque>

#include "model/common/status.h"

namespace mpdrig::observer {

struct FrequencyTrackerOptions {
  double initial_hz = 0.2;
  double min_hz = 0.02;
  double max_hz = 2.0;
  double mean_time_constant_s = 20.0;
  double hysteresis = 0.5;  // in units of the mean absolute deviation
  int periods_averaged = 3;

  Status Validate() const;
};

class FrequencyTracker {
 public:
  static Result<FrequencyTracker> Create(const FrequencyTrackerOptions& options,
                                         double start_time_s, double start_value);

  // One sample; times must increase.
  void Update(double time_s, double value);
  double frequency_hz() const { return frequency_hz_; }
  // True once `periods_averaged` periods were measured.
  bool locked() const { return static_cast<int>(periods_s_.size()) >= options_.periods_averaged; }

 private:
  explicit FrequencyTracker(const FrequencyTrackerOptions& options) : options_(options) {}

  FrequencyTrackerOptions options_;
  double frequency_hz_ = 0.0;
  double last_time_s_ = 0.0;
  double last_deviation_ = 0.0;  // s - m at the last sample
  double mean_ = 0.0;
  double amplitude_ = 0.0;
  bool armed_ = false;
  bool have_crossing_ = false;
  double last_crossing_s_ = 0.0;
  std::deque<double> periods_s_;
};

}  // namespace mpdrig::observer
