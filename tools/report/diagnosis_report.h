// The diagnosis (model/identification/diagnose.h) as JSON and as one self-contained HTML page.
// JSON field names are a stable interface (docs/effects-and-diagnose.md, "JSON fields"):
//   baseline   {error, fit_error, params {key: {value, std_error}}, channels {name: nrmse}}
//   candidates [ranked best first: {effect, params, error, penalised_error, improvement,
//               significant, explains, extra_params, fit_error, channels, failure?}]
//   verdict    the missing effect's name, or null
//   noise_floor, fit_end_s, replays, where_baseline_fails {worst_channels, bands, lag}
// `error` is compare's error (mean NRMSE over the compared channels) on the scoring data.
#pragma once

#include <string>

#include "model/identification/diagnose.h"

namespace mpdrig::report {

std::string DiagnosisJson(const Diagnosis& diagnosis, const std::string& log_path);
// Error before and after the winning effect side by side per channel, the ranking, and where
// the fitted base model fails (inline SVG, no script, opens offline).
std::string DiagnosisHtml(const Diagnosis& diagnosis, const std::string& log_path);

}  // namespace mpdrig::report
