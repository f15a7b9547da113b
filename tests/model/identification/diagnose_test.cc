// diagnose on data with a hidden effect: logs from the model with one catalogue effect switched
// on at a random strength, perturbed base parameters, lab-like excitation and sensor noise
// (MakeSyntheticLog), diagnosed as a user would (prepared as `mpdrig diagnose` prepares them).
// Every test runs twice: at MakeSyntheticLog's quiet noise and at the lab's (thesis Table 4.1.1
// on every channel, inputs too). Seeds are fixed.
//
// Required: the hidden effect ranked first in at least 9 of 10 cases per effect where
// it changes the signals clearly beyond the noise; the error falls by at least half or to the
// noise floor; on logs without a hidden effect no candidate is significant, and what the base
// model leaves is noise (not "misses something the catalogue does not hold").
//
// "Changes the signals clearly beyond the noise" is judged the way the data allow: the same seed
// without the hidden effect gives the same log but for the effect (MakeSyntheticLog draws the
// effect's strength from its own stream); the effect is detectable when the refitted base
// model's scoring error on the log with the effect exceeds that on the log without it by
// kDetectableMargin. An effect the base parameters can absorb (e.g. a tiny lag taken up by a
// slightly lower wave speed) is not detectable from the log, and no method could rank it.
// Where it is not detectable, the diagnosis may find nothing but must not name another effect
// (a wrong verdict in at most 1 case in 10).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/effects/effect.h"
#include "model/identification/diagnose.h"
#include "model/identification/synthetic_log.h"
#include "model/sim/sensor_noise.h"
#include "tests/model/identification/diagnosis_checks.h"

namespace mpdrig {
namespace {

// 10 cases per effect are asked for; a full run takes about 40 minutes of CPU per noise level on
// the 2-core machine, so CI runs the first kCiCases seeds at the lab's noise (the noise every
// claim must hold at) and kCiQuietCases on the quiet logs (where each effect shows clearly: a
// check of the model's side, not of the noise), and MPDRIG_DIAGNOSE_CASES=10 runs them all
// (docs/effects-and-diagnose.md quotes the full run).
constexpr int kCiCases = 3;
constexpr int kCiQuietCases = 2;
constexpr double kDurationS = 40.0;
constexpr double kRateHz = 50.0;
// Detectable: the refitted base model's scoring error with the effect exceeds the one without it
// by this share (25%: well beyond the seed-to-seed spread of the no-effect baseline).
constexpr double kDetectableMargin = 0.25;

struct Case {
  SyntheticLog synthetic;
  Diagnosis diagnosis;
};

// The logs' sensor noise: MakeSyntheticLog's quiet one (0.003 bar, 0.03 L/min, 20 um, 0.01 deg),
// or the lab's (thesis Table 4.1.1, 8-25 times more).
enum class Noise { kQuiet, kLab };

int CasesPerEffect(Noise noise) {
  const char* value = std::getenv("MPDRIG_DIAGNOSE_CASES");
  if (value != nullptr) return std::max(1, std::atoi(value));
  return noise == Noise::kLab ? kCiCases : kCiQuietCases;
}

Case RunCase(std::optional<std::string> effect, std::uint64_t seed, bool baseline_only = false,
             std::optional<bool> low_pressure = std::nullopt, Noise noise = Noise::kQuiet) {
  SyntheticLogOptions options;
  options.seed = seed;
  options.low_pressure = low_pressure;
  options.duration_s = kDurationS;
  options.rate_hz = kRateHz;
  if (effect) options.hidden_effects = {*effect};
  if (noise == Noise::kLab) options.sensor_noise = SensorNoise::Lab();
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  Case result;
  if (!synthetic.ok()) return result;
  result.synthetic = *synthetic;
  auto log = MeasuredLogFromRigLog(synthetic->log, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  DiagnoseOptions diagnose;
  diagnose.simulation.cells = kDiagnoseCells;
  diagnose.simulation.stop_on_range_violation = false;
  diagnose.baseline_only = baseline_only;
  // As `mpdrig diagnose` prepares the replay: the start and the inputs' levels.
  const Status prepared = PrepareLogReplay(&*log, RigParams(), diagnose.simulation,
                                           &diagnose.replay, InputLevels::kAfterTheFit);
  EXPECT_TRUE(prepared.ok()) << prepared.message();
  auto diagnosis = Diagnose(*log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  if (diagnosis.ok()) result.diagnosis = *diagnosis;
  return result;
}

std::string Ranking(const Diagnosis& d) {
  std::string out;
  for (const CandidateResult& c : d.candidates) {
    char line[200];
    // error, and the improvement over its standard error (the significance test's z)
    std::snprintf(
        line, sizeof(line), " %s %.4g(z%.1f)%s", c.effect.c_str(), 100.0 * c.penalised_error,
        (d.baseline.error - c.penalised_error) / (c.improvement_std_error * d.baseline.error),
        c.significant ? "*" : "");
    out += line;
  }
  for (const std::string& name : d.equivalent) out += " =" + name;
  return out;
}

class DiagnoseWithoutHiddenEffect : public ::testing::TestWithParam<Noise> {};

// At the lab's noise these are the logs selection_test's forward selection would diagnose
// without a hidden effect (the same options): its checks run here, on the same diagnoses,
// rather than diagnosing the logs twice. Nothing selected, the best candidate says what the log
// could show, and no candidate fits worse than the base model (ExpectNeverWorseThanTheBaseModel).
TEST_P(DiagnoseWithoutHiddenEffect, NoCandidateIsSignificant) {
  for (int seed = 1; seed <= CasesPerEffect(GetParam()); ++seed) {
    const Case c = RunCase(std::nullopt, seed, false, std::nullopt, GetParam());
    SCOPED_TRACE(c.synthetic.description);
    std::printf("seed %d: base %.4g%% floor %.4g%% |%s\n", seed, 100.0 * c.diagnosis.baseline.error,
                100.0 * c.diagnosis.noise_floor, Ranking(c.diagnosis).c_str());
    EXPECT_FALSE(c.diagnosis.verdict.has_value()) << *c.diagnosis.verdict;
    for (const CandidateResult& candidate : c.diagnosis.candidates) {
      EXPECT_FALSE(candidate.significant) << candidate.effect;
    }
    // What the base model leaves is noise: not "misses something" (residual_signature.h).
    ASSERT_TRUE(c.diagnosis.residual.has_value());
    std::printf("  %s\n", c.diagnosis.residual->Summary().c_str());
    EXPECT_FALSE(c.diagnosis.residual->above_noise) << c.diagnosis.residual->Summary();
    if (GetParam() != Noise::kLab) continue;
    EXPECT_TRUE(c.diagnosis.selected.empty());
    ASSERT_TRUE(c.diagnosis.next.has_value());
    EXPECT_FALSE(c.diagnosis.next->strength_key.empty());
    ExpectNeverWorseThanTheBaseModel(c.diagnosis);
    ExpectEveryRoundReported(c.diagnosis);
  }
}

INSTANTIATE_TEST_SUITE_P(Noise, DiagnoseWithoutHiddenEffect,
                         ::testing::Values(Noise::kQuiet, Noise::kLab), [](const auto& info) {
                           return info.param == Noise::kLab ? "lab" : "quiet";
                         });

class DiagnoseHiddenEffect : public ::testing::TestWithParam<std::tuple<std::string, Noise>> {};

// Ranked first: the verdict, or one of the candidates the diagnosis reports as explaining the
// log as well (`equivalent`). On these logs the two inlet compliances are one such pair: the
// compartment's own mode (piston_compressibility at water-like bulk moduli) lies far above the
// rig's band, so it acts as a lumped compliance V/K at the inlet, as hose_compliance does, and
// the diagnosis names both (measured on piston_compressibility seed 6: the true model scores
// 1.177 %, the best hose fit 1.181 %).
bool RankedFirst(const std::string& hidden, const Diagnosis& d) {
  if (!d.verdict) return false;
  return *d.verdict == hidden ||
         std::find(d.equivalent.begin(), d.equivalent.end(), hidden) != d.equivalent.end();
}

// At the lab's noise, logs whose single hidden effect (drawn as `mpdrig synth` draws it) the
// forward selection must select alone (selection_test's case (b), checked here on the same
// diagnoses rather than diagnosing the logs twice): a lag that leaves a little to gain after it,
// and a pump curve that removes almost all the error (the second round then judges gains against
// a model near the noise).
bool SelectedAlone(const std::string& effect, int seed, Noise noise) {
  return noise == Noise::kLab &&
         ((effect == "sensor_lag" && seed == 1) || (effect == "pump_curve" && seed == 2));
}

TEST_P(DiagnoseHiddenEffect, RanksTheHiddenEffectFirstAndTheErrorFalls) {
  const auto& [effect, noise] = GetParam();
  int detectable = 0, first_detectable = 0, first = 0, alone = 0, wrong = 0;
  const int cases = CasesPerEffect(noise);
  for (int seed = 1; seed <= cases; ++seed) {
    const Case c = RunCase(effect, seed, false, std::nullopt, noise);
    const Diagnosis& d = c.diagnosis;
    if (SelectedAlone(effect, seed, noise)) {
      SCOPED_TRACE(effect + " seed " + std::to_string(seed) + ": selected alone");
      std::vector<std::string> selected;
      for (const CandidateResult& step : d.selected) selected.push_back(step.effect);
      EXPECT_EQ(selected, std::vector<std::string>{effect}) << Ranking(d);
      EXPECT_EQ(d.verdict, std::optional<std::string>(effect));
      // What ended it: the next candidate, not significant against the model with the effect.
      EXPECT_TRUE(d.next.has_value() && !d.next->significant && d.next->round == 2);
      ExpectNeverWorseThanTheBaseModel(d);
      ExpectEveryRoundReported(d);
    }
    // The same log without the effect: same seed, same excitation and noise (column_separation's
    // logs are the low-pressure runs).
    const double without = RunCase(std::nullopt, seed, true, effect == "column_separation", noise)
                               .diagnosis.baseline.error;
    const bool is_detectable = d.baseline.error > (1.0 + kDetectableMargin) * without;
    std::printf("%s seed %d: %s | base %.4g%% (without the effect %.4g%%)%s |%s\n", effect.c_str(),
                seed, c.synthetic.description.c_str(), 100.0 * d.baseline.error, 100.0 * without,
                is_detectable ? "" : " not detectable", Ranking(d).c_str());
    // What the best model leaves against the noise floor (residual_signature.h): reported.
    if (d.residual) {
      std::printf("  left: %s error %.4g%% floor %.4g%%%s\n", d.residual->model.c_str(),
                  100.0 * d.residual->error, 100.0 * d.residual->noise_floor,
                  d.residual->misses        ? " MISSES"
                  : d.residual->above_noise ? " ABOVE NOISE"
                                            : "");
    }
    const bool ranked_first = RankedFirst(effect, d);
    first += ranked_first;
    alone += d.verdict && *d.verdict == effect;
    wrong += d.verdict && !ranked_first;
    if (!is_detectable) continue;
    ++detectable;
    if (!ranked_first) continue;
    ++first_detectable;
    const double after = d.candidates.front().error;
    // Half the error, or down to the noise floor: the no-effect log's baseline error (what
    // noise and the replay of noisy inputs leave), with 10% to spare.
    EXPECT_TRUE(after <= 0.5 * d.baseline.error || after <= 1.1 * without)
        << "seed " << seed << ": error " << d.baseline.error << " -> " << after;
  }
  std::printf(
      "%s: ranked first and significant in %d of %d detectable cases, %d of %d in all (the "
      "verdict alone in %d)\n",
      effect.c_str(), first_detectable, detectable, first, cases, alone);
  EXPECT_GE(first_detectable, detectable - detectable / 10) << "at least 9 in 10";
  // Where the effect is too weak to show, the diagnosis may find nothing, but it must not name
  // another effect: a wrong verdict in at most 1 case in 10 (0 of the CI's 2 or 3).
  EXPECT_LE(wrong, cases / 10) << wrong << " wrong verdicts";
}

std::vector<std::string> AllEffects() {
  std::vector<std::string> names;
  for (const EffectInfo* info : DiagnoseCandidateEffects()) names.emplace_back(info->name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Catalogue, DiagnoseHiddenEffect,
                         ::testing::Combine(::testing::ValuesIn(AllEffects()),
                                            ::testing::Values(Noise::kQuiet, Noise::kLab)),
                         [](const auto& info) {
                           return std::get<0>(info.param) +
                                  (std::get<1>(info.param) == Noise::kLab ? "_lab" : "_quiet");
                         });

}  // namespace
}  // namespace mpdrig

namespace mpdrig {
namespace {

// At the lab's noise (thesis Table 4.1.1 on every channel, inputs too; 120 s at 100 Hz as the
// issue measured it): no false alarm on effect-free logs, a clear hidden effect named with its
// error falling, and every candidate that is not significant says what the log could show of it.
Diagnosis DiagnoseAtLabNoise(std::optional<std::string> effect, std::uint64_t seed) {
  SyntheticLogOptions options;
  options.seed = seed;
  if (effect) options.hidden_effects = {*effect};
  options.sensor_noise = SensorNoise::Lab();
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  if (!synthetic.ok()) return {};
  auto log = MeasuredLogFromRigLog(synthetic->log, "lab noise");
  EXPECT_TRUE(log.ok()) << log.status().message();
  if (!log.ok()) return {};
  DiagnoseOptions diagnose;
  diagnose.simulation.cells = kDiagnoseCells;
  const Status prepared = PrepareLogReplay(&*log, RigParams(), diagnose.simulation,
                                           &diagnose.replay, InputLevels::kAfterTheFit);
  EXPECT_TRUE(prepared.ok()) << prepared.message();
  auto diagnosis = Diagnose(*log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  return diagnosis.ok() ? *diagnosis : Diagnosis{};
}

// A floating rig's heave in an irregular sea (SyntheticHeave::kIrregularSea: 24 tones of a
// Pierson-Moskowitz spectrum, random phases, never periodic) instead of the lab's sines and sweep,
// 40 s at 50 Hz at the lab's noise: a clear sensor lag named, and nothing on the same log without
// it, with what is left at the noise floor on both (measured: 6.37 % against a floor of 6.41 %,
// and 6.64 % against 6.52 %; `mpdrig synth --heave sea`).
TEST(DiagnoseIrregularSea, NamesAClearEffectAndNothingWithoutIt) {
  for (const std::optional<std::string>& effect :
       {std::optional<std::string>("sensor_lag:time_constant_s=0.1"),
        std::optional<std::string>()}) {
    SCOPED_TRACE(effect.value_or("no hidden effect"));
    SyntheticLogOptions options;
    options.seed = 1;
    options.duration_s = 40.0;
    options.rate_hz = 50.0;
    options.heave = SyntheticHeave::kIrregularSea;
    options.sensor_noise = SensorNoise::Lab();
    if (effect) options.hidden_effects = {*effect};
    auto synthetic = MakeSyntheticLog(options);
    ASSERT_TRUE(synthetic.ok()) << synthetic.status().message();
    auto log = MeasuredLogFromRigLog(synthetic->log, "irregular sea");
    ASSERT_TRUE(log.ok()) << log.status().message();
    DiagnoseOptions diagnose;
    diagnose.simulation.cells = kDiagnoseCells;
    ASSERT_TRUE(PrepareLogReplay(&*log, RigParams(), diagnose.simulation, &diagnose.replay,
                                 InputLevels::kAfterTheFit)
                    .ok());
    auto d = Diagnose(*log, RigParams(), diagnose);
    ASSERT_TRUE(d.ok()) << d.status().message();
    if (effect) {
      ASSERT_EQ(d->selected.size(), 1u) << Ranking(*d);
      EXPECT_EQ(d->selected.front().effect, "sensor_lag") << Ranking(*d);
    } else {
      EXPECT_TRUE(d->selected.empty()) << Ranking(*d);
    }
    ASSERT_TRUE(d->residual.has_value());
    EXPECT_FALSE(d->residual->above_noise) << d->residual->Summary();
  }
}

TEST(DiagnoseAtLabNoise, NoFalseAlarmAndClearEffectsNamedDownToTheEffectFreeError) {
  // Effect-free logs: nothing significant, and every candidate says what the log could show.
  std::map<std::uint64_t, double> effect_free_error;
  for (std::uint64_t seed : {1, 2}) {
    SCOPED_TRACE("no hidden effect, seed " + std::to_string(seed));
    const Diagnosis d = DiagnoseAtLabNoise(std::nullopt, seed);
    EXPECT_FALSE(d.verdict.has_value()) << Ranking(d);
    for (const CandidateResult& c : d.candidates) {
      EXPECT_FALSE(c.significant) << c.effect;
      EXPECT_FALSE(c.strength_key.empty()) << c.effect << ": no detectability estimate";
    }
    ASSERT_TRUE(d.residual.has_value());
    EXPECT_FALSE(d.residual->above_noise) << d.residual->Summary();
    effect_free_error[seed] = d.baseline.error;
  }
  // Clear hidden effects on the same seeds (same excitation, parameters and noise): named, and
  // the error falls by half or to within 10 % of the effect-free log's (the floor of a replay at
  // this noise: the second-difference noise estimate is below it, as the inputs' residual noise
  // is not white). sensor_lag seed 1 and unsteady_friction seed 2: baseline errors 4.4 % and
  // 5.1 % against 3.7 % and 4.2 % without the effect (measured).
  for (const auto& [effect, seed] :
       {std::pair<std::string, std::uint64_t>{"sensor_lag", 1}, {"unsteady_friction", 2}}) {
    SCOPED_TRACE(effect + " seed " + std::to_string(seed));
    const Diagnosis d = DiagnoseAtLabNoise(effect, seed);
    ASSERT_TRUE(d.verdict.has_value()) << Ranking(d);
    const bool named = *d.verdict == effect || std::find(d.equivalent.begin(), d.equivalent.end(),
                                                         effect) != d.equivalent.end();
    EXPECT_TRUE(named) << Ranking(d);
    const double after = d.candidates.front().error;
    EXPECT_TRUE(after <= 0.5 * d.baseline.error || after <= 1.1 * effect_free_error[seed])
        << "error " << d.baseline.error << " -> " << after << ", effect-free "
        << effect_free_error[seed];
  }
}

}  // namespace
}  // namespace mpdrig
