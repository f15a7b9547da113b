#include "model/params/rig_layout.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mpdrig {

double ValveClosure::RelativeOpening(double time_s) const {
  if (!points.empty()) {
    if (time_s <= points.front().time_s) return points.front().opening;
    if (time_s >= points.back().time_s) return points.back().opening;
    const auto after =
        std::upper_bound(points.begin(), points.end(), time_s,
                         [](double t, const ValveOpeningPoint& point) { return t < point.time_s; });
    const ValveOpeningPoint& b = *after;
    const ValveOpeningPoint& a = *(after - 1);
    const double w = (time_s - a.time_s) / (b.time_s - a.time_s);
    return (1.0 - w) * a.opening + w * b.opening;
  }
  if (time_s <= start_s) return 1.0;
  if (time_s >= start_s + closure_time_s) return 0.0;
  return std::pow(1.0 - (time_s - start_s) / closure_time_s, exponent);
}

double ValveClosure::ClosedAtS() const {
  if (points.empty()) return start_s + closure_time_s;
  for (const ValveOpeningPoint& point : points) {
    if (point.opening == 0.0) return point.time_s;
  }
  return std::numeric_limits<double>::infinity();
}

Status ValveClosure::Validate() const {
  auto finite = [](double value) { return std::isfinite(value); };
  if (!finite(downstream_head_m) || downstream_head_m < -10.0 || downstream_head_m > 1.0e4) {
    return Status::Error("valve downstream_head_m must be in [-10, 1e4] m");
  }
  if (points.empty()) {
    if (!finite(start_s) || !finite(closure_time_s) || !(closure_time_s > 0.0)) {
      return Status::Error("valve closure_time_s must be a finite number > 0 s");
    }
    if (!finite(exponent) || exponent < 0.1 || exponent > 10.0) {
      return Status::Error("valve exponent must be in [0.1, 10]");
    }
    return Status::Ok();
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ValveOpeningPoint& point = points[i];
    const std::string name = "valve opening point " + std::to_string(i);
    if (!finite(point.time_s) || !finite(point.opening) || point.opening < 0.0 ||
        point.opening > 1.0) {
      return Status::Error(name + ": time_s must be finite and opening in [0, 1]");
    }
    if (i > 0 && !(point.time_s > points[i - 1].time_s)) {
      return Status::Error(name + ": times must be strictly increasing");
    }
  }
  return Status::Ok();
}

Status RigLayout::Validate() const {
  if (is_ntnu_rig()) return Status::Ok();
  if (inlet != Inlet::kReservoir || outlet != Outlet::kValve) {
    return Status::Error(
        "a reservoir inlet goes with a valve outlet, and the heave generator with the choke: "
        "give both `reservoir` and `valve`, or neither");
  }
  if (!std::isfinite(reservoir_head_m) || reservoir_head_m < -10.0 || reservoir_head_m > 1.0e4) {
    return Status::Error("reservoir head_m must be in [-10, 1e4] m");
  }
  if (!std::isfinite(steady_velocity_mps) || !(steady_velocity_mps > 0.0) ||
      steady_velocity_mps > 50.0) {
    return Status::Error(
        "steady_flow velocity_mps must be in (0, 50] m/s: the run starts from steady flow "
        "towards the valve");
  }
  return valve.Validate();
}

std::string RigLayout::Describe() const {
  if (is_ntnu_rig()) return "heave generator - pipe - choke";
  std::ostringstream out;
  out << "reservoir " << reservoir_head_m << " m - pipe - valve (";
  if (valve.points.empty()) {
    out << "closes in " << valve.closure_time_s << " s from t = " << valve.start_s << " s";
  } else {
    out << valve.points.size() << " opening points";
  }
  out << "), V0 = " << steady_velocity_mps << " m/s";
  return out.str();
}

}  // namespace mpdrig
