// The comparison as one self-contained HTML page: a summary table on top, then the
// error along the pipe, measured vs model empirical transfer functions piston -> PT1 and -> C2,
// per channel the measured and model traces (min/max envelopes per pixel column, so an hour at
// 1 kHz draws as fast as a minute) with their residual, the bands, and the residual analysis
// (autocorrelation and cross-correlation with the inputs against the 99% band).
// Inline SVG and CSS only: no script, no fonts, no network reference, so it opens offline.
#pragma once

#include <string>

#include "model/analysis/compare.h"
#include "tools/report/comparison_json.h"

namespace mpdrig::report {

std::string ComparisonHtml(const Comparison& comparison, const ReportContext& context);

}  // namespace mpdrig::report
