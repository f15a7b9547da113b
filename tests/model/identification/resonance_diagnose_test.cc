// The frequency-domain diagnosis (resonance_diagnose.h): from first resonances that a rig with
// known hidden effects produced, read off with the errors of a measured peak, forward selection
// names the hidden effects and no other (or one the resonances cannot tell apart from it: hose and
// compartment are both compliances at the pipe inlet); the chi-square quantiles it tests with are
// the textbook's.
#include "model/identification/resonance_diagnose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "model/analysis/empirical_response.h"
#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"
#include "tests/support/sweep_log.h"

namespace mpdrig {
namespace {

TEST(ChiSquareQuantile, MatchesTheTables) {
  // Abramowitz & Stegun Table 26.8 (upper percentage points).
  EXPECT_NEAR(ChiSquareQuantile(1, 0.05), 3.841, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(1, 0.01), 6.635, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(2, 0.01), 9.210, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(3, 0.05), 7.815, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(10, 0.01), 23.209, 1e-3);
}

RigParams With(RigParams params, const std::string& spec) {
  const Status applied = ApplyEffectSpec(&params, spec);
  EXPECT_TRUE(applied.ok()) << applied.message();
  return params;
}

// The three terminations' first resonances of `truth`, each read with a Gaussian error of
// standard deviation `uncertainty` (the reading of a measured peak), which the list states.
std::vector<MeasuredResonance> MeasuredResonancesOf(const RigParams& truth, double uncertainty,
                                                    unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> reading(0.0, uncertainty);
  std::vector<MeasuredResonance> list;
  for (const TerminationInfo& info : TerminationTable()) {
    auto resonance = FirstResonance(truth, info.termination, {});
    EXPECT_TRUE(resonance.ok()) << resonance.status().message();
    list.push_back({info.termination, (resonance.ok() ? resonance->freq_hz : 0.0) + reading(random),
                    uncertainty, 0});
  }
  return list;
}

// Whether `s` names `effect`: itself or one it cannot be told apart from (its equivalents).
bool Names(const ResonanceCandidate& s, const std::string& effect) {
  return s.effect == effect ||
         std::find(s.equivalent.begin(), s.equivalent.end(), effect) != s.equivalent.end();
}

// The effects the analytic response holds (the others need the simulated response, ~0.3 s per
// resonance: too slow for a statistical test; the screen and fit of one are tested below).
ResonanceDiagnoseOptions AnalyticCatalogue() {
  ResonanceDiagnoseOptions options;
  options.candidates = {"topside_compliance", "hose_compliance", "gas_entrainment",
                        "piston_compressibility", "pump_curve"};
  options.hold = {"wave_speed_mps"};
  return options;
}

struct HiddenCase {
  std::string name;
  std::vector<std::string> effects;   // --effect specs of the truth
  std::vector<std::string> expected;  // sorted names
};

// The thesis's readings are +-0.01 Hz; a 0.002 Hz reading (a 100 s Welch segment's peak,
// docs/rig-measurements.md: 0.0003-0.006 Hz) is what a sweep log gives. Both are tried.
class HiddenResonanceEffects : public ::testing::TestWithParam<std::tuple<HiddenCase, double>> {};

TEST_P(HiddenResonanceEffects, AreNamedAndNoOtherWithTheWaveSpeedHeldAtItsMeasuredValue) {
  const auto& [hidden, uncertainty] = GetParam();
  RigParams truth;
  truth.wave_speed_mps = 1173.0;
  for (const std::string& spec : hidden.effects) truth = With(truth, spec);
  RigParams start;
  start.wave_speed_mps = 1173.0;  // as a travel time would measure it
  int named = 0, false_ones = 0;
  constexpr int kSeeds = 6;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    auto d = DiagnoseResonances(MeasuredResonancesOf(truth, uncertainty, seed), start,
                                AnalyticCatalogue());
    ASSERT_TRUE(d.ok()) << d.status().message();
    bool all = d->selected.size() == hidden.expected.size();
    for (const std::string& effect : hidden.expected) {
      all = all && std::any_of(d->selected.begin(), d->selected.end(),
                               [&](const ResonanceCandidate& s) { return Names(s, effect); });
    }
    named += all;
    for (const ResonanceCandidate& s : d->selected) {
      false_ones += std::none_of(hidden.expected.begin(), hidden.expected.end(),
                                 [&](const std::string& effect) { return Names(s, effect); });
    }
    // What is selected reproduces the readings within their errors: chi2 at most its 99 %
    // quantile (the selection stops there).
    const int dof = 3 - static_cast<int>(d->Final().keys.size());
    if (dof > 0 && all) {
      EXPECT_LE(d->Final().chi2_after, ChiSquareQuantile(dof, 0.01)) << "seed " << seed;
    }
  }
  std::printf("%s at +-%.3f Hz: named in %d of %d seeds, %d effects named that are not there\n",
              hidden.name.c_str(), uncertainty, named, kSeeds, false_ones);
  // A selection at the 1 % level may add a wrong effect in about 1 % of the readings per round.
  EXPECT_GE(named, kSeeds - 1);
  EXPECT_LE(false_ones, 1);
}

const HiddenCase kHidden[] = {
    {"tubes", {"topside_compliance:compliance_m3_per_pa=4e-11"}, {"topside_compliance"}},
    {"tubes_and_gas",
     {"topside_compliance:compliance_m3_per_pa=3e-11", "gas_entrainment:void_fraction=1e-3"},
     {"gas_entrainment", "topside_compliance"}},
    {"tubes_and_hose",
     {"topside_compliance:compliance_m3_per_pa=3e-11",
      "hose_compliance:compliance_m3_per_pa=5e-11"},
     {"hose_compliance", "topside_compliance"}},
};

// The tubes with an inlet compliance at the thesis's +-0.01 Hz: see the next test.
INSTANTIATE_TEST_SUITE_P(
    ThreeTerminations, HiddenResonanceEffects,
    ::testing::Values(std::make_tuple(kHidden[0], 0.01), std::make_tuple(kHidden[0], 0.002),
                      std::make_tuple(kHidden[1], 0.01), std::make_tuple(kHidden[1], 0.002),
                      std::make_tuple(kHidden[2], 0.002)),
    [](const ::testing::TestParamInfo<HiddenResonanceEffects::ParamType>& info) {
      return std::get<0>(info.param).name +
             (std::get<1>(info.param) > 0.005 ? "_thesis" : "_sweep");
    });

TEST(ResonanceDiagnosis, AtTheThesisPrecisionAnInletComplianceBesideTheTubesIsNotToldFromGas) {
  // The tubes (3e-11) with a compliant inlet (5e-11) move the open choke's peak 0.007 Hz from
  // where the tubes with free gas put it (0.2405 against 0.2462 Hz on the thesis's readings);
  // read to +-0.01 Hz the two pairs fit alike. The tubes are named every time; the second effect
  // is the inlet compliance or the gas, the readings are met, and where gas is named the
  // diagnosis says that the inlet compliance in its place is not excluded.
  RigParams truth;
  truth.wave_speed_mps = 1173.0;
  truth = With(truth, "topside_compliance:compliance_m3_per_pa=3e-11");
  truth = With(truth, "hose_compliance:compliance_m3_per_pa=5e-11");
  RigParams start;
  start.wave_speed_mps = 1173.0;
  int inlet = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    auto d =
        DiagnoseResonances(MeasuredResonancesOf(truth, 0.01, seed), start, AnalyticCatalogue());
    ASSERT_TRUE(d.ok()) << d.status().message();
    std::string names;
    for (const ResonanceCandidate& s : d->selected) names += s.effect + " ";
    std::printf("seed %u: %s(largest error %.4f Hz)\n", seed, names.c_str(),
                d->Final().max_error_hz);
    EXPECT_TRUE(
        std::any_of(d->selected.begin(), d->selected.end(),
                    [](const ResonanceCandidate& s) { return s.effect == "topside_compliance"; }))
        << names;
    EXPECT_EQ(d->selected.size(), 2u) << names;
    const bool named =
        std::any_of(d->selected.begin(), d->selected.end(),
                    [](const ResonanceCandidate& s) { return Names(s, "hose_compliance"); });
    // Where gas is named instead, the diagnosis says the inlet compliance is not excluded.
    const bool not_excluded =
        std::any_of(d->selected.begin(), d->selected.end(), [](const ResonanceCandidate& s) {
          return std::any_of(s.not_excluded.begin(), s.not_excluded.end(),
                             [](const auto& a) { return a.effect == "hose_compliance"; });
        });
    EXPECT_TRUE(named || not_excluded) << names;
    inlet += named;
    EXPECT_LT(d->Final().max_error_hz, 0.03) << names;  // three reading errors
  }
  std::printf("the inlet compliance named in %d of 6 seeds (free gas in the others)\n", inlet);
}

// The resonances as a user gets them from the rig: a 400 s sweep log at the lab's noise in each
// termination (tests/support/sweep_log.h: the quasi-linear simulator, 60 cells, the tuned
// friction), the first peak of PT1 (p(0), the pipe's inlet) in its empirical response with its
// reported uncertainty, what `mpdrig freqresp --from-log --resonance-list` writes.
std::vector<MeasuredResonance> SweptResonancesOf(const RigParams& truth, std::uint64_t seed) {
  std::vector<MeasuredResonance> list;
  for (const TerminationInfo& info : TerminationTable()) {
    const TerminatedRig rig = ApplyTermination(truth, info.termination);
    const riglog::RigLog log = testing::MakeSweepLog(rig.params, rig.choke, seed);
    auto response = EstimateEmpiricalResponse(log);
    EXPECT_TRUE(response.ok()) << response.status().message();
    if (!response.ok()) continue;
    for (const ChannelResponse& channel : response->channels) {
      if (channel.channel != "PT1") continue;
      EXPECT_FALSE(channel.peaks.empty()) << info.name;
      if (channel.peaks.empty()) continue;
      list.push_back({info.termination, channel.peaks.front().freq_hz,
                      channel.peaks.front().uncertainty_hz, 0});
    }
  }
  return list;
}

TEST(ResonanceDiagnosis, SweepLogsInTheThreeTerminationsNameTheTubes) {
  // Hidden: the tubes, and the tubes with a compliant inlet; c held at 1173 m/s as the fronts
  // measure it. Two seeds each (a log costs about a second).
  const std::vector<HiddenCase> cases = {
      {"tubes", {"topside_compliance:compliance_m3_per_pa=4e-11"}, {"topside_compliance"}},
      {"tubes_and_hose",
       {"topside_compliance:compliance_m3_per_pa=3e-11",
        "hose_compliance:compliance_m3_per_pa=5e-11"},
       {"hose_compliance", "topside_compliance"}}};
  RigParams start;
  start.wave_speed_mps = 1173.0;
  for (const HiddenCase& hidden : cases) {
    RigParams truth = start;
    for (const std::string& spec : hidden.effects) truth = With(truth, spec);
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      const std::vector<MeasuredResonance> measured = SweptResonancesOf(truth, seed);
      ASSERT_EQ(measured.size(), 3u);
      auto d = DiagnoseResonances(measured, start, AnalyticCatalogue());
      ASSERT_TRUE(d.ok()) << d.status().message();
      std::string names;
      for (const ResonanceCandidate& s : d->selected) names += s.effect + " ";
      std::printf("%s seed %d: %.4f+-%.4f %.4f+-%.4f %.4f+-%.4f Hz -> %s\n", hidden.name.c_str(),
                  static_cast<int>(seed), measured[0].frequency_hz, measured[0].uncertainty_hz,
                  measured[1].frequency_hz, measured[1].uncertainty_hz, measured[2].frequency_hz,
                  measured[2].uncertainty_hz, names.c_str());
      for (const std::string& effect : hidden.expected) {
        EXPECT_TRUE(std::any_of(d->selected.begin(), d->selected.end(),
                                [&](const ResonanceCandidate& s) { return Names(s, effect); }))
            << hidden.name << " seed " << seed << ": " << names;
      }
      EXPECT_EQ(d->selected.size(), hidden.expected.size()) << names;
    }
  }
}

TEST(ResonanceDiagnosis, NothingHiddenNamesNothingAndTheWaveSpeedAloneFits) {
  // The bare pipe at an unknown wave speed, c not held: the base fit finds it and no effect is
  // significant.
  RigParams truth;
  truth.wave_speed_mps = 900.0;
  ResonanceDiagnoseOptions options = AnalyticCatalogue();
  options.hold.clear();
  int false_ones = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    auto d = DiagnoseResonances(MeasuredResonancesOf(truth, 0.01, seed), RigParams(), options);
    ASSERT_TRUE(d.ok()) << d.status().message();
    false_ones += static_cast<int>(d->selected.size());
    EXPECT_NEAR(d->base.estimates[0], 900.0, 40.0);  // 0.01 Hz of 0.5 Hz is 2 % of c
  }
  EXPECT_LE(false_ones, 1);
}

TEST(ResonanceDiagnosis, AUniformWaveSpeedKeepsTheRatioAtTwo) {
  // The thesis's three readings: the wave speed alone fits them with closed/open = 2 and the
  // valve equal to the closed choke, where the rig shows 1.76 and 1.11.
  const std::vector<MeasuredResonance> thesis = {{Termination::kChokeClosed, 0.44, 0.01, 0},
                                                 {Termination::kChokeOpen, 0.25, 0.01, 0},
                                                 {Termination::kClosedAtPipeEnd, 0.49, 0.01, 0}};
  RigParams start;
  start.wave_speed_mps = 1173.0;
  auto d = DiagnoseResonances(thesis, start, AnalyticCatalogue());
  ASSERT_TRUE(d.ok()) << d.status().message();
  const auto& u = d->uniform.configurations;
  EXPECT_NEAR(u[0].model_hz / u[1].model_hz, 2.0, 0.01);  // friction moves it by < 0.5 %
  EXPECT_NEAR(u[2].model_hz, u[0].model_hz, 1e-9);
  EXPECT_GT(d->uniform.max_error_hz, 0.015);  // no uniform speed meets all three
  // With c held at the fronts' 1173 m/s, the selection meets all three within 0.015 Hz, with
  // every parameter inside its physical bounds and none at a bound.
  EXPECT_LT(d->Final().max_error_hz, 0.015);
  EXPECT_GE(d->selected.size(), 2u);
  for (const ResonanceParamEstimate& p : d->selected.back().params) {
    EXPECT_FALSE(p.at_bound) << p.key;
  }
}

TEST(ResonanceDiagnosis, AnEffectThatCannotMoveThePeaksIsScreenedOutNotFitted) {
  // sensor_lag needs the simulated response; at the rig's plausible lags it moves the closed
  // choke's peak by less than a quarter of 0.01 Hz, so it is not fitted (which would cost
  // minutes) and says so. pump_curve (the pump is off in every termination) moves nothing.
  const std::vector<MeasuredResonance> thesis = {{Termination::kChokeClosed, 0.44, 0.01, 0},
                                                 {Termination::kChokeOpen, 0.25, 0.01, 0},
                                                 {Termination::kClosedAtPipeEnd, 0.49, 0.01, 0}};
  ResonanceDiagnoseOptions options;
  options.candidates = {"pump_curve", "sensor_lag"};
  options.fit.resonance.simulation.cells = 60;
  options.fit.resonance.simulation.model = PipeModel::kLinear;
  options.fit.resonance.simulated.amplitude_m = 2.5e-4;
  auto d = DiagnoseResonances(thesis, RigParams(), options);
  ASSERT_TRUE(d.ok()) << d.status().message();
  ASSERT_EQ(d->not_fitted.size(), 2u) << d->selection_end << " chi2 " << d->base.chi2_after;
  for (const ResonanceCandidate& c : d->not_fitted) {
    EXPECT_EQ(c.outcome, ResonanceCandidate::Outcome::kDoesNotMovePeaks) << c.effect << c.note;
    EXPECT_LT(c.screen_shift_hz, 0.0025) << c.effect;
  }
  EXPECT_TRUE(d->selected.empty());
}

TEST(ResonanceDiagnosis, RefusesUnknownEffectsAndHeldKeys) {
  const std::vector<MeasuredResonance> one = {{Termination::kChokeClosed, 0.44, 0.01, 0}};
  ResonanceDiagnoseOptions options;
  options.candidates = {"no_such_effect"};
  auto unknown = DiagnoseResonances(one, RigParams(), options);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("no_such_effect"), std::string::npos);
  options.candidates.clear();
  options.hold = {"wave_speed"};
  auto bad_hold = DiagnoseResonances(one, RigParams(), options);
  ASSERT_FALSE(bad_hold.ok());
  EXPECT_NE(bad_hold.status().message().find("wave_speed"), std::string::npos);
}

}  // namespace
}  // namespace mpdrig
