// hello_controller (clients/examples/hello_controller.cc: at most 60 lines, an update for the
// client library's control loop) against `mpdrig serve` at the lab's sensor noise (serve's
// default, thesis Table 4.1.1), two rigs of one service under the same heave: `controlled` under
// hello_controller, `fixed` with the choke left where it is. PT1's periodic swing (harmonics 1-3
// of the heave, least squares: client::HeaveFit, as bhp_controller's summary) over the last 20 s
// must be at least 5x smaller under control, around the same mean, in lockstep and in real time.
// The test reads both rigs itself, every sample, through the client library.
#include <signal.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "clients/client/heave_control.h"
#include "clients/client/rig_client.h"
#include "tests/support/process.h"
#include "tests/support/shell.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

constexpr double kWindowS = 20.0;

// PT1 over a rig's window (end - kWindowS, end]: its periodic part at the heave frequency and its
// mean.
struct Swing {
  client::HeaveFit fit;
  double sum = 0.0;
  long n = 0;
  void Add(const client::Sensors& s, double end_s, double heave_hz) {
    if (s.time_s <= end_s - kWindowS || s.time_s > end_s + 1e-9) return;
    fit.Add(s.time_s, s.PT_barg[0], heave_hz);
    sum += s.PT_barg[0];
    ++n;
  }
  double rms() const { return fit.Amplitudes().second; }
  double mean() const { return sum / static_cast<double>(n); }
};

std::unique_ptr<client::Rig> Reader(int domain, const std::string& rig_id) {
  client::RigOptions options;
  options.rig_id = rig_id;
  options.domain = domain;
  options.timeout_s = 30.0;
  options.keep_every_sample = true;  // every sample, from before the controller starts
  options.read_estimates = options.read_profiles = false;
  auto rig = client::Rig::Connect(options);
  EXPECT_TRUE(rig.ok()) << rig.status().message();
  return rig.ok() ? std::move(rig).value() : nullptr;
}

struct Heave {
  const char* name;
  const char* heave_hz;
  const char* pump_lpm;
  const char* choke_deg;
  const char* noise_seed;
  // How far the held mean may be from the fixed rig's (see ExpectAttenuated).
  double mean_tolerance_bar;
};

void PrintTo(const Heave& h, std::ostream* os) {
  *os << h.heave_hz << " Hz, " << h.pump_lpm << " L/min, " << h.choke_deg << " deg, seed "
      << h.noise_seed;
}

std::unique_ptr<testing::ChildProcess> Serve(int domain, const char* clock, const Heave& h) {
  return std::make_unique<testing::ChildProcess>(
      std::vector<std::string>{MPDRIG_EXE,      "serve",
                               "--clock",       clock,
                               "--rate-hz",     "100",
                               "--heave-amp-m", "0.1",
                               "--heave-hz",    h.heave_hz,
                               "--pump-lpm",    h.pump_lpm,
                               "--choke-deg",   h.choke_deg,
                               "--noise-seed",  h.noise_seed,
                               "--rig",         "fixed",
                               "--rig",         "controlled",
                               "--domain",      std::to_string(domain)},
      testing::ChildOptions::Quiet());
}

std::unique_ptr<testing::ChildProcess> Hello(int domain, const std::string& err,
                                             std::vector<std::string> extra) {
  std::vector<std::string> args = {HELLO_CONTROLLER_EXE, "--rig", "controlled", "--domain",
                                   std::to_string(domain)};
  args.insert(args.end(), extra.begin(), extra.end());
  testing::ChildOptions options;
  options.out = testing::Output::Discard();
  options.err = testing::Output::File(err);
  options.stop_signal = SIGINT;
  return std::make_unique<testing::ChildProcess>(args, options);
}

void ExpectAttenuated(const Swing& fixed, const Swing& controlled, const char* clock,
                      double mean_tolerance_bar) {
  std::printf(
      "%s: PT1 periodic RMS fixed choke %.4f bar, hello_controller %.4f bar, ratio %.1f; means "
      "%.4f / %.4f barg; %ld / %ld samples\n",
      clock, fixed.rms(), controlled.rms(), fixed.rms() / controlled.rms(), fixed.mean(),
      controlled.mean(), fixed.n, controlled.n);
  // Every sample of the 20 s at 100 Hz (the window's edges may fall either side of a sample).
  EXPECT_NEAR(fixed.n, 2000, 1);
  EXPECT_NEAR(controlled.n, 2000, 1);
  EXPECT_GT(fixed.rms(), 0.2) << "the heave must move the BHP by tenths of a bar";
  // PI alone: 0.98x (docs/service.md); bhp_controller 20-27x. 5x is the bar.
  EXPECT_GT(fixed.rms() / controlled.rms(), 5.0);
  // The set point is the mean BHP_est over whole heave periods with the choke left alone
  // (client::SetpointLearner); the noise moves each 20 s mean by 0.0005 bar (0.024 / sqrt(2000)).
  EXPECT_NEAR(controlled.mean(), fixed.mean(), mean_tolerance_bar);
}

TEST(HelloController, IsAtMostSixtyLines) {
  std::ifstream file(std::string(MPDRIG_SOURCE_DIR) + "/clients/examples/hello_controller.cc");
  ASSERT_TRUE(file.good());
  int lines = 0;
  for (std::string line; std::getline(file, line);) ++lines;
  EXPECT_LE(lines, 60);
}

// A signal to the process (Ctrl-C, or SIGTERM from a supervisor) while it steps a lockstep rig:
// it stops after the tick in progress (the rig stands at the time it reports, or one step past
// it when the signal cut a step's wait short), says so and exits 0.
TEST(HelloController, StopsAfterTheTickInProgressAtSigintAndSigterm) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, "lockstep", Heave{"demo", "0.2", "5", "31", "14", 0.0});
  ASSERT_TRUE(serve->started()) << serve->error();
  auto rig = Reader(domain, "controlled");
  ASSERT_NE(rig, nullptr);
  const std::string dir = testing::TestTempDir("hello_signal_").string();
  double until_s = 0.0;
  for (const int signal : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(signal == SIGINT ? "SIGINT" : "SIGTERM");
    const std::string err = dir + "/hello" + std::to_string(signal) + ".err";
    auto hello = Hello(domain, err, {});
    ASSERT_TRUE(hello->started());
    until_s += 1.0;  // the rig moves only while hello steps it: then hello is in its loop
    for (double t = 0.0; t < until_s;) {
      auto s = rig->Next();
      ASSERT_TRUE(s.ok()) << s.status().message() << "\n" << testing::ReadFile(err);
      t = s->time_s;
    }
    ASSERT_TRUE(hello->Signal(signal));
    EXPECT_EQ(hello->Wait(10.0), 0) << testing::ReadFile(err);
    const std::string said = testing::ReadFile(err);
    const auto at = said.find("hello_controller: signal at rig time ");
    ASSERT_NE(at, std::string::npos) << said;
    const double stopped_s = std::stod(said.substr(at + 37));
    auto status = rig->LatestStatus();
    ASSERT_TRUE(status.ok());
    EXPECT_GE(status->sim_time_s, stopped_s - 0.006) << said;
    EXPECT_LE(status->sim_time_s, stopped_s + 0.016) << said;
    until_s = status->sim_time_s + 0.5;
  }
}

class HelloControllerLockstep : public ::testing::TestWithParam<Heave> {};

// 65 s of rig time: 20-25 s to watch and learn the set point, about 20 s for the canceller to
// converge (the swing over 20 s windows of the demo's heave, lockstep: 12.9x from 30 s, 20.8x
// from 40 s, 22.2x from 45 s and 60 s), the last 20 s measured. The test steps the fixed rig;
// hello_controller its own.
TEST_P(HelloControllerLockstep, HoldsTheBhpSwingFiveTimesBelowTheFixedChokes) {
  const Heave& h = GetParam();
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, "lockstep", h);
  ASSERT_TRUE(serve->started()) << serve->error();
  auto fixed_rig = Reader(domain, "fixed");
  auto controlled_rig = Reader(domain, "controlled");
  ASSERT_TRUE(fixed_rig && controlled_rig);
  const double end_s = 65.0, heave_hz = std::stod(h.heave_hz);
  const std::string err = (testing::TestTempDir("hello_lockstep_") / "hello.err").string();
  auto hello = Hello(domain, err, {"--duration", "65"});
  ASSERT_TRUE(hello->started());

  Swing fixed, controlled;
  for (double t = 0.0; t < end_s - 1e-9;) {
    ASSERT_TRUE(fixed_rig->Step(100).ok());
    auto arrived = fixed_rig->TakeArrived();
    ASSERT_TRUE(arrived.ok()) << arrived.status().message();
    for (const client::Sensors& s : *arrived) fixed.Add(s, end_s, heave_hz), t = s.time_s;
  }
  for (double t = 0.0; t < end_s - 1e-9;) {
    auto s = controlled_rig->Next();
    ASSERT_TRUE(s.ok()) << s.status().message() << "\n" << testing::ReadFile(err);
    controlled.Add(*s, end_s, heave_hz);
    t = s->time_s;
  }
  EXPECT_EQ(hello->Wait(60.0), 0) << testing::ReadFile(err);
  EXPECT_NE(testing::ReadFile(err).find("duration at rig time 65.00 s"), std::string::npos)
      << testing::ReadFile(err);
  ExpectAttenuated(fixed, controlled, "lockstep", h.mean_tolerance_bar);
}

// The demo's heave (deploy/demo.sh), and a slower one at a higher flow whose 10 s learning window
// is not a whole number of periods (0.12 Hz: one period of 8.3 s, after 16.7 s). There the set
// point is learnt while the rig has not settled: the fixed rig's own PT1 mean still drifts (3.8926
// barg over 45-65 s, 3.9165 over 60-80 s; one-period means of 3.91, 3.87, 3.91 barg over 10-17,
// 17-25, 25-33 s), and the held mean came out 0.026 bar below the fixed rig's over 45-65 s
// (bhp_controller's the same: set point 3.8643 barg on that service and seed), so that case
// allows 0.08 bar. The swing is the point.
INSTANTIATE_TEST_SUITE_P(
    LabNoise, HelloControllerLockstep,
    ::testing::Values(Heave{"demo_0p2Hz", "0.2", "5", "31", "11", 0.02},
                      Heave{"high_flow_0p12Hz", "0.12", "20", "45", "12", 0.08}),
    [](const ::testing::TestParamInfo<Heave>& info) { return info.param.name; });

// Real time, the demo's heave: hello_controller runs until Ctrl-C, which the test sends once the
// rig is past 65 s; it must end after the tick in progress, exit 0 and say so. About 66 s of wall
// time.
TEST(HelloControllerRealTime, HoldsTheBhpSwingFiveTimesBelowTheFixedChokesAndStopsAtCtrlC) {
  const Heave h{"demo", "0.2", "5", "31", "13", 0.02};
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, "realtime", h);
  ASSERT_TRUE(serve->started()) << serve->error();
  auto fixed_rig = Reader(domain, "fixed");
  auto controlled_rig = Reader(domain, "controlled");
  ASSERT_TRUE(fixed_rig && controlled_rig);
  const double end_s = 65.0, heave_hz = 0.2;
  const std::string err = (testing::TestTempDir("hello_realtime_") / "hello.err").string();
  auto hello = Hello(domain, err, {});
  ASSERT_TRUE(hello->started());

  Swing fixed, controlled;
  for (double t = 0.0; t < end_s - 1e-9;) {
    auto s = controlled_rig->Next();
    ASSERT_TRUE(s.ok()) << s.status().message() << "\n" << testing::ReadFile(err);
    controlled.Add(*s, end_s, heave_hz);
    t = s->time_s;
  }
  hello->Signal(SIGINT);
  EXPECT_EQ(hello->Wait(10.0), 0) << testing::ReadFile(err);
  EXPECT_NE(testing::ReadFile(err).find("hello_controller: signal at rig time"), std::string::npos)
      << testing::ReadFile(err);
  auto arrived = fixed_rig->TakeArrived();
  ASSERT_TRUE(arrived.ok()) << arrived.status().message();
  for (const client::Sensors& s : *arrived) fixed.Add(s, end_s, heave_hz);
  ExpectAttenuated(fixed, controlled, "real time", h.mean_tolerance_bar);
}

}  // namespace
}  // namespace mpdrig
