// The example controller against a running `mpdrig serve`, as processes over loopback DDS in a
// domain of the test's own, lockstep clock (deterministic on a loaded machine): two rigs under the
// same heave, one with its choke fixed, one controlled; the controlled one's bottom-hole pressure
// must oscillate a clear factor less, around the same mean.
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/process.h"
#include "tests/support/shell.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

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

// At the lab's sensor noise (serve's default, thesis Table 4.1.1): the controller reads the
// observer's estimate, which the service computes from the noisy topside channels. The swing is
// measured as the RMS of PT1's periodic part at the heave's harmonics (least squares, so the
// noise's own 0.07 bar of half peak-to-peak is not in it). Three heaves, three noise seeds.
struct Excitation {
  const char* name;
  const char* heave_hz;
  const char* pump_lpm;
  const char* choke_deg;
  const char* noise_seed;
};

void PrintTo(const Excitation& x, std::ostream* os) {
  *os << x.heave_hz << " Hz, " << x.pump_lpm << " L/min, " << x.choke_deg << " deg, seed "
      << x.noise_seed;
}

class BhpController : public ::testing::TestWithParam<Excitation> {};

TEST_P(BhpController, AttenuatesTheHeaveInducedBottomHolePressureOscillation) {
  const Excitation& x = GetParam();
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  // 0.1 m heave, about 0.38 bar of BHP amplitude with the choke fixed at 5 L/min and 31 deg
  // (3.4 bar on it), 0.97 bar at 20 L/min and 45 deg. 65 s: 20-30 s to settle and learn the set
  // point (two heave periods, then whole periods of at least 10 s), about 20 s to converge, the
  // last 20 s measured (80 s before: the same bounds held, at 15% more CPU).
  testing::ChildProcess serve(
      {MPDRIG_EXE,      "serve",      "--clock",      "lockstep",   "--rate-hz",  "100",
       "--heave-amp-m", "0.1",        "--heave-hz",   x.heave_hz,   "--pump-lpm", x.pump_lpm,
       "--choke-deg",   x.choke_deg,  "--noise-seed", x.noise_seed, "--rig",      "fixed",
       "--rig",         "controlled", "--domain",     domain},
      testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  // Each controller's summary line on stdout (captured), its progress on stderr (dropped).
  testing::ChildOptions captured;
  captured.out = testing::Output::Capture();
  captured.err = testing::Output::Discard();
  auto controller = [&](const std::string& rig, const std::string& mode) {
    return std::make_unique<testing::ChildProcess>(
        std::vector<std::string>{BHP_CONTROLLER_EXE, "--lockstep", "--domain", domain, "--duration",
                                 "65", "--measure-last", "20", "--timeout", "30", "--rig", rig,
                                 mode},
        captured);
  };
  auto fixed_run = controller("fixed", "--open-loop");
  auto controlled_run = controller("controlled", "--use-estimate");
  ASSERT_TRUE(fixed_run->started() && controlled_run->started());
  EXPECT_EQ(fixed_run->Wait(600.0), 0);
  EXPECT_EQ(controlled_run->Wait(600.0), 0);
  const std::string output = fixed_run->out() + controlled_run->out();
  auto fixed = Summary(output, "fixed");
  auto controlled = Summary(output, "controlled");
  ASSERT_FALSE(fixed.empty()) << output;
  ASSERT_FALSE(controlled.empty()) << output;
  const double a_fixed = std::stod(fixed["PT1_periodic_rms_bar"]);
  const double a_controlled = std::stod(controlled["PT1_periodic_rms_bar"]);
  std::printf(
      "PT1 periodic RMS: fixed choke %.4f bar, controlled (observer estimate) %.4f bar, ratio "
      "%.1f; mean %.4f vs %.4f barg\n",
      a_fixed, a_controlled, a_fixed / a_controlled, std::stod(fixed["PT1_mean_barg"]),
      std::stod(controlled["PT1_mean_barg"]));
  EXPECT_GT(a_fixed, 0.2) << "the heave must move the BHP by tenths of a bar";
  // Measured: 22.7x, 22.4x, 18.3x (25.4x, 23.0x, 20.8x over the last 20 s of 80 s; 20-27x over
  // 40 s windows of 120 s, docs/service.md). A factor of 5 leaves room for tuning changes, not
  // for a controller that merely does no harm.
  EXPECT_GT(a_fixed / a_controlled, 5.0);
  // It holds the mean too: the set point learnt over whole periods after the settling, from the
  // choke as the rig had it (measured: within 0.0035, 0.0034 and 0.0034 bar; over 40 s windows
  // 0.002-0.007 bar, docs/service.md). Both means are over the same 20 s; the noise moves each by
  // 0.0005 bar (0.024 bar / sqrt(2000)).
  EXPECT_NEAR(std::stod(controlled["PT1_mean_barg"]), std::stod(fixed["PT1_mean_barg"]), 0.02);
}

INSTANTIATE_TEST_SUITE_P(LabNoise, BhpController,
                         ::testing::Values(Excitation{"slow_0p1Hz", "0.1", "5", "31", "1"},
                                           Excitation{"resonant_0p2Hz", "0.2", "5", "31", "2"},
                                           Excitation{"high_flow_0p15Hz", "0.15", "20", "45", "3"}),
                         [](const ::testing::TestParamInfo<Excitation>& info) {
                           return info.param.name;
                         });

// Two controllers on one rig: the choke's topic has exclusive ownership, so the strongest live
// writer's commands are the ones in force and the other's are dropped without a word; of two of
// equal strength one wins the tie by its GUID. The one that does not own the choke must say so
// and not end as if its summary were its own doing (exit 4); the owner exits 0. Before: both
// exited 0 with summaries of their commands.
TEST(BhpControllerOwnership, TheControllerThatDoesNotOwnTheChokeSaysSo) {
  const int claimed = testing::ClaimTestDomain();
  ASSERT_GT(claimed, 0);
  const std::string domain = std::to_string(claimed);
  testing::ChildProcess serve({MPDRIG_EXE, "serve", "--clock", "realtime", "--rate-hz", "100",
                               "--heave-amp-m", "0.05", "--heave-hz", "0.2", "--pump-lpm", "5",
                               "--choke-deg", "31", "--rig", "rig-1", "--domain", domain},
                              testing::ChildOptions::Quiet());
  ASSERT_TRUE(serve.started()) << serve.error();
  // --duration is the rig time to stop at: each pair runs about 7 s past the previous one.
  double until_s = 0.0;
  auto controller = [&](const char* strength, const std::string& err) {
    testing::ChildOptions options;
    options.out = testing::Output::Discard();
    options.err = testing::Output::File(err);
    return std::make_unique<testing::ChildProcess>(
        std::vector<std::string>{BHP_CONTROLLER_EXE, "--domain", domain, "--rig", "rig-1",
                                 "--setpoint-barg", "3.6", "--duration", std::to_string(until_s),
                                 "--timeout", "20", "--strength", strength},
        options);
  };
  const std::string dir = ::testing::TempDir();
  for (const auto& [a, b] : {std::pair{"20", "10"}, std::pair{"10", "10"}}) {
    SCOPED_TRACE(std::string("strengths ") + a + " and " + b);
    const std::string err_a = dir + "owner_a.err", err_b = dir + "owner_b.err";
    until_s += 8.0;
    auto first = controller(a, err_a);
    auto second = controller(b, err_b);
    ASSERT_TRUE(first->started() && second->started());
    const int code_a = first->Wait(60.0), code_b = second->Wait(60.0);
    const std::string said_a = testing::ReadFile(err_a), said_b = testing::ReadFile(err_b);
    // Exactly one owns the choke at the end: 0 and 4, in some order.
    EXPECT_EQ(std::min(code_a, code_b), 0) << said_a << said_b;
    EXPECT_EQ(std::max(code_a, code_b), 4) << said_a << said_b;
    const std::string& loser = code_a == 4 ? said_a : said_b;
    EXPECT_NE(loser.find("obeys another controller"), std::string::npos) << loser;
    if (std::string(a) != b) {
      EXPECT_EQ(code_a, 0) << "the stronger controller owns the choke: " << said_a;
    }
  }
}

}  // namespace
}  // namespace mpdrig
