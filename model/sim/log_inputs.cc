#include "model/sim/log_inputs.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "model/common/units.h"
#include "model/signal/smoothing.h"

namespace mpdrig {
namespace {

// A log column that must be finite on every row.
Result<std::vector<double>> RequireFinite(const riglog::RigLog& log, std::string_view channel,
                                          const std::string& path) {
  const std::vector<double>* values = log.Find(channel);
  if (values == nullptr) {
    return Status::Error(path + ": required input column '" + std::string(channel) +
                         "_<unit>' is missing");
  }
  for (std::size_t row = 0; row < values->size(); ++row) {
    if (!std::isfinite((*values)[row])) {
      std::ostringstream out;
      out << path << ": input " << channel << " is not measured (empty or nan) at data row "
          << row + 1 << " (time_s = " << log.time_s[row] << "); the model needs every input sample";
      return Status::Error(out.str());
    }
  }
  return *values;
}

// The input columns behind the time functions, interpolated linearly (as PiecewiseLinear) with
// one shared time vector and a remembered bracket: the simulator asks for increasing times, so
// the search is O(1) amortised instead of a binary search per call.
class SharedInputs {
 public:
  SharedInputs(LogInputColumns columns, std::vector<double> smoothed_piston_m)
      : columns_(std::move(columns)), piston_m_(std::move(smoothed_piston_m)) {}

  double At(const std::vector<double>& values, double t) const {
    const std::vector<double>& time = columns_.time_s;
    if (t <= time.front()) return values.front();
    if (t >= time.back()) return values.back();
    std::size_t j = hint_;
    if (!(j > 0 && j < time.size() && time[j - 1] <= t && t < time[j])) {
      j = static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), t) - time.begin());
      hint_ = j;
    }
    const double w = (t - time[j - 1]) / (time[j] - time[j - 1]);
    return (1.0 - w) * values[j - 1] + w * values[j];
  }
  double Piston(double t) const { return At(piston_m_, t); }
  RigInputs Rig(double t) const {
    RigInputs in;
    in.choke_opening_frac = At(columns_.choke_opening_frac, t);
    in.pump_flow_m3ps = At(columns_.pump_flow_m3ps, t);
    in.outlet_pressure_pa = At(columns_.outlet_pressure_pa, t);
    return in;
  }

 private:
  LogInputColumns columns_;
  std::vector<double> piston_m_;
  mutable std::size_t hint_ = 0;  // a search cache only: the values do not depend on it
};

}  // namespace

void InitialInputs::Add(double time_s, const RigInputs& row) {
  if (count_ == 0) first_time_s_ = time_s;
  if (time_s > first_time_s_ + kInitialInputWindowS) return;
  sum_.choke_opening_frac += row.choke_opening_frac;
  sum_.pump_flow_m3ps += row.pump_flow_m3ps;
  sum_.outlet_pressure_pa += row.outlet_pressure_pa;
  ++count_;
}

RigInputs InitialInputs::Mean() const {
  MPDRIG_CHECK(count_ > 0);
  const double n = static_cast<double>(count_);
  return {sum_.choke_opening_frac / n, sum_.pump_flow_m3ps / n, sum_.outlet_pressure_pa / n};
}

Result<LogInputColumns> InputColumnsFromLog(const riglog::RigLog& log, const std::string& path) {
  LogInputColumns columns;
  auto piston = RequireFinite(log, "piston_position", path);
  if (!piston.ok()) return piston.status();
  auto choke = RequireFinite(log, "choke_position", path);
  if (!choke.ok()) return choke.status();
  const std::size_t n = log.num_rows();
  columns.time_s = log.time_s;
  columns.piston_position_m = std::move(piston).value();
  columns.choke_opening_frac = std::move(choke).value();
  // Optional inputs: absent means the documented default; present means measured everywhere.
  columns.pump_flow_m3ps.assign(n, 0.0);
  columns.outlet_pressure_pa.assign(n, log.atmospheric_pressure_pa);
  if (log.Find("FT2") != nullptr) {
    auto values = RequireFinite(log, "FT2", path);
    if (!values.ok()) return values.status();
    columns.pump_flow_m3ps = std::move(values).value();
  }
  if (log.Find("C1") != nullptr) {
    auto values = RequireFinite(log, "C1", path);
    if (!values.ok()) return values.status();
    columns.outlet_pressure_pa = std::move(values).value();
  }
  return columns;
}

std::vector<double> SmoothedPistonPosition(const LogInputColumns& columns, double smoothing_s) {
  return SmoothLocalQuadratic(columns.time_s, columns.piston_position_m, smoothing_s);
}

Result<InputSignals> SignalsFromColumns(LogInputColumns columns, const std::string& path,
                                        double smoothing_s) {
  const std::size_t n = columns.time_s.size();
  if (n < 2) return Status::Error(path + ": needs at least 2 samples");
  MPDRIG_CHECK(columns.piston_position_m.size() == n && columns.choke_opening_frac.size() == n &&
               columns.pump_flow_m3ps.size() == n && columns.outlet_pressure_pa.size() == n);
  std::vector<double> smoothed = SmoothedPistonPosition(columns, smoothing_s);
  // As RowPipeline (compare's replay): the mean over the first kInitialInputWindowS.
  InitialInputs initial;
  for (std::size_t i = 0; i < n; ++i) {
    if (columns.time_s[i] > columns.time_s[0] + kInitialInputWindowS) break;
    initial.Add(columns.time_s[i], {columns.choke_opening_frac[i], columns.pump_flow_m3ps[i],
                                    columns.outlet_pressure_pa[i]});
  }
  auto shared = std::make_shared<SharedInputs>(std::move(columns), std::move(smoothed));
  InputSignals signals;
  signals.piston_position_m = [shared](double t) { return shared->Piston(t); };
  signals.rig = [shared](double t) { return shared->Rig(t); };
  signals.initial = initial.Mean();
  return signals;
}

Result<InputSignals> SignalsFromLog(const riglog::RigLog& log, const std::string& path,
                                    double smoothing_s) {
  if (log.num_rows() < 2) return Status::Error(path + ": needs at least 2 samples");
  auto columns = InputColumnsFromLog(log, path);
  if (!columns.ok()) return columns.status();
  return SignalsFromColumns(std::move(columns).value(), path, smoothing_s);
}

}  // namespace mpdrig
