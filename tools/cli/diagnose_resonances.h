// mpdrig diagnose --resonances FILE: which effects of the catalogue explain the rig's measured
// first resonances (model/identification/resonance_diagnose.h).
#pragma once

#include <string>
#include <vector>

#include "tools/cli/model_options.h"

namespace mpdrig::cli {

struct ResonanceDiagnoseArgs {
  std::string resonances_path;
  std::vector<std::string> hold;        // keys kept at their start values
  std::vector<std::string> candidates;  // empty: the catalogue
  std::string method = "auto";          // auto, analytic, simulated
  std::string json_path;                // empty: none
  int max_iterations = 25;
  int max_effects = 3;
  double significance = 0.01;
  double outlet_barg = 4.0;
  double amplitude_m = 2.5e-4;  // the simulated response's piston amplitude
  bool quiet = false;
  bool thorough = false;  // simulated candidates in every round
};

int RunDiagnoseResonances(const ModelOptions& model, const ResonanceDiagnoseArgs& args);

}  // namespace mpdrig::cli
