// mpdrig: the command-line front end of the virtual MPD heave rig. main only parses flags and
// hands over to one subcommand (tools/cli/).
#include <CLI/CLI.hpp>

#include "tools/cli/commands.h"

int main(int argc, char** argv) {
  CLI::App app(
      "mpdrig - virtual twin of the NTNU MPD heave lab rig (900 m copper pipe, heave generator,\n"
      "choke and back-pressure pump). Model of J. M. Anestad's thesis (2013). Pressures in the\n"
      "lab's units (bar gauge) at the edges; run `mpdrig <command> --help` for each command.",
      "mpdrig");
  app.require_subcommand(1);
  int exit_code = 0;
  mpdrig::cli::AddDemoCommand(&app, &exit_code);
  mpdrig::cli::AddSimulateCommand(&app, &exit_code);
  mpdrig::cli::AddFreqrespCommand(&app, &exit_code);
  mpdrig::cli::AddParamsCommand(&app, &exit_code);
  mpdrig::cli::AddServeCommand(&app, &exit_code);
  mpdrig::cli::AddCompareCommand(&app, &exit_code);
  mpdrig::cli::AddObserveCommand(&app, &exit_code);
  mpdrig::cli::AddGainsCommand(&app, &exit_code);
  mpdrig::cli::AddEffectsCommand(&app, &exit_code);
  mpdrig::cli::AddDiagnoseCommand(&app, &exit_code);
  mpdrig::cli::AddFitCommand(&app, &exit_code);
  mpdrig::cli::AddTravelTimeCommand(&app, &exit_code);
  mpdrig::cli::AddRevealCommand(&app, &exit_code);
  mpdrig::cli::AddShadowCommand(&app, &exit_code);
  CLI11_PARSE(app, argc, argv);
  return exit_code;
}
