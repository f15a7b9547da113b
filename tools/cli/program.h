// What both mpdrig programs share: the top-level help text, and which commands the front runs
// itself (see tools/CMakeLists.txt for why there are two programs).
#pragma once

#include <CLI/CLI.hpp>
#include <string_view>

namespace mpdrig::cli {

inline constexpr const char* kProgramDescription =
    "mpdrig - virtual twin of the NTNU MPD heave lab rig (900 m copper pipe, heave generator,\n"
    "choke and back-pressure pump). Model of J. M. Anestad's thesis (2013). Pressures in the\n"
    "lab's units (bar gauge) at the edges; run `mpdrig <command> --help` for each command.";

// The commands that need only the model's core (no DDS, no least squares): `mpdrig` runs these in
// its own process; every other command line goes to mpdrig-all unchanged.
inline constexpr std::string_view kCoreCommands[] = {"simulate", "params", "effects", "freqresp",
                                                     "traveltime"};

// Registers the commands of kCoreCommands (both programs hold them).
void AddCoreCommands(CLI::App* app, int* exit_code);

// The program that holds every command, installed beside `mpdrig`.
inline constexpr const char* kAllCommandsProgram = "mpdrig-all";

}  // namespace mpdrig::cli
