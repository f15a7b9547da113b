// Helpers for tests that run the `mpdrig` executable through the shell (header-only).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace mpdrig::testing {

// A directory of the current test's own: <tmp>/<prefix><test name>.
inline std::filesystem::path TestTempDir(const std::string& prefix) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      (prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs a shell command with stdout and stderr into `output_file`; returns its exit code and (in
// *output) what it printed.
inline int RunShell(const std::string& command, const std::filesystem::path& output_file,
                    std::string* output) {
  const int status = std::system((command + " > " + output_file.string() + " 2>&1").c_str());
  if (output != nullptr) *output = ReadFile(output_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace mpdrig::testing
