// The comparison (model/analysis/compare.h) as JSON, in each channel's lab unit. The field
// names are a stable interface, documented in docs/compare.md ("JSON fields"); add
// fields, never rename or remove them. Numbers that are undefined (NaN) are written as null.
#pragma once

#include <string>

#include "model/analysis/compare.h"

namespace mpdrig::report {

// What the comparison was run with, for the JSON and the HTML report.
struct ReportContext {
  std::string log_path;
  std::string model_description;  // "quasilinear, 200 cells, characteristics (dt 5.29 ms)"
  std::string config;             // config file and --set overrides, as given
  double atmospheric_pressure_pa = 101325.0;
};

std::string ComparisonJson(const Comparison& comparison, const ReportContext& context);

}  // namespace mpdrig::report
