// The example controller against a running `mpdrig serve`, as processes over loopback DDS in a
// domain of the test's own, lockstep clock (deterministic on a loaded machine): two rigs under the
// same heave, one with its choke fixed, one controlled; the controlled one's bottom-hole pressure
// must oscillate a clear factor less.
#include <cstdio>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

// Runs `command` and returns its stdout.
std::string Capture(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return out;
  char buffer[512];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  ::pclose(pipe);
  return out;
}

// "key=value" pairs of the controller's summary line for `rig`.
std::map<std::string, std::string> Summary(const std::string& output, const std::string& rig) {
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("rig=" + rig + " ", 0) != 0) continue;
    std::map<std::string, std::string> fields;
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      const auto eq = word.find('=');
      if (eq != std::string::npos) fields[word.substr(0, eq)] = word.substr(eq + 1);
    }
    return fields;
  }
  return {};
}

TEST(BhpController, AttenuatesTheHeaveInducedBottomHolePressureOscillation) {
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  // 0.1 m heave at 0.2 Hz near the pipe's quarter-wave resonance (c/4l = 0.24 Hz), 5 L/min
  // through a 31 deg choke (3.4 bar on it): about 0.38 bar of BHP amplitude with the choke
  // fixed. 60 s: 10 s to learn the set point, about 20 s to converge, the last 20 s measured.
  // Without sensor noise: on the lab's (serve's default) the observer's estimate, with the
  // thesis's poles, is too noisy for this controller (measured: ratio 1.9 and a mean 0.10 bar
  // off); the observer at lab noise is tested in observer_noise_test.cc.
  const std::string controller = "\"" BHP_CONTROLLER_EXE "\" --lockstep --domain " + domain +
                                 " --duration 60 --measure-last 20 --timeout 30";
  const std::string command =
      "bash -c '\"" MPDRIG_EXE
      "\" serve --clock lockstep --rate-hz 100 --heave-amp-m 0.1 "
      "--heave-hz 0.2 --pump-lpm 5 --choke-deg 31 --sensor-noise none --rig fixed --rig "
      "controlled --domain " +
      domain + " 2>/dev/null & serve=$!; " + controller + " --rig fixed --open-loop & " +
      controller + " --rig controlled --use-estimate; wait $!; kill $serve; wait $serve' " +
      "2>/dev/null";
  const std::string output = Capture(command);
  auto fixed = Summary(output, "fixed");
  auto controlled = Summary(output, "controlled");
  ASSERT_FALSE(fixed.empty()) << output;
  ASSERT_FALSE(controlled.empty()) << output;
  const double a_fixed = std::stod(fixed["PT1_amplitude_bar"]);
  const double a_controlled = std::stod(controlled["PT1_amplitude_bar"]);
  std::printf(
      "PT1 amplitude: fixed choke %.4f bar, controlled (observer estimate) %.4f bar, "
      "ratio %.1f\n",
      a_fixed, a_controlled, a_fixed / a_controlled);
  EXPECT_GT(a_fixed, 0.3) << "the heave must move the BHP by tenths of a bar";
  // Measured: 18.7x (docs/service.md). A factor of 5 leaves room for tuning changes, not for a
  // controller that merely does no harm.
  EXPECT_GT(a_fixed / a_controlled, 5.0);
  // It holds the mean too: the set point learnt over the first 10 s, within 0.05 bar.
  EXPECT_NEAR(std::stod(controlled["PT1_mean_barg"]), std::stod(fixed["PT1_mean_barg"]), 0.05);
}

}  // namespace
}  // namespace mpdrig
