// mpdrig-all: every command of mpdrig in one program (`mpdrig` runs the light ones itself and
// hands the others here; tools/CMakeLists.txt). main only parses the command name and hands over
// to one subcommand (tools/cli/).
#if __has_include(<malloc.h>)
#include <malloc.h>  // mallopt (glibc)
#endif

#include <CLI/CLI.hpp>

#include "tools/cli/commands.h"
#include "tools/cli/program.h"

namespace {

// The fits (fit, diagnose, the shadow's "fit now") solve thousands of least-squares problems of a
// few MB each (Ceres's Jacobian and scratch, the replay's residuals). glibc serves blocks above its
// mmap threshold (128 kB at first, raised as blocks are freed, up to 32 MB) with fresh pages from
// the kernel, which faults and zeroes them on every use: 0.9 s of system time in a 26 s diagnosis
// of a 120 s log. Served from the heap and kept there they are reused: 0.1 s. The cost: freed
// memory is not handed back to the system until 512 MB of it lie free at the heap's top (that
// diagnosis peaks at 124 MB).
void KeepLargeBlocksInTheHeap() {
#if defined(M_MMAP_THRESHOLD) && defined(M_TRIM_THRESHOLD)
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  KeepLargeBlocksInTheHeap();
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
