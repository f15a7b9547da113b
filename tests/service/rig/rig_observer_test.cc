// The service's observer (service/rig/rig_observer.h) at the lab's sensor noise: it estimates the
// noise over its start-up window and designs its gains for it (the thesis's gains fail at lab
// noise).
#include "service/rig/rig_observer.h"

#include <cstdio>

#include <gtest/gtest.h>

#include "tests/model/observer/noisy_topside.h"

namespace mpdrig::service {
namespace {

using mpdrig::testing::FitPercent;
using mpdrig::testing::SimulateTopside;
using mpdrig::testing::WithLabNoise;

struct ServiceRun {
  double fit = 0.0;
  observer::NoiseDesign design;
  observer::MeasurementNoise noise;
};

// Feeds the 100 Hz topside samples one by one, as the service does, with the heave's commanded
// frequency, and scores the estimate after each sample against the true p(0).
ServiceRun RunService(const mpdrig::testing::TopsideLog& log,
                      const observer::TopsideSeries& measured, const RigObserverOptions& options) {
  auto sample = [&](std::size_t k) {
    RigSample s;
    s.time_s = measured.time_s[k];
    s.values[Index(Channel::kTime)] = s.time_s;
    s.values[Index(Channel::kC2)] = measured.outlet_pressure_pa[k];
    s.values[Index(Channel::kFT1)] = measured.outlet_flow_m3ps[k];
    return s;
  };
  ServiceRun run;
  auto created = RigObserver::Create(RigParams(), options, sample(0));
  EXPECT_TRUE(created.ok()) << created.status().message();
  if (!created.ok()) return run;
  std::vector<double> bhp(measured.time_s.size());
  bhp[0] = created->Estimate().estimate.bhp_pa;
  for (std::size_t k = 1; k < bhp.size(); ++k) {
    const Status status = created->Update(sample(k), log.heave_hz);
    EXPECT_TRUE(status.ok()) << status.message();
    bhp[k] = created->Estimate().estimate.bhp_pa;
  }
  run.fit = FitPercent(log.truth.time_s, log.bhp_pa, bhp, 20.0);
  run.design = created->gains().design;
  run.noise = created->options().noise;
  return run;
}

// At lab noise, 0.2 Hz heave (the case) and 0.1 / 0.33 Hz: BHP fit >= 90 % after 20 s
// with the service's defaults (measured 94.3-96.8 %; the noise is estimated over the first 5 s, so
// the first 5 s run the thesis's poles, well before the scored window). On the noise-free rig
// (the service today) the estimate keeps the thesis's poles and the fit is the noise-free one.
TEST(RigObserverNoiseTest, DefaultsFitTheTrueBhpAtLabNoiseAndWithoutNoise) {
  const RigObserverOptions defaults;
  for (double hz : {0.1, 0.2, 0.33}) {
    const auto log = SimulateTopside(hz, 45.0, 60.0);
    const ServiceRun noisy = RunService(log, WithLabNoise(log.truth, 11), defaults);
    const ServiceRun clean = RunService(log, log.truth, defaults);
    std::printf(
        "service, %.2f Hz, 45 deg: lab noise fit %.1f %% (noise %.0f Pa, %.3f L/min; poles "
        "%.2f%+.2fi, tau %.3f s); noise-free fit %.1f %% (poles %.0f%+.0fi)\n",
        hz, noisy.fit, noisy.noise.outlet_pressure_pa,
        units::M3psToLpm(noisy.noise.outlet_flow_m3ps), noisy.design.poles[0].real(),
        noisy.design.poles[0].imag(), noisy.design.prefilter_tau_s, clean.fit,
        clean.design.poles[0].real(), clean.design.poles[0].imag());
    EXPECT_GE(noisy.fit, 90.0) << hz;
    EXPECT_GE(clean.fit, 99.0) << hz;
    EXPECT_EQ(clean.design.poles[0], std::complex<double>(-40, 20));
    EXPECT_EQ(clean.design.prefilter_tau_s, 0.0);
  }
}

// The thesis's poles given explicitly (serve --observer-pole -40 20) are kept at lab noise, and
// fall short there: the check above can fail.
TEST(RigObserverNoiseTest, ExplicitThesisPolesAreKept) {
  RigObserverOptions thesis;
  thesis.observer.gain_design = observer::GainDesign::kPoles;
  const auto log = SimulateTopside(0.2, 45.0, 60.0);
  const ServiceRun run = RunService(log, WithLabNoise(log.truth, 11), thesis);
  std::printf("service, thesis poles at lab noise: fit %.1f %%\n", run.fit);
  EXPECT_EQ(run.design.poles[0], std::complex<double>(-40, 20));
  EXPECT_LT(run.fit, 85.0);
}

}  // namespace
}  // namespace mpdrig::service
