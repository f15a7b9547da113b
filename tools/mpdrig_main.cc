// mpdrig: the command-line front end of the virtual MPD heave rig. The commands that need only
// the model's core (program.h) run here; any other command line, `--help` and mistakes included,
// is handed unchanged to mpdrig-all beside this program (execv: same process, same pid, same
// arguments), which holds every command. Why two programs: tools/CMakeLists.txt.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>

#include "tools/cli/program.h"

namespace {

bool IsCoreCommand(const char* name) {
  return std::ranges::find(mpdrig::cli::kCoreCommands, std::string_view(name)) !=
         std::end(mpdrig::cli::kCoreCommands);
}

int RunCoreCommand(int argc, char** argv) {
  CLI::App app(mpdrig::cli::kProgramDescription, "mpdrig");
  app.require_subcommand(1);
  int exit_code = 0;
  mpdrig::cli::AddCoreCommands(&app, &exit_code);
  CLI11_PARSE(app, argc, argv);
  return exit_code;
}

// Replaces this process with mpdrig-all from this program's own directory (not from PATH: a
// build tree's mpdrig must run that tree's commands).
int HandOver(char** argv) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) {
    std::cerr << "mpdrig: cannot find this program's directory (/proc/self/exe: " << error.message()
              << ")\n";
    return 127;
  }
  const std::string all = (self.parent_path() / mpdrig::cli::kAllCommandsProgram).string();
  execv(all.c_str(), argv);
  const int exec_errno = errno;
  std::cerr << "mpdrig: cannot run " << all << ": " << std::strerror(exec_errno)
            << "\n  (this program runs only";
  for (const std::string_view name : mpdrig::cli::kCoreCommands) std::cerr << ' ' << name;
  std::cerr << "; every command is in " << mpdrig::cli::kAllCommandsProgram
            << ", built and installed beside it)\n";
  return 127;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && IsCoreCommand(argv[1])) return RunCoreCommand(argc, argv);
  return HandOver(argv);
}
