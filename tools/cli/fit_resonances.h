// mpdrig fit --resonances FILE: shared parameters fitted to the rig's measured first resonances
// (model/identification/resonance_fit.h).
#pragma once

#include <string>
#include <vector>

#include "model/analysis/resonance.h"
#include "model/analysis/resonance_list.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {

// What fit --resonances and diagnose --resonances load before they start: the start parameters,
// the measured list, and how the model's resonances are computed (--response, the model options'
// simulation, --outlet-barg).
struct ResonanceInputs {
  RigParams start;
  std::vector<MeasuredResonance> measured;
  ResonanceOptions resonance;
};
Result<ResonanceInputs> LoadResonanceInputs(const ModelOptions& model, const std::string& path,
                                            const std::string& method, double outlet_barg);

// --hold, --response and --outlet-barg, as both commands take them.
void AddResonanceOptions(CLI::App* command, std::vector<std::string>* hold, std::string* method,
                         double* outlet_barg);

struct ResonanceFitArgs {
  std::string resonances_path;
  std::vector<std::string> params;  // empty: wave_speed_mps and the effects' fitted parameters
  std::vector<std::string> bounds;  // KEY=LOWER:UPPER
  std::vector<std::string> hold;    // keys kept at their start values
  std::string method = "auto";      // auto, analytic, simulated
  std::string json_path;            // empty: none
  int max_iterations = 50;
  double outlet_barg = 4.0;
  bool quiet = false;
};

int RunFitResonances(const ModelOptions& model, const ResonanceFitArgs& args);

}  // namespace mpdrig::cli
