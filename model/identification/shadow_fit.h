// "Fit now" for the shadow model (`mpdrig shadow`, its model command): the base parameters that
// a shadow's error most often comes from (the wave speed c and the linear friction f1, thesis
// Table 9.4.1) and the strength of each effect switched on (its parameters that diagnose fits,
// EffectParamInfo::fitted), fitted as `mpdrig fit` fits them (FitParametersAndInputLevels: the
// inputs reconstructed, the choke's and FT2's levels estimated at the first fit's parameters,
// then refitted) on the rows the shadow holds. Pure computation: the caller decides where it runs
// (the service on a worker thread, the shadow running on meanwhile).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/identification/fit.h"
#include "model/params/rig_params.h"

namespace mpdrig {

// The base keys fitted (with DefaultFitParameter's bounds).
inline constexpr const char* kShadowFitBaseKeys[] = {"wave_speed_mps", "friction_f1_per_s"};

// c, f1, then every fitted parameter of the effects on in `params`, with their default bounds.
Result<std::vector<FitParameter>> ShadowFitParameters(const RigParams& params);

struct ShadowFitOutcome {
  RigParams params;     // `start` with the estimates written in
  FitResult fit;        // keys, estimates, errors before and after on the rows
  std::string summary;  // "c=851 m/s, f1=0.152 1/s, unsteady_friction.k=0.98, err a -> b"
};

// Fits on `log` (the shadow's rows, ShadowModel::HeldLog) from `start`.
// `cancelled` (optional) is asked after each solver iteration: true ends the fit with the
// error kFitCancelled (fit.h).
Result<ShadowFitOutcome> FitShadowParameters(MeasuredLog log, const RigParams& start,
                                             const SimulationOptions& simulation,
                                             int max_iterations = 15,
                                             std::function<bool()> cancelled = {});

}  // namespace mpdrig
