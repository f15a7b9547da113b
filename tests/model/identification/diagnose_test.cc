// diagnose on data with a hidden effect (issue 4): logs from the model with one catalogue effect
// switched on at a random strength, perturbed base parameters, lab-like excitation and sensor
// noise (MakeSyntheticLog), diagnosed as a user would. Seeds are fixed.
//
// Required (issue 4): the hidden effect ranked first in at least 9 of 10 cases per effect where
// it changes the signals clearly beyond the noise; the error falls by at least half or to the
// noise floor; on logs without a hidden effect no candidate is significant.
//
// "Changes the signals clearly beyond the noise" is judged the way the data allow: the same seed
// without the hidden effect gives the same log but for the effect (MakeSyntheticLog draws the
// effect's strength from its own stream); the effect is detectable when the refitted base
// model's scoring error on the log with the effect exceeds that on the log without it by
// kDetectableMargin. An effect the base parameters can absorb (e.g. a tiny lag taken up by a
// slightly lower wave speed) is not detectable from the log, and no method could rank it.
#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "model/analysis/compare.h"
#include "model/effects/effect.h"
#include "model/identification/diagnose.h"
#include "model/identification/synthetic_log.h"

namespace mpdrig {
namespace {

constexpr int kCasesPerEffect = 10;
constexpr double kDurationS = 40.0;
constexpr double kRateHz = 50.0;
// Detectable: the refitted base model's scoring error with the effect exceeds the one without it
// by this share (25%: well beyond the seed-to-seed spread of the no-effect baseline).
constexpr double kDetectableMargin = 0.25;

struct Case {
  SyntheticLog synthetic;
  Diagnosis diagnosis;
};

Case RunCase(std::optional<std::string> effect, std::uint64_t seed, bool baseline_only = false) {
  SyntheticLogOptions options;
  options.seed = seed;
  options.duration_s = kDurationS;
  options.rate_hz = kRateHz;
  options.hidden_effect = effect;
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
  auto diagnosis = Diagnose(*log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  if (diagnosis.ok()) result.diagnosis = *diagnosis;
  return result;
}

std::string Ranking(const Diagnosis& d) {
  std::string out;
  for (const CandidateResult& c : d.candidates) {
    char line[200];
    std::snprintf(line, sizeof(line), " %s %.4g%s", c.effect.c_str(), 100.0 * c.error,
                  c.significant ? "*" : "");
    out += line;
  }
  return out;
}

TEST(DiagnoseWithoutHiddenEffect, NoCandidateIsSignificant) {
  for (int seed = 1; seed <= kCasesPerEffect; ++seed) {
    const Case c = RunCase(std::nullopt, seed);
    SCOPED_TRACE(c.synthetic.description);
    std::printf("seed %d: base %.4g%% floor %.4g%% |%s\n", seed, 100.0 * c.diagnosis.baseline.error,
                100.0 * c.diagnosis.noise_floor, Ranking(c.diagnosis).c_str());
    EXPECT_FALSE(c.diagnosis.verdict.has_value()) << *c.diagnosis.verdict;
    for (const CandidateResult& candidate : c.diagnosis.candidates) {
      EXPECT_FALSE(candidate.significant) << candidate.effect;
    }
  }
}

class DiagnoseHiddenEffect : public ::testing::TestWithParam<std::string> {};

TEST_P(DiagnoseHiddenEffect, RanksTheHiddenEffectFirstAndTheErrorFalls) {
  const std::string effect = GetParam();
  int detectable = 0, first = 0;
  for (int seed = 1; seed <= kCasesPerEffect; ++seed) {
    const Case c = RunCase(effect, seed);
    const Diagnosis& d = c.diagnosis;
    const double without = RunCase(std::nullopt, seed, true).diagnosis.baseline.error;
    const bool is_detectable = d.baseline.error > (1.0 + kDetectableMargin) * without;
    std::printf("%s seed %d: %s | base %.4g%% (without the effect %.4g%%)%s |%s\n",
                effect.c_str(), seed, c.synthetic.description.c_str(), 100.0 * d.baseline.error,
                100.0 * without, is_detectable ? "" : " not detectable", Ranking(d).c_str());
    if (!is_detectable) continue;
    ++detectable;
    if (!d.candidates.empty() && d.candidates.front().effect == effect &&
        d.verdict == effect) {
      ++first;
      const double after = d.candidates.front().error;
      // Half the error, or down to the noise floor: the no-effect log's baseline error (what
      // noise and the replay of noisy inputs leave), with 10% to spare.
      EXPECT_TRUE(after <= 0.5 * d.baseline.error || after <= 1.1 * without)
          << "seed " << seed << ": error " << d.baseline.error << " -> " << after;
    }
  }
  std::printf("%s: ranked first and significant in %d of %d detectable cases\n", effect.c_str(),
              first, detectable);
  EXPECT_GE(detectable, kCasesPerEffect / 2) << "the generator's strengths are too weak to test";
  EXPECT_GE(first, detectable - detectable / 10) << "at least 9 in 10";
}

std::vector<std::string> AllEffects() {
  std::vector<std::string> names;
  for (const EffectInfo* info : EffectCatalogue()) names.emplace_back(info->name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Catalogue, DiagnoseHiddenEffect, ::testing::ValuesIn(AllEffects()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace mpdrig
