// mpdrig-all: every command of mpdrig in one program (`mpdrig` runs the light ones itself and
// hands the others here; tools/CMakeLists.txt). main only parses the command name and hands over
// to one subcommand (tools/cli/).
#include <CLI/CLI.hpp>

#include "tools/cli/commands.h"
#include "tools/cli/program.h"

int main(int argc, char** argv) {
  CLI::App app(mpdrig::cli::kProgramDescription, "mpdrig");
  app.require_subcommand(1);
  int exit_code = 0;
  mpdrig::cli::AddDemoCommand(&app, &exit_code);
  mpdrig::cli::AddCoreCommands(&app, &exit_code);
  mpdrig::cli::AddServeCommand(&app, &exit_code);
  mpdrig::cli::AddCompareCommand(&app, &exit_code);
  mpdrig::cli::AddObserveCommand(&app, &exit_code);
  mpdrig::cli::AddGainsCommand(&app, &exit_code);
  mpdrig::cli::AddDiagnoseCommand(&app, &exit_code);
  mpdrig::cli::AddFitCommand(&app, &exit_code);
  mpdrig::cli::AddRevealCommand(&app, &exit_code);
  mpdrig::cli::AddShadowCommand(&app, &exit_code);
  CLI11_PARSE(app, argc, argv);
  return exit_code;
}
