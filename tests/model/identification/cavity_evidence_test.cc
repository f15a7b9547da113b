// Column separation told apart from free gas by what a log shows (cavity_evidence.h): pressures
// held on a floor at one level and ended by a collapse's jump. On synthetic logs at the lab's
// noise (thesis Table 4.1.1) and low pressure (open choke, little pump flow, a large heave: where
// the column can separate), from diagnose's grid (50 cells) and from another (360 cells, so the
// logs do not come from the model diagnose replays): floors on every column separation log at
// its vapour pressure, none on free gas or effect-free logs with the same excitation; and the
// floor error of the true model is at the noise, that of a model without cavities far above.
#include "model/identification/cavity_evidence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/analysis/log_replay.h"
#include "model/identification/diagnose.h"
#include "model/identification/synthetic_log.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig {
namespace {

struct Logged {
  SyntheticLog synthetic;
  MeasuredLog log;
  CavityEvidence evidence;
};

Logged EvidenceOf(const std::string& effect, std::uint64_t seed, int cells, double duration_s,
                  double rate_hz, SyntheticHeave heave = SyntheticHeave::kLabSeries) {
  SyntheticLogOptions options;
  options.heave = heave;
  options.seed = seed;
  options.duration_s = duration_s;
  options.rate_hz = rate_hz;
  options.cells = cells;
  options.low_pressure = true;
  if (effect != "none") options.hidden_effects = {effect};
  options.sensor_noise = SensorNoise::Lab();
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  auto log = MeasuredLogFromRigLog(synthetic->log, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  Logged out{*synthetic, *log, FindPressureFloors(*log)};
  std::printf("%s seed %d, %d cells, %.0f s at %.0f Hz: %d holds on %zu channels at %.0f Pa\n",
              effect.c_str(), static_cast<int>(seed), cells, duration_s, rate_hz,
              out.evidence.holds, out.evidence.floors.size(), out.evidence.level_pa);
  return out;
}

double TrueVapourPressure(const RigParams& truth) {
  for (const EffectSetting& effect : truth.effects) {
    for (const auto& [key, value] : effect.values) {
      if (key == "vapour_pressure_pa") return value;
    }
  }
  return 0.0;
}

TEST(CavityEvidence, FloorsAtTheVapourPressureOnColumnSeparationLogs) {
  // Measured: 3-14 holds in 40 s at 50 Hz, 27-69 in 120 s at 100 Hz, at levels within 200 Pa of
  // p_v. The level is the mean of a few hundred samples of 2400 Pa noise, with the solver's
  // interpolation between nodes at a channel beside a cavity: 1000 Pa.
  for (int cells : {kDiagnoseCells, 360}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE(testing::Message() << cells << " cells, seed " << seed);
      const Logged logged = EvidenceOf("column_separation", seed, cells, 40.0, 50.0);
      EXPECT_TRUE(logged.evidence.present());
      EXPECT_NEAR(logged.evidence.level_pa, TrueVapourPressure(logged.synthetic.truth), 1000.0);
    }
  }
}

TEST(CavityEvidence, NoFloorsOnFreeGasOrEffectFreeLogsAtLowPressure) {
  // The same excitations (same seeds) with free gas instead, or nothing: no evidence. The 120 s
  // logs include the free-gas troughs that bottom out at 24-36 kPa and end in a steepened front
  // (seeds 2 and 3), which the level bound (kMaxFloorPa) and the rule that nothing lies below
  // the floor reject.
  for (const char* effect : {"gas_entrainment", "none"}) {
    for (std::uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE(testing::Message() << effect << " seed " << seed);
      EXPECT_FALSE(EvidenceOf(effect, seed, kDiagnoseCells, 40.0, 50.0).evidence.present());
      EXPECT_FALSE(EvidenceOf(effect, seed, kDiagnoseCells, 120.0, 100.0).evidence.present());
    }
  }
}

TEST(CavityEvidence, FloorErrorSeparatesAModelWithCavitiesFromOneWithout) {
  // On a column separation log from 360 cells: the true parameters replayed at diagnose's 50
  // cells hold the floor (floor error near the noise, 2400 Pa over the channel's deviation),
  // the same model without the effect runs through it (below zero absolute: the range is not
  // enforced, as in diagnose). Its floor error is several times the true model's, and with the
  // floors scored as channels its ranking score is the worse one.
  const Logged logged = EvidenceOf("column_separation", 2, 360, 40.0, 50.0);
  ASSERT_TRUE(logged.evidence.present());
  SimulationOptions simulation;
  simulation.cells = kDiagnoseCells;
  simulation.stop_on_range_violation = false;
  RigParams without = logged.synthetic.truth;
  without.effects.clear();
  auto with_traces = ReplayModel(logged.log, logged.synthetic.truth, simulation);
  auto without_traces = ReplayModel(logged.log, without, simulation);
  ASSERT_TRUE(with_traces.ok()) << with_traces.status().message();
  ASSERT_TRUE(without_traces.ok()) << without_traces.status().message();
  const double with_error = FloorError(logged.log, logged.evidence, *with_traces);
  const double without_error = FloorError(logged.log, logged.evidence, *without_traces);
  std::printf("floor error: with cavities %.4f, without %.4f\n", with_error, without_error);
  EXPECT_LT(with_error, 0.1);
  EXPECT_GT(without_error, 3.0 * with_error);
  // Equal ordinary errors: the floors decide.
  EXPECT_LT(ErrorWithFloors(0.1, 15, logged.evidence, with_error),
            ErrorWithFloors(0.1, 15, logged.evidence, without_error));
  // A log without floors: the score is the ordinary error.
  EXPECT_EQ(ErrorWithFloors(0.1, 15, CavityEvidence{}, 1.0), 0.1);
}

// diagnose on low-pressure logs at the lab's noise: column separation from 360 cells (not the
// model diagnose replays, whose grid is 50 cells) named first, with the floors found; free gas at
// the same low pressure never named column separation, and no floors there. One seed each in CI
// (two diagnoses, about 75 s of CPU); MPDRIG_DIAGNOSE_CASES=10 runs seeds 1-10.
int Cases() {
  const char* value = std::getenv("MPDRIG_DIAGNOSE_CASES");
  return value != nullptr ? std::max(1, std::atoi(value)) : 1;
}

Diagnosis DiagnoseLog(const Logged& logged) {
  MeasuredLog log = logged.log;
  DiagnoseOptions diagnose;
  diagnose.simulation.cells = kDiagnoseCells;
  diagnose.simulation.stop_on_range_violation = false;
  const Status prepared = PrepareLogReplay(&log, RigParams(), diagnose.simulation, &diagnose.replay,
                                           InputLevels::kAfterTheFit);
  EXPECT_TRUE(prepared.ok()) << prepared.message();
  auto diagnosis = Diagnose(log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  return diagnosis.ok() ? *diagnosis : Diagnosis{};
}

void PrintRanking(const Diagnosis& d) {
  std::printf("  baseline %.2f%%", 100.0 * d.baseline.error);
  for (const CandidateResult& c : d.candidates) {
    std::printf(" %s %.2f/%.2f%%%s", c.effect.c_str(), 100.0 * c.error, 100.0 * c.penalised_error,
                c.significant ? "*" : "");
  }
  std::printf(" -> %s\n", d.verdict ? d.verdict->c_str() : "none");
}

TEST(CavityEvidenceDiagnose, ColumnSeparationFromAnotherGridNamedFirstFreeGasNot) {
  int named = 0, cases = Cases();
  for (int seed = 1; seed <= cases; ++seed) {
    SCOPED_TRACE(seed);
    const Logged cavities = EvidenceOf("column_separation", seed, 360, 40.0, 50.0);
    const Diagnosis d = DiagnoseLog(cavities);
    PrintRanking(d);
    EXPECT_TRUE(d.pressure_floors.present());
    if (d.verdict == "column_separation") ++named;
    const Logged gas = EvidenceOf("gas_entrainment", seed, kDiagnoseCells, 40.0, 50.0);
    const Diagnosis g = DiagnoseLog(gas);
    PrintRanking(g);
    EXPECT_FALSE(g.pressure_floors.present());
    EXPECT_NE(g.verdict, "column_separation");
  }
  std::printf("column_separation named first in %d of %d\n", named, cases);
  EXPECT_GE(named, cases - cases / 10);  // 9 of 10
}

// Free gas at the low-pressure point under an irregular sea: the base model takes the slow
// waves for a low wave speed, outside the range its own scan takes as plausible (850 m/s +-30 %),
// and the gas candidate must be searched from the start's wave speed to be found (SearchAndFit).
// Measured before that: the candidate, searched only around the base model's 373-470 m/s, ended
// worse than the base model and nothing was named. The seeds are ones whose base model absorbs
// the gas so (checked below, so the test cannot pass without exercising it); a few candidates
// only, to keep CI's time (two diagnoses, about 20 s of CPU each; MPDRIG_DIAGNOSE_CASES > 1 adds a
// third).
TEST(CavityEvidenceDiagnose, FreeGasAbsorbedIntoASlowWaveSpeedIsStillNamed) {
  // Of seeds 1-6 (lab noise, sea, low pressure), 1, 4 and 5 make the base model leave the range
  // (365, 464 and 380 m/s; the others 634-707 m/s, where the gas is named as well).
  std::vector<std::uint64_t> seeds = {1, 5};
  if (Cases() > 1) seeds.push_back(4);
  for (std::uint64_t seed : seeds) {
    SCOPED_TRACE(seed);
    const Logged gas = EvidenceOf("gas_entrainment", seed, kDiagnoseCells, 40.0, 50.0,
                                  SyntheticHeave::kIrregularSea);
    MeasuredLog log = gas.log;
    DiagnoseOptions diagnose;
    diagnose.simulation.cells = kDiagnoseCells;
    diagnose.simulation.stop_on_range_violation = false;
    diagnose.candidates = {"gas_entrainment", "sensor_lag", "hose_compliance", "choke_inertia"};
    ASSERT_TRUE(PrepareLogReplay(&log, RigParams(), diagnose.simulation, &diagnose.replay,
                                 InputLevels::kAfterTheFit)
                    .ok());
    auto d = Diagnose(log, RigParams(), diagnose);
    ASSERT_TRUE(d.ok()) << d.status().message();
    PrintRanking(*d);
    const double base_c = d->baseline.fitted.wave_speed_mps;
    std::printf("seed %d: base model c %.0f m/s (truth %.0f)\n", static_cast<int>(seed), base_c,
                gas.synthetic.truth.wave_speed_mps);
    EXPECT_GT(std::fabs(base_c / RigParams().wave_speed_mps - 1.0), kWaveSpeedScanSpan)
        << "this log no longer makes the base model absorb the gas: choose another seed";
    EXPECT_EQ(d->verdict, "gas_entrainment");
  }
}

}  // namespace
}  // namespace mpdrig
