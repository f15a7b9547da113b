// Lab units for the comparison's edges (JSON, HTML): each channel in the unit its log used.
#pragma once

#include <string>

#include "model/riglog/channels.h"

namespace mpdrig::report {

// A level (a mean, a trace value) in `unit`: bar gauge for barg, etc.
double LabValue(riglog::Unit unit, double value_si, double atmospheric_pressure_pa);
// A difference (rms, bias, amplitude, a transfer function's numerator) in `unit`'s scale: gauge
// and absolute pressures differ by an offset only, so both give bar (or Pa).
double LabDifference(riglog::Unit unit, double difference_si);
// The unit of a difference: "bar" for barg/bara, "Pa" for pag/paa, else the suffix ("lpm").
std::string DifferenceUnit(riglog::Unit unit);

}  // namespace mpdrig::report
