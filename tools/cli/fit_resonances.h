// mpdrig fit --resonances FILE: shared parameters fitted to the rig's measured first resonances
// (model/identification/resonance_fit.h).
#pragma once

#include <string>
#include <vector>

#include "tools/cli/model_options.h"

namespace mpdrig::cli {

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
