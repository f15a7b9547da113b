// A rig parameter by its key, base or effect: the one accessor for code that takes either kind
// (fit and diagnose, the shadow's fit now, `mpdrig fit --params`).
//   base    a key of ParamTable() ("wave_speed_mps"): a field of RigParams, read and set through
//           its ParamInfo;
//   effect  "EFFECT.KEY" ("unsteady_friction.k"): a parameter of an effect of the catalogue
//           (effect.h), held in that effect's EffectSetting, its default until one is set; the
//           effect must be switched on in the params read or set.
// Values are numbers in the tables' units (ParamInfo::unit, EffectParamInfo::unit: SI); the text
// form (`--set key=value`) is SetParam's (rig_params.h).
#pragma once

#include <string_view>
#include <utility>

#include "model/common/status.h"
#include "model/effects/effect.h"
#include "model/params/rig_params.h"

namespace mpdrig {

// What a key names, with its unit and ranges.
struct ParamByKey {
  const ParamInfo* base = nullptr;                // a base key, or
  const EffectInfo* effect = nullptr;             // an effect key: the effect
  const EffectParamInfo* effect_param = nullptr;  // and its parameter
  std::string_view unit;
  double min_value = 0.0;  // bounds, inclusive: what SetParamValue accepts
  double max_value = 0.0;

  // The range fit searches by default, within the bounds: ParamInfo::FitRange() for a base key,
  // the bounds for an effect's. Computed when asked (a base key's may build the thesis's
  // RigParams), not on every get or set inside a fit's replays.
  std::pair<double, double> FitRange() const;
};

// What `key` names, or an error that names it and lists the valid keys (an unknown effect: the
// effects; an unknown key of a known effect: that effect's keys).
Result<ParamByKey> FindParamByKey(std::string_view key);

// The value of `key` in `params`: the effect's default where its setting gives none.
Result<double> GetParamValue(const RigParams& params, std::string_view key);

// Sets `key` in `params` to `value`, which must be finite and within the bounds; on an error
// `params` is unchanged.
Status SetParamValue(RigParams* params, std::string_view key, double value);

}  // namespace mpdrig
