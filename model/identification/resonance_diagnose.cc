#include "model/identification/resonance_diagnose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"

namespace mpdrig {
namespace {

// Regularised lower incomplete gamma function P(a, x): the series for x < a + 1, else the
// continued fraction of Q = 1 - P (Lentz's method); both converge to 1e-14 in well under 200
// terms for the a = k/2 <= 10 used here (Abramowitz & Stegun 6.5.29 and 6.5.31).
double RegularizedGammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 500; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::fabs(term) < 1e-15 * std::fabs(sum)) break;
    }
    return sum * std::exp(log_prefactor);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int n = 1; n < 500; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < 1e-15) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

// The range the lab is expected to meet: the catalogue's plausible range, or [default/2,
// 2 default] where it gives none (effect.h), within the physical bounds.
std::pair<double, double> PlausibleRange(const EffectParamInfo& info) {
  double lo = info.plausible_min, hi = info.plausible_max;
  if (!(lo > 0.0 && lo < hi)) lo = 0.5 * info.default_value, hi = 2.0 * info.default_value;
  lo = std::clamp(lo, info.min_value, info.max_value);
  hi = std::clamp(hi, info.min_value, info.max_value);
  return {std::min(lo, hi), std::max(lo, hi)};
}

std::vector<const EffectParamInfo*> FittedParams(const EffectInfo& info) {
  std::vector<const EffectParamInfo*> fitted;
  for (const EffectParamInfo& p : info.params) {
    if (p.fitted) fitted.push_back(&p);
  }
  return fitted;
}

// Every effect parameter fitted in `fit`, against the catalogue's ranges.
std::vector<ResonanceParamEstimate> EffectEstimates(const ResonanceFitResult& fit) {
  std::vector<ResonanceParamEstimate> estimates;
  for (std::size_t j = 0; j < fit.keys.size(); ++j) {
    const std::string& key = fit.keys[j];
    const std::size_t dot = key.find('.');
    if (dot == std::string::npos) continue;  // a base parameter
    const EffectInfo* info = FindEffectInfo(key.substr(0, dot));
    const EffectParamInfo* param = info ? info->FindParam(key.substr(dot + 1)) : nullptr;
    if (param == nullptr) continue;
    ResonanceParamEstimate e;
    e.key = key;
    e.estimate = fit.estimates[j];
    e.standard_error = fit.standard_errors[j];
    e.bound_lower = fit.lower[j], e.bound_upper = fit.upper[j];
    std::tie(e.plausible_lower, e.plausible_upper) = PlausibleRange(*param);
    const double span = e.bound_upper - e.bound_lower;
    e.at_bound =
        e.estimate <= e.bound_lower + 1e-9 * span || e.estimate >= e.bound_upper - 1e-9 * span;
    e.within_plausible = e.estimate >= e.plausible_lower && e.estimate <= e.plausible_upper;
    estimates.push_back(e);
  }
  return estimates;
}

Result<std::vector<FitParameter>> ParametersFor(const std::vector<std::string>& keys) {
  std::vector<FitParameter> parameters;
  for (const std::string& key : keys) {
    auto parameter = DefaultFitParameter(key);
    if (!parameter.ok()) return parameter.status();
    parameters.push_back(*parameter);
  }
  return parameters;
}

// The model's resonances at `params`, one per measurement, or the first error.
Result<std::vector<double>> ModelResonances(const std::vector<MeasuredResonance>& measured,
                                            const RigParams& params,
                                            const ResonanceOptions& options, int* computed) {
  std::vector<double> freqs;
  for (const MeasuredResonance& m : measured) {
    auto resonance = FirstResonance(params, m.configuration, options);
    ++*computed;
    if (!resonance.ok()) return resonance.status();
    freqs.push_back(resonance->freq_hz);
  }
  return freqs;
}

class RoundRunner {
 public:
  RoundRunner(const std::vector<MeasuredResonance>& measured, const ResonanceDiagnoseOptions& opts)
      : measured_(measured), options_(opts) {
    min_uncertainty_ = std::numeric_limits<double>::infinity();
    for (const MeasuredResonance& m : measured) {
      min_uncertainty_ = std::min(min_uncertainty_, m.uncertainty_hz);
    }
  }

  // `effect` added to `model` (the round's fit), screened and refitted with `keys` and its own.
  ResonanceCandidate Try(const std::string& effect, int round, const ResonanceFitResult& model,
                         const std::vector<FitParameter>& keys) const {
    ResonanceCandidate candidate;
    candidate.effect = effect, candidate.round = round;
    const EffectInfo* info = FindEffectInfo(effect);
    MPDRIG_CHECK(info != nullptr);
    const std::vector<const EffectParamInfo*> own = FittedParams(*info);
    candidate.new_parameters = static_cast<int>(own.size());
    if (round > 1 && !options_.simulated_every_round &&
        options_.fit.resonance.method != ResponseMethod::kAnalytic && !AnalyticRepresents(effect)) {
      candidate.outcome = ResonanceCandidate::Outcome::kNotTried;
      candidate.note = "needs the simulated response, tried in round 1 only";
      return candidate;
    }
    if (keys.size() + own.size() > measured_.size()) {
      candidate.outcome = ResonanceCandidate::Outcome::kUnidentifiable;
      candidate.note = std::to_string(keys.size() + own.size()) + " parameters for " +
                       std::to_string(measured_.size()) + " resonances";
      return candidate;
    }
    RigParams with = model.params;
    const Status applied = ApplyEffectSpec(&with, effect);
    if (!applied.ok()) return Failed(std::move(candidate), applied.message());
    const Status valid = ValidateEffects(with);
    if (!valid.ok()) return Failed(std::move(candidate), valid.message());

    // The screen: the effect at both ends of its plausible range against the round's model.
    std::vector<double> reference;
    for (const ResonanceFitConfiguration& c : model.configurations) reference.push_back(c.model_hz);
    std::string screen_error;
    bool screened = false;
    for (int end = 0; end < 2; ++end) {
      RigParams probe = with;
      for (const EffectParamInfo* p : own) {
        const auto [lo, hi] = PlausibleRange(*p);
        const Status set = SetParamValue(&probe, effect + "." + std::string(p->key), end ? hi : lo);
        MPDRIG_CHECK(set.ok());
      }
      auto freqs = ModelResonances(measured_, probe, options_.fit.resonance, &computed_);
      if (!freqs.ok()) {
        screen_error = freqs.status().message();
        continue;
      }
      screened = true;
      for (std::size_t i = 0; i < freqs->size(); ++i) {
        candidate.screen_shift_hz =
            std::max(candidate.screen_shift_hz, std::fabs((*freqs)[i] - reference[i]));
      }
    }
    if (!screened) return Failed(std::move(candidate), screen_error);
    if (candidate.screen_shift_hz < options_.screen_fraction * min_uncertainty_) {
      candidate.outcome = ResonanceCandidate::Outcome::kDoesNotMovePeaks;
      candidate.note = "moves no resonance by more than " + Hz(candidate.screen_shift_hz) +
                       " over its plausible range";
      return candidate;
    }

    std::vector<FitParameter> all = keys;
    for (const EffectParamInfo* p : own) {
      auto parameter = DefaultFitParameter(effect + "." + std::string(p->key));
      MPDRIG_CHECK(parameter.ok());
      all.push_back(*parameter);
    }
    ResonanceFitOptions fit_options = options_.fit;
    if (!AnalyticRepresents(effect)) {
      fit_options.max_iterations =
          std::min(fit_options.max_iterations, options_.simulated_max_iterations);
    }
    auto fit = FitResonances(measured_, with, all, fit_options);
    // From the effect's default the fit may end in a valley worse than the model without it;
    // from the weak end of its plausible range it starts next to that model.
    if (!fit.ok() || fit->chi2_after > model.chi2_after) {
      RigParams weak = with;
      for (const EffectParamInfo* p : own) {
        const Status set =
            SetParamValue(&weak, effect + "." + std::string(p->key), PlausibleRange(*p).first);
        MPDRIG_CHECK(set.ok());
      }
      auto again = FitResonances(measured_, weak, all, fit_options);
      if (again.ok() && (!fit.ok() || again->chi2_after < fit->chi2_after)) fit = std::move(again);
    }
    if (!fit.ok()) return Failed(std::move(candidate), fit.status().message());
    computed_ += fit->evaluations;
    candidate.fit = std::move(*fit);
    candidate.chi2 = candidate.fit.chi2_after;
    candidate.delta_chi2 = model.chi2_after - candidate.chi2;
    candidate.threshold =
        ChiSquareQuantile(std::max(1, candidate.new_parameters), options_.significance_level);
    candidate.significant = candidate.delta_chi2 > candidate.threshold;
    candidate.params = EffectEstimates(candidate.fit);
    return candidate;
  }

  int computed() const { return computed_; }

 private:
  static ResonanceCandidate Failed(ResonanceCandidate candidate, std::string why) {
    candidate.outcome = ResonanceCandidate::Outcome::kFailed;
    candidate.note = std::move(why);
    return candidate;
  }
  static std::string Hz(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.2g Hz", value);
    return text;
  }

  const std::vector<MeasuredResonance>& measured_;
  const ResonanceDiagnoseOptions& options_;
  double min_uncertainty_;
  // Per candidate task; summed by the caller after the round (tasks may run on threads).
  mutable int computed_ = 0;
};

// `model` without the effect `name` (its setting and its keys), refitted from the others'
// estimates.
Result<ResonanceFitResult> FitWithout(const std::vector<MeasuredResonance>& measured,
                                      const ResonanceFitOptions& options,
                                      const ResonanceFitResult& model, const std::string& name) {
  RigParams params = model.params;
  std::erase_if(params.effects, [&](const EffectSetting& e) { return e.name == name; });
  std::vector<FitParameter> keys;
  for (std::size_t j = 0; j < model.keys.size(); ++j) {
    if (model.keys[j].rfind(name + ".", 0) == 0) continue;
    keys.push_back({model.keys[j], model.lower[j], model.upper[j]});
  }
  return FitResonances(measured, params, keys, options);
}

ResonanceFitOptions CappedFor(const RigParams& params, const ResonanceDiagnoseOptions& options) {
  ResonanceFitOptions fit = options.fit;
  if (!EffectsOutsideAnalytic(params).empty()) {
    fit.max_iterations = std::min(fit.max_iterations, options.simulated_max_iterations);
  }
  return fit;
}

// The backward step after an addition (the header): takes out the earlier effect whose removal
// costs least, if that is below its threshold, and refits the selection's steps without it.
Result<bool> BackwardStep(const std::vector<MeasuredResonance>& measured,
                          const ResonanceDiagnoseOptions& options,
                          const std::vector<std::string>& base_keys, int round,
                          ResonanceDiagnosis* d, ResonanceFitResult* model) {
  if (d->selected.size() < 2) return false;
  std::optional<std::size_t> weakest;
  RemovedEffect removal;
  ResonanceFitResult without_weakest;
  const ResonanceFitOptions fit_options = CappedFor(model->params, options);
  for (std::size_t i = 0; i + 1 < d->selected.size(); ++i) {
    const ResonanceCandidate& earlier = d->selected[i];
    auto without = FitWithout(measured, fit_options, *model, earlier.effect);
    if (!without.ok()) continue;  // it cannot be taken out: keep it
    d->resonances_computed += without->evaluations;
    const double delta = without->chi2_after - model->chi2_after;
    const double threshold =
        ChiSquareQuantile(std::max(1, earlier.new_parameters), options.significance_level);
    if (delta < threshold && (!weakest || delta < removal.delta_chi2)) {
      weakest = i;
      removal = {earlier.effect, round, delta, threshold};
      without_weakest = std::move(*without);
    }
  }
  if (!weakest) return false;
  d->removed.push_back(removal);
  d->selected.erase(d->selected.begin() + static_cast<std::ptrdiff_t>(*weakest));
  // The steps again without it: each the base keys and the effects up to it, started from the
  // final model's estimates.
  RigParams params = without_weakest.params;
  params.effects.clear();
  std::vector<std::string> keys = base_keys;
  double chi2_before = d->base.chi2_after;
  for (ResonanceCandidate& step : d->selected) {
    for (const EffectSetting& e : without_weakest.params.effects) {
      if (e.name == step.effect) params.effects.push_back(e);
    }
    for (const std::string& key : without_weakest.keys) {
      if (key.rfind(step.effect + ".", 0) == 0) keys.push_back(key);
    }
    std::vector<FitParameter> parameters;
    for (const std::string& key : keys) {
      const auto at = std::find(without_weakest.keys.begin(), without_weakest.keys.end(), key);
      MPDRIG_CHECK(at != without_weakest.keys.end());
      const std::size_t j = static_cast<std::size_t>(at - without_weakest.keys.begin());
      parameters.push_back({key, without_weakest.lower[j], without_weakest.upper[j]});
    }
    auto fit = FitResonances(measured, params, parameters, CappedFor(params, options));
    if (!fit.ok()) return fit.status().Within("refitting " + step.effect);
    d->resonances_computed += fit->evaluations;
    step.fit = std::move(*fit);
    step.chi2 = step.fit.chi2_after;
    step.delta_chi2 = chi2_before - step.chi2;
    step.significant = step.delta_chi2 > step.threshold;
    step.params = EffectEstimates(step.fit);
    chi2_before = step.chi2;
  }
  *model = d->selected.back().fit;
  return true;
}

// For each selected effect, the round-1 candidates that could take its place (the header).
void AddAlternatives(const std::vector<MeasuredResonance>& measured,
                     const ResonanceDiagnoseOptions& options, ResonanceDiagnosis* d) {
  if (d->selected.empty()) return;
  const ResonanceFitResult& final_model = d->Final();
  for (ResonanceCandidate& chosen : d->selected) {
    // The final model without the chosen effect, once: every swap starts from it.
    auto without = FitWithout(measured, options.fit, final_model, chosen.effect);
    if (!without.ok()) continue;
    d->resonances_computed += without->evaluations;
    for (const ResonanceCandidate& other : d->candidates) {
      const bool in_model =
          std::any_of(d->selected.begin(), d->selected.end(),
                      [&](const ResonanceCandidate& s) { return s.effect == other.effect; });
      if (in_model || other.effect == chosen.effect) continue;
      // A swap that needs the simulated response costs minutes: as in the rounds after the first.
      if (!options.simulated_every_round && !AnalyticRepresents(other.effect) &&
          options.fit.resonance.method != ResponseMethod::kAnalytic) {
        continue;
      }
      RigParams params = without->params;
      if (!ApplyEffectSpec(&params, other.effect).ok() || !ValidateEffects(params).ok()) continue;
      std::vector<FitParameter> keys;
      for (std::size_t j = 0; j < without->keys.size(); ++j) {
        keys.push_back({without->keys[j], without->lower[j], without->upper[j]});
      }
      for (const EffectParamInfo* p : FittedParams(*FindEffectInfo(other.effect))) {
        auto parameter = DefaultFitParameter(other.effect + "." + std::string(p->key));
        MPDRIG_CHECK(parameter.ok());
        keys.push_back(*parameter);
      }
      auto swapped = FitResonances(measured, params, keys, CappedFor(params, options));
      if (!swapped.ok()) continue;
      d->resonances_computed += swapped->evaluations;
      const double threshold =
          ChiSquareQuantile(std::max(1, other.new_parameters), options.significance_level);
      if (swapped->chi2_after - final_model.chi2_after < threshold) {
        chosen.not_excluded.push_back({other.effect, swapped->chi2_after, swapped->max_error_hz});
      }
    }
  }
}

}  // namespace

std::string_view OutcomeName(ResonanceCandidate::Outcome outcome) {
  switch (outcome) {
    case ResonanceCandidate::Outcome::kFitted:
      return "fitted";
    case ResonanceCandidate::Outcome::kFailed:
      return "failed";
    case ResonanceCandidate::Outcome::kDoesNotMovePeaks:
      return "does_not_move_peaks";
    case ResonanceCandidate::Outcome::kUnidentifiable:
      return "unidentifiable";
    case ResonanceCandidate::Outcome::kNotTried:
      return "not_tried";
  }
  return "?";
}

double ChiSquareQuantile(int k, double alpha) {
  MPDRIG_CHECK(k >= 1 && alpha > 0.0 && alpha < 1.0);
  // P(k/2, x/2) = 1 - alpha, by bisection: P is increasing in x.
  double lo = 0.0, hi = 10.0 * k + 100.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (RegularizedGammaP(0.5 * k, 0.5 * mid) < 1.0 - alpha ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Result<ResonanceDiagnosis> DiagnoseResonances(const std::vector<MeasuredResonance>& measured,
                                              const RigParams& start,
                                              const ResonanceDiagnoseOptions& options) {
  if (measured.empty()) return Status::Error("no measured resonance to diagnose");
  if (!(options.significance_level > 0.0 && options.significance_level < 0.5)) {
    return Status::Error("the significance level must be in (0, 0.5)");
  }
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(start));
  for (const std::string& held : options.hold) {
    auto value = GetParamValue(start, held);
    if (!value.ok()) return value.status().Within("hold");
  }
  std::vector<std::string> pool = options.candidates;
  if (pool.empty()) {
    for (const EffectInfo* info : DiagnoseCandidateEffects()) pool.emplace_back(info->name);
  }
  for (const std::string& name : pool) MPDRIG_RETURN_IF_ERROR(CheckDiagnoseCandidate(name));
  // An effect already in the start model is part of the base, not a candidate.
  std::erase_if(pool, [&](const std::string& name) {
    return std::any_of(start.effects.begin(), start.effects.end(),
                       [&](const EffectSetting& e) { return e.name == name; });
  });

  ResonanceDiagnosis d;
  d.measured = measured;
  d.held = options.hold;
  std::vector<std::string> base_keys;
  for (const std::string& key : options.base_keys) {
    if (std::find(options.hold.begin(), options.hold.end(), key) == options.hold.end()) {
      base_keys.push_back(key);
    }
  }
  auto keys = ParametersFor(base_keys);
  if (!keys.ok()) return keys.status().Within("base parameters");
  auto base = FitResonances(measured, start, *keys, options.fit);
  if (!base.ok()) return base.status().Within("the base model");
  d.base = std::move(*base);
  d.resonances_computed += d.base.evaluations;

  RigParams bare = start;
  bare.effects.clear();
  auto uniform = FitResonances(measured, bare, *ParametersFor({"wave_speed_mps"}), options.fit);
  if (!uniform.ok()) return uniform.status().Within("the wave speed alone");
  d.uniform = std::move(*uniform);
  d.resonances_computed += d.uniform.evaluations;

  ResonanceFitResult model = d.base;  // the round's model
  std::vector<FitParameter> model_keys = *keys;
  const int n = static_cast<int>(measured.size());
  for (int round = 1;; ++round) {
    const int dof = n - static_cast<int>(model_keys.size());
    if (static_cast<int>(d.selected.size()) >= options.max_effects) {
      d.selection_end = "at most " + std::to_string(options.max_effects) + " effects";
      break;
    }
    if (dof <= 0) {
      d.selection_end = "as many parameters as measured resonances";
      break;
    }
    const double agree = ChiSquareQuantile(dof, options.significance_level);
    if (model.chi2_after <= agree) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "the model agrees with the measurements (chi2 %.3g, at most %.3g for %d "
                    "degrees of freedom)",
                    model.chi2_after, agree, dof);
      d.selection_end = text;
      break;
    }
    if (pool.empty()) {
      d.selection_end = "no candidate left";
      break;
    }
    std::vector<ResonanceCandidate> results(pool.size());
    std::vector<int> computed(pool.size(), 0);
    std::vector<Task> tasks;
    for (std::size_t i = 0; i < pool.size(); ++i) {
      const auto try_candidate = [&, i] {
        // Its own runner: each task counts its own resonances (tasks may run on several threads).
        const RoundRunner own(measured, options);
        results[i] = own.Try(pool[i], round, model, model_keys);
        computed[i] = own.computed();
        if (options.progress) {
          options.progress("round " + std::to_string(round) + ": " + pool[i] + " " +
                           std::string(OutcomeName(results[i].outcome)));
        }
      };
      tasks.push_back({"candidate " + pool[i], try_candidate});
    }
    if (options.run_tasks) {
      options.run_tasks(tasks);
    } else {
      RunInTurn(tasks);
    }
    for (int c : computed) d.resonances_computed += c;
    std::vector<ResonanceCandidate> fitted;
    for (ResonanceCandidate& r : results) {
      // An effect that cannot move the peaks is not tried again in a later round.
      if (r.outcome == ResonanceCandidate::Outcome::kDoesNotMovePeaks) std::erase(pool, r.effect);
      (r.outcome == ResonanceCandidate::Outcome::kFitted ? fitted : d.not_fitted)
          .push_back(std::move(r));
    }
    std::stable_sort(
        fitted.begin(), fitted.end(),
        [](const ResonanceCandidate& a, const ResonanceCandidate& b) { return a.chi2 < b.chi2; });
    if (round == 1) d.candidates = fitted;
    if (fitted.empty()) {
      d.selection_end = "no candidate could be fitted";
      break;
    }
    if (!fitted.front().significant) {
      d.next = fitted.front();
      d.selection_end = "no candidate lowers chi2 significantly (level " +
                        std::to_string(options.significance_level).substr(0, 4) + ")";
      break;
    }
    for (std::size_t i = 1; i < fitted.size(); ++i) {
      if (fitted[i].chi2 - fitted.front().chi2 <= kEquivalentChi2) {
        fitted.front().equivalent.push_back(fitted[i].effect);
      }
    }
    d.selected.push_back(std::move(fitted.front()));
    std::erase(pool, d.selected.back().effect);
    model = d.selected.back().fit;
    auto removed = BackwardStep(measured, options, base_keys, round, &d, &model);
    if (!removed.ok()) return removed.status();
    // The next round refits every key of this model, the new effect's from their estimates.
    model_keys.clear();
    for (std::size_t j = 0; j < model.keys.size(); ++j) {
      model_keys.push_back({model.keys[j], model.lower[j], model.upper[j]});
    }
  }
  AddAlternatives(measured, options, &d);
  return d;
}

}  // namespace mpdrig
