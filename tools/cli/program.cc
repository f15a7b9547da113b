#include "tools/cli/program.h"

#include "tools/cli/commands.h"

namespace mpdrig::cli {

void AddCoreCommands(CLI::App* app, int* exit_code) {
  AddSimulateCommand(app, exit_code);
  AddFreqrespCommand(app, exit_code);
  AddParamsCommand(app, exit_code);
  AddEffectsCommand(app, exit_code);
  AddTravelTimeCommand(app, exit_code);
}

}  // namespace mpdrig::cli
