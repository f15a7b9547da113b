#include "model/identification/shadow_fit.h"

#include <cstdio>

#include "model/effects/effect.h"

namespace mpdrig {

Result<std::vector<FitParameter>> ShadowFitParameters(const RigParams& params) {
  std::vector<FitParameter> parameters;
  for (const char* key : kShadowFitBaseKeys) {
    auto parameter = DefaultFitParameter(key);
    if (!parameter.ok()) return parameter.status();
    parameters.push_back(*parameter);
  }
  for (const EffectSetting& effect : params.effects) {
    const EffectInfo* info = FindEffectInfo(effect.name);
    if (info == nullptr) return UnknownEffect(effect.name);
    for (const EffectParamInfo& param : info->params) {
      if (!param.fitted) continue;
      auto parameter = DefaultFitParameter(effect.name + "." + std::string(param.key));
      if (!parameter.ok()) return parameter.status();
      parameters.push_back(*parameter);
    }
  }
  return parameters;
}

namespace {

std::string Summary(const FitResult& fit) {
  std::string text;
  char number[64];
  for (std::size_t j = 0; j < fit.keys.size(); ++j) {
    const std::string& key = fit.keys[j];
    std::snprintf(number, sizeof number, "%.4g", fit.estimates[j]);
    const std::string name = key == "wave_speed_mps"      ? "c"
                             : key == "friction_f1_per_s" ? "f1"
                                                          : key;
    text += name + "=" + number;
    if (key == "wave_speed_mps") text += " m/s";
    if (key == "friction_f1_per_s") text += " 1/s";
    if (fit.held[j]) text += " (held: no influence)";
    text += ", ";
  }
  std::snprintf(number, sizeof number, "err %.4f -> %.4f", fit.error_before, fit.error_after);
  return text + number;
}

}  // namespace

Result<ShadowFitOutcome> FitShadowParameters(MeasuredLog log, const RigParams& start,
                                             const SimulationOptions& simulation,
                                             int max_iterations, std::function<bool()> cancelled) {
  auto parameters = ShadowFitParameters(start);
  if (!parameters.ok()) return parameters.status();
  FitOptions options;
  options.simulation = simulation;
  options.max_iterations = max_iterations;
  options.cancelled = std::move(cancelled);
  // As `mpdrig fit`: the start chosen from the rows (a heave already running), the levels
  // estimated after the first fit.
  MPDRIG_RETURN_IF_ERROR(
      PrepareLogReplay(&log, start, simulation, &options.replay, InputLevels::kAfterTheFit));
  auto fit = FitParametersAndInputLevels(&log, start, *parameters, options);
  if (!fit.ok()) return fit.status();
  ShadowFitOutcome outcome;
  outcome.params = fit->params;
  outcome.summary = Summary(*fit);
  outcome.fit = std::move(fit).value();
  return outcome;
}

}  // namespace mpdrig
