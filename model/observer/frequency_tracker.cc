#include "model/observer/frequency_tracker.h"

#include <cmath>
#include <sstream>

namespace mpdrig::observer {

Status FrequencyTrackerOptions::Validate() const {
  std::ostringstream out;
  if (!(min_hz > 0.0 && max_hz > min_hz && std::isfinite(max_hz))) {
    out << "frequency tracker: need 0 < min_hz < max_hz, got " << min_hz << ", " << max_hz;
  } else if (!(initial_hz >= min_hz && initial_hz <= max_hz)) {
    out << "frequency tracker: initial frequency " << initial_hz << " Hz outside [" << min_hz
        << ", " << max_hz << "] Hz";
  } else if (!(mean_time_constant_s > 0.0 && std::isfinite(mean_time_constant_s))) {
    out << "frequency tracker: mean_time_constant_s must be > 0";
  } else if (!(hysteresis >= 0.0 && hysteresis < 10.0) || periods_averaged < 1) {
    out << "frequency tracker: need hysteresis in [0, 10) and periods_averaged >= 1";
  } else {
    return Status::Ok();
  }
  return Status::Error(out.str());
}

Result<FrequencyTracker> FrequencyTracker::Create(const FrequencyTrackerOptions& options,
                                                  double start_time_s, double start_value) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  if (!std::isfinite(start_time_s) || !std::isfinite(start_value)) {
    return Status::Error("frequency tracker: start sample must be finite");
  }
  FrequencyTracker t(options);
  t.frequency_hz_ = options.initial_hz;
  t.last_time_s_ = start_time_s;
  t.mean_ = start_value;
  return t;
}

void FrequencyTracker::Update(double time_s, double value) {
  const double dt = time_s - last_time_s_;
  if (!(dt > 0.0) || !std::isfinite(value)) return;
  // Exact discretisation of the first-order filters for a held input.
  const double w = 1.0 - std::exp(-dt / options_.mean_time_constant_s);
  mean_ += w * (value - mean_);
  const double deviation = value - mean_;
  amplitude_ += w * (std::fabs(deviation) - amplitude_);
  if (deviation < -options_.hysteresis * amplitude_) armed_ = true;
  if (armed_ && last_deviation_ < 0.0 && deviation >= 0.0) {
    armed_ = false;
    const double crossing = last_time_s_ + dt * (-last_deviation_) / (deviation - last_deviation_);
    if (have_crossing_) {
      const double period = crossing - last_crossing_s_;
      if (period >= 1.0 / options_.max_hz && period <= 1.0 / options_.min_hz) {
        periods_s_.push_back(period);
        while (static_cast<int>(periods_s_.size()) > options_.periods_averaged) {
          periods_s_.pop_front();
        }
        if (locked()) {
          double total = 0.0;
          for (double p : periods_s_) total += p;
          frequency_hz_ = periods_s_.size() / total;
        }
      }
    }
    have_crossing_ = true;
    last_crossing_s_ = crossing;
  }
  last_deviation_ = deviation;
  last_time_s_ = time_s;
}

}  // namespace mpdrig::observer
