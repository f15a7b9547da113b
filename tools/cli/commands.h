// The subcommands of `mpdrig`. Each Add*Command registers its options on the app and a callback
// that runs it; the exit code is left in *exit_code.
#pragma once

#include <CLI/CLI.hpp>

namespace mpdrig::cli {

void AddSimulateCommand(CLI::App* app, int* exit_code);
void AddFreqrespCommand(CLI::App* app, int* exit_code);
void AddParamsCommand(CLI::App* app, int* exit_code);
void AddDemoCommand(CLI::App* app, int* exit_code);
void AddServeCommand(CLI::App* app, int* exit_code);
void AddCompareCommand(CLI::App* app, int* exit_code);
void AddObserveCommand(CLI::App* app, int* exit_code);
void AddGainsCommand(CLI::App* app, int* exit_code);
void AddEffectsCommand(CLI::App* app, int* exit_code);     // the effect catalogue
void AddDiagnoseCommand(CLI::App* app, int* exit_code);    // which effect is missing (and synth)
void AddFitCommand(CLI::App* app, int* exit_code);         // parameters fitted to a log
void AddTravelTimeCommand(CLI::App* app, int* exit_code);  // wave speed from the fronts
void AddRevealCommand(CLI::App* app, int* exit_code);
void AddShadowCommand(CLI::App* app, int* exit_code);

}  // namespace mpdrig::cli
