// The frequency-domain fit (resonance_fit.h): resonances the model itself produced, fitted back
// from other start values, give the parameters that made them.
#include "model/identification/resonance_fit.h"

#include <cmath>

#include <gtest/gtest.h>

#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"

namespace mpdrig {
namespace {

RigParams With(RigParams params, const std::string& spec) {
  const Status applied = ApplyEffectSpec(&params, spec);
  EXPECT_TRUE(applied.ok()) << applied.message();
  return params;
}

// The three terminations' first resonances of `truth`, each with uncertainty 0.01 Hz.
std::vector<MeasuredResonance> ResonancesOf(const RigParams& truth,
                                            const ResonanceOptions& options = {}) {
  std::vector<MeasuredResonance> list;
  for (const TerminationInfo& info : TerminationTable()) {
    auto resonance = FirstResonance(truth, info.termination, options);
    EXPECT_TRUE(resonance.ok()) << resonance.status().message();
    list.push_back({info.termination, resonance.ok() ? resonance->freq_hz : 0.0, 0.01, 0});
  }
  return list;
}

FitParameter Parameter(const std::string& key) {
  auto parameter = DefaultFitParameter(key);
  EXPECT_TRUE(parameter.ok()) << parameter.status().message();
  return *parameter;
}

// Relative tolerance of a recovered parameter from noise-free analytic resonances: the
// resonances are refined to 1e-9 Hz and the fit stops at a relative change of 1e-10.
constexpr double kRecoveryTolerance = 1e-4;

TEST(ResonanceFit, RecoversWaveSpeedAndTopsideCompliance) {
  const RigParams truth = With(RigParams(), "topside_compliance:compliance_m3_per_pa=4.0e-11");
  RigParams start = With(RigParams(), "topside_compliance");  // 8.2e-11
  ASSERT_TRUE(SetParamValue(&start, "wave_speed_mps", 1050.0).ok());
  RigParams truth_c = truth;
  ASSERT_TRUE(SetParamValue(&truth_c, "wave_speed_mps", 930.0).ok());
  auto fit = FitResonances(
      ResonancesOf(truth_c), start,
      {Parameter("wave_speed_mps"), Parameter("topside_compliance.compliance_m3_per_pa")});
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  EXPECT_NEAR(fit->estimates[0], 930.0, kRecoveryTolerance * 930.0);
  EXPECT_NEAR(fit->estimates[1], 4.0e-11, kRecoveryTolerance * 4.0e-11);
  EXPECT_LT(fit->max_error_hz, 1e-6);
  EXPECT_GT(fit->chi2_before, 1.0);
  for (const ResonanceFitConfiguration& c : fit->configurations) {
    EXPECT_EQ(c.method, ResponseMethod::kAnalytic);
  }
  EXPECT_TRUE(std::isfinite(fit->standard_errors[0]));
  std::printf("c %.4f m/s (1050 -> 930), C %.5g (8.2e-11 -> 4e-11), %d resonances computed\n",
              fit->estimates[0], fit->estimates[1], fit->evaluations);
}

TEST(ResonanceFit, HeldWaveSpeedStaysAndTheEffectsAreFound) {
  // c held at 1173 m/s; gas and tubes from 2e-4 and 8.2e-11 to the 1e-3 and 3e-11 that made the
  // resonances.
  RigParams truth = With(RigParams(), "topside_compliance:compliance_m3_per_pa=3.0e-11");
  truth = With(truth, "gas_entrainment:void_fraction=1e-3");
  ASSERT_TRUE(SetParamValue(&truth, "wave_speed_mps", 1173.0).ok());
  RigParams start = With(RigParams(), "topside_compliance");
  start = With(start, "gas_entrainment:void_fraction=2e-4");
  ASSERT_TRUE(SetParamValue(&start, "wave_speed_mps", 1173.0).ok());
  auto fit = FitResonances(ResonancesOf(truth), start,
                           {Parameter("topside_compliance.compliance_m3_per_pa"),
                            Parameter("gas_entrainment.void_fraction")});
  ASSERT_TRUE(fit.ok()) << fit.status().message();
  EXPECT_EQ(fit->params.wave_speed_mps, 1173.0);
  EXPECT_NEAR(fit->estimates[0], 3.0e-11, kRecoveryTolerance * 3.0e-11);
  EXPECT_NEAR(fit->estimates[1], 1e-3, kRecoveryTolerance * 1e-3);
}

}  // namespace
}  // namespace mpdrig
