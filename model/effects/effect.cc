#include "model/effects/effect.h"

#include <charconv>
#include <cmath>

namespace mpdrig {

#define MPDRIG_EFFECT(Name) const EffectInfo& Name##Effect();
#include "model/effects/catalogue.inc"
#undef MPDRIG_EFFECT

namespace {

const std::vector<const EffectInfo*>& Catalogue() {
  static const std::vector<const EffectInfo*> catalogue = {
#define MPDRIG_EFFECT(Name) &Name##Effect(),
#include "model/effects/catalogue.inc"
#undef MPDRIG_EFFECT
  };
  return catalogue;
}

std::string ParamKeys(const EffectInfo& info) {
  std::string keys;
  for (const EffectParamInfo& param : info.params) {
    if (!keys.empty()) keys += ", ";
    keys += std::string(param.key) + " [" + std::string(param.unit) + "]";
  }
  return keys.empty() ? "none" : keys;
}

Status CheckValue(const EffectInfo& info, const EffectParamInfo& param, double value) {
  return CheckInRange(std::string(info.name) + "." + std::string(param.key), value, param.unit,
                      param.min_value, param.max_value);
}

}  // namespace

double EffectValues::Get(std::string_view key) const {
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (params[i].key == key) return values[i];
  }
  MPDRIG_CHECK(false && "effect parameter key not in its table");
  return 0.0;
}

double EffectContext::Get(std::string_view key) const {
  return EffectValues{params, values}.Get(key);
}

const EffectParamInfo* EffectInfo::FindParam(std::string_view key) const {
  for (const EffectParamInfo& param : params) {
    if (param.key == key) return &param;
  }
  return nullptr;
}

std::span<const EffectInfo* const> EffectCatalogue() { return Catalogue(); }

std::vector<const EffectInfo*> DiagnoseCandidateEffects() {
  std::vector<const EffectInfo*> candidates;
  for (const EffectInfo* info : Catalogue()) {
    if (info->diagnose_candidate) candidates.push_back(info);
  }
  return candidates;
}

Status CheckDiagnoseCandidate(std::string_view name) {
  const EffectInfo* info = FindEffectInfo(name);
  if (info == nullptr) return UnknownEffect(name);
  if (info->diagnose_candidate) return Status::Ok();
  std::string names;
  for (const EffectInfo* candidate : DiagnoseCandidateEffects()) {
    if (!names.empty()) names += ", ";
    names += candidate->name;
  }
  return Status::Error("effect '" + std::string(name) +
                       "' is not a diagnose candidate (it has nothing diagnose fits; switch it on "
                       "with --effect); the candidates: " +
                       names);
}

const EffectInfo* FindEffectInfo(std::string_view name) {
  for (const EffectInfo* info : Catalogue()) {
    if (info->name == name) return info;
  }
  return nullptr;
}

std::string EffectNames() {
  std::string names;
  for (const EffectInfo* info : Catalogue()) {
    if (!names.empty()) names += ", ";
    names += info->name;
  }
  return names;
}

Status UnknownEffect(std::string_view name) {
  return Status::Error("unknown effect '" + std::string(name) +
                       "'; valid effects: " + EffectNames());
}

Status ApplyEffectSpec(RigParams* params, std::string_view spec) {
  const std::size_t colon = spec.find(':');
  const std::string name(spec.substr(0, colon));
  const EffectInfo* info = FindEffectInfo(name);
  if (info == nullptr) {
    return UnknownEffect(name);
  }
  EffectSetting* setting = params->FindEffect(name);
  if (setting == nullptr) {
    params->effects.push_back({name, {}});
    setting = &params->effects.back();
  }
  if (colon == std::string_view::npos) return Status::Ok();
  std::string_view rest = spec.substr(colon + 1);
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    const std::string_view assignment = rest.substr(0, comma);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    const std::size_t equals = assignment.find('=');
    if (equals == std::string_view::npos) {
      return Status::Error("effect " + name + ": expected key=value, got '" +
                           std::string(assignment) + "'");
    }
    const std::string key(assignment.substr(0, equals));
    const EffectParamInfo* param = info->FindParam(key);
    if (param == nullptr) {
      return Status::Error("effect " + name + " has no parameter '" + key +
                           "'; its parameters: " + ParamKeys(*info));
    }
    MPDRIG_RETURN_IF_ERROR(SetParam(params, name + "." + key, assignment.substr(equals + 1)));
    setting = params->FindEffect(name);  // SetParam does not reallocate, but stay safe
    MPDRIG_RETURN_IF_ERROR(CheckValue(*info, *param, *setting->Find(key)));
  }
  return Status::Ok();
}

Status CheckEffectParam(const EffectInfo& info, std::string_view key, double value) {
  const EffectParamInfo* param = info.FindParam(key);
  if (param == nullptr) {
    return Status::Error("effect " + std::string(info.name) + " has no parameter '" +
                         std::string(key) + "'; its parameters: " + ParamKeys(info));
  }
  return CheckValue(info, *param, value);
}

Status ValidateEffects(const RigParams& params) {
  for (std::size_t i = 0; i < params.effects.size(); ++i) {
    const EffectSetting& setting = params.effects[i];
    const EffectInfo* info = FindEffectInfo(setting.name);
    if (info == nullptr) {
      return UnknownEffect(setting.name);
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (params.effects[j].name == setting.name) {
        return Status::Error("effect '" + setting.name + "' is switched on twice");
      }
    }
    auto values = ResolveEffectValues(*info, setting);
    if (!values.ok()) return values.status();
  }
  return Status::Ok();
}

Result<std::vector<double>> ResolveEffectValues(const EffectInfo& info,
                                                const EffectSetting& setting) {
  for (const auto& [key, value] : setting.values) {
    if (info.FindParam(key) == nullptr) {
      return Status::Error("effect " + std::string(info.name) + " has no parameter '" + key +
                           "'; its parameters: " + ParamKeys(info));
    }
  }
  std::vector<double> values;
  for (const EffectParamInfo& param : info.params) {
    const double* given = setting.Find(param.key);
    const double value = given != nullptr ? *given : param.default_value;
    MPDRIG_RETURN_IF_ERROR(CheckValue(info, param, value));
    values.push_back(value);
  }
  if (info.check) {
    MPDRIG_RETURN_IF_ERROR(info.check(EffectValues{info.params, values}));
  }
  return values;
}

Result<std::vector<std::unique_ptr<Effect>>> CreateEffects(const RigParams& params,
                                                           const PipeConfig& pipe, double dt_s) {
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(params));
  std::vector<std::unique_ptr<Effect>> effects;
  for (const EffectSetting& setting : params.effects) {
    const EffectInfo& info = *FindEffectInfo(setting.name);
    auto values = ResolveEffectValues(info, setting);
    if (!values.ok()) return values.status();
    const EffectContext context{params, pipe, dt_s, info.params, *values};
    effects.push_back(info.create(context));
  }
  return effects;
}

}  // namespace mpdrig
