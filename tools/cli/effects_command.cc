// mpdrig effects: the catalogue of physical effects, with their parameters and what they explain.
#include <cstdio>
#include <memory>
#include <string>

#include "model/effects/effect.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

void Print(std::string_view label, std::string_view text) {
  std::printf("  %-9.*s %.*s\n", static_cast<int>(label.size()), label.data(),
              static_cast<int>(text.size()), text.data());
}

int RunEffects(const std::string& only) {
  if (!only.empty() && FindEffectInfo(only) == nullptr) {
    return Fail("effects", UnknownEffect(only));
  }
  for (const EffectInfo* info : EffectCatalogue()) {
    if (!only.empty() && info->name != only) continue;
    std::printf("%.*s\n", static_cast<int>(info->name.size()), info->name.data());
    Print("physics", info->summary);
    Print("thesis", info->thesis);
    Print("explains", info->explains);
    if (!info->diagnose_candidate) Print("diagnose", "not a candidate: switched on by name only");
    for (const EffectParamInfo& param : info->params) {
      const std::string key = std::string(info->name) + "." + std::string(param.key);
      char range[64];
      std::snprintf(range, sizeof(range), "[%g, %g]", param.min_value, param.max_value);
      char plausible[64] = "";
      if (param.plausible_min > 0.0 && param.plausible_min < param.plausible_max) {
        std::snprintf(plausible, sizeof(plausible), "; plausible on the rig %g..%g",
                      param.plausible_min, param.plausible_max);
      }
      std::printf("  %-34s %-6.*s default %-9.4g %-16s %.*s%s%s\n", key.c_str(),
                  static_cast<int>(param.unit.size()), param.unit.data(), param.default_value,
                  range, static_cast<int>(param.description.size()), param.description.data(),
                  param.fitted ? " (diagnose fits it)" : "", plausible);
    }
    std::printf("\n");
  }
  return 0;
}

}  // namespace

void AddEffectsCommand(CLI::App* app, int* exit_code) {
  auto only = std::make_shared<std::string>();
  CLI::App* command = app->add_subcommand(
      "effects", "List the physical effects that can be switched on, with their parameters");
  command->footer(
      "Switch one on in any model command with --effect NAME[:KEY=VALUE,...], set a parameter\n"
      "with --set NAME.KEY=VALUE, or write `effect { name: \"NAME\" param { key: \"KEY\" value: V "
      "} }`\n"
      "in the config file. `mpdrig diagnose` tries each of them on a log (but those marked\n"
      "`diagnose  not a candidate`).\n"
      "  mpdrig simulate --effect unsteady_friction:k=0.05 --piston sine:amp_m=0.1,freq_hz=0.4 \\\n"
      "      --duration 60 --out run.csv\n"
      "  mpdrig compare lab.csv --effect sensor_lag --set sensor_lag.time_constant_s=0.1 "
      "--json -");
  command->add_option("name", *only, "show only this effect");
  command->callback([only, exit_code]() { *exit_code = RunEffects(*only); });
}

}  // namespace mpdrig::cli
