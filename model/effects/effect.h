// Physical effects: named pieces of physics beyond the thesis's model that can be switched on,
// so that a log the base model cannot explain can be tested against each suspect. The thesis lists
// its own suspects (chapters 5, 8, 11); each is an effect here.
//
// An effect has
//   - an EffectInfo: its name, the physics in one line, the thesis sections, what it explains
//     in a residual (diagnose's words), and its parameters with units, defaults and bounds;
//   - an Effect: one instance per simulation run, which may hold states, and acts through hooks:
//       pipe      an extra momentum source along the pipe, or its own closure of the inlet or
//                 the outlet (PipeExtension, model/pipe/pipe_extension.h);
//       pump      the back-pressure pump's delivered flow;
//       sensors   what the transmitters report (a lag, a filter);
//     and advances its states after every step.
// Every hook has a neutral default: an effect overrides what it changes and nothing else.
//
// Switching one on: `--effect NAME[:key=value,...]` on the command line, `effect { ... }` in the
// config file (rig_config.proto), RigParams::effects from C++. Parameters are set as
// "NAME.key" by `--set` and by `mpdrig fit`.
//
// Adding one: a source file defining `const EffectInfo& <Name>Effect()` and one line in
// catalogue.inc (docs/effects-and-diagnose.md, "Add a physical effect").
#pragma once

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"
#include "model/core/rig_channels.h"
#include "model/params/rig_params.h"
#include "model/pipe/pipe_extension.h"
#include "model/pipe/pipe_solver.h"

namespace mpdrig {

// The boundary inputs of the step just taken (at its end) and its length.
struct StepRecord {
  const PipeBoundaryValues& boundary;
  double dt_s;
};

class Effect : public PipeExtension {
 public:
  // Called once, with the pipe in its initial steady state and the channels it gives (before
  // any sensor filter): start the states in equilibrium with it.
  virtual void Initialize(const PipeSolver& /*pipe*/, const ChannelValues& /*channels*/) {}

  // The back-pressure pump's delivered flow for its command and the choke inlet pressure
  // (evaluated with the last step's pressure: the pump is slow against one step).
  virtual bool changes_pump_flow() const { return false; }
  virtual double PumpFlowM3ps(double commanded_m3ps, double /*choke_pressure_pa*/) const {
    return commanded_m3ps;
  }

  // Advances the effect's own states over the step just taken (the pipe is at the new level).
  virtual void AfterStep(const PipeSolver& /*pipe*/, const StepRecord& /*step*/) {}

  // What the sensors report: called once per step with the model's channels; replaces values
  // in place (e.g. a transmitter lag).
  virtual bool filters_sensors() const { return false; }
  virtual void FilterSensors(ChannelValues* /*values*/, double /*dt_s*/) {}
};

struct EffectParamInfo {
  std::string_view key;
  std::string_view unit;
  std::string_view description;
  double default_value;
  double min_value;  // inclusive: physical plausibility, and the range `fit` searches
  double max_value;
  bool fitted;  // diagnose fits it (the effect's strength); the others stay at their defaults
  // The range the lab may meet, where it differs from [default/2, 2 default] (0, 0: that one):
  // where `mpdrig synth` draws a hidden effect's strength (log-uniformly).
  double plausible_min = 0.0;
  double plausible_max = 0.0;
};

// An effect's resolved parameter values (one per EffectInfo::params entry, defaults filled in).
struct EffectValues {
  std::span<const EffectParamInfo> params;
  std::span<const double> values;

  double Get(std::string_view key) const;  // MPDRIG_CHECKs that the key exists
};

// What an effect is created with.
struct EffectContext {
  const RigParams& rig;
  const PipeConfig& pipe;
  double dt_s;
  std::span<const EffectParamInfo> params;
  std::span<const double> values;  // resolved: one per params entry, defaults filled in

  double Get(std::string_view key) const;  // MPDRIG_CHECKs that the key exists
};

struct EffectInfo {
  std::string_view name;      // registry name, as on the command line
  std::string_view summary;   // the physics in one line, with its equation
  std::string_view thesis;    // sections and equations of the thesis it comes from
  std::string_view explains;  // what it removes from a residual, in a user's words
  std::vector<EffectParamInfo> params;
  std::function<std::unique_ptr<Effect>(const EffectContext&)> create;
  // diagnose (and resonance diagnose, and `serve --hidden-effect random`) try it on a log. False
  // for a model of a rig other than the NTNU one that diagnose has nothing to fit of
  // (weighted_friction): it is switched on by name, never suspected.
  bool diagnose_candidate = true;
  // Rules between parameters that each parameter's bounds cannot state (e.g. a reference pressure
  // above the vapour pressure); null: none. Checked with the bounds, so a config file's error
  // points at the effect's line.
  std::function<Status(const EffectValues&)> check = nullptr;

  const EffectParamInfo* FindParam(std::string_view key) const;
};

// Every registered effect, in catalogue.inc's order.
std::span<const EffectInfo* const> EffectCatalogue();
// The effects diagnose tries when it is not told which (diagnose_candidate), in the same order.
std::vector<const EffectInfo*> DiagnoseCandidateEffects();
// Ok for a diagnose candidate; else the error that says `name` is unknown or not a candidate.
Status CheckDiagnoseCandidate(std::string_view name);
const EffectInfo* FindEffectInfo(std::string_view name);
// "unsteady_friction, helical_friction, ..." for error messages.
std::string EffectNames();
// The error for a name the catalogue does not hold: "unknown effect 'NAME'; valid effects: ...".
Status UnknownEffect(std::string_view name);

// Switches an effect on from "NAME" or "NAME:key=value,key=value" (`--effect`). Switching on an
// effect that is already on merges the values. Names, keys, numbers and bounds are checked.
Status ApplyEffectSpec(RigParams* params, std::string_view spec);

// Checks one parameter of `info`: a known key, a value within its bounds (not info.check, which
// needs all of them).
Status CheckEffectParam(const EffectInfo& info, std::string_view key, double value);

// Checks every effect setting of `params`: known name, no duplicate, known keys, finite values
// within bounds.
Status ValidateEffects(const RigParams& params);

// The values of every parameter of `info` (defaults where `setting` does not set one), each within
// its bounds and together passing info.check.
Result<std::vector<double>> ResolveEffectValues(const EffectInfo& info,
                                                const EffectSetting& setting);

// The effect instances for one run, in the order of params.effects.
Result<std::vector<std::unique_ptr<Effect>>> CreateEffects(const RigParams& params,
                                                           const PipeConfig& pipe, double dt_s);

}  // namespace mpdrig
