#include "model/analysis/termination.h"

#include <algorithm>
#include <array>

namespace mpdrig {
namespace {

constexpr std::array<TerminationInfo, 3> kTerminations = {{
    {Termination::kChokeClosed, "choke-closed",
     "choke shut, pump off: pipe, topside tubes, closed choke (thesis 9.1: 0.44 Hz)"},
    {Termination::kChokeOpen, "choke-open",
     "choke fully open, pump off: outlet held at p_0 (thesis 9.1: 0.25 Hz)"},
    {Termination::kClosedAtPipeEnd, "closed-at-pipe-end",
     "valve shut right after the copper pipe: tubes and choke cut off (thesis 11.1: 0.49 Hz)"},
}};

constexpr std::array<std::string_view, 3> kTopsideEffects = {"topside_compliance", "choke_inertia",
                                                             "pump_curve"};

}  // namespace

std::span<const TerminationInfo> TerminationTable() { return kTerminations; }

std::string_view TerminationName(Termination termination) {
  for (const TerminationInfo& info : kTerminations) {
    if (info.termination == termination) return info.name;
  }
  MPDRIG_CHECK(false);
  return {};
}

std::string TerminationNames() {
  std::string names;
  for (const TerminationInfo& info : kTerminations) {
    if (!names.empty()) names += ", ";
    names += info.name;
  }
  return names;
}

Result<Termination> ParseTermination(std::string_view name) {
  for (const TerminationInfo& info : kTerminations) {
    if (info.name == name) return info.termination;
  }
  return Status::Error("unknown termination '" + std::string(name) +
                       "'; valid terminations: " + TerminationNames());
}

bool IsTopsideEffect(std::string_view effect_name) {
  return std::find(kTopsideEffects.begin(), kTopsideEffects.end(), effect_name) !=
         kTopsideEffects.end();
}

TerminatedRig ApplyTermination(const RigParams& params, Termination termination) {
  TerminatedRig rig{params, ChokeSetting::Closed(), 0.0};
  switch (termination) {
    case Termination::kChokeClosed:
      rig.params.choke_leak_m2 = 0.0;
      break;
    case Termination::kChokeOpen:
      rig.choke = ChokeSetting::Open();
      break;
    case Termination::kClosedAtPipeEnd: {
      // The valve closes the copper pipe itself: u(L) = 0 whatever lies beyond it.
      rig.params.choke_leak_m2 = 0.0;
      auto& effects = rig.params.effects;
      effects.erase(std::remove_if(effects.begin(), effects.end(),
                                   [](const EffectSetting& e) { return IsTopsideEffect(e.name); }),
                    effects.end());
      break;
    }
  }
  return rig;
}

}  // namespace mpdrig
