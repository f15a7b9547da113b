#include "model/effects/param_by_key.h"

#include <cmath>
#include <string>

namespace mpdrig {
namespace {

// What an unknown base key's error offers besides the table's keys.
constexpr std::string_view kEffectKeys = "EFFECT.KEY of an effect (`mpdrig effects`)";

// "sensor_lag.time_constant_s, ..." for an unknown key of a known effect.
std::string EffectKeys(const EffectInfo& info) {
  std::string keys;
  for (const EffectParamInfo& param : info.params) {
    if (!keys.empty()) keys += ", ";
    keys += std::string(info.name) + "." + std::string(param.key);
  }
  return keys;
}

Status NotSwitchedOn(std::string_view key, const EffectInfo& effect) {
  return Status::Error(std::string(key) + ": effect '" + std::string(effect.name) +
                       "' is not switched on");
}

}  // namespace

Result<ParamByKey> FindParamByKey(std::string_view key) {
  const std::size_t dot = key.find('.');
  if (dot == std::string_view::npos) {
    auto info = LookUpParam(key, kEffectKeys);
    if (!info.ok()) return info.status();
    const ParamInfo& base = **info;
    return ParamByKey{
        .base = &base, .unit = base.unit, .min_value = base.min_value, .max_value = base.max_value};
  }
  const std::string_view effect_name = key.substr(0, dot);
  const EffectInfo* effect = FindEffectInfo(effect_name);
  if (effect == nullptr) {
    return UnknownEffect(effect_name).Within(std::string(key));
  }
  const EffectParamInfo* param = effect->FindParam(key.substr(dot + 1));
  if (param == nullptr) {
    return Status::Error("unknown parameter '" + std::string(key) +
                         "'; valid keys: " + EffectKeys(*effect));
  }
  return ParamByKey{.effect = effect,
                    .effect_param = param,
                    .unit = param->unit,
                    .min_value = param->min_value,
                    .max_value = param->max_value};
}

std::pair<double, double> ParamByKey::FitRange() const {
  return base != nullptr ? base->FitRange() : std::make_pair(min_value, max_value);
}

Result<double> GetParamValue(const RigParams& params, std::string_view key) {
  auto found = FindParamByKey(key);
  if (!found.ok()) return found.status();
  if (found->base != nullptr) return found->base->Get(params);
  const EffectSetting* setting = params.FindEffect(found->effect->name);
  if (setting == nullptr) return NotSwitchedOn(key, *found->effect);
  const double* value = setting->Find(found->effect_param->key);
  return value != nullptr ? *value : found->effect_param->default_value;
}

Status SetParamValue(RigParams* params, std::string_view key, double value) {
  if (!std::isfinite(value)) {
    return Status::Error(std::string(key) + ": value must be finite");
  }
  auto found = FindParamByKey(key);
  if (!found.ok()) return found.status();
  if (found->base != nullptr) return found->base->Set(params, value);
  EffectSetting* setting = params->FindEffect(found->effect->name);
  if (setting == nullptr) return NotSwitchedOn(key, *found->effect);
  MPDRIG_RETURN_IF_ERROR(CheckInRange(key, value, found->unit, found->min_value, found->max_value));
  setting->Set(found->effect_param->key, value);
  return Status::Ok();
}

}  // namespace mpdrig
