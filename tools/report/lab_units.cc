#include "tools/report/lab_units.h"

namespace mpdrig::report {

double LabValue(riglog::Unit unit, double value_si, double atmospheric_pressure_pa) {
  return riglog::FromSi(unit, value_si, atmospheric_pressure_pa);
}

double LabDifference(riglog::Unit unit, double difference_si) {
  // Every conversion is affine: the offset cancels in a difference.
  return riglog::FromSi(unit, difference_si, 0.0) - riglog::FromSi(unit, 0.0, 0.0);
}

std::string DifferenceUnit(riglog::Unit unit) {
  switch (unit) {
    case riglog::Unit::kBarg:
    case riglog::Unit::kBara:
      return "bar";
    case riglog::Unit::kPag:
    case riglog::Unit::kPaa:
      return "Pa";
    default:
      return std::string(riglog::UnitSuffix(unit));
  }
}

}  // namespace mpdrig::report
