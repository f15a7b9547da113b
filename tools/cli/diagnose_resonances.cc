#include "tools/cli/diagnose_resonances.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>

#include "model/analysis/resonance_list.h"
#include "model/common/units.h"
#include "model/effects/param_by_key.h"
#include "model/identification/resonance_diagnose.h"
#include "tools/cli/fit_resonances.h"
#include "tools/cli/parallel_tasks.h"
#include "tools/report/json.h"

namespace mpdrig::cli {
namespace {

using report::Json;
using report::JsonNumber;
using report::JsonText;

std::string Name(Termination t) { return std::string(TerminationName(t)); }

// The measured value of a termination, if the list has it.
std::optional<double> Measured(const ResonanceDiagnosis& d, Termination t) {
  for (const MeasuredResonance& m : d.measured) {
    if (m.configuration == t) return m.frequency_hz;
  }
  return std::nullopt;
}
std::optional<double> Modelled(const ResonanceFitResult& fit, Termination t) {
  for (const ResonanceFitConfiguration& c : fit.configurations) {
    if (c.configuration == t) return c.model_hz;
  }
  return std::nullopt;
}

Json JsonFitParams(const ResonanceFitResult& fit) {
  Json out = Json::object();
  for (std::size_t j = 0; j < fit.keys.size(); ++j) out[fit.keys[j]] = JsonNumber(fit.estimates[j]);
  return out;
}

Json JsonModelHz(const ResonanceFitResult& fit) {
  Json out = Json::array();
  for (const ResonanceFitConfiguration& c : fit.configurations)
    out.push_back(JsonNumber(c.model_hz));
  return out;
}

Json JsonCandidate(const ResonanceCandidate& c) {
  Json out = {{"effect", c.effect},
              {"round", c.round},
              {"outcome", std::string(OutcomeName(c.outcome))},
              {"screen_shift_hz", JsonNumber(c.screen_shift_hz)}};
  if (c.outcome != ResonanceCandidate::Outcome::kFitted) {
    out["note"] = c.note;
    return out;
  }
  Json not_excluded = Json::array();
  for (const auto& other : c.not_excluded) {
    not_excluded.push_back({{"effect", other.effect},
                            {"chi2", JsonNumber(other.chi2)},
                            {"max_error_hz", JsonNumber(other.max_error_hz)}});
  }
  Json params = Json::array();
  for (const ResonanceParamEstimate& p : c.params) {
    params.push_back({{"key", p.key},
                      {"estimate", JsonNumber(p.estimate)},
                      {"std_error", JsonNumber(p.standard_error)},
                      {"lower", JsonNumber(p.bound_lower)},
                      {"upper", JsonNumber(p.bound_upper)},
                      {"plausible_lower", JsonNumber(p.plausible_lower)},
                      {"plausible_upper", JsonNumber(p.plausible_upper)},
                      {"at_bound", p.at_bound},
                      {"within_plausible", p.within_plausible}});
  }
  out["chi2"] = JsonNumber(c.chi2);
  out["delta_chi2"] = JsonNumber(c.delta_chi2);
  out["threshold"] = JsonNumber(c.threshold);
  out["significant"] = c.significant;
  out["max_error_hz"] = JsonNumber(c.fit.max_error_hz);
  out["model_hz"] = JsonModelHz(c.fit);
  out["fitted"] = JsonFitParams(c.fit);
  out["equivalent"] = c.equivalent;
  out["not_excluded"] = std::move(not_excluded);
  out["params"] = std::move(params);
  return out;
}

Json JsonCandidates(const std::vector<ResonanceCandidate>& candidates) {
  Json out = Json::array();
  for (const ResonanceCandidate& c : candidates) out.push_back(JsonCandidate(c));
  return out;
}

// closed/open and valve/closed ratios of a set of resonances (NaN where one is missing).
struct Ratios {
  double closed_open = std::nan("");
  double valve_closed = std::nan("");
};
template <typename Get>
Ratios RatiosOf(Get get) {
  Ratios r;
  const auto closed = get(Termination::kChokeClosed), open = get(Termination::kChokeOpen),
             valve = get(Termination::kClosedAtPipeEnd);
  if (closed && open) r.closed_open = *closed / *open;
  if (closed && valve) r.valve_closed = *valve / *closed;
  return r;
}

std::string DiagnosisJson(const ResonanceDiagnosis& d, const ResonanceDiagnoseArgs& args) {
  Json resonances = Json::array();
  for (std::size_t i = 0; i < d.measured.size(); ++i) {
    const MeasuredResonance& m = d.measured[i];
    Json after_each = Json::array();
    for (const ResonanceCandidate& s : d.selected) {
      after_each.push_back(JsonNumber(s.fit.configurations[i].model_hz));
    }
    resonances.push_back(
        {{"configuration", Name(m.configuration)},
         {"measured_hz", JsonNumber(m.frequency_hz)},
         {"uncertainty_hz", JsonNumber(m.uncertainty_hz)},
         {"base_model_hz", JsonNumber(d.base.configurations[i].model_hz)},
         {"model_hz", JsonNumber(d.Final().configurations[i].model_hz)},
         {"after_each", after_each},
         {"response", std::string(ResponseMethodName(d.Final().configurations[i].method))}});
  }
  const Ratios measured = RatiosOf([&](Termination t) { return Measured(d, t); });
  const Ratios uniform = RatiosOf([&](Termination t) { return Modelled(d.uniform, t); });
  Json removed = Json::array();
  for (const RemovedEffect& r : d.removed) {
    removed.push_back({{"effect", r.effect},
                       {"round", r.round},
                       {"delta_chi2", JsonNumber(r.delta_chi2)},
                       {"threshold", JsonNumber(r.threshold)}});
  }
  const Json json = {
      {"resonance_list", args.resonances_path},
      {"held", d.held},
      {"resonances", resonances},
      {"base",
       {{"fitted", JsonFitParams(d.base)},
        {"chi2", JsonNumber(d.base.chi2_after)},
        {"max_error_hz", JsonNumber(d.base.max_error_hz)}}},
      {"uniform_wave_speed",
       {{"wave_speed_mps",
         JsonNumber(d.uniform.estimates.empty() ? std::nan("") : d.uniform.estimates[0])},
        {"chi2", JsonNumber(d.uniform.chi2_after)},
        {"max_error_hz", JsonNumber(d.uniform.max_error_hz)},
        {"model_hz", JsonModelHz(d.uniform)},
        {"closed_open_ratio", JsonNumber(uniform.closed_open)},
        {"measured_closed_open_ratio", JsonNumber(measured.closed_open)},
        {"valve_closed_ratio", JsonNumber(uniform.valve_closed)},
        {"measured_valve_closed_ratio", JsonNumber(measured.valve_closed)}}},
      {"candidates", JsonCandidates(d.candidates)},
      {"selected", JsonCandidates(d.selected)},
      {"removed", removed},
      {"next", d.next ? JsonCandidate(*d.next) : Json(nullptr)},
      {"not_fitted", JsonCandidates(d.not_fitted)},
      {"selection_end", d.selection_end},
      {"verdict", d.selected.empty() ? Json(nullptr) : Json(d.selected[0].effect)},
      {"max_error_hz", JsonNumber(d.Final().max_error_hz)},
      {"resonances_computed", d.resonances_computed}};
  return JsonText(json, 2);
}

void PrintParams(const ResonanceCandidate& c, FILE* out) {
  for (const ResonanceParamEstimate& p : c.params) {
    std::fprintf(out, "      %s = %.4g +- %.2g (plausible %.3g..%.3g%s%s)\n", p.key.c_str(),
                 p.estimate, p.standard_error, p.plausible_lower, p.plausible_upper,
                 p.within_plausible ? "" : "; OUTSIDE it", p.at_bound ? "; at a bound" : "");
  }
}

void PrintSummary(const ResonanceDiagnosis& d, FILE* out) {
  std::fprintf(out, "%-20s %8s %7s %9s", "configuration", "measured", "+-", "base");
  for (const ResonanceCandidate& s : d.selected) {
    std::fprintf(out, " %22s", ("+ " + s.effect).c_str());
  }
  std::fprintf(out, "\n");
  for (std::size_t i = 0; i < d.measured.size(); ++i) {
    std::fprintf(out, "%-20s %8.4f %7.4f %9.4f", Name(d.measured[i].configuration).c_str(),
                 d.measured[i].frequency_hz, d.measured[i].uncertainty_hz,
                 d.base.configurations[i].model_hz);
    for (const ResonanceCandidate& s : d.selected) {
      std::fprintf(out, " %22.4f", s.fit.configurations[i].model_hz);
    }
    std::fprintf(out, "\n");
  }
  std::fprintf(out, "%-20s %8s %7s %9.4f", "largest error [Hz]", "", "", d.base.max_error_hz);
  for (const ResonanceCandidate& s : d.selected) std::fprintf(out, " %22.4f", s.fit.max_error_hz);
  std::fprintf(out, "\n%-20s %8s %7s %9.3g", "chi2", "", "", d.base.chi2_after);
  for (const ResonanceCandidate& s : d.selected) std::fprintf(out, " %22.3g", s.chi2);
  std::fprintf(out, "\n");
  for (std::size_t j = 0; j < d.base.keys.size(); ++j) {
    std::fprintf(out, "base: %s = %.5g\n", d.base.keys[j].c_str(), d.base.estimates[j]);
  }
  for (const std::string& held : d.held) {
    std::fprintf(out, "held: %s = %.6g\n", held.c_str(), *GetParamValue(d.base.params, held));
  }

  std::fprintf(out, "candidates of round 1 (chi2 after adding each; base %.3g):\n",
               d.base.chi2_after);
  for (const ResonanceCandidate& c : d.candidates) {
    std::fprintf(out, "  %-24s chi2 %9.3g  largest error %.4f Hz  %s\n", c.effect.c_str(), c.chi2,
                 c.fit.max_error_hz, c.significant ? "significant" : "not significant");
  }
  for (const ResonanceCandidate& c : d.not_fitted) {
    std::fprintf(
        out, "  %-24s %s%s: %s\n", c.effect.c_str(), std::string(OutcomeName(c.outcome)).c_str(),
        c.round > 1 ? (" (round " + std::to_string(c.round) + ")").c_str() : "", c.note.c_str());
  }
  for (std::size_t i = 0; i < d.selected.size(); ++i) {
    const ResonanceCandidate& s = d.selected[i];
    std::string equivalent;
    for (const std::string& e : s.equivalent) equivalent += (equivalent.empty() ? "" : ", ") + e;
    std::fprintf(out, "selected %zu: %s (chi2 %.3g -> %.3g, needed a drop of %.3g)%s%s\n", i + 1,
                 s.effect.c_str(), s.chi2 + s.delta_chi2, s.chi2, s.threshold,
                 equivalent.empty() ? "" : "; as good: ", equivalent.c_str());
    PrintParams(s, out);
    for (const ResonanceCandidate::Alternative& a : s.not_excluded) {
      std::fprintf(out,
                   "      not excluded in its place: %s (chi2 %.3g against %.3g, largest error "
                   "%.4f Hz)\n",
                   a.effect.c_str(), a.chi2, d.Final().chi2_after, a.max_error_hz);
    }
  }
  for (const RemovedEffect& r : d.removed) {
    std::fprintf(out,
                 "removed after round %d: %s (without it chi2 rises by %.3g only, under %.3g)\n",
                 r.round, r.effect.c_str(), r.delta_chi2, r.threshold);
  }
  if (d.next) {
    std::fprintf(out, "next: %s would lower chi2 by %.3g only (needs %.3g)\n",
                 d.next->effect.c_str(), d.next->delta_chi2, d.next->threshold);
  }
  std::string selected;
  for (const ResonanceCandidate& s : d.selected) {
    selected += (selected.empty() ? "" : " + ") + s.effect;
  }
  std::fprintf(out, "selected: %s (%s); largest error %.4f Hz\n",
               selected.empty() ? "none" : selected.c_str(), d.selection_end.c_str(),
               d.Final().max_error_hz);

  // Why a uniformly slower line cannot do it.
  const Ratios measured = RatiosOf([&](Termination t) { return Measured(d, t); });
  const Ratios uniform = RatiosOf([&](Termination t) { return Modelled(d.uniform, t); });
  std::fprintf(out,
               "a uniform wave speed alone (fitted, not held): c = %.4g m/s, largest error "
               "%.4f Hz",
               d.uniform.estimates.empty() ? std::nan("") : d.uniform.estimates[0],
               d.uniform.max_error_hz);
  if (std::isfinite(measured.closed_open)) {
    std::fprintf(out, "; closed/open %.3f (measured %.3f)", uniform.closed_open,
                 measured.closed_open);
  }
  if (std::isfinite(measured.valve_closed)) {
    std::fprintf(out, "; valve/closed choke %.3f (measured %.3f)", uniform.valve_closed,
                 measured.valve_closed);
  }
  std::fprintf(out, "\n");
  if (std::isfinite(measured.closed_open) &&
      std::fabs(uniform.closed_open - measured.closed_open) > 0.05) {
    std::fprintf(out,
                 "  a uniform speed scales every resonance alike (closed c/2L, open c/4L): its "
                 "ratio stays %.2f whatever c\n",
                 uniform.closed_open);
  }
}

}  // namespace

int RunDiagnoseResonances(const ModelOptions& model, const ResonanceDiagnoseArgs& args) {
  const std::string name = "diagnose";
  auto inputs = LoadResonanceInputs(model, args.resonances_path, args.method, args.outlet_barg);
  if (!inputs.ok()) return Fail(name, inputs.status());
  const RigParams* start = &inputs->start;
  const std::vector<MeasuredResonance>* measured = &inputs->measured;

  ResonanceDiagnoseOptions options;
  options.hold = args.hold;
  options.candidates = args.candidates;
  options.max_effects = args.max_effects;
  options.significance_level = args.significance;
  options.simulated_every_round = args.thorough;
  options.fit.max_iterations = args.max_iterations;
  options.fit.resonance = inputs->resonance;
  options.fit.resonance.simulated.amplitude_m = args.amplitude_m;
  std::mutex progress_lock;
  if (!args.quiet) {
    std::fprintf(stderr, "mpdrig diagnose: %zu measured resonances from %s\n", measured->size(),
                 args.resonances_path.c_str());
    options.progress = [&progress_lock](const std::string& line) {
      std::lock_guard<std::mutex> lock(progress_lock);
      std::fprintf(stderr, "diagnose: %s\n", line.c_str());
    };
  }
  // options.progress says what each found.
  options.run_tasks = LongestFirstRunner::Shared(/*workers=*/0, /*quiet=*/true);
  auto diagnosis = DiagnoseResonances(*measured, *start, options);
  if (!diagnosis.ok()) return Fail(name, diagnosis.status().Within(args.resonances_path));
  if (!args.json_path.empty()) {
    const Status written = WriteText(args.json_path, DiagnosisJson(*diagnosis, args));
    if (!written.ok()) return Fail(name, written);
  }
  PrintSummary(*diagnosis, args.json_path == "-" ? stderr : stdout);
  return 0;
}

}  // namespace mpdrig::cli
