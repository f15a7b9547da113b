// diagnose on logs with regimes and on logs with something no catalogue effect makes (diagnose.h
// steps 1 and 6): MakeSyntheticLog at the lab's noise (thesis Table 4.1.1 on every channel,
// inputs too), 40 s at 50 Hz, diagnosed as `mpdrig diagnose` prepares a log.
//
// Required: on an effect-free log with a pump stop, the split moves so the stop is in both parts,
// nothing is selected, and what is left is noise; with a sensor fault the catalogue does not hold
// (every pressure 0.3 bar high while the pump is stopped; one transmitter's gain 30 % high), the
// diagnosis says the model misses something the catalogue does not hold and names the regime or
// the transmitter. On every log no candidate fits its fitting data worse than the base model.
//
// Cost: the effect-free log is diagnosed with the whole catalogue (a false alarm there is what
// matters), the faulty ones with the candidates that could pass for them (an offset of the
// pressures at low flow: the pump curve, free gas, a lag; a transmitter: a lag, the friction),
// about 15-40 s of one core each. MPDRIG_DIAGNOSE_CASES=N runs N seeds of each and the whole
// catalogue on all.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
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

int Cases() {
  const char* value = std::getenv("MPDRIG_DIAGNOSE_CASES");
  return value != nullptr ? std::max(1, std::atoi(value)) : 1;
}
bool WholeCatalogue() { return std::getenv("MPDRIG_DIAGNOSE_CASES") != nullptr; }

// The pump stops at 14 s for 8 s (0.5 s ramps): 40 % of the log is scored from 24 s, after it.
constexpr SyntheticInterval kPumpStop{14.0, 8.0};

// A sensor fault the model cannot make: applied to the measured log before diagnose sees it.
enum class Fault { kNone, kOffsetWhilePumpStopped, kGainOfPT6 };

Diagnosis DiagnoseLog(std::uint64_t seed, bool pump_stop, Fault fault,
                      const std::vector<std::string>& candidates) {
  SyntheticLogOptions options;
  options.seed = seed;
  options.duration_s = 40.0;
  options.rate_hz = 50.0;
  options.sensor_noise = SensorNoise::Lab();
  if (pump_stop) options.pump_stops = {kPumpStop};
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  if (!synthetic.ok()) return {};
  riglog::RigLog& rig = synthetic->log;
  for (std::size_t c = 0; c < rig.columns.size(); ++c) {
    const auto channel = riglog::FindChannel(rig.columns[c].channel);
    if (!channel || riglog::QuantityOf(*channel) != riglog::Quantity::kPressure ||
        *channel == Channel::kC1) {
      continue;
    }
    std::vector<double>& p = rig.values_si[c];
    if (fault == Fault::kOffsetWhilePumpStopped) {
      // 0.3 bar (12 times the transmitters' noise) while the pump is off, past its ramps.
      for (std::size_t n = 0; n < p.size(); ++n) {
        const double t = rig.time_s[n];
        if (t >= kPumpStop.start_s + 0.5 && t < kPumpStop.start_s + kPumpStop.duration_s - 0.5) {
          p[n] += 3.0e4;
        }
      }
    }
    if (fault == Fault::kGainOfPT6 && *channel == Channel::kPT6) {
      double mean = 0.0;
      for (double v : p) mean += v;
      mean /= static_cast<double>(p.size());
      for (double& v : p) v = mean + 1.3 * (v - mean);
    }
  }
  auto log = MeasuredLogFromRigLog(rig, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  if (!log.ok()) return {};
  DiagnoseOptions diagnose;
  diagnose.simulation.cells = kDiagnoseCells;
  diagnose.simulation.stop_on_range_violation = false;
  if (!WholeCatalogue()) diagnose.candidates = candidates;
  const Status prepared = PrepareLogReplay(&*log, RigParams(), diagnose.simulation,
                                           &diagnose.replay, InputLevels::kAfterTheFit);
  EXPECT_TRUE(prepared.ok()) << prepared.message();
  auto diagnosis = Diagnose(*log, RigParams(), diagnose);
  EXPECT_TRUE(diagnosis.ok()) << diagnosis.status().message();
  if (!diagnosis.ok()) return {};
  std::printf("seed %d: %s | selected %zu (%s) | %s\n", static_cast<int>(seed),
              synthetic->description.c_str(), diagnosis->selected.size(),
              diagnosis->selection_end.c_str(),
              diagnosis->residual ? diagnosis->residual->Summary().c_str() : "no residual");
  return *std::move(diagnosis);
}

bool Contains(const std::vector<std::string>& texts, const std::string& part) {
  return std::any_of(texts.begin(), texts.end(),
                     [&](const std::string& text) { return text.find(part) != std::string::npos; });
}

const Regime* Find(const Diagnosis& d, const std::string& name) {
  for (const Regime& regime : d.regimes) {
    if (regime.name == name) return &regime;
  }
  return nullptr;
}

TEST(DiagnoseWithRegimes, PumpStopInBothPartsNothingSelectedNoiseLeft) {
  for (int seed = 1; seed <= Cases(); ++seed) {
    const Diagnosis d = DiagnoseLog(seed, true, Fault::kNone, {});
    ASSERT_TRUE(d.residual.has_value());
    SCOPED_TRACE(d.residual->Summary());
    const Regime* stopped = Find(d, "pump stopped");
    ASSERT_NE(stopped, nullptr);
    EXPECT_LT(d.fit_end_s, d.requested_fit_end_s) << "moved back into the stop";
    EXPECT_TRUE(OnSide(*stopped, stopped->fit_s) && OnSide(*stopped, stopped->score_s));
    EXPECT_TRUE(d.one_sided_regimes.empty());
    EXPECT_TRUE(d.selected.empty()) << d.selected.front().effect;
    EXPECT_FALSE(d.residual->above_noise);
    ExpectNeverWorseThanTheBaseModel(d);
    ExpectEveryRoundReported(d);
  }
}

TEST(DiagnoseWithRegimes, AnOffsetOnlyWhileThePumpIsStoppedIsMissed) {
  for (int seed = 1; seed <= Cases(); ++seed) {
    const Diagnosis d = DiagnoseLog(seed, true, Fault::kOffsetWhilePumpStopped,
                                    {"pump_curve", "gas_entrainment", "sensor_lag"});
    ASSERT_TRUE(d.residual.has_value());
    const ResidualSignature& r = *d.residual;
    SCOPED_TRACE(r.Summary());
    EXPECT_TRUE(r.misses);
    EXPECT_TRUE(Contains(r.reasons, "while pump stopped"));
    EXPECT_FALSE(Contains(r.reasons, "while pump running"));
    EXPECT_TRUE(Contains(r.findings, "regimes: concentrated while pump stopped"));
    EXPECT_TRUE(Contains(r.findings, "steady there"));
    ExpectNeverWorseThanTheBaseModel(d);
    ExpectEveryRoundReported(d);
  }
}

TEST(DiagnoseWithoutRegimes, AGainErrorOfOneTransmitterIsMissed) {
  for (int seed = 2; seed < 2 + Cases(); ++seed) {
    const Diagnosis d =
        DiagnoseLog(seed, false, Fault::kGainOfPT6, {"sensor_lag", "unsteady_friction"});
    ASSERT_TRUE(d.residual.has_value());
    const ResidualSignature& r = *d.residual;
    SCOPED_TRACE(r.Summary());
    EXPECT_TRUE(d.regimes.empty());
    EXPECT_TRUE(d.selected.empty());
    EXPECT_TRUE(r.misses);
    EXPECT_TRUE(Contains(r.reasons, "1 channel's error on the scoring data"));
    EXPECT_TRUE(Contains(r.findings, "channels: PT6 (500 m)"));
    EXPECT_TRUE(Contains(r.findings, "along the pipe: one transmitter, PT6 (500 m)"));
    ExpectNeverWorseThanTheBaseModel(d);
    ExpectEveryRoundReported(d);
  }
}

}  // namespace
}  // namespace mpdrig
