#include "model/identification/diagnose.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "model/analysis/window_error.h"
#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"

namespace mpdrig {
namespace {

// The catalogue's key of the absolute pressure at which a cavity holds (column_separation's).
constexpr std::string_view kVapourPressureKey = "vapour_pressure_pa";

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Mean NRMSE over channels, with the residual of `block` normalised by the variation of the
// whole scoring window (per channel: ss_tot per sample), so blocks are comparable.
double BlockError(const std::vector<WindowSums>& block,
                  const std::vector<double>& variance_per_sample) {
  double sum = 0.0;
  int used = 0;
  for (std::size_t c = 0; c < block.size(); ++c) {
    if (block[c].count == 0 || !(variance_per_sample[c] > 0.0)) continue;
    sum += std::sqrt(block[c].ss_res / (block[c].count * variance_per_sample[c]));
    ++used;
  }
  return used > 0 ? sum / used : kNaN;
}

struct Scored {
  double error = kNaN;
  std::vector<double> block_errors;
  std::vector<std::pair<Channel, double>> channel_errors;
};

Scored Score(const MeasuredLog& log, const ModelTraces& model, double t0, double t1) {
  Scored scored;
  const std::vector<double> means = WindowMeans(log, t0, t1);
  const std::vector<WindowSums> whole = ChannelWindowSums(log, model, t0, t1, &means);
  std::vector<double> variance(log.channels.size(), 0.0);
  double sum = 0.0;
  int used = 0;
  for (std::size_t c = 0; c < whole.size(); ++c) {
    if (!(whole[c].ss_tot > 0.0) || whole[c].constant) continue;  // nothing to explain
    variance[c] = whole[c].ss_tot / whole[c].count;
    scored.channel_errors.emplace_back(log.channels[c].channel, whole[c].nrmse());
    sum += whole[c].nrmse();
    ++used;
  }
  scored.error = used > 0 ? sum / used : kNaN;
  // Blocks [b0, b1) of the window, deviations about the whole window's means: their spread
  // gives the improvement's standard error.
  const double width = (t1 - t0) / kScoreBlocks;
  for (int k = 0; k < kScoreBlocks; ++k) {
    const double b0 = t0 + k * width;
    const double b1 = k + 1 == kScoreBlocks ? t1 : b0 + width;
    const auto block = ChannelWindowSums(log, model, b0, std::nextafter(b1, b0), &means);
    scored.block_errors.push_back(BlockError(block, variance));
  }
  return scored;
}

std::vector<NamedValue> Named(const FitResult& fit) {
  std::vector<NamedValue> values;
  for (std::size_t i = 0; i < fit.keys.size(); ++i) {
    values.push_back({fit.keys[i], fit.estimates[i], fit.standard_errors[i], fit.held[i]});
  }
  return values;
}

// Fills a candidate's scores from its Score on the scoring data: error, penalised error,
// improvement over the baseline, the improvement's standard error from the blocks, significance.
void Assess(const Scored& score, const Scored& base_score, double base_error,
            CandidateResult* candidate) {
  candidate->error = score.error;
  candidate->penalised_error = score.error * (1.0 + kParameterPrice * candidate->extra_params);
  candidate->channel_errors = score.channel_errors;
  candidate->block_errors = score.block_errors;
  candidate->improvement = (base_error - score.error) / base_error;
  // Spread of the block improvements: their standard error.
  double mean = 0.0, squares = 0.0;
  int blocks = 0;
  for (int k = 0; k < kScoreBlocks; ++k) {
    const double d = base_score.block_errors[k] - score.block_errors[k];
    if (!std::isfinite(d)) continue;
    mean += d, squares += d * d, ++blocks;
  }
  candidate->improvement_std_error = 0.0;
  if (blocks >= 2) {
    mean /= blocks;
    const double variance = std::max(0.0, (squares - blocks * mean * mean) / (blocks - 1));
    // Relative, as `improvement` beside it in the report.
    candidate->improvement_std_error = std::sqrt(variance / blocks) / base_error;
  }
  const double absolute = base_error - candidate->penalised_error;
  candidate->significant =
      blocks >= 2 && absolute > kMinRelativeImprovement * base_error &&
      absolute > kSignificanceZ * candidate->improvement_std_error * base_error;
}

// A candidate's score as Assess left it (to assess it again against another reference).
Scored ScoredOf(const CandidateResult& candidate) {
  return {candidate.error, candidate.block_errors, candidate.channel_errors};
}

// The fit kept of those tried (fit on `log` with `options`, which leave out the standard
// errors): its standard errors added, their replays counted.
void KeepFit(const MeasuredLog& log, const std::vector<FitParameter>& parameters,
             const FitOptions& options, FitResult* fit, StageRuns* runs) {
  const int before = fit->replays;
  MPDRIG_CHECK(EstimateStandardErrors(log, parameters, options, fit).ok());
  runs->fits += fit->replays - before;
}

// What a local search (scans, then Levenberg-Marquardt) needs to know, shared by the candidates
// and the baseline's second search.
struct SearchContext {
  const MeasuredLog* fit_log = nullptr;
  const RigParams* start = nullptr;  // the user's start values (base parameters)
  SimulationOptions simulation;
  FitOptions fit_options;
  double t_begin = 0.0, t_end = 0.0;  // the fitting data
  bool fits_wave_speed = false;
  std::size_t base_count = 0;  // parameters[0, base_count) are base parameters
};

// The catalogue's entry for an effect parameter key ("effect.param") if it has a plausible
// range (EffectParamInfo::plausible_min/max), else null.
const EffectParamInfo* PlausibleRange(const std::string& key) {
  auto found = FindParamByKey(key);
  if (!found.ok() || found->effect_param == nullptr) return nullptr;
  const EffectParamInfo* param = found->effect_param;
  return param->plausible_min > 0.0 && param->plausible_min < param->plausible_max ? param
                                                                                   : nullptr;
}

// The replays of a search's scans on the fitting data: every point (for a second start) and the
// best. A point that can be neither (FitFromTwoStarts) is not kept, and its replay stops as soon as
// that is certain (StopAbove): a scan's result is the same as with every replay run to its end.
struct ScanPoints {
  struct Point {
    double error;
    RigParams params;
  };
  std::vector<Point> points;
  // The fitting data's own side of the error (ss_tot per channel), measured once for the scan's
  // replays.
  WindowReference window;
  double best_error = std::numeric_limits<double>::infinity();
  RigParams best;  // the search's start until a scan point fits better
  // FitFromTwoStarts's rule for the second start: the best point within kFineScanSpan of this
  // wave speed where given, else the best one more than kSecondStartSpan from the best point's.
  std::optional<double> near_wave_speed;

  // The error above which a point at `wave_speed_mps` is neither the best nor the second start,
  // whatever the points still to come: above the best so far, and above what rules it out as the
  // second start. Near a given wave speed: outside its window it never is one, inside it is not
  // once a point there fits better. Otherwise the second start is the best point away from the
  // final best one; two points too far apart to be both near any wave speed (one of them is then
  // away from the final best, whichever it is) both fitting better rule it out.
  double StopAbove(double wave_speed_mps) const {
    double second = std::numeric_limits<double>::infinity();
    if (near_wave_speed) {
      if (!InNearWindow(wave_speed_mps)) {
        second = -std::numeric_limits<double>::infinity();
      } else {
        for (const Point& point : points) {
          if (InNearWindow(point.params.wave_speed_mps)) second = std::min(second, point.error);
        }
      }
    } else {
      // No wave speed within kSecondStartSpan of both c_a < c_b: c_b / (1 + s) > c_a / (1 - s).
      const double apart = (1.0 + kSecondStartSpan) / (1.0 - kSecondStartSpan);
      for (std::size_t a = 0; a < points.size(); ++a) {
        for (std::size_t b = a + 1; b < points.size(); ++b) {
          const double lo =
              std::min(points[a].params.wave_speed_mps, points[b].params.wave_speed_mps);
          const double hi =
              std::max(points[a].params.wave_speed_mps, points[b].params.wave_speed_mps);
          if (hi > lo * apart * (1.0 + 1e-9)) {
            second = std::min(second, std::max(points[a].error, points[b].error));
          }
        }
      }
    }
    return std::max(best_error, second);
  }
  bool InNearWindow(double wave_speed_mps) const {
    return std::fabs(wave_speed_mps / *near_wave_speed - 1.0) <= kFineScanSpan * (1.0 + 1e-9);
  }
};

void ReplayScanPoint(const SearchContext& context, const RigParams& trial, ScanPoints* scan,
                     StageRuns* runs) {
  auto error =
      ReplayWindowError(*context.fit_log, trial, context.simulation, context.fit_options.replay,
                        scan->window, scan->StopAbove(trial.wave_speed_mps));
  ++runs->scans;
  if (!error.ok() || !error->has_value()) return;
  scan->points.push_back({**error, trial});
  if (**error < scan->best_error) scan->best_error = **error, scan->best = trial;
}

// `strength` with the effect's parameters (parameters[base_count...]) at `factor` of their
// values there (of 5% of their range where the value is 0) or, where the catalogue gives a
// plausible range, at the same relative place in it, log-spaced; none where one cannot be set.
std::optional<RigParams> AtStrength(RigParams strength, const std::vector<FitParameter>& parameters,
                                    std::size_t base_count, double factor,
                                    const std::vector<double>& factors) {
  for (std::size_t j = base_count; j < parameters.size(); ++j) {
    const FitParameter& parameter = parameters[j];
    auto value = GetParamValue(strength, parameter.key);
    if (!value.ok()) return std::nullopt;
    double scaled = *value != 0.0
                        ? *value * factor
                        : parameter.lower + 0.05 * factor * (parameter.upper - parameter.lower);
    // A strength whose plausible range spans decades (trapped air in the compartment, free
    // gas) is scanned over that range, log-spaced, as the factors span theirs.
    if (const EffectParamInfo* info = PlausibleRange(parameter.key)) {
      const double position =
          std::log(factor / factors.front()) / std::log(factors.back() / factors.front());
      scaled = info->plausible_min * std::pow(info->plausible_max / info->plausible_min, position);
    }
    if (!SetParamValue(&strength, parameter.key,
                       std::clamp(scaled, parameter.lower, parameter.upper))
             .ok()) {
      return std::nullopt;
    }
  }
  return strength;
}

// Two local fits: from the best scan point, and from the best one in another valley of the
// wave speed (more than kSecondStartSpan away); the better one. The effect's strength and the
// wave speed trade against each other (a compliance or a lag lowers the resonances as a lower c
// does), and the scan's best point can sit in the wrong valley of that trade: measured on a
// hidden hose_compliance (seed 2), the fit from the best point ended 0.9% high in c with 4% more
// error on the fitting data than the fit from the second start, 0.4% from the true c.
// Where the scan has a `near_wave_speed`, the second start is the best point within kFineScanSpan
// of it instead (SearchAndFit: the start's wave speed, where the reference's has absorbed an
// effect).
Result<FitResult> FitFromTwoStarts(const SearchContext& context, const ScanPoints& scan,
                                   const std::vector<FitParameter>& parameters, StageRuns* runs) {
  const ScanPoints::Point* second = nullptr;
  for (const ScanPoints::Point& point : scan.points) {
    const bool elsewhere = scan.near_wave_speed
                               ? scan.InNearWindow(point.params.wave_speed_mps)
                               : std::fabs(point.params.wave_speed_mps / scan.best.wave_speed_mps -
                                           1.0) > kSecondStartSpan;
    if (elsewhere && (second == nullptr || point.error < second->error)) second = &point;
  }
  auto fit = FitParameters(*context.fit_log, scan.best, parameters, context.fit_options);
  if (fit.ok()) runs->fits += fit->replays;
  if (second != nullptr) {
    auto other = FitParameters(*context.fit_log, second->params, parameters, context.fit_options);
    if (other.ok()) {
      runs->fits += other->replays;
      if (!fit.ok() || other->error_after < fit->error_after) return other;
    }
  }
  return fit;
}

// Local fit of `parameters` (the base ones, then the effect's) from the fitted baseline `params`
// (with the effect switched on). Starts from a scan: the effect's strength over its plausible
// range (its fitted parameters together, x {1/4, 1/2, 1, 2, 4} of their defaults, or five
// log-spaced points of EffectParamInfo's plausible range where it has one) and, for each,
// the fine wave-speed scan. An effect that slows or delays the waves (added inertia, a lag, a
// compliance) moves the best wave speed; a local fit from the baseline's c can trade one for the
// other and stop short. Two starting points for the other base parameters: the baseline's
// estimates, and the start values (the baseline's may have absorbed the missing effect, e.g. a
// higher f1 standing in for unsteady friction, and then hold the candidate back). Without effect
// parameters this is the same search for the base model alone.
//
// The second starting point keeps the reference's wave speed, unless that lies outside the range
// the base model's scan took as plausible (kWaveSpeedScanSpan around the start value): then the
// reference has absorbed something that slows the waves, the second origin is scanned around the
// start's wave speed, and the second local fit starts from its best point, however it compares
// with the first origin's. Measured: free gas at a low-pressure operating point (void fraction
// 8.4e-4, the pipe's c 788 m/s) was fitted by the base model as c = 373 m/s; the gas candidate,
// scanned and fitted only around 373 m/s, ended worse than the base model and nothing was named
// (47 % left against a floor of 20 %). Around 850 m/s the scan's best point fits worse than the
// best near 373 m/s (36 % against 33 % on the fitting data), so it also had to be the second start.
Result<FitResult> SearchAndFit(const SearchContext& context, const RigParams& params,
                               const std::vector<FitParameter>& parameters, StageRuns* runs) {
  RigParams from_start = *context.start;
  const bool wave_speed_absorbed =
      context.fits_wave_speed &&
      std::fabs(params.wave_speed_mps / context.start->wave_speed_mps - 1.0) > kWaveSpeedScanSpan;
  if (!wave_speed_absorbed) from_start.wave_speed_mps = params.wave_speed_mps;
  from_start.effects = params.effects;
  ScanPoints scan;
  scan.window = MeasureWindow(*context.fit_log, context.t_begin, context.t_end);
  scan.best = params;
  if (wave_speed_absorbed) scan.near_wave_speed = from_start.wave_speed_mps;
  const bool has_effect = parameters.size() > context.base_count;
  const std::vector<double> factors =
      has_effect ? std::vector<double>{0.25, 0.5, 1.0, 2.0, 4.0} : std::vector<double>{1.0};
  for (int origin = 0; origin < 2; ++origin) {
    const double centre = origin == 0 ? params.wave_speed_mps : from_start.wave_speed_mps;
    for (double factor : factors) {
      const std::optional<RigParams> strength = AtStrength(
          origin == 0 ? params : from_start, parameters, context.base_count, factor, factors);
      if (!strength) continue;
      const int speeds = context.fits_wave_speed ? kFineScanPoints : 1;
      for (int k = 0; k < speeds; ++k) {
        RigParams trial = *strength;
        if (context.fits_wave_speed) {
          trial.wave_speed_mps =
              centre * (1.0 - kFineScanSpan + 2.0 * kFineScanSpan * k / (speeds - 1));
        }
        ReplayScanPoint(context, trial, &scan, runs);
      }
    }
  }
  // The finest wave-speed step around the best point.
  if (context.fits_wave_speed) {
    const RigParams around = scan.best;
    for (int k = 0; k < kFineScanPoints; ++k) {
      RigParams trial = around;
      trial.wave_speed_mps =
          around.wave_speed_mps *
          (1.0 - kFinestScanSpan + 2.0 * kFinestScanSpan * k / (kFineScanPoints - 1));
      ReplayScanPoint(context, trial, &scan, runs);
    }
  }
  return FitFromTwoStarts(context, scan, parameters, runs);
}

// The strengths of an effect parameter over which detectability is scanned: its plausible range
// where the catalogue gives one, else [default / 4, 4 default], within its bounds; log-spaced.
std::vector<double> StrengthScan(const FitParameter& parameter, double default_value) {
  double lo = default_value / 4.0, hi = default_value * 4.0;
  if (const EffectParamInfo* info = PlausibleRange(parameter.key)) {
    lo = info->plausible_min, hi = info->plausible_max;
  }
  if (!(default_value > 0.0) && PlausibleRange(parameter.key) == nullptr) {
    lo = parameter.lower + 0.01 * (parameter.upper - parameter.lower);
    hi = parameter.lower + 0.5 * (parameter.upper - parameter.lower);
  }
  lo = std::max(lo, parameter.lower), hi = std::min(hi, parameter.upper);
  std::vector<double> strengths;
  if (!(lo > 0.0) || !(hi > lo)) return strengths;
  for (int k = 0; k < kDetectabilityPoints; ++k) {
    strengths.push_back(lo *
                        std::pow(hi / lo, static_cast<double>(k) / (kDetectabilityPoints - 1)));
  }
  return strengths;
}

// See kDetectabilityPoints: the first strength whose change of the baseline's channels on the
// scoring data reaches the detectable share of the baseline's error there.
void EstimateDetectability(const MeasuredLog& log, const RigParams& baseline,
                           const ModelTraces& baseline_traces, double baseline_error,
                           const SimulationOptions& simulation, const ReplayOptions& replay,
                           const FitParameter& parameter, double default_value, double score_begin,
                           double score_end, CandidateResult* candidate, StageRuns* runs) {
  candidate->strength_key = parameter.key;
  // The baseline as the "measurement": the change is measured against its own variation.
  MeasuredLog reference = log;
  for (std::size_t c = 0; c < reference.channels.size(); ++c) {
    std::vector<double>& values = reference.channels[c].values_si;
    for (std::size_t n = 0; n < values.size(); ++n) {
      if (std::isfinite(values[n])) values[n] = baseline_traces.values_si[c][n];
    }
  }
  const double needed =
      baseline_error *
      std::sqrt(1.0 / ((1.0 - kMinRelativeImprovement) * (1.0 - kMinRelativeImprovement)) - 1.0);
  RigParams params = baseline;
  params.effects.push_back({candidate->effect, {}});
  const std::vector<double> strengths = StrengthScan(parameter, default_value);
  for (double strength : strengths) {
    if (!SetParamValue(&params, parameter.key, strength).ok()) return;
  }
  if (strengths.empty()) return;
  // The change at strength k, replayed when first asked for: the scan stops at the first
  // detectable strength from the weak end, and the strengths past it are never replayed.
  std::vector<std::optional<double>> change(strengths.size());
  const auto change_at = [&](std::size_t k) {
    if (!change[k]) {
      MPDRIG_CHECK(SetParamValue(&params, parameter.key, strengths[k]).ok());
      auto traces = ReplayModel(log, params, simulation, replay);
      ++runs->detectability;
      change[k] = traces.ok() ? WindowError(reference, *traces, score_begin, score_end) : 0.0;
    }
    return *change[k];
  };
  // Most parameters grow with the effect (a friction factor, a time constant); some shrink (a
  // bulk modulus): the weak end is the one with the smaller change.
  candidate->strength_inverse = change_at(0) > change_at(strengths.size() - 1);
  candidate->strength_scan_limit =
      candidate->strength_inverse ? strengths.front() : strengths.back();
  for (std::size_t j = 0; j < strengths.size(); ++j) {
    const std::size_t k = candidate->strength_inverse ? strengths.size() - 1 - j : j;
    if (change_at(k) >= needed) {
      candidate->detectable_from = strengths[k];
      candidate->detectable_at_weakest = j == 0;
      return;
    }
  }
}

}  // namespace

double EstimateNoiseFloor(const MeasuredLog& log) {
  double sum = 0.0;
  int used = 0;
  std::vector<double> d2;
  for (const MeasuredChannel& channel : log.channels) {
    const std::vector<double>& y = channel.values_si;
    double s1 = 0.0, s2 = 0.0;
    long n_y = 0;
    d2.clear();
    for (std::size_t n = 0; n < y.size(); ++n) {
      if (!std::isfinite(y[n])) continue;
      s1 += y[n], s2 += y[n] * y[n], ++n_y;
      if (n >= 2 && std::isfinite(y[n - 1]) && std::isfinite(y[n - 2])) {
        d2.push_back(y[n] - 2.0 * y[n - 1] + y[n - 2]);
      }
    }
    if (n_y < 3 || d2.size() < 3) continue;
    const double var_y = s2 / n_y - (s1 / n_y) * (s1 / n_y);
    if (!(var_y > 0.0)) continue;
    // d2 of white noise of variance s^2 is normal with variance 6 s^2; the signal's own d2 is
    // small where the log oversamples it, but not at water-hammer fronts or cavity collapses:
    // the median absolute deviation (x 1.4826 for a normal) ignores those few samples.
    auto median = [](std::vector<double>& v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    const double centre = median(d2);
    for (double& v : d2) v = std::fabs(v - centre);
    const double sigma_d2 = 1.4826 * median(d2);
    sum += sigma_d2 / std::sqrt(6.0) / std::sqrt(var_y);
    ++used;
  }
  return used > 0 ? sum / used : 0.0;
}

// The significant candidates first, each group best first by the penalised error; ties keep
// their order. Significance first: the floor samples (ScoreFloors) can rank a candidate that
// matches the held pressures but gains too little over the baseline ahead of one that gains
// enough; the verdict is the leading candidate, which must be a significant one if any is (a
// hidden choke inertia, significant at 19.6 %, lost its verdict to a column separation fitted to
// its bound at 6.2 %).
void RankCandidates(std::vector<CandidateResult>* candidates) {
  std::stable_sort(candidates->begin(), candidates->end(),
                   [](const CandidateResult& a, const CandidateResult& b) {
                     if (a.significant != b.significant) return a.significant;
                     return a.penalised_error < b.penalised_error;
                   });
}

// The effects a round tries: those of the round before that removed some of its reference's
// error and are not selected yet. Those `equivalent` to the verdict stay: a second effect present
// beside the first also explains much of the log on its own, and may come within the equivalence
// margin of it (measured: a hidden unsteady friction beside a sensor lag, 0.93 points behind it
// against a margin of 0.92); where the two are one explanation (the inlet compliances), the round
// finds no gain in the second.
std::vector<const EffectInfo*> NextCandidates(const std::vector<CandidateResult>& ranked,
                                              const Diagnosis& diagnosis) {
  // Where the effect just selected removed most of the error, the round before measured every
  // other candidate against a misfit that effect dominated: one that removed nothing of it may
  // remove much of what is left (a hidden unsteady friction beside a pump curve that left the
  // base model 97 % off: its fit stayed at zero strength in round 1, and was never tried again).
  const bool dominated =
      !diagnosis.selected.empty() && diagnosis.selected.back().improvement > kDominatingImprovement;
  std::vector<const EffectInfo*> next;
  for (const CandidateResult& candidate : ranked) {
    // One that explained nothing of the misfit in the round before is not tried with the
    // selected effects either; every one that explained some is (a leaders' cut missed a hidden
    // gas entrainment ranked 6th beside a sensor lag, once the catalogue had 10 effects).
    if (!(candidate.improvement > 0.0) && !dominated) continue;
    if (std::any_of(diagnosis.selected.begin(), diagnosis.selected.end(),
                    [&](const CandidateResult& s) { return s.effect == candidate.effect; })) {
      continue;
    }
    if (const EffectInfo* info = FindEffectInfo(candidate.effect)) next.push_back(info);
  }
  return next;
}

namespace {

// The log and replay options a model is fitted and scored with: where `replay` chooses its start
// from the log (ChooseReplayStart: the steady state, a warm-up on the first period, or the pipe's
// state estimated from the pressures of the first travel times), the start chosen for this
// model; then, where it estimates the inputs' levels, the levels estimated at this model
// (EstimateInputLevels on the log as reconstructed).
//
// Each model its own start (but a polished candidate's fit, PolishLeaders): the command line
// chose the start for the start values, and a pipe state estimated with a model far off is a
// wrong initial state for every model replayed from it. Measured on a hidden pump curve
// (scale 1.91): the base model leaves 97 % of the log unexplained; from the state estimated with
// it, the pump curve's fit stopped at 21 % on its fitting data (scale 1.66); from the state
// estimated with the pump curve's own model the same fit reached 5.7 % (scale 1.87).
//
// Each model its own levels: the same freedom for the baseline and every candidate. (Levels
// estimated at the baseline alone handicap the model that is right: on a log with a hidden sensor
// lag they absorbed part of the baseline's misfit, and the lag, fitted to within 5 % of its
// truth, then scored 4.11 % against the effect-free log's 3.65 %.)
struct OwnReplay {
  MeasuredLog log;
  ReplayOptions replay;
  InputLevelCorrection levels;  // applied to `log` and `replay` where applied()
};
enum class Start { kOwn, kGiven };  // the start chosen for `params`, or the one `replay` has
OwnReplay ReplayFor(const MeasuredLog& reconstructed, const RigParams& params,
                    const SimulationOptions& simulation, const ReplayOptions& replay,
                    StageRuns* runs, Start start = Start::kOwn) {
  OwnReplay own{.log = reconstructed, .replay = replay, .levels = {}};
  if (start == Start::kOwn && replay.choose_warmup &&
      !reconstructed.reconstruction.levels.applied()) {
    ReplayOptions chosen = replay;
    // About three whole-log replays' worth: the profile's Jacobian (2 kProfilePoints replays over
    // kProfileFitTravelTimes travel times) and up to three over the choice's window.
    runs->scoring += 3;
    if (ChooseReplayStart(reconstructed, params, simulation, &chosen).ok()) own.replay = chosen;
  }
  if (own.replay.reconstruct_inputs && own.replay.estimate_levels &&
      !reconstructed.reconstruction.levels.applied()) {
    auto levels = EstimateInputLevels(reconstructed, params, simulation, own.replay);
    runs->scoring += 3;
    if (levels.ok() && levels->applied()) {
      ApplyInputLevels(*levels, &own.log);
      ApplyInputLevels(*levels, &own.replay);
      own.levels = *levels;
    }
  }
  return own;
}

// The replay of `params` over the whole log from its own start with its own levels (ReplayFor).
Result<ModelTraces> ReplayWithOwnLevels(const MeasuredLog& reconstructed, const RigParams& params,
                                        const SimulationOptions& simulation,
                                        const ReplayOptions& replay, StageRuns* runs,
                                        InputLevelCorrection* levels_used = nullptr) {
  const OwnReplay own = ReplayFor(reconstructed, params, simulation, replay, runs);
  if (levels_used != nullptr && own.levels.applied()) *levels_used = own.levels;
  ++runs->scoring;
  return ReplayModel(own.log, params, simulation, own.replay);
}

// --- Diagnose's steps ------------------------------------------------------------------------

// The effects to try: none for the baseline alone, else options.candidates (checked by
// DiagnoseOptions::Validate), or every diagnose candidate of the catalogue where it is empty.
std::vector<const EffectInfo*> CandidateEffects(const DiagnoseOptions& options) {
  std::vector<const EffectInfo*> candidates;
  if (options.baseline_only) return candidates;
  if (options.candidates.empty()) return DiagnoseCandidateEffects();
  for (const std::string& name : options.candidates) {
    const EffectInfo* info = FindEffectInfo(name);
    MPDRIG_CHECK(info != nullptr);  // DiagnoseOptions::Validate refused unknown names
    candidates.push_back(info);
  }
  return candidates;
}

// What Diagnose's steps share: the log split in time (step 1 of diagnose.h), the options of every
// replay and fit, and the progress report.
struct DiagnoseRun {
  const MeasuredLog& measured;  // as given: levels are estimated from it, per model scored
  const DiagnoseOptions& options;
  // Copies: the inputs' levels are estimated once the base model is fitted (FitBaseModel).
  MeasuredLog log;
  ReplayOptions replay;
  // Fits and the scans before them see only the fitting data. Fitting needs no replay past the
  // fitting data (40% of every fit's model time saved).
  MeasuredLog fit_log = {};
  SimulationOptions simulation = {};
  FitOptions fit_options = {};
  double t_begin = 0.0, t_end = 0.0;  // the whole log
  double fit_end_s = 0.0;             // fitting data: [t_begin, fit_end_s)
  double score_begin = 0.0;           // scoring data: [score_begin, t_end]
  double progress_steps = 1.0;        // the baseline, then one per candidate
  // Pressures held on a floor (cavity_evidence.h), found once: the floor samples are scored
  // (ScoreFloors) and their level starts a vapour pressure's search (FitCandidate).
  CavityEvidence floors = {};

  void Report(std::string_view stage, double done) const {
    if (options.progress) options.progress(stage, done / progress_steps);
  }
};

// Splits the log at options.fit_fraction and sets the fits' options; the split and the noise
// floor into *diagnosis.
DiagnoseRun SplitLog(const MeasuredLog& measured, const RigParams& start,
                     const DiagnoseOptions& options, std::size_t candidate_count,
                     Diagnosis* diagnosis) {
  DiagnoseRun run{
      .measured = measured, .options = options, .log = measured, .replay = options.replay};
  const std::vector<double>& t = run.log.time_s();
  run.t_begin = t.front();
  run.t_end = t.back();
  // At fit_fraction, or moved so that every regime of the log is on both sides (regimes.h).
  std::vector<Regime> regimes = DetectRegimes(run.log, start);
  RegimeSplit split =
      options.split_by_regimes
          ? SplitByRegimes(std::move(regimes), run.t_begin, run.t_end, options.fit_fraction)
          : SplitAt(std::move(regimes), run.t_begin, run.t_end,
                    run.t_begin + options.fit_fraction * (run.t_end - run.t_begin));
  diagnosis->fit_end_s = split.split_s;
  diagnosis->requested_fit_end_s = split.requested_s;
  diagnosis->regimes = std::move(split.regimes);
  diagnosis->one_sided_regimes = std::move(split.one_sided);
  diagnosis->noise_floor = EstimateNoiseFloor(run.log);
  run.floors = FindPressureFloors(run.log);
  run.fit_end_s = run.score_begin = diagnosis->fit_end_s;
  run.fit_log = MeasuredLogUntil(run.log, run.fit_end_s);
  run.simulation = options.simulation;
  // A missing effect may be what drives the base model out of its range (column separation):
  // then it must still be scored, not stopped.
  run.simulation.stop_on_range_violation = false;
  run.fit_options.simulation = run.simulation;
  run.fit_options.replay = run.replay;
  run.fit_options.window_end_s = run.fit_end_s;
  run.fit_options.max_iterations = options.max_iterations;
  run.fit_options.solver_log = options.solver_log;
  // Several fits from several starts, one kept: its standard errors only (KeepFit).
  run.fit_options.standard_errors = false;
  // The baseline, then one per candidate, per later round of the selection up to its cap.
  run.progress_steps = 1.0 + static_cast<double>(candidate_count) +
                       static_cast<double>((kMaxSelectedEffects - 1) * candidate_count);
  return run;
}

// The fitted base model, and what the candidates are measured against.
// The same for the model with the effects selected so far (SelectEffects): a reference.
struct Baseline {
  std::vector<FitParameter> parameters;  // options.base_params with their default bounds
  FitResult fit;
  SearchContext search;  // the local search each candidate repeats (SearchAndFit)
  ModelTraces traces;    // over the whole log, with the levels estimated at the fit
  Scored score;          // on the scoring data
  // The log and replay with the levels the fits run on (the detectability scan replays them).
  const MeasuredLog* log = nullptr;
  const ReplayOptions* replay = nullptr;
};

// Wave speed first, by a coarse scan on the fitting data (the thesis also tuned c before the
// friction, 9.4): the cost is not convex in c. A wrong c puts the resonances in the wrong place,
// and a local fit from there finds it cheaper to damp the response (raise f1) than to move c.
// Returns `start` with the best wave speed (and f1, where another one moved it).
RigParams ScanWaveSpeed(const DiagnoseRun& run, const RigParams& start, StageRuns* runs) {
  // Coarse then fine: the valley in c is about 1% wide (the sweep's higher resonances), so a
  // coarse step of 2.5% finds its side and a fine step of 0.25% its floor.
  double best_error = std::numeric_limits<double>::infinity();
  double best_c = start.wave_speed_mps;
  const WindowReference window = MeasureWindow(run.fit_log, run.t_begin, run.fit_end_s);
  auto scan = [&](const RigParams& from, double centre, double span, int points) {
    for (int k = 0; k < points; ++k) {
      RigParams trial = from;
      trial.wave_speed_mps = centre * (1.0 - span + 2.0 * span * k / (points - 1));
      // Only the best point matters: a replay stops once it cannot be that.
      auto error =
          ReplayWindowError(run.fit_log, trial, run.simulation, run.replay, window, best_error);
      ++runs->scans;
      if (!error.ok() || !error->has_value()) continue;
      if (**error < best_error) best_error = **error, best_c = trial.wave_speed_mps;
    }
  };
  scan(start, start.wave_speed_mps, kWaveSpeedScanSpan, kWaveSpeedScanPoints);
  scan(start, best_c, kFineScanSpan, kFineScanPoints);
  scan(start, best_c, kFinestScanSpan, kFineScanPoints);
  RigParams base_start = start;
  base_start.wave_speed_mps = best_c;
  // The friction moves the best wave speed a little (damping shifts the resonances) and the
  // valley is narrow: the finest scan again at half and twice the start's f1.
  for (double factor : {0.5, 2.0}) {
    const double before = best_error;
    RigParams trial_start = start;
    trial_start.friction_f1_per_s = start.friction_f1_per_s * factor;
    scan(trial_start, best_c, kFinestScanSpan, kFineScanPoints);
    if (best_error < before) {
      base_start = trial_start;
      base_start.wave_speed_mps = best_c;
    }
  }
  return base_start;
}

// The base model fitted from `base_start` on the fitting data, then the inputs' levels
// (EstimateInputLevels) at the fitted base parameters and the refit on them: at the start values
// a wrong leak or wave speed would pass for a level error (measured: a log whose leak differs
// 3 % from the default got its levels moved to their bound, the baseline error rose from 4.9 %
// to 6.8 % and pump_curve was named on an effect-free log). The replay's start is chosen again at
// the fitted base parameters (ReplayFor) for the same reason. Both are applied to run's log,
// replay and fitting data: every candidate's screening fit starts from them.
Result<FitResult> FitBaseModel(const RigParams& base_start,
                               const std::vector<FitParameter>& parameters, DiagnoseRun* run,
                               StageRuns* runs) {
  auto base_fit = FitParameters(run->fit_log, base_start, parameters, run->fit_options);
  if (!base_fit.ok()) return base_fit.status().Within("fitting the base model");
  runs->fits += base_fit->replays;
  const bool levels = run->replay.reconstruct_inputs && run->replay.estimate_levels &&
                      !run->log.reconstruction.levels.applied();
  const bool start = run->replay.choose_warmup && !run->log.reconstruction.levels.applied();
  if (levels || start) {
    // The start chosen and the levels estimated at the fitted base model (ReplayFor), the refit
    // on them.
    OwnReplay own = ReplayFor(run->measured, base_fit->params, run->simulation, run->replay, runs);
    run->log = std::move(own.log);
    run->replay = std::move(own.replay);
    run->fit_log = MeasuredLogUntil(run->log, run->fit_end_s);
    run->fit_options.replay = run->replay;
    auto refit = FitParameters(run->fit_log, base_fit->params, parameters, run->fit_options);
    if (!refit.ok()) return refit.status().Within("refitting the base model on the input levels");
    runs->fits += refit->replays;
    base_fit = std::move(refit);
  }
  return base_fit;
}

// Step 2 of diagnose.h: the base parameters fitted (after the wave-speed scan), given the
// candidates' search too, and scored; diagnosis->baseline and its comparison filled in.
Result<Baseline> FitBaseline(const RigParams& start, DiagnoseRun* run, Diagnosis* diagnosis,
                             StageRuns* runs) {
  const DiagnoseOptions& options = run->options;
  Baseline baseline;
  for (const std::string& key : options.base_params) {
    auto parameter = DefaultFitParameter(key);
    if (!parameter.ok()) return parameter.status();
    baseline.parameters.push_back(*parameter);
  }
  run->Report("baseline", 0.0);
  const bool fits_wave_speed = std::find(options.base_params.begin(), options.base_params.end(),
                                         "wave_speed_mps") != options.base_params.end();
  const RigParams base_start = fits_wave_speed ? ScanWaveSpeed(*run, start, runs) : start;
  auto base_fit = FitBaseModel(base_start, baseline.parameters, run, runs);
  if (!base_fit.ok()) return base_fit.status();
  SearchContext& search = baseline.search;
  search.fit_log = &run->fit_log;
  search.start = &start;
  search.simulation = run->simulation;
  search.fit_options = run->fit_options;
  search.t_begin = run->t_begin;
  search.t_end = run->fit_end_s;
  search.fits_wave_speed = fits_wave_speed;
  search.base_count = baseline.parameters.size();
  baseline.log = &run->log;
  baseline.replay = &run->replay;
  // The baseline also gets the candidates' search (their scans and two starting points, without
  // an effect), and keeps whichever fits the fitting data better. Otherwise a candidate could win
  // by its search alone: a better base point found from its other start, credited to its effect.
  {
    auto second = SearchAndFit(search, base_fit->params, baseline.parameters, runs);
    if (second.ok() && second->error_after < base_fit->error_after) {
      second->error_before = base_fit->error_before;
      base_fit = std::move(second);
    }
  }
  KeepFit(run->fit_log, baseline.parameters, run->fit_options, &*base_fit, runs);
  baseline.fit = std::move(base_fit).value();
  auto traces = ReplayWithOwnLevels(run->measured, baseline.fit.params, run->simulation,
                                    options.replay, runs, &diagnosis->input_levels);
  if (!traces.ok()) return traces.status();
  baseline.traces = std::move(traces).value();
  baseline.score = Score(run->log, baseline.traces, run->score_begin, run->t_end);
  CandidateResult& result = diagnosis->baseline;
  result.params = Named(baseline.fit);
  result.fit_error = baseline.fit.error_after;
  result.error = baseline.score.error;
  result.penalised_error = baseline.score.error;
  result.channel_errors = baseline.score.channel_errors;
  result.fitted = baseline.fit.params;
  auto comparison = CompareTraces(run->log, baseline.traces);
  if (!comparison.ok()) return comparison.status();
  diagnosis->baseline_comparison = std::move(comparison).value();
  return baseline;
}

// The reference at which an effect switched on in it is at its weakest: the first fitted
// parameter (its strength) at the bound where the effect vanishes (0 for a friction factor, a
// lag, a compliance, a void fraction; the stiff end for a bulk modulus, the lowest vapour
// pressure), the others at their defaults. Where that bound switches the effect off it is the
// reference itself; elsewhere near it (a compartment at 2.5 GPa, cavities below 500 Pa).
RigParams AtZeroStrength(RigParams params, const std::vector<FitParameter>& parameters,
                         std::size_t base_count, bool inverse) {
  if (parameters.size() > base_count) {
    const FitParameter& strength = parameters[base_count];
    MPDRIG_CHECK(
        SetParamValue(&params, strength.key, inverse ? strength.upper : strength.lower).ok());
  }
  return params;
}

// One candidate (step 3 of diagnose.h): its detectability at this log, then the effect switched
// on in the reference (the fitted baseline, or the model with the effects selected so far) and
// `parameters` (the reference's, then the effect's) searched and fitted on a short budget,
// scored on the scoring data (*score; Assess compares it with the reference). Reads only shared
// state: candidates run in parallel.
//
// Never worse than the reference on the data it is fitted on: with the effect at zero strength
// the candidate is the reference, so its fit must end at or below the reference's error there.
// The search's fits start from scan points at finite strengths and can stop above it (measured:
// 58 % against the base model's 48 % on a lab log); then a fit also starts from the reference's
// own point with the effect at zero strength (AtZeroStrength), and the better one is kept.
void FitCandidate(const DiagnoseRun& run, const Baseline& reference, const EffectInfo& info,
                  const std::vector<FitParameter>& parameters, CandidateResult* candidate,
                  Scored* score, StageRuns* runs) {
  const std::size_t base_count = reference.parameters.size();
  candidate->effect = std::string(info.name);
  candidate->explains = std::string(info.explains);
  candidate->extra_params = static_cast<int>(parameters.size() - base_count);
  candidate->error = candidate->penalised_error = std::numeric_limits<double>::infinity();
  if (parameters.size() > base_count) {
    const FitParameter& strength = parameters[base_count];
    auto found = FindParamByKey(strength.key);
    const double default_value =
        found.ok() && found->effect_param != nullptr ? found->effect_param->default_value : 0.0;
    EstimateDetectability(*reference.log, reference.fit.params, reference.traces,
                          reference.score.error, run.simulation, *reference.replay, strength,
                          default_value, run.score_begin, run.t_end, candidate, runs);
  }
  RigParams params = reference.fit.params;
  params.effects.push_back({candidate->effect, {}});
  // Where the log holds pressures on a floor, that floor is a measurement of the pressure at
  // which the column separates (the DVCM holds a cavity's pressure there): a vapour pressure's
  // search starts at it, not at the catalogue's 2300 Pa. From the default the search could not
  // find it: the discrete model's error changes in steps with p_v (a cavity forms or does not),
  // which the fit's difference steps do not see, and its five-point scan around 2300 Pa ended at
  // the 500 Pa bound on a log whose pressures held at 4.7 kPa (hidden p_v 4.4 kPa).
  if (run.floors.present()) {
    for (const EffectParamInfo& param : info.params) {
      if (param.fitted && param.key == kVapourPressureKey) {
        params.effects.back().Set(
            param.key, std::clamp(run.floors.level_pa, param.min_value, param.max_value));
      }
    }
  }
  SearchContext context = reference.search;
  context.fit_options.max_iterations = run.options.candidate_iterations;
  auto fit = SearchAndFit(context, params, parameters, runs);
  // The reference's own point, the effect at zero strength: its error on the fitting data.
  const RigParams zero =
      AtZeroStrength(params, parameters, base_count, candidate->strength_inverse);
  double zero_error = std::numeric_limits<double>::infinity();
  {
    auto traces =
        ReplayModel(*context.fit_log, zero, context.simulation, context.fit_options.replay);
    ++runs->fits;
    if (traces.ok())
      zero_error = WindowError(*context.fit_log, *traces, context.t_begin, context.t_end);
  }
  if (!fit.ok() || !(fit->error_after <= zero_error)) {
    auto from_zero = FitParameters(*context.fit_log, zero, parameters, context.fit_options);
    if (from_zero.ok()) {
      runs->fits += from_zero->replays;
      if (!fit.ok() || from_zero->error_after < fit->error_after) fit = std::move(from_zero);
    }
  }
  // The solver minimises the mean squared NRMSE over the channels, which can fall while their
  // mean (the error reported and ranked) rises (measured: hose_compliance from zero strength,
  // cost -0.2 %, error +0.4 %). Where every fit ends above the zero-strength point, that point
  // is the better fit: kept as it is (its standard errors estimated there).
  if (fit.ok() && !(fit->error_after <= zero_error)) {
    FitOptions stay_options = context.fit_options;
    stay_options.max_iterations = 0;
    auto stay = FitParameters(*context.fit_log, zero, parameters, stay_options);
    if (stay.ok()) {
      runs->fits += stay->replays;
      fit = std::move(stay);
    }
  }
  candidate->zero_fit_error = zero_error;
  if (!fit.ok()) {
    candidate->failure = fit.status().message();
    return;
  }
  auto traces =
      ReplayWithOwnLevels(run.measured, fit->params, run.simulation, run.options.replay, runs);
  if (!traces.ok()) {
    candidate->failure = traces.status().message();
    return;
  }
  *score = Score(run.log, *traces, run.score_begin, run.t_end);
  KeepFit(*context.fit_log, parameters, context.fit_options, &*fit, runs);
  candidate->params = Named(*fit);
  candidate->fit_error = fit->error_after;
  candidate->fitted = fit->params;
  Assess(*score, reference.score, reference.score.error, candidate);
}

// Runs independent tasks by options.run_tasks: in turn where there is none, in parallel when the
// caller (the command line) supplies threads. Each task writes only its own slot.
void RunTasks(const DiagnoseRun& run, const std::vector<Task>& tasks) {
  if (run.options.run_tasks) {
    run.options.run_tasks(tasks);
  } else {
    RunInTurn(tasks);
  }
}

// The candidates' parameters: the reference's, then each effect's fitted ones.
Result<std::vector<std::vector<FitParameter>>> CandidateParameters(
    const Baseline& reference, const std::vector<const EffectInfo*>& candidates) {
  std::vector<std::vector<FitParameter>> candidate_parameters(candidates.size(),
                                                              reference.parameters);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    for (const EffectParamInfo& param : candidates[i]->params) {
      if (!param.fitted) continue;
      auto parameter =
          DefaultFitParameter(std::string(candidates[i]->name) + "." + std::string(param.key));
      if (!parameter.ok()) return parameter.status();
      candidate_parameters[i].push_back(*parameter);
    }
  }
  return candidate_parameters;
}

// Every candidate fitted and scored against `reference` (FitCandidate) as one independent task
// each. Ranked into *ranked; those whose fit failed into *failed (not ranked: a failed fit says
// nothing of the effect). `extra_task`, if any, runs beside them (the reference's own search).
Status ScreenCandidates(const DiagnoseRun& run, const Baseline& reference,
                        const std::vector<const EffectInfo*>& candidates, double progress_at,
                        std::vector<CandidateResult>* ranked, std::vector<CandidateResult>* failed,
                        StageRuns* runs_total, const std::function<void()>& extra_task = {}) {
  auto candidate_parameters = CandidateParameters(reference, candidates);
  if (!candidate_parameters.ok()) return candidate_parameters.status();
  std::vector<CandidateResult> results(candidates.size());
  std::vector<Scored> scores(candidates.size());
  std::vector<StageRuns> runs(candidates.size());
  std::vector<Task> tasks;
  if (extra_task) tasks.push_back({"reference search", extra_task});
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    tasks.push_back({"candidate " + std::string(candidates[i]->name), [&, i] {
                       if (!run.options.run_tasks) {
                         run.Report(candidates[i]->name, progress_at + i);
                       }
                       FitCandidate(run, reference, *candidates[i], (*candidate_parameters)[i],
                                    &results[i], &scores[i], &runs[i]);
                     }});
  }
  RunTasks(run, tasks);
  for (std::size_t i = 0; i < results.size(); ++i) {
    *runs_total += runs[i];
    (results[i].failure.empty() ? ranked : failed)->push_back(std::move(results[i]));
  }
  RankCandidates(ranked);
  return Status::Ok();
}

// The candidates' fits ran on a short budget: the leading ones get the baseline's (in parallel),
// and the ranking is redone. A polished fit is kept when it fits the fitting data better (never
// chosen by the scoring data, which must stay unseen).
void PolishLeaders(const DiagnoseRun& run, const Baseline& reference,
                   std::vector<CandidateResult>* ranked, StageRuns* runs_total) {
  const std::size_t count = std::min(kPolishedCandidates, ranked->size());
  std::vector<StageRuns> runs(count);
  const auto polish = [&](std::size_t i) {
    CandidateResult& candidate = (*ranked)[i];
    std::vector<FitParameter> parameters;
    for (const NamedValue& value : candidate.params) {
      auto parameter = DefaultFitParameter(value.key);
      if (parameter.ok()) parameters.push_back(*parameter);
    }
    // On the levels that suit this candidate (estimated at its fit), as the baseline was
    // refitted on its own: an effect that moves the mean pressure (gas entrainment's slower
    // waves at low pressure) is otherwise fitted on levels bent to the baseline's misfit.
    // The start stays the command line's: the candidate is scored from its own
    // (ReplayWithOwnLevels), but a polish from a start chosen for it let an outlet compliance
    // that was not in the log gain 13 % in round 3 after a lag and free gas (selection_test,
    // seed 2: 3.97 -> 3.45 % against a floor of 3.41 %); the rounds' references keep their own.
    FitOptions own_options = run.fit_options;
    OwnReplay own = ReplayFor(run.measured, candidate.fitted, run.simulation, run.options.replay,
                              &runs[i], Start::kGiven);
    own_options.replay = own.replay;
    const MeasuredLog own_fit_log = MeasuredLogUntil(own.log, run.fit_end_s);
    auto polished = FitParameters(own_fit_log, candidate.fitted, parameters, own_options);
    if (!polished.ok()) return;
    runs[i].fits += polished->replays;
    if (!(polished->error_after < candidate.fit_error)) return;
    auto traces = ReplayWithOwnLevels(run.measured, polished->params, run.simulation,
                                      run.options.replay, &runs[i]);
    if (!traces.ok()) return;
    KeepFit(own_fit_log, parameters, own_options, &*polished, &runs[i]);
    candidate.params = Named(*polished);
    candidate.fit_error = polished->error_after;
    candidate.fitted = polished->params;
    Assess(Score(run.log, *traces, run.score_begin, run.t_end), reference.score,
           reference.score.error, &candidate);
  };
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < count; ++i) {
    tasks.push_back({"polish " + (*ranked)[i].effect, [&polish, i] { polish(i); }});
  }
  RunTasks(run, tasks);
  for (const StageRuns& r : runs) *runs_total += r;
  RankCandidates(ranked);
}

// Pressures held on a floor (cavity_evidence.h): the base model and every ranked candidate are
// also scored on the floor samples, one more channel per channel with a floor, and ranked again.
// Nothing changes on a log without floors.
void ScoreFloors(const DiagnoseRun& run, const Baseline& baseline, Diagnosis* diagnosis,
                 StageRuns* runs_total) {
  diagnosis->pressure_floors = run.floors;
  const CavityEvidence& evidence = diagnosis->pressure_floors;
  if (!evidence.present()) return;
  const auto rescore = [&](const ModelTraces& traces, CandidateResult* candidate) {
    candidate->floor_error = FloorError(run.measured, evidence, traces);
    candidate->penalised_error =
        ErrorWithFloors(candidate->error, static_cast<int>(candidate->channel_errors.size()),
                        evidence, *candidate->floor_error) *
        (1.0 + kParameterPrice * candidate->extra_params);
  };
  rescore(baseline.traces, &diagnosis->baseline);
  std::vector<CandidateResult>& ranked = diagnosis->candidates;
  std::vector<StageRuns> runs(ranked.size());
  std::vector<Task> tasks;
  for (std::size_t i = 0; i < ranked.size(); ++i) {
    tasks.push_back({"floors " + ranked[i].effect, [&, i] {
                       auto traces =
                           ReplayWithOwnLevels(run.measured, ranked[i].fitted, run.simulation,
                                               run.options.replay, &runs[i]);
                       if (traces.ok()) rescore(*traces, &ranked[i]);
                     }});
  }
  RunTasks(run, tasks);
  for (const StageRuns& r : runs) *runs_total += r;
  RankCandidates(&ranked);
}

// The verdict (step 4 of diagnose.h): the leading candidate if it is significant, the others as
// good as it, and its model compared over the whole log.
void DecideVerdict(const DiagnoseRun& run, Diagnosis* diagnosis, StageRuns* runs) {
  if (diagnosis->candidates.empty() || !diagnosis->candidates.front().significant) return;
  const CandidateResult& winner = diagnosis->candidates.front();
  // Others as good as the winner: significant, and the winner's lead over them below what
  // would count as significant over the baseline.
  for (std::size_t i = 1; i < diagnosis->candidates.size(); ++i) {
    const CandidateResult& other = diagnosis->candidates[i];
    if (other.significant && other.penalised_error - winner.penalised_error <
                                 kMinRelativeImprovement * diagnosis->baseline.error) {
      diagnosis->equivalent.push_back(other.effect);
    }
  }
  diagnosis->verdict = winner.effect;
  run.Report("compare",
             1.5 + static_cast<double>(diagnosis->candidates.size() + diagnosis->failed.size()));
  auto traces =
      ReplayWithOwnLevels(run.measured, winner.fitted, run.simulation, run.options.replay, runs);
  if (!traces.ok()) return;
  auto comparison = CompareTraces(run.log, *traces);
  if (comparison.ok()) diagnosis->winner_comparison = std::move(comparison).value();
}

// --- Forward selection (step 5 of diagnose.h) ----------------------------------------------

// The data a selection round fits on: the log with the inputs' levels estimated at the model
// selected so far (as the baseline's are at the base model), owned here; the reference points
// into it.
struct RoundData {
  MeasuredLog log;
  ReplayOptions replay;
  MeasuredLog fit_log;
};

// The model with the effects selected so far (`current`: the last one added, whose params are
// every parameter of the model) as the reference of the next round: its parameters, the search
// the candidates repeat (now with every one of them as base), its fitting error on the round's
// data, its traces with its own levels and its score.
Result<Baseline> SelectedReference(const DiagnoseRun& run, const Baseline& baseline,
                                   const CandidateResult& current, RoundData* data,
                                   StageRuns* runs) {
  Baseline reference;
  for (const NamedValue& value : current.params) {
    auto parameter = DefaultFitParameter(value.key);
    if (!parameter.ok()) return parameter.status();
    reference.parameters.push_back(*parameter);
  }
  OwnReplay own = ReplayFor(run.measured, current.fitted, run.simulation, run.options.replay, runs);
  data->log = std::move(own.log);
  data->replay = std::move(own.replay);
  data->fit_log = MeasuredLogUntil(data->log, run.fit_end_s);
  reference.log = &data->log;
  reference.replay = &data->replay;
  reference.search = baseline.search;
  reference.search.fit_log = &data->fit_log;
  reference.search.fit_options.replay = data->replay;
  reference.search.base_count = reference.parameters.size();
  reference.fit.params = current.fitted;
  auto fit_traces = ReplayModel(data->fit_log, current.fitted, run.simulation, data->replay);
  ++runs->fits;
  if (!fit_traces.ok()) return fit_traces.status().Within("replaying " + current.effect);
  reference.fit.error_after = WindowError(data->fit_log, *fit_traces, run.t_begin, run.fit_end_s);
  return reference;
}

// The reference's traces over the whole log (its own levels) and its score.
Status ScoreReference(const DiagnoseRun& run, Baseline* reference, StageRuns* runs) {
  auto traces = ReplayWithOwnLevels(run.measured, reference->fit.params, run.simulation,
                                    run.options.replay, runs);
  if (!traces.ok()) return traces.status();
  reference->traces = std::move(traces).value();
  reference->score = Score(run.log, reference->traces, run.score_begin, run.t_end);
  return Status::Ok();
}

// Forward selection: after the verdict, the leading candidates are fitted again with the
// selected effects in the model (their strengths refitted with the new one and the base
// parameters), scored against that model by the same rule, and the best is added while it is
// significant, up to kMaxSelectedEffects. The reference gets the candidates' search too (no
// candidate wins by its search alone), and keeps it if it fits its data better.
Status SelectEffects(const DiagnoseRun& run, const Baseline& baseline, Diagnosis* diagnosis) {
  if (diagnosis->candidates.empty()) {
    diagnosis->selection_end =
        diagnosis->failed.empty() ? "no candidate tried" : "no candidate could be fitted";
    return Status::Ok();
  }
  if (!diagnosis->verdict) {
    diagnosis->next = diagnosis->candidates.front();
    diagnosis->selection_end = "no candidate significant";
    return Status::Ok();
  }
  diagnosis->selected.push_back(diagnosis->candidates.front());
  // The score of the model the last selected effect was added to (its improvement's reference).
  Scored below = baseline.score;
  std::vector<CandidateResult> previous = diagnosis->candidates;
  double progress = 1.0 + static_cast<double>(previous.size() + diagnosis->failed.size());
  while (true) {
    if (diagnosis->selected.size() >= kMaxSelectedEffects) {
      diagnosis->selection_end =
          "at the cap of " + std::to_string(kMaxSelectedEffects) + " effects";
      return Status::Ok();
    }
    const std::vector<const EffectInfo*> candidates = NextCandidates(previous, *diagnosis);
    if (candidates.empty()) {
      diagnosis->selection_end = "no candidate left";
      return Status::Ok();
    }
    run.Report("selection", progress);
    // This round's runs: the screening (reference included), then the polishing.
    const std::string round = "round " + std::to_string(diagnosis->selected.size() + 1);
    diagnosis->runs.push_back({.stage = round});
    diagnosis->runs.push_back({.stage = round + " polish"});
    StageRuns* screening = &diagnosis->runs[diagnosis->runs.size() - 2];
    StageRuns* polishing = &diagnosis->runs.back();
    RoundData data;
    auto reference = SelectedReference(run, baseline, diagnosis->selected.back(), &data, screening);
    if (!reference.ok()) return reference.status();
    // The reference's own search (without a new effect) beside the candidates.
    std::optional<FitResult> searched;
    StageRuns search_runs;
    const auto own_search = [&] {
      SearchContext context = reference->search;
      context.fit_options.max_iterations = run.options.candidate_iterations;
      auto fit = SearchAndFit(context, reference->fit.params, reference->parameters, &search_runs);
      if (fit.ok() && fit->error_after < reference->fit.error_after) {
        KeepFit(*context.fit_log, reference->parameters, context.fit_options, &*fit, &search_runs);
        searched = *std::move(fit);
      }
    };
    // The candidates start from the reference as it is; they are scored against it as the
    // search leaves it.
    MPDRIG_RETURN_IF_ERROR(ScoreReference(run, &*reference, screening));
    const Scored as_selected = reference->score;
    std::vector<CandidateResult> ranked, failed;
    MPDRIG_RETURN_IF_ERROR(ScreenCandidates(run, *reference, candidates, progress, &ranked, &failed,
                                            screening, own_search));
    *screening += search_runs;
    progress += static_cast<double>(candidates.size());
    CandidateResult& current = diagnosis->selected.back();
    if (searched) {
      const FitResult selected_fit = reference->fit;
      reference->fit = *searched;
      MPDRIG_RETURN_IF_ERROR(ScoreReference(run, &*reference, screening));
      // The search's fit replaces the selected one only where it scores no worse on the scoring
      // data. A search that fits the fitting data better may score worse (the data it was not
      // fitted on can hold a regime the fitting data lack): measured, a search raised a selected
      // lag's scoring error from 5.30 to 5.49 %, and an outlet compliance that was not in the log
      // then gained 23 % over it; on another log a pump curve's from 23.1 to 32.1 %, and the
      // report and the next rounds went on from the worse fit (11 of 67 pair logs with two
      // effects selected had their first one's fit replaced by a worse-scoring one). The
      // candidates, fitted from the model as selected, are measured against the better of the
      // two.
      if (reference->score.error <= as_selected.error) {
        current.params = Named(*searched);
        current.fit_error = searched->error_after;
        current.fitted = searched->params;
        Assess(reference->score, below, below.error, &current);
        for (CandidateResult& candidate : ranked) {
          Assess(ScoredOf(candidate), reference->score, reference->score.error, &candidate);
        }
        RankCandidates(&ranked);
      } else {
        reference->fit = selected_fit;
        reference->score = as_selected;
      }
    }
    for (CandidateResult& f : failed) {
      f.round = static_cast<int>(diagnosis->selected.size()) + 1;
      diagnosis->failed.push_back(std::move(f));
    }
    for (CandidateResult& candidate : ranked) {
      candidate.round = static_cast<int>(diagnosis->selected.size()) + 1;
    }
    PolishLeaders(run, *reference, &ranked, polishing);
    diagnosis->later_rounds.push_back(ranked);
    if (ranked.empty() || !ranked.front().significant) {
      if (!ranked.empty()) diagnosis->next = ranked.front();
      diagnosis->selection_end =
          ranked.empty() ? "no candidate could be fitted" : "no candidate significant";
      return Status::Ok();
    }
    diagnosis->selected.push_back(ranked.front());
    below = reference->score;
    previous = std::move(ranked);
  }
}

// Step 6 of diagnose.h: what the best model (the base model with the effects selected) leaves,
// replayed with its own levels, and once more with fresh noise on its inputs for the floor.
void DescribeWhatIsLeft(const DiagnoseRun& run, Diagnosis* diagnosis, StageRuns* runs) {
  const CandidateResult& best =
      diagnosis->selected.empty() ? diagnosis->baseline : diagnosis->selected.back();
  const OwnReplay own =
      ReplayFor(run.measured, best.fitted, run.simulation, run.options.replay, runs);
  const MeasuredLog& log = own.log;
  const ReplayOptions& replay = own.replay;
  auto traces = ReplayModel(log, best.fitted, run.simulation, replay);
  ++runs->scoring;
  if (!traces.ok()) return;
  constexpr std::uint64_t kInputNoiseSeed = 1;
  auto noisy =
      ReplayModel(WithFreshInputNoise(log, kInputNoiseSeed), best.fitted, run.simulation, replay);
  ++runs->scoring;
  std::string name = "base model";
  for (const CandidateResult& step : diagnosis->selected) name += " + " + step.effect;
  diagnosis->residual = DescribeResidual(
      {.log = &log,
       .model = &*traces,
       .input_noise = noisy.ok() ? &*noisy : nullptr,
       .score_begin_s = run.score_begin,
       .score_end_s = run.t_end,
       .regimes = &diagnosis->regimes,
       .quarter_wave_hz = best.fitted.wave_speed_mps / (4.0 * best.fitted.pipe_length_m),
       .model_name = name,
       .selected_effects = diagnosis->selected.size()});
}

}  // namespace

StageRuns& StageRuns::operator+=(const StageRuns& other) {
  scans += other.scans;
  fits += other.fits;
  detectability += other.detectability;
  scoring += other.scoring;
  return *this;
}

Status DiagnoseOptions::Validate() const {
  if (!(fit_fraction > 0.1 && fit_fraction < 0.95)) {
    return Status::Error("fit fraction must be in (0.1, 0.95)");
  }
  if (baseline_only) return Status::Ok();  // the candidates are not tried
  for (const std::string& name : candidates) {
    MPDRIG_RETURN_IF_ERROR(CheckDiagnoseCandidate(name));
  }
  return Status::Ok();
}

Result<Diagnosis> Diagnose(const MeasuredLog& measured, const RigParams& start,
                           const DiagnoseOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  if (!start.effects.empty()) {
    return Status::Error(
        "diagnose starts from the base model: remove the effects from the configuration (it "
        "tries each of them itself)");
  }
  const std::vector<const EffectInfo*> candidates = CandidateEffects(options);
  Diagnosis diagnosis;
  DiagnoseRun run = SplitLog(measured, start, options, candidates.size(), &diagnosis);
  if (run.fit_log.time_s().size() < 4) return Status::Error("too few samples to fit on");

  StageRuns base_runs{.stage = "baseline"};
  auto baseline = FitBaseline(start, &run, &diagnosis, &base_runs);
  diagnosis.runs.push_back(base_runs);
  if (!baseline.ok()) return baseline.status();
  run.Report("candidates", 1.0);
  StageRuns screening{.stage = "round 1"}, polishing{.stage = "round 1 polish"},
      verdict{.stage = "verdict"};
  MPDRIG_RETURN_IF_ERROR(ScreenCandidates(run, *baseline, candidates, 1.0, &diagnosis.candidates,
                                          &diagnosis.failed, &screening));
  diagnosis.runs.push_back(screening);
  run.Report("polish", 1.0 + static_cast<double>(candidates.size()));
  PolishLeaders(run, *baseline, &diagnosis.candidates, &polishing);
  ScoreFloors(run, *baseline, &diagnosis, &polishing);
  diagnosis.runs.push_back(polishing);
  DecideVerdict(run, &diagnosis, &verdict);
  diagnosis.runs.push_back(verdict);
  MPDRIG_RETURN_IF_ERROR(SelectEffects(run, *baseline, &diagnosis));
  StageRuns residual{.stage = "residual"};
  DescribeWhatIsLeft(run, &diagnosis, &residual);
  diagnosis.runs.push_back(residual);
  run.Report("done", run.progress_steps);
  for (const StageRuns& stage : diagnosis.runs) diagnosis.replays += stage.total();
  return diagnosis;
}

std::string DescribeCandidate(const CandidateResult& candidate, const CandidateResult& baseline) {
  std::ostringstream out;
  out.precision(3);
  if (!candidate.failure.empty()) {
    out << candidate.effect << ": could not be fitted (" << candidate.failure << ")";
    return out.str();
  }
  out << candidate.effect << (candidate.significant ? " " : " (not significant) ")
      << candidate.explains << ": error " << 100.0 * baseline.error << "% -> "
      << 100.0 * candidate.error << "% on the scoring data";
  // The channel it helps most.
  double best = 0.0;
  Channel best_channel = Channel::kPT1;
  for (const auto& [channel, error] : candidate.channel_errors) {
    for (const auto& [base_channel, base_error] : baseline.channel_errors) {
      if (base_channel == channel && base_error - error > best) {
        best = base_error - error;
        best_channel = channel;
      }
    }
  }
  if (best > 0.0) out << ", most on " << riglog::ChannelName(best_channel);
  if (!candidate.significant && !candidate.strength_key.empty()) {
    out << "; " << DescribeDetectability(candidate);
  }
  return out.str();
}

std::string DescribeDetectability(const CandidateResult& candidate) {
  if (candidate.strength_key.empty()) return "";
  std::ostringstream out;
  out.precision(2);
  const char* stronger = candidate.strength_inverse ? " <= " : " >= ";
  if (candidate.detectable_from && candidate.detectable_at_weakest) {
    out << "detectable at this noise even at " << candidate.strength_key << " = "
        << *candidate.detectable_from << " (the weakest tried)";
  } else if (candidate.detectable_from) {
    out << "detectable at this noise from " << candidate.strength_key << stronger
        << *candidate.detectable_from;
  } else {
    out << "not detectable at this noise even at " << candidate.strength_key << " = "
        << candidate.strength_scan_limit;
  }
  return out.str();
}

}  // namespace mpdrig
