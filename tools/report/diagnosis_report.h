// The diagnosis (model/identification/diagnose.h) as JSON and as one self-contained HTML page.
// JSON field names are a stable interface (docs/effects-and-diagnose.md, "JSON fields"):
//   baseline   {error, fit_error, params {key: {value, std_error}}, channels {name: nrmse}}
//   candidates [ranked best first: {effect, round, params, error, penalised_error, improvement,
//               significant, explains, extra_params, fit_error, channels, strength_key?, ...}]
//   verdict    the missing effect's name, or null (the first of `selected`)
//   selected   [the effects added in order, each as a candidate against the model before it]
//   next       the candidate that ended the selection (not significant), or null
//   selection_end  why the selection ended; failed [{effect, round, failure}]: not ranked
//   noise_floor, fit_end_s, replays, where_baseline_fails {worst_channels, bands, lag}
//   split      {fit_end_s, requested_fit_end_s, one_sided}; regimes [{name, input, duration_s,
//               fit_s, score_s, intervals}] (regimes.h)
//   residual   what the best model leaves (residual_signature.h): {model, misses, reasons, error,
//               noise_floor, sensor_floor, input_floor, summary, findings, channels, bands,
//               regimes, ...}
// `error` is compare's error (mean NRMSE over the compared channels) on the scoring data.
#pragma once

#include <string>

#include "model/identification/diagnose.h"

namespace mpdrig::report {

std::string DiagnosisJson(const Diagnosis& diagnosis, const std::string& log_path);
// Error step by step as the selected effects are added, what the best model leaves against the
// noise floor, the regimes and the split, before and after the winning effect side by side per
// channel, the ranking, and where the fitted base model fails (inline SVG, no script, opens
// offline).
std::string DiagnosisHtml(const Diagnosis& diagnosis, const std::string& log_path);

}  // namespace mpdrig::report
