// diagnose's forward selection (diagnose.h, step 5) on lab-like logs: MakeSyntheticLog at the
// lab's sensor noise (thesis Table 4.1.1 on every channel, inputs too), perturbed base
// parameters, its excitation (piston sines at two amplitudes, a sweep, choke and pump steps),
// diagnosed as `mpdrig diagnose` prepares a log. Seeds are fixed.
//
// Required: with two hidden effects, each clearly visible beyond its partner, the selection names
// both (in any order); with one, it selects that one alone; without any, nothing. On every log,
// no candidate fits its fitting data worse than the base model it extends (a fit whose zero
// strength is the base model can always end there). The cases with one hidden effect and with
// none are logs diagnose_test diagnoses anyway: their selection is checked there.
//
// "Clearly visible": the hidden effects are set at twice their catalogue defaults (the top of
// the range `mpdrig synth` draws from, [default / 2, 2 default]; for the void fraction, whose
// plausible range spans decades, its top, 1e-3: at 5e-4 beside a 0.1 s lag, seed 1, the gas
// ranked below the leading four in round 1 and the selection stopped after the lag). At their
// defaults alone, at the lab's noise, these five are detectable in 1 to 8 of 10 logs
// (docs/effects-and-diagnose.md). At twice that, on seeds 1-3 of these pairs, the second effect
// added removes 15-38 % of the error left by the first, well above the 10 % that counts
// (measured by bench/diagnose_selection.sh, which also measures drawn strengths).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/identification/diagnose.h"
#include "model/identification/synthetic_log.h"
#include "model/sim/sensor_noise.h"
#include "tests/model/identification/diagnosis_checks.h"

namespace mpdrig {
namespace {

// 40 s at 50 Hz, as diagnose_test's catalogue at the lab's noise: one diagnosis with its
// selection takes 10-20 s of one core.
constexpr double kDurationS = 40.0;
constexpr double kRateHz = 50.0;

struct Diagnosed {
  SyntheticLog synthetic;
  Diagnosis diagnosis;
};

Diagnosed DiagnoseLog(const std::vector<std::string>& hidden, std::uint64_t seed) {
  SyntheticLogOptions options;
  options.seed = seed;
  options.duration_s = kDurationS;
  options.rate_hz = kRateHz;
  options.hidden_effects = hidden;
  options.sensor_noise = SensorNoise::Lab();
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  Diagnosed run;
  if (!synthetic.ok()) return run;
  run.synthetic = *synthetic;
  auto log = MeasuredLogFromRigLog(synthetic->log, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  if (!log.ok()) return run;
  DiagnoseOptions diagnose;
  diagnose.simulation.cells = kDiagnoseCells;
  diagnose.simulation.stop_on_range_violation = false;
  const Status prepared = PrepareLogReplay(&*log, RigParams(), diagnose.simulation,
                                           &diagnose.replay, InputLevels::kAfterTheFit);
  EXPECT_TRUE(prepared.ok()) << prepared.message();
  auto diagnosis = Diagnose(*log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  if (diagnosis.ok()) run.diagnosis = *std::move(diagnosis);
  return run;
}

std::vector<std::string> Selected(const Diagnosis& d) {
  std::vector<std::string> names;
  for (const CandidateResult& step : d.selected) names.push_back(step.effect);
  return names;
}

// The selection, step by step, and what ended it: for the test's log.
std::string Describe(const Diagnosed& run) {
  const Diagnosis& d = run.diagnosis;
  char text[160];
  std::snprintf(text, sizeof text, "base %.4g%% (fit %.4g%%)", 100.0 * d.baseline.error,
                100.0 * d.baseline.fit_error);
  std::string out = run.synthetic.description + " | " + text + " | round 1:";
  for (const CandidateResult& c : d.candidates) {
    std::snprintf(text, sizeof text, " %s %.4g%%%s", c.effect.c_str(), 100.0 * c.error,
                  c.significant ? "*" : "");
    out += text;
  }
  for (const std::string& name : d.equivalent) out += " =" + name;
  out += " |";
  for (const CandidateResult& step : d.selected) {
    std::snprintf(text, sizeof text, " + %s %.4g%% (%+.1f%%)", step.effect.c_str(),
                  100.0 * step.error, -100.0 * step.improvement);
    out += text;
  }
  if (d.next) {
    std::snprintf(text, sizeof text, " | next %s %.4g%% (%+.1f%%, not significant)",
                  d.next->effect.c_str(), 100.0 * d.next->error, -100.0 * d.next->improvement);
    out += text;
  }
  for (const CandidateResult& failed : d.failed) {
    out += " | failed in round " + std::to_string(failed.round) + ": " + failed.effect + " (" +
           failed.failure + ")";
  }
  if (d.residual) {
    std::snprintf(text, sizeof text, " | left %.4g%% against a floor of %.4g%%%s",
                  100.0 * d.residual->error, 100.0 * d.residual->noise_floor,
                  d.residual->above_noise ? " (above the noise)" : "");
    out += text;
  }
  return out + " | " + d.selection_end;
}

// Named: selected, or reported as explaining the log as well as the verdict (`equivalent`):
// the two inlet compliances, hose_compliance and piston_compressibility, tie where the log does
// not excite the compartment's own mode (diagnose_test's RankedFirst), and the model cannot
// hold both (each closes the inlet).
// A selection step has no `equivalent` list of its own (only the verdict has), so where the inlet
// compliance is selected second, the other one of the pair names it too.
bool IsInletCompliance(const std::string& effect) {
  return effect == "hose_compliance" || effect == "piston_compressibility";
}

bool Named(const std::string& effect, const Diagnosis& d) {
  const std::vector<std::string> selected = Selected(d);
  const auto is_selected = [&](const std::string& name) {
    return std::find(selected.begin(), selected.end(), name) != selected.end();
  };
  return is_selected(effect) ||
         std::find(d.equivalent.begin(), d.equivalent.end(), effect) != d.equivalent.end() ||
         (IsInletCompliance(effect) &&
          is_selected(effect == "hose_compliance" ? "piston_compressibility" : "hose_compliance"));
}

// (a) Two hidden effects, each at twice its default: both selected, in any order.
class SelectionOfTwoHiddenEffects
    : public ::testing::TestWithParam<std::tuple<std::string, std::string, std::uint64_t>> {};

TEST_P(SelectionOfTwoHiddenEffects, NamesBoth) {
  const auto& [first, second, seed] = GetParam();
  const auto strong = [](const std::string& name) {
    if (name == "sensor_lag") return name + ":time_constant_s=0.1";
    if (name == "unsteady_friction") return name + ":k=0.06";
    if (name == "choke_inertia") return name + ":b1_per_m=1e6";
    if (name == "hose_compliance") return name + ":compliance_m3_per_pa=8e-12";
    if (name == "gas_entrainment") return name + ":void_fraction=1e-3";
    if (name == "topside_compliance") return name + ":compliance_m3_per_pa=6e-11";
    return name;
  };
  const Diagnosed run = DiagnoseLog({strong(first), strong(second)}, seed);
  std::printf("%s\n", Describe(run).c_str());
  const std::vector<std::string> selected = Selected(run.diagnosis);
  EXPECT_TRUE(Named(first, run.diagnosis)) << Describe(run);
  EXPECT_TRUE(Named(second, run.diagnosis)) << Describe(run);
  EXPECT_LE(selected.size(), 2u) << "a third, false effect: " << Describe(run);
  ASSERT_FALSE(selected.empty());
  EXPECT_EQ(run.diagnosis.verdict, std::optional<std::string>(selected.front()));
  ExpectNeverWorseThanTheBaseModel(run.diagnosis);
  ExpectEveryRoundReported(run.diagnosis);
}

INSTANTIATE_TEST_SUITE_P(Pairs, SelectionOfTwoHiddenEffects,
                         ::testing::Values(std::make_tuple("sensor_lag", "unsteady_friction", 1),
                                           std::make_tuple("sensor_lag", "unsteady_friction", 2),
                                           std::make_tuple("choke_inertia", "hose_compliance", 1),
                                           std::make_tuple("choke_inertia", "hose_compliance", 2),
                                           std::make_tuple("sensor_lag", "gas_entrainment", 1),
                                           std::make_tuple("sensor_lag", "gas_entrainment", 2),
                                           // The topside tubes with a compliant inlet (the
                                           // resonance issue's pair, in the time domain).
                                           std::make_tuple("topside_compliance", "hose_compliance",
                                                           1)),
                         [](const auto& info) {
                           return std::get<0>(info.param) + "_" + std::get<1>(info.param) +
                                  "_seed" + std::to_string(std::get<2>(info.param));
                         });

// (b) One hidden effect, selected alone, and (c) none, nothing selected: checked by diagnose_test
// on the logs it diagnoses anyway (DiagnoseHiddenEffect's SelectedAlone cases,
// DiagnoseWithoutHiddenEffect at the lab's noise), the same logs this test would diagnose again.

}  // namespace
}  // namespace mpdrig
