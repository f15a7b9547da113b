// Diagnosis in the frequency domain: which effects of the catalogue explain the rig's measured
// first resonances (resonance_list.h), chosen by forward selection as the time-domain diagnosis
// chooses them (diagnose.h), but scored by what the fits leave of the measured peaks.
//
// The base model fits `base_keys` (the wave speed, unless held) to the measured resonances
// (resonance_fit.h): chi2_0 = sum_i ((f_model,i - f_i) / u_i)^2. Each round then adds one
// candidate effect at a time to the model of the round before, refits its fitted parameters
// together with the base keys and the effects already selected (from their estimates), and ranks
// the candidates by chi2. The best is selected when it lowers chi2 significantly: the likelihood
// ratio of nested least-squares models with Gaussian errors of known standard deviation,
// Delta chi2 = chi2_before - chi2_after, is chi-square distributed with k degrees of freedom
// (k = the candidate's new parameters) when the candidate explains nothing (Wilks 1938; e.g.
// Press et al., Numerical Recipes, 3rd ed., 15.6), so it is significant when Delta chi2 exceeds
// the chi-square quantile at 1 - significance_level. After each addition the effects selected
// before it are tested the other way (stepwise selection, Efroymson 1960): one whose removal
// raises chi2 by less than its threshold is taken out and not tried again (forward selection
// alone takes a uniform effect such as free gas first, and a pair of local ones may then explain
// everything without it). Selection stops when no candidate is
// significant, when the model already agrees with the measurements (chi2 no larger than its
// degrees of freedom' quantile at the same level), when a further effect would leave more
// parameters than measured resonances, or at max_effects.
//
// A candidate the analytic response (9.2.13) does not represent needs the simulated response,
// about 0.3 s per resonance: before it is fitted it is screened at the ends of its plausible
// range (EffectParamInfo::plausible_min/max) in the round's model; one that cannot move any
// resonance by a quarter of its uncertainty there is reported as such, not fitted and not tried
// again. Every candidate is screened so (for an analytic one it costs two responses). Unless
// simulated_every_round, such a candidate is fitted in round 1 only.
//
// Besides the selection, the diagnosis fits the wave speed alone (not held, no effect): a
// uniformly slower line (lower c, or free gas at one mean pressure) scales every resonance alike,
// so its closed/open ratio stays 2 (c/2L against c/4L) and the valve's equals the closed choke's.
// The measured ratio against that one is what rules it out.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "model/analysis/resonance_list.h"
#include "model/common/status.h"
#include "model/common/tasks.h"
#include "model/identification/resonance_fit.h"
#include "model/params/rig_params.h"

namespace mpdrig {

struct ResonanceDiagnoseOptions {
  ResonanceFitOptions fit;
  // Base parameters refitted in every model; held keys are left out.
  std::vector<std::string> base_keys = {"wave_speed_mps"};
  std::vector<std::string> hold;        // never fitted (e.g. a measured wave speed)
  std::vector<std::string> candidates;  // effect names; empty: the whole catalogue
  double significance_level = 0.01;     // of the Delta chi2 test
  int max_effects = 3;
  // Solver iterations for a candidate that needs the simulated response (each iteration costs
  // about 3 x 3 simulated resonances, ~3 s): the fit of one to three peaks converges in a few.
  int simulated_max_iterations = 6;
  // Whether a candidate that needs the simulated response is tried after round 1 as well (each
  // such fit takes minutes); if not, it is listed as not tried, with the reason.
  bool simulated_every_round = false;
  // The screen's threshold, in units of the smallest measured uncertainty.
  double screen_fraction = 0.25;
  // Runs independent tasks (the candidates of a round, kind "candidate E"); default: one after
  // the other.
  TaskRunner run_tasks;
  std::function<void(const std::string&)> progress;  // one line per candidate fitted
};

// A fitted parameter against the catalogue's ranges.
struct ResonanceParamEstimate {
  std::string key;
  double estimate = 0.0;
  double standard_error = 0.0;
  double bound_lower = 0.0, bound_upper = 0.0;          // physical bounds (the fit's search range)
  double plausible_lower = 0.0, plausible_upper = 0.0;  // the range the lab is expected to meet
  bool at_bound = false;
  bool within_plausible = false;
};

struct ResonanceCandidate {
  std::string effect;
  int round = 1;
  enum class Outcome {
    kFitted,
    kFailed,
    kDoesNotMovePeaks,
    kUnidentifiable,
    kNotTried
  } outcome = Outcome::kFitted;
  std::string note;              // why it failed, or what the screen found
  double screen_shift_hz = 0.0;  // largest |resonance shift| over the plausible range
  ResonanceFitResult fit;        // kFitted: the round's model with this effect, refitted
  std::vector<ResonanceParamEstimate> params;  // every effect parameter of `fit`
  int new_parameters = 0;
  double chi2 = 0.0;
  double delta_chi2 = 0.0;  // the round's chi2 before it minus chi2
  double threshold = 0.0;   // the chi-square quantile Delta chi2 must exceed
  bool significant = false;
  // Candidates of the same round whose chi2 is within kEquivalentChi2 of this one's: effects the
  // resonances cannot tell apart from it (e.g. two compliances at the pipe inlet).
  std::vector<std::string> equivalent;
  // For a selected effect, once the selection has ended: the other fitted candidates that, put in
  // its place in the final model and refitted, leave chi2 less than the test's threshold above
  // the final model's: the readings do not exclude them (a stricter reading would). Candidates
  // that need the simulated response are swapped in only with simulated_every_round.
  struct Alternative {
    std::string effect;
    double chi2 = 0.0;
    double max_error_hz = 0.0;
  };
  std::vector<Alternative> not_excluded;
};

// Delta chi2 = 1: the one-standard-deviation band of a least-squares fit's likelihood.
inline constexpr double kEquivalentChi2 = 1.0;

// An effect taken out again after a later one was added (the backward step of stepwise
// selection): without it chi2 rose by less than the test's threshold.
struct RemovedEffect {
  std::string effect;
  int round = 0;            // the round after which it was removed
  double delta_chi2 = 0.0;  // chi2 without it minus chi2 with it
  double threshold = 0.0;
};
std::string_view OutcomeName(ResonanceCandidate::Outcome outcome);

struct ResonanceDiagnosis {
  std::vector<MeasuredResonance> measured;
  std::vector<std::string> held;
  ResonanceFitResult base;     // the base keys fitted, no effect (beyond the start's)
  ResonanceFitResult uniform;  // the wave speed alone fitted, no effect (even if held)
  std::vector<ResonanceCandidate> candidates;  // round 1, best (lowest chi2) first
  std::vector<ResonanceCandidate> selected;    // the final model's effects, in the order added;
                                               // each fit cumulative over those before it
  std::vector<RemovedEffect> removed;
  std::optional<ResonanceCandidate> next;      // the best of the last round, not selected
  std::vector<ResonanceCandidate> not_fitted;  // failed, screened out or unidentifiable
  std::string selection_end;                   // why the selection stopped
  int resonances_computed = 0;

  // The final model: the base fit with every selected effect and its estimates.
  const ResonanceFitResult& Final() const { return selected.empty() ? base : selected.back().fit; }
};

// Chi-square quantile for k degrees of freedom at probability 1 - alpha (k >= 1).
double ChiSquareQuantile(int k, double alpha);

Result<ResonanceDiagnosis> DiagnoseResonances(const std::vector<MeasuredResonance>& measured,
                                              const RigParams& start,
                                              const ResonanceDiagnoseOptions& options = {});

}  // namespace mpdrig
