// "Which physical effect is missing?": fit the base model to a log, show where it still
// fails, try every effect of the catalogue, and rank them on data they were not fitted on.
//
// 1. Split the log in time: the first `fit_fraction` is the fitting data, the rest the scoring
//    data (the replay always runs over the whole log, so the scoring part starts from the state
//    the fitting part left). Where the log has regimes (regimes.h: the pump stopped, the choke
//    closed, the heave stopped), the split moves (within 40-80 % of the log) to the nearest point
//    that leaves each regime on both sides, or the diagnosis names the regimes it cannot.
// 2. Baseline: fit the base parameters (wave speed, pipe friction f1, choke leak by default) on
//    the fitting data; its error on the scoring data is the number to beat. The compare metrics
//    of the fitted baseline over the whole log (channels, bands, profile, lag, residual
//    correlation) show where it fails.
// 3. Each candidate effect: switched on, its fitted parameters (EffectParamInfo::fitted) fitted
//    together with the base ones: a scan of its strength and the wave speed from two starts (the
//    baseline's estimates, the start values), then local fits from the best scan point and from
//    the best one in another wave-speed valley. The baseline gets the same search without an
//    effect and keeps it if it fits better, so that no candidate wins by its search alone.
// 4. Score: the compare error (mean NRMSE over the compared channels) on the scoring data, with a
//    price for freedom: penalised = error (1 + kParameterPrice extra parameters). Ranked by the
//    penalised score. A candidate is `significant` when it beats the baseline on the scoring
//    data by more than (a) kMinRelativeImprovement of the baseline error and (b) kSignificanceZ
//    standard errors of the improvement, estimated from its spread over kScoreBlocks blocks
//    of the scoring data (blocks, because residuals are correlated in time and noise of one
//    sample says little about the next). The leading kPolishedCandidates are then refitted
//    with the baseline's iterations and the ranking redone; where the log holds pressures on a
//    floor ended by a jump (column separation, cavity_evidence.h), it is redone with the floor
//    samples scored as channels of their own (significance stays that of the plain score). The
//    verdict is the best significant
//    candidate, or none; `equivalent` names the significant ones it does not clearly beat. A
//    candidate whose fit fails is reported as failed, not ranked. No candidate fits its fitting
//    data worse than the model it extends: where its search's fits end above that model's
//    error, it is also fitted from that model's own point with the effect at zero strength.
// 5. Forward selection: a real rig lacks more than one effect. With the verdict in the model
//    (the reference), the candidates of the round before that removed some of its error are
//    fitted again (the
//    reference's effect strengths refitted with the new one and the base parameters, from the
//    same search) and scored against the reference by the same rule as in step 4; the best is
//    added while it is significant, up to kMaxSelectedEffects. `selected` lists them in order,
//    `next` is the best candidate that was not (with what the log could show of it).
// 6. What is left (residual_signature.h): the best model (the base model with the effects
//    selected) against the noise floor; where it stays far above it, "the model misses something
//    the catalogue does not hold", with the signature of its residual: channels, bands, along the
//    pipe, steady or dynamic, and regimes.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "model/analysis/compare.h"
#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/common/tasks.h"
#include "model/effects/effect.h"
#include "model/identification/cavity_evidence.h"
#include "model/identification/fit.h"
#include "model/identification/regimes.h"
#include "model/identification/residual_signature.h"
#include "model/params/rig_params.h"

namespace mpdrig {

inline constexpr double kParameterPrice = 0.01;  // 1% of the error per extra parameter
// Significance is first a matter of size: on logs without a hidden effect no candidate's
// penalised error was more than 6.9% below the baseline's (10 synthetic logs x 9 candidates; the
// replay of noisy inputs lets a smoothing effect gain a little), while a hidden effect that the
// refitted base model cannot absorb left 21% or more to gain (diagnose_test, 10 seeds).
inline constexpr double kMinRelativeImprovement = 0.10;  // 10% of the baseline's scoring error
inline constexpr int kScoreBlocks = 8;
// ... and of consistency: the improvement beyond this many of its standard errors over the
// blocks, so that one block's fluke does not count. Not more: an effect that shows at events
// (a choke step) improves a few blocks a lot and the rest not at all, which a t-test over 8
// correlated blocks rates at 2-3 standard errors however large the gain.
inline constexpr double kSignificanceZ = 2.0;
// The leading candidates (by penalised error) whose fits are polished with the baseline's
// iterations before the final ranking.
inline constexpr std::size_t kPolishedCandidates = 3;
// Forward selection: at most this many effects (a log of minutes rarely supports more: each adds
// a parameter whose gain must stand 10 % above the noise), and each round after the first tries
// the candidates of the round before that removed some of its error and are not selected yet:
// a missing effect that shows beyond its partners removes error in the round before as well
// (there, the partners' misfit only adds to every model's), if only a little (a hidden gas
// entrainment beside a sensor lag: 7.391 % against the base model's 7.417 %, 6th of 10); one
// that removed none is not tried again, unless the effect selected last removed more than this
// share of its reference's error: then the round before saw every other candidate against a
// misfit that effect dominated (a pump curve leaving the base model 97 % off), and one that
// removed none of it may still remove much of the rest.
inline constexpr std::size_t kMaxSelectedEffects = 3;
inline constexpr double kDominatingImprovement = 0.5;
// Detectability: an effect of strength s changes the fitted base model's channels by d(s) (mean
// NRMSE of the change, relative to the baseline's own variation). If the base parameters cannot
// absorb it, the baseline's error rises from e0 to sqrt(e0^2 + d^2) and the candidate removes
// that: a gain above kMinRelativeImprovement needs d > e0 sqrt(1 / (1 - 0.1)^2 - 1) = 0.484 e0.
// The smallest strength on a log-spaced scan of kDetectabilityPoints over the plausible range
// that reaches it is the smallest detectable strength at this log's noise and excitation (a
// lower bound: absorption by the base parameters raises it).
inline constexpr int kDetectabilityPoints = 9;
// The baseline's wave speed starts from the best of a scan over start +-kWaveSpeedScanSpan...
inline constexpr int kWaveSpeedScanPoints = 25;
inline constexpr double kWaveSpeedScanSpan = 0.3;
// ... then of a fine scan over best +-kFineScanSpan (each candidate repeats this one).
inline constexpr int kFineScanPoints = 11;
inline constexpr double kFineScanSpan = 0.025;
// ... and a finest one over +-kFinestScanSpan: the valley in c can be narrower than 0.5% (light
// damping, many reflections over a long log).
inline constexpr double kFinestScanSpan = 0.005;
// A local search also fits from its best scan point in another valley of the wave speed: more
// than this (relative) away from the best.
inline constexpr double kSecondStartSpan = 0.0075;

struct DiagnoseOptions {
  SimulationOptions simulation;  // cells: kDiagnoseCells unless set
  ReplayOptions replay;  // how the log's inputs are fed (reconstructed by default) and started
  std::vector<std::string> base_params = {"wave_speed_mps", "friction_f1_per_s", "choke_leak_m2"};
  double fit_fraction = 0.6;
  // Move the split so that each regime of the log is on both sides (step 1); false: at
  // fit_fraction whatever the regimes (they are still detected and reported).
  bool split_by_regimes = true;
  int max_iterations = 25;       // the baseline's fit
  int candidate_iterations = 8;  // each candidate's (it starts from the fitted baseline)
  // Only the baseline (fit and score), no candidates.
  bool baseline_only = false;
  // Effects to try; empty: the whole catalogue.
  std::vector<std::string> candidates;
  // Runs independent tasks (one per candidate) to completion; empty: one after the other. The
  // model has no threads (design.md); the command line passes a thread pool here. Tasks share
  // nothing mutable and the model's functions they call are reentrant. Their kinds:
  // "candidate E", "polish E", "floors E" (E an effect), "reference search".
  TaskRunner run_tasks;
  // "baseline", "<effect>", "compare"; fraction of the whole diagnosis done.
  std::function<void(std::string_view stage, double fraction)> progress;
  bool solver_log = false;  // FitOptions::solver_log for every fit

  // fit_fraction in (0.1, 0.95), and every name of `candidates` an effect of the catalogue
  // (unless baseline_only); else an error that says which.
  [[nodiscard]] Status Validate() const;
};

inline constexpr int kDiagnoseCells = 50;

struct NamedValue {
  std::string key;
  double value = 0.0;
  double standard_error = 0.0;
  bool held = false;  // no influence on the log: kept at its start value (FitResult::held)
};

struct CandidateResult {
  std::string effect;
  std::string explains;            // EffectInfo::explains
  std::vector<NamedValue> params;  // every fitted parameter (base and effect)
  int extra_params = 0;
  double fit_error = 0.0;  // on the fitting data
  // On the fitting data, the reference (the model it extends) with this effect at its weakest
  // within its bounds: fit_error never exceeds it. Equal to the reference's own error where that
  // bound switches the effect off (all but piston_compressibility, whose 2.5 GPa bound is not
  // the base model's rigid compartment).
  double zero_fit_error = 0.0;
  double error = 0.0;                  // on the scoring data (the compare metric)
  double penalised_error = 0.0;        // ranking score
  double improvement = 0.0;            // (baseline error - error) / baseline error
  double improvement_std_error = 0.0;  // of `improvement` (relative), from the blocks
  bool significant = false;
  std::string failure;  // non-empty when the candidate could not be fitted (e.g. range left)
  // The selection round that fitted it: 1 against the base model, 2 against the model with the
  // verdict, ... (its improvement and significance are against that round's reference).
  int round = 1;
  // The smallest strength of the effect's first fitted parameter that this log could show
  // (kDetectabilityPoints); absent when none in its plausible range could, or not computed.
  std::string strength_key;  // "unsteady_friction.k"
  std::optional<double> detectable_from;
  bool detectable_at_weakest = false;  // already at the weakest strength scanned
  bool strength_inverse = false;       // the effect grows as the parameter falls (a bulk modulus)
  double strength_scan_limit = 0.0;    // the strongest value scanned
  // Per channel: error (NRMSE) on the scoring data, baseline and this candidate.
  std::vector<std::pair<Channel, double>> channel_errors;
  std::vector<double> block_errors;  // over the kScoreBlocks blocks of the scoring data
  // Where the log holds pressures on a floor (cavity_evidence.h): the NRMSE on the floor samples,
  // averaged into penalised_error as one channel per channel with a floor; absent otherwise.
  std::optional<double> floor_error;
  RigParams fitted;
};

// Where a diagnosis's model runs went, by stage and kind (bench/diagnose_speed.sh prints them):
// its wall time follows them, a run on the fitting data costing fit_fraction of one over the
// whole log.
struct StageRuns {
  std::string stage;      // "baseline", "round 1", "round 1 polish", "verdict", "round 2", ...
  int scans = 0;          // scan points on the fitting data (wave speed; strength x wave speed)
  int fits = 0;           // the local fits' replays on the fitting data
  int detectability = 0;  // the detectability scans, over the whole log
  int scoring = 0;        // the inputs' levels and the scored replays, over the whole log
  int total() const { return scans + fits + detectability + scoring; }
  StageRuns& operator+=(const StageRuns& other);
};

struct Diagnosis {
  double fit_end_s = 0.0;            // fitting data: [start, fit_end_s), scoring: [fit_end_s, end]
  double requested_fit_end_s = 0.0;  // where fit_fraction puts it (fit_end_s unless regimes)
  // The log's regimes (regimes.h) with their time in each part, and those left on one side.
  std::vector<Regime> regimes;
  std::vector<std::string> one_sided_regimes;
  double noise_floor = 0.0;  // estimated measurement noise as a mean NRMSE (second differences)
  CandidateResult baseline;  // effect ""
  Comparison baseline_comparison;           // fitted baseline over the whole log
  std::vector<CandidateResult> candidates;  // ranked best first (round 1, against the baseline)
  std::vector<CandidateResult> failed;      // candidates whose fit failed (any round): not ranked
  // Pressures held on a floor and ended by a jump (column separation's signature; empty where
  // the log has none): round 1 is ranked with the floors scored too (cavity_evidence.h).
  CavityEvidence pressure_floors;
  // The choke's and FT2's levels as estimated at the fitted base model (EstimateInputLevels;
  // none where the log came with levels applied or options.replay says not to). The fits run on
  // these; each candidate is scored with levels estimated at its own fit.
  InputLevelCorrection input_levels;
  std::optional<std::string> verdict;  // the missing effect, if one is significant
  // Other significant candidates that explain the log as well as the verdict: the verdict's lead
  // over them is below kMinRelativeImprovement of the baseline error (e.g. the two inlet
  // compliances, hose_compliance and piston_compressibility, where the log does not excite
  // what tells them apart).
  std::vector<std::string> equivalent;
  std::optional<Comparison> winner_comparison;  // the verdict's model over the whole log
  // Forward selection (step 5): the effects added in order; selected[0] is the verdict's
  // candidate. Each entry's params are every parameter of the model at that step (base and
  // effects), its error the scoring error after adding it, its improvement and significance
  // against the model before it. (An entry's fit is replaced where the next round's search of
  // the same model fits the fitting data better and scores no worse on the scoring data.)
  std::vector<CandidateResult> selected;
  // The best candidate of the round that ended the selection (not significant), with its
  // detectability measured against the model selected so far; none where no round tried one.
  std::optional<CandidateResult> next;
  // Every selection round after the first, in order (rounds[0] is round 2): its candidates ranked
  // best first, measured against the model with the effects selected before the round (the
  // round-1 ranking is `candidates`). The round that ended the selection is the last; its first
  // candidate is `next`.
  std::vector<std::vector<CandidateResult>> later_rounds;
  std::string selection_end;  // why the selection ended ("no candidate significant", ...)
  // What the best model (the base model with the effects selected) leaves (step 6).
  std::optional<ResidualSignature> residual;
  int replays = 0;              // model runs: the sum over `runs`
  std::vector<StageRuns> runs;  // in the order of the stages
};

Result<Diagnosis> Diagnose(const MeasuredLog& log, const RigParams& start,
                           const DiagnoseOptions& options = {});

// A sentence on what the candidate explains, with its numbers ("removes ...: error 4.1% -> 1.2%
// on the scoring data").
std::string DescribeCandidate(const CandidateResult& candidate, const CandidateResult& baseline);

// What this log could show of the candidate (kDetectabilityPoints): "detectable at this noise
// from unsteady_friction.k >= 0.02" or "not detectable at this noise even at ... = 0.5"; empty
// where not computed.
std::string DescribeDetectability(const CandidateResult& candidate);

// The order of a ranking (Diagnosis::candidates, a selection round's): the significant candidates
// first, each group best first by the penalised error, ties in their order. The verdict and each
// round's pick are the first, so a significant candidate is chosen if there is one.
void RankCandidates(std::vector<CandidateResult>* candidates);

// The effects the next selection round tries, from the ranking of the round before (`ranked`):
// those that removed some of its error and are not selected yet; every one not selected where
// the effect selected last (diagnosis.selected.back()) removed more than kDominatingImprovement.
std::vector<const EffectInfo*> NextCandidates(const std::vector<CandidateResult>& ranked,
                                              const Diagnosis& diagnosis);

// Mean over the compared channels of sigma_noise / std(y), sigma_noise from second differences
// (std(d2 y) / sqrt(6)): the error a perfect model would have on this log.
double EstimateNoiseFloor(const MeasuredLog& log);

}  // namespace mpdrig
