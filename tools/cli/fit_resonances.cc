#include "tools/cli/fit_resonances.h"

#include <algorithm>
#include <cstdio>

#include "model/analysis/resonance_list.h"
#include "model/common/units.h"
#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"
#include "model/identification/resonance_fit.h"
#include "tools/report/json.h"

namespace mpdrig::cli {
namespace {

using report::Json;
using report::JsonNumber;
using report::JsonText;

// The keys fitted: --params, or the wave speed and every fitted parameter of the effects on;
// without the --hold keys.
Result<std::vector<FitParameter>> Parameters(const RigParams& start, const ResonanceFitArgs& args) {
  std::vector<std::string> keys = args.params;
  if (keys.empty()) {
    keys.push_back("wave_speed_mps");
    for (const EffectSetting& effect : start.effects) {
      const EffectInfo* info = FindEffectInfo(effect.name);
      if (info == nullptr) return UnknownEffect(effect.name);
      for (const EffectParamInfo& p : info->params) {
        if (p.fitted) keys.push_back(effect.name + "." + std::string(p.key));
      }
    }
  }
  for (const std::string& held : args.hold) {
    auto value = GetParamValue(start, held);
    if (!value.ok()) return value.status().Within("--hold");
  }
  std::vector<FitParameter> parameters;
  for (const std::string& key : keys) {
    if (std::find(args.hold.begin(), args.hold.end(), key) != args.hold.end()) continue;
    auto parameter = DefaultFitParameter(key);
    if (!parameter.ok()) return parameter.status().Within("--params");
    auto value = GetParamValue(start, key);
    if (!value.ok()) return value.status().Within("--params");
    parameters.push_back(*parameter);
  }
  for (const std::string& spec : args.bounds) {
    auto bounds = ParseBoundsSpec(spec);
    if (!bounds.ok()) return bounds.status();
    auto it = std::find_if(parameters.begin(), parameters.end(),
                           [&](const FitParameter& p) { return p.key == bounds->key; });
    if (it == parameters.end()) {
      return Status::Error("--bounds " + spec + ": '" + bounds->key + "' is not fitted");
    }
    it->lower = bounds->lower, it->upper = bounds->upper;
  }
  return parameters;
}

std::string FitJson(const ResonanceFitResult& fit, const ResonanceFitArgs& args,
                    const std::vector<std::string>& effects) {
  Json params = Json::object();
  for (std::size_t j = 0; j < fit.keys.size(); ++j) {
    params[fit.keys[j]] = {{"initial", JsonNumber(fit.initial[j])},
                           {"estimate", JsonNumber(fit.estimates[j])},
                           {"std_error", JsonNumber(fit.standard_errors[j])},
                           {"lower", JsonNumber(fit.lower[j])},
                           {"upper", JsonNumber(fit.upper[j])}};
  }
  Json configurations = Json::array();
  for (const ResonanceFitConfiguration& c : fit.configurations) {
    configurations.push_back({{"configuration", std::string(TerminationName(c.configuration))},
                              {"measured_hz", JsonNumber(c.measured_hz)},
                              {"uncertainty_hz", JsonNumber(c.uncertainty_hz)},
                              {"base_model_hz", JsonNumber(c.base_model_hz)},
                              {"model_hz", JsonNumber(c.model_hz)},
                              {"response", std::string(ResponseMethodName(c.method))}});
  }
  const Json json = {{"resonances", args.resonances_path},
                     {"effects", effects},
                     {"held", args.hold},
                     {"params", params},
                     {"configurations", configurations},
                     {"chi2_before", JsonNumber(fit.chi2_before)},
                     {"chi2_after", JsonNumber(fit.chi2_after)},
                     {"max_error_hz", JsonNumber(fit.max_error_hz)},
                     {"iterations", fit.iterations},
                     {"resonances_computed", fit.evaluations},
                     {"converged", fit.converged},
                     {"solver_report", fit.solver_report}};
  return JsonText(json, 2);
}

}  // namespace

Result<ResonanceInputs> LoadResonanceInputs(const ModelOptions& model, const std::string& path,
                                            const std::string& method, double outlet_barg) {
  ResonanceInputs inputs;
  auto start = model.LoadNtnuRigParams("fit --resonances");
  if (!start.ok()) return start.status();
  inputs.start = *start;
  auto simulation = model.LoadSimulationOptions();
  if (!simulation.ok()) return simulation.status();
  auto measured = ReadResonanceList(path);
  if (!measured.ok()) return measured.status();
  inputs.measured = *measured;
  inputs.resonance.simulation = *simulation;
  inputs.resonance.simulated.outlet_pressure_pa =
      units::BargToPaAbs(outlet_barg, start->atmospheric_pressure_pa);
  inputs.resonance.method = method == "analytic"    ? ResponseMethod::kAnalytic
                            : method == "simulated" ? ResponseMethod::kSimulated
                                                    : ResponseMethod::kAuto;
  return inputs;
}

void AddResonanceOptions(CLI::App* command, std::vector<std::string>* hold, std::string* method,
                         double* outlet_barg) {
  command
      ->add_option("--hold", *hold,
                   "--resonances: keep this parameter at its start value (repeatable)")
      ->type_name("KEY");
  command
      ->add_option("--response", *method,
                   "--resonances: auto (analytic where it holds the effects, else simulated), "
                   "analytic or simulated")
      ->check(CLI::IsMember({"auto", "analytic", "simulated"}))
      ->capture_default_str();
  command
      ->add_option("--outlet-barg", *outlet_barg,
                   "--resonances: outlet pressure of the terminations [bar gauge]")
      ->capture_default_str();
}

int RunFitResonances(const ModelOptions& model, const ResonanceFitArgs& args) {
  const std::string name = "fit";
  auto inputs = LoadResonanceInputs(model, args.resonances_path, args.method, args.outlet_barg);
  if (!inputs.ok()) return Fail(name, inputs.status());
  const RigParams* start = &inputs->start;
  const std::vector<MeasuredResonance>* measured = &inputs->measured;
  auto parameters = Parameters(*start, args);
  if (!parameters.ok()) return Fail(name, parameters.status());

  ResonanceFitOptions options;
  options.max_iterations = args.max_iterations;
  options.resonance = inputs->resonance;
  if (!args.quiet) {
    std::string keys;
    for (const FitParameter& p : *parameters) keys += (keys.empty() ? "" : ", ") + p.key;
    const std::string outside = EffectsOutsideAnalytic(*start);
    std::fprintf(stderr, "mpdrig fit: %zu resonances; fitting %s; response %s\n", measured->size(),
                 keys.empty() ? "nothing (evaluating)" : keys.c_str(),
                 args.method != "auto" ? args.method.c_str()
                 : outside.empty()     ? "analytic (9.2.13)"
                                       : ("simulated where " + outside + " is on").c_str());
  }
  auto fit = FitResonances(*measured, *start, *parameters, options);
  if (!fit.ok()) return Fail(name, fit.status().Within(args.resonances_path));

  std::vector<std::string> effects;
  for (const EffectSetting& e : start->effects) effects.push_back(e.name);
  if (!args.json_path.empty()) {
    Status written = WriteText(args.json_path, FitJson(*fit, args, effects));
    if (!written.ok()) return Fail(name, written);
    if (args.json_path == "-") return 0;
  }
  std::printf("%-20s %9s %9s %9s %9s  %s\n", "configuration", "measured", "+-", "base", "model",
              "response");
  for (const ResonanceFitConfiguration& c : fit->configurations) {
    std::printf("%-20s %9.4f %9.4f %9.4f %9.4f  %s\n",
                std::string(TerminationName(c.configuration)).c_str(), c.measured_hz,
                c.uncertainty_hz, c.base_model_hz, c.model_hz,
                std::string(ResponseMethodName(c.method)).c_str());
  }
  for (std::size_t j = 0; j < fit->keys.size(); ++j) {
    const bool at_bound = fit->estimates[j] <= fit->lower[j] || fit->estimates[j] >= fit->upper[j];
    std::printf("%s = %.6g +- %.3g (from %.6g, bounds %g..%g)%s\n", fit->keys[j].c_str(),
                fit->estimates[j], fit->standard_errors[j], fit->initial[j], fit->lower[j],
                fit->upper[j], at_bound ? "  at a bound" : "");
  }
  for (const std::string& held : args.hold) {
    std::printf("%s held at %.6g\n", held.c_str(), *GetParamValue(*start, held));
  }
  std::printf("chi2 %.4g -> %.4g, largest error %.4f Hz; %d iterations, %d resonances, %s\n",
              fit->chi2_before, fit->chi2_after, fit->max_error_hz, fit->iterations,
              fit->evaluations, fit->converged ? "converged" : "NOT converged");
  return 0;
}

}  // namespace mpdrig::cli
