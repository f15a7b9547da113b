// mpdrig reveal, and the choice behind `mpdrig serve --hidden-effect random`.
#include "tools/cli/hidden_effect.h"

#include <cstdio>
#include <memory>
#include <random>
#include <sstream>

#include "model/effects/effect.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {

std::string ResolveHiddenEffect(const std::string& argument, std::uint64_t seed) {
  if (argument != "random") return argument;
  // The diagnose candidates: a mystery rig hides what diagnose can find.
  const auto catalogue = DiagnoseCandidateEffects();
  std::mt19937_64 random(seed);
  const std::uint64_t draw = random();
  return std::string(catalogue[static_cast<std::size_t>(draw % catalogue.size())]->name);
}

Result<std::string> DescribeHiddenEffect(const std::string& spec) {
  RigParams params;
  MPDRIG_RETURN_IF_ERROR(ApplyEffectSpec(&params, spec));
  const EffectSetting& setting = params.effects.front();
  const EffectInfo* info = FindEffectInfo(setting.name);
  auto values = ResolveEffectValues(*info, setting);
  if (!values.ok()) return values.status();
  std::ostringstream out;
  out << setting.name << ":";
  for (std::size_t i = 0; i < info->params.size(); ++i) {
    out << (i == 0 ? "" : ",") << info->params[i].key << "=" << (*values)[i];
  }
  out << "  (" << info->summary << ")";
  return out.str();
}

void AddRevealCommand(CLI::App* app, int* exit_code) {
  auto seed = std::make_shared<std::uint64_t>(1);
  CLI::App* command = app->add_subcommand(
      "reveal", "Tell which effect `mpdrig serve --hidden-effect random --seed S` hides");
  command->footer(
      "The instructor's answer to a mystery rig: the same seed gives the same effect and\n"
      "strength (its catalogue defaults) on every machine.\n"
      "  mpdrig serve --hidden-effect random --seed 7    # the class's rig\n"
      "  mpdrig reveal --seed 7                          # after the diagnosis");
  command->add_option("--seed", *seed, "the seed the rig was started with")->capture_default_str();
  command->callback([seed, exit_code]() {
    auto described = DescribeHiddenEffect(ResolveHiddenEffect("random", *seed));
    if (!described.ok()) {
      *exit_code = Fail("reveal", described.status());
      return;
    }
    std::printf("seed %llu: %s\n", static_cast<unsigned long long>(*seed), described->c_str());
    *exit_code = 0;
  });
}

}  // namespace mpdrig::cli
