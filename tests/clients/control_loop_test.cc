// The client library's control loop (clients/client/control_loop.h) in this process, against a
// `mpdrig serve` process over loopback in a domain of the test's own: every way a run ends
// (its duration, the update's stop, a signal, the rig lost, the rig's clean end, another client
// stepping the rig), the signal handlers restored, and a lockstep run that is the same twice.
#include "clients/client/control_loop.h"

#include <signal.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "clients/rig_watch.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

using client::Commands;
using client::LoopEnd;
using client::LoopOptions;
using client::Tick;

std::unique_ptr<testing::ChildProcess> Serve(int domain, std::vector<std::string> extra) {
  std::vector<std::string> args = {
      MPDRIG_EXE,   "serve", "--rate-hz",   "100", "--domain",      std::to_string(domain),
      "--pump-lpm", "5",     "--choke-deg", "31",  "--heave-amp-m", "0.1",
      "--heave-hz", "0.2"};
  args.insert(args.end(), extra.begin(), extra.end());
  return std::make_unique<testing::ChildProcess>(args, testing::ChildOptions::Quiet());
}

std::unique_ptr<client::Rig> Connect(int domain, const std::string& rig_id, double timeout_s) {
  client::RigOptions options;
  options.rig_id = rig_id;
  options.domain = domain;
  options.timeout_s = timeout_s;
  auto rig = client::Rig::Connect(options);
  EXPECT_TRUE(rig.ok()) << rig.status().message();
  return rig.ok() ? std::move(rig).value() : nullptr;
}

// A rig whose loss `timeout_s` notices quickly, found with patience: a sanitizer build on a loaded
// machine can take longer than that short timeout to start the service and discover its status, so
// connecting is retried until `patience_s` (each attempt's failure is not the test's).
std::unique_ptr<client::Rig> ConnectPatiently(int domain, const std::string& rig_id,
                                              double timeout_s, double patience_s) {
  client::RigOptions options;
  options.rig_id = rig_id;
  options.domain = domain;
  options.timeout_s = timeout_s;
  const auto give_up = std::chrono::steady_clock::now() +
                       std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                           std::chrono::duration<double>(patience_s));
  while (true) {
    auto rig = client::Rig::Connect(options);
    if (rig.ok()) return std::move(rig).value();
    if (std::chrono::steady_clock::now() >= give_up) {
      ADD_FAILURE() << rig.status().message() << " (tried for " << patience_s << " s)";
      return nullptr;
    }
  }
}

std::atomic<int> g_own_handler_calls{0};
void OwnHandler(int) { ++g_own_handler_calls; }

// Lockstep: each tick is one step of 10 ms with the estimate of its own sample; the run ends after
// the tick at its duration (rig time), at the update's stop, or after the tick in progress when
// SIGINT comes (its commands sent), and the process's own handler is back afterwards.
TEST(ControlLoop, EndsAtItsDurationAStopOrASignalAfterTheTickInProgress) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, {"--clock", "lockstep", "--rig", "r1"});
  ASSERT_TRUE(serve->started()) << serve->error();
  auto rig = Connect(domain, "r1", 20.0);
  ASSERT_NE(rig, nullptr);

  LoopOptions options;
  options.duration_s = 1.0;
  options.estimates = LoopOptions::Estimates::kPaired;
  int paired = 0, steady = 0;
  auto result = client::RunController(*rig, options, [&](const Tick& t) {
    paired += t.estimate && t.estimate->sample_counter == t.sensors.sample_counter;
    steady += t.index == 0 ? t.dt_s == 0.0 : std::abs(t.dt_s - 0.01) < 1e-9;
    return Commands();
  });
  EXPECT_EQ(result.end, LoopEnd::kDuration) << result.message;
  EXPECT_EQ(result.ticks, 100u);  // t = 0.01 .. 1.00 s
  EXPECT_NEAR(result.last_time_s, 1.0, 1e-9);
  EXPECT_EQ(paired, 100);
  EXPECT_EQ(steady, 100);
  EXPECT_EQ(result.ExitCode(), 0);

  // A duration that is no rig time: an error at once, never a crash or a run without end.
  LoopOptions bad;
  bad.duration_s = -1.0;
  result = client::RunController(*rig, bad, [](const Tick&) { return Commands(); });
  EXPECT_EQ(result.end, LoopEnd::kError);
  EXPECT_EQ(result.ticks, 0u);
  EXPECT_NE(result.message.find("duration"), std::string::npos) << result.message;

  // The update's stop: its tick is the last.
  options.duration_s = 0.0;
  result = client::RunController(
      *rig, options, [](const Tick& t) { return t.index == 9 ? Commands::Stop() : Commands(); });
  EXPECT_EQ(result.end, LoopEnd::kStopped);
  EXPECT_EQ(result.ticks, 10u);
  EXPECT_EQ(result.ExitCode(), 0);

  // SIGINT in the fourth tick: that tick's choke command still goes out, then the run ends. The
  // process's handler is not called while the loop handles the signal, and is back after.
  struct sigaction own {};
  own.sa_handler = OwnHandler;
  sigemptyset(&own.sa_mask);
  struct sigaction before {};
  ASSERT_EQ(sigaction(SIGINT, &own, &before), 0);
  g_own_handler_calls = 0;
  result = client::RunController(*rig, options, [](const Tick& t) {
    if (t.index == 3) {
      raise(SIGINT);
      return Commands::Choke(45.0);
    }
    return Commands();
  });
  EXPECT_EQ(result.end, LoopEnd::kSignal);
  EXPECT_EQ(result.ticks, 4u);
  EXPECT_EQ(result.ExitCode(), 0);
  EXPECT_EQ(g_own_handler_calls, 0);
  raise(SIGINT);
  EXPECT_EQ(g_own_handler_calls, 1) << "the handler the loop replaced is restored";
  auto opened = rig->Step(300);
  ASSERT_TRUE(opened.ok()) << opened.status().message();
  EXPECT_NEAR(opened->choke_position_deg, 45.0, 0.5) << "the last tick's command was sent";

  // An interrupt of one's own (Python's Ctrl-C check) instead of the handlers: they stay.
  int asked = 0;
  options.interrupt = [&] { return ++asked > 5; };
  client::ControlLoop loop(*rig, options);
  raise(SIGINT);
  EXPECT_EQ(g_own_handler_calls, 2) << "with an interrupt the loop leaves the handlers alone";
  std::uint64_t ticks = 0;
  while (loop.Next()) ++ticks;
  EXPECT_EQ(loop.result().end, LoopEnd::kSignal);
  EXPECT_GT(ticks, 0u);
  sigaction(SIGINT, &before, nullptr);
}

// Every sample in order (a recorder, Python's stream): what a Step of one's own brought first,
// then one step per tick. Another client stepping the rig under a controller is an error.
TEST(ControlLoop, HandsOutEverySampleAndNoticesAnotherClientStepping) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, {"--clock", "lockstep", "--rig", "r1"});
  ASSERT_TRUE(serve->started()) << serve->error();
  auto rig = Connect(domain, "r1", 20.0);
  auto other = Connect(domain, "r1", 20.0);
  ASSERT_TRUE(rig && other);
  ASSERT_TRUE(rig->Step(5).ok());
  LoopOptions every;
  every.samples = LoopOptions::Samples::kEvery;
  client::ControlLoop recorder(*rig, every);
  std::vector<std::uint64_t> counters;
  for (int i = 0; i < 8; ++i) {
    auto tick = recorder.Next();
    ASSERT_TRUE(tick.has_value()) << recorder.result().message;
    counters.push_back(tick->sensors.sample_counter);
  }
  for (std::size_t i = 1; i < counters.size(); ++i) EXPECT_EQ(counters[i], counters[i - 1] + 1);
  EXPECT_NEAR(rig->LatestStatus()->sim_time_s, 0.08, 1e-9) << "5 steps, then 3 of the loop";

  auto result = client::RunController(*rig, LoopOptions(), [&](const Tick& t) {
    if (t.index == 4) (void)other->Step(1);
    return Commands();
  });
  EXPECT_EQ(result.end, LoopEnd::kError);
  EXPECT_NE(result.message.find("another client steps this rig"), std::string::npos)
      << result.message;
  EXPECT_EQ(result.ExitCode(), 1);
}

// The same lockstep run twice (a fresh service with the same noise seed each time): a controller
// on the loop sees and commands bit for bit the same, at the lab's noise, however loaded the
// machine is.
TEST(ControlLoop, ALockstepRunIsTheSameTwice) {
  std::vector<double> runs[2];
  for (std::vector<double>& trace : runs) {
    const int domain = testing::ClaimTestDomain();
    ASSERT_GT(domain, 0);
    auto serve = Serve(domain, {"--clock", "lockstep", "--rig", "r1", "--noise-seed", "9"});
    ASSERT_TRUE(serve->started()) << serve->error();
    auto rig = Connect(domain, "r1", 20.0);
    ASSERT_NE(rig, nullptr);
    LoopOptions options;
    options.duration_s = 3.0;
    options.estimates = LoopOptions::Estimates::kPaired;
    double integral = 31.0;
    const auto result = client::RunController(*rig, options, [&](const Tick& t) {
      const double e = t.estimate->BHP_est_barg - 3.66;
      integral += 0.05 * e * t.dt_s;
      trace.insert(trace.end(), {t.sensors.time_s, t.sensors.PT_barg[0],
                                 t.sensors.choke_position_deg, t.estimate->BHP_est_barg});
      return Commands::Choke(integral + 2.0 * e);
    });
    EXPECT_EQ(result.end, LoopEnd::kDuration) << result.message;
  }
  ASSERT_EQ(runs[0].size(), 4u * 300u);
  EXPECT_EQ(runs[0], runs[1]);
}

// A real-time rig killed under the loop (SIGKILL: no goodbye): lost after its timeout, exit 3.
// Stopped as asked (its --duration, 6 s: time to connect on a loaded machine): the rig's clean
// end, exit 3 too for a controller, whose run did not end as it asked.
TEST(ControlLoop, ARigLostOrEndedUnderTheLoopEndsTheRun) {
  const int domain = testing::ClaimTestDomain();
  ASSERT_GT(domain, 0);
  auto serve = Serve(domain, {"--clock", "realtime", "--rig", "r1"});
  ASSERT_TRUE(serve->started()) << serve->error();
  auto rig = ConnectPatiently(domain, "r1", 1.0, 20.0);
  ASSERT_NE(rig, nullptr);
  auto result = client::RunController(*rig, LoopOptions(), [&](const Tick& t) {
    if (t.index == 20) serve->Kill();
    return Commands();
  });
  EXPECT_EQ(result.end, LoopEnd::kRigLost);
  EXPECT_FALSE(result.message.empty());
  EXPECT_EQ(result.ExitCode(), clients::kExitRigLost);

  const int domain2 = testing::ClaimTestDomain();
  ASSERT_GT(domain2, 0);
  auto ending = Serve(domain2, {"--clock", "realtime", "--rig", "r1", "--duration", "6"});
  ASSERT_TRUE(ending->started()) << ending->error();
  auto rig2 = ConnectPatiently(domain2, "r1", 5.0, 6.0);
  ASSERT_NE(rig2, nullptr);
  result = client::RunController(*rig2, LoopOptions(), [](const Tick&) { return Commands(); });
  EXPECT_EQ(result.end, LoopEnd::kRigEnded) << result.message;
  EXPECT_EQ(result.ExitCode(), clients::kExitRigLost);
}

}  // namespace
}  // namespace mpdrig
