// The clients' rule for a lost rig (clients/rig_watch.h): bhp_controller and rig_echo against a
// real `mpdrig serve` that is killed, restarted or stopped under them. Each must say why and exit
// with status 3 (kExitRigLost), never 0 with its normal summary and never carry on across a
// restart. Processes over loopback DDS, a domain of the test's own.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "model/riglog/rig_log.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"
#include "tests/support/process.h"
#include "tests/support/shell.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

using Clock = std::chrono::steady_clock;

class RigLost : public ::testing::Test {
 protected:
  void SetUp() override {
    const int claimed = testing::ClaimTestDomain();
    ASSERT_GT(claimed, 0);
    domain_ = std::to_string(claimed);
    dir_ = testing::TestTempDir("rig_lost_");
  }
  std::vector<std::string> Serve() const {
    return {MPDRIG_EXE, "serve", "--clock", "realtime",   "--rate-hz", "100",         "--domain",
            domain_,    "--rig", "rig-1",   "--pump-lpm", "5",         "--choke-deg", "31"};
  }
  std::vector<std::string> Controller(const std::string& timeout_s) const {
    return {BHP_CONTROLLER_EXE, "--rig", "rig-1", "--domain", domain_, "--timeout", timeout_s};
  }
  std::vector<std::string> Echo(const std::string& timeout_s) const {
    return {RIG_ECHO_EXE, "--rig", "rig-1",
            "--domain",   domain_, "--timeout",
            timeout_s,    "--out", (dir_ / "echo.csv").string()};
  }
  // stdout and stderr of a process into the file `name` of the test's directory, which
  // Output(name) reads.
  testing::ChildOptions Log(const char* name) const {
    return testing::ChildOptions::Log((dir_ / name).string());
  }
  std::string Output(const char* name) const { return testing::ReadFile(dir_ / name); }
  // Until `mpdrig serve` says it serves (its banner, on stderr, once its DDS entities exist; its
  // samples follow at once), up to 30 s. A client whose --timeout is short also gives up on a
  // first sample that is that late, which a slow start (a sanitizer build under load) can be.
  void AwaitServing() const {
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (Output("serve.txt").find("stop with Ctrl-C") == std::string::npos &&
           Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  // The recording up to the loss is a rig log the model reads, ending on a whole row.
  void ExpectReadableRecording() const {
    auto read = riglog::ReadRigLog((dir_ / "echo.csv").string());
    ASSERT_TRUE(read.ok()) << read.status().message();
    EXPECT_GT(read->num_rows(), 50u) << "about 3 s at 100 Hz were recorded";
  }

  std::string domain_;
  std::filesystem::path dir_;
};

// kill -9 of the service: both clients notice within their --timeout (1 s) plus the 100 ms of
// their wait, and exit 3. Before: bhp_controller waited its timeout and exited 0 with its summary.
TEST_F(RigLost, KilledServiceMakesTheClientsExitWithRigLost) {
  testing::ChildProcess serve(Serve(), Log("serve.txt"));
  ASSERT_TRUE(serve.started());
  AwaitServing();  // the clients' 1 s timeout is for a lost rig, not for the service's start
  testing::ChildProcess controller(Controller("1"), Log("controller.txt"));
  testing::ChildProcess echo(Echo("1"), Log("echo.txt"));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  serve.Signal(SIGKILL);
  const auto killed = Clock::now();
  const int controller_code = controller.Wait(10.0);
  const double controller_s = std::chrono::duration<double>(Clock::now() - killed).count();
  EXPECT_EQ(controller_code, 3) << Output("controller.txt");
  EXPECT_NE(Output("controller.txt").find("rig rig-1 lost: no sample for"), std::string::npos)
      << Output("controller.txt");
  EXPECT_EQ(Output("controller.txt").find("rig=rig-1 "), std::string::npos)
      << "no summary line as if the run had ended well";
  std::printf("bhp_controller noticed the killed service after %.2f s\n", controller_s);
  // The timeout (1 s) plus slack for a loaded machine; far below the 10 s lease.
  EXPECT_GE(controller_s, 0.9);
  EXPECT_LT(controller_s, 5.0);
  EXPECT_EQ(echo.Wait(10.0), 3) << Output("echo.txt");
  EXPECT_NE(Output("echo.txt").find("rig rig-1 lost"), std::string::npos) << Output("echo.txt");
  ExpectReadableRecording();
}

// A killed service never disposes its rig's status: a recorder that waits for ever (--timeout 0)
// learns of the loss only when the service's lease ends (10 s), and then it is a loss (exit 3),
// not the clean end of a run (a status writer that disposed on going made it exit 0 "complete").
TEST_F(RigLost, AKilledServiceIsNotACleanEndEvenAfterItsLease) {
  testing::ChildProcess serve(Serve(), Log("serve.txt"));
  ASSERT_TRUE(serve.started());
  testing::ChildProcess echo(Echo("0"), Log("echo.txt"));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  serve.Signal(SIGKILL);
  EXPECT_EQ(echo.Wait(20.0), 3) << Output("echo.txt");
  EXPECT_EQ(Output("echo.txt").find("the recording is complete"), std::string::npos)
      << Output("echo.txt");
  EXPECT_NE(Output("echo.txt").find("the rig's service left"), std::string::npos)
      << Output("echo.txt");
  ExpectReadableRecording();
}

// The service restarts within the clients' timeout: the rig's time goes back to 0. Both clients
// say so and exit 3 instead of going on with the old run's state. Before: the controller went on
// without noticing.
TEST_F(RigLost, RestartedServiceIsNoticedByTheRigTimeGoingBack) {
  auto serve = std::make_unique<testing::ChildProcess>(Serve(), Log("serve.txt"));
  ASSERT_TRUE(serve->started());
  testing::ChildProcess controller(Controller("8"), Log("controller.txt"));
  testing::ChildProcess echo(Echo("8"), Log("echo.txt"));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  serve->Signal(SIGKILL);
  serve.reset();
  testing::ChildProcess again(Serve(), Log("serve2.txt"));
  ASSERT_TRUE(again.started());
  EXPECT_EQ(controller.Wait(15.0), 3) << Output("controller.txt");
  EXPECT_NE(Output("controller.txt").find("rig time went back from"), std::string::npos)
      << Output("controller.txt");
  EXPECT_EQ(echo.Wait(15.0), 3) << Output("echo.txt");
  EXPECT_NE(Output("echo.txt").find("rig time went back from"), std::string::npos)
      << Output("echo.txt");
  ExpectReadableRecording();
}

// A service that stops cleanly (SIGTERM) ends its rig's run: it disposes the rig's status and
// takes its sensor writer with it. The clients notice at once, long before their --timeout of
// 30 s: the controller's run did not end as asked (exit 3), the recording is complete (exit 0;
// before, rig_echo exited 3 as if the rig had crashed).
TEST_F(RigLost, StoppedServiceIsNoticedByItsWriterLeaving) {
  testing::ChildProcess serve(Serve(), Log("serve.txt"));
  ASSERT_TRUE(serve.started());
  testing::ChildProcess controller(Controller("30"), Log("controller.txt"));
  testing::ChildProcess echo(Echo("30"), Log("echo.txt"));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  serve.Signal(SIGTERM);
  const auto stopped = Clock::now();
  EXPECT_EQ(controller.Wait(10.0), 3) << Output("controller.txt");
  const double noticed_s = std::chrono::duration<double>(Clock::now() - stopped).count();
  std::printf("bhp_controller noticed the stopped service after %.2f s\n", noticed_s);
  // Measured well under a second; 5 s leaves room for a loaded machine and is far from 30 s.
  EXPECT_LT(noticed_s, 5.0);
  EXPECT_NE(Output("controller.txt").find("the rig's service ended its run"), std::string::npos)
      << Output("controller.txt");
  EXPECT_EQ(echo.Wait(10.0), 0) << Output("echo.txt");
  EXPECT_NE(Output("echo.txt").find("the recording is complete"), std::string::npos)
      << Output("echo.txt");
  ExpectReadableRecording();
}

// Without --security anyone on the domain can write a sensor sample. One forged sample (counter
// 1e9, rig time 1e6 s) is no evidence that the service restarted: both clients go on, and the
// recording holds no row of it. Before: both exited 3 ("rig time went back") at the rig's next
// genuine sample.
TEST_F(RigLost, AStraySampleOfAnotherWriterIsNoEvidenceOfARestart) {
  testing::ChildProcess serve(Serve(), Log("serve.txt"));
  ASSERT_TRUE(serve.started());
  testing::ChildProcess controller(Controller("8"), Log("controller.txt"));
  testing::ChildProcess echo(Echo("8"), Log("echo.txt"));
  std::this_thread::sleep_for(std::chrono::seconds(3));

  const int domain = std::stoi(domain_);
  auto dds_domain = dds::Domain::Create(domain, dds::LoopbackConfig());
  ASSERT_TRUE(dds_domain.ok()) << dds_domain.status().message();
  auto participant = dds::CreateParticipant(domain);
  ASSERT_TRUE(participant.ok());
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kSensors);
  ASSERT_TRUE(topic.ok());
  auto forger = dds::Writer<mpdrig_RigSensors>::Create(participant->handle(), topic->handle(),
                                                       dds::SensorQos());
  ASSERT_TRUE(forger.ok());
  // The forged sample must reach both clients: wait until their readers have matched.
  for (int i = 0; i < 100; ++i) {
    dds_publication_matched_status_t matched{};
    dds_get_publication_matched_status(forger->handle(), &matched);
    if (matched.current_count >= 2) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  mpdrig_RigSensors forged{};
  forged.rig_id = const_cast<char*>("rig-1");
  forged.sample_counter = 1000000000ull;
  forged.sim_time_s = 1e6;
  ASSERT_TRUE(forger->Write(forged).ok());
  std::this_thread::sleep_for(std::chrono::seconds(2));
  EXPECT_EQ(controller.Wait(0.0), testing::ChildProcess::kNoExit) << Output("controller.txt");
  EXPECT_EQ(echo.Wait(0.0), testing::ChildProcess::kNoExit) << Output("echo.txt");

  serve.Signal(SIGTERM);  // the genuine end: both notice and say so
  EXPECT_EQ(controller.Wait(10.0), 3) << Output("controller.txt");
  EXPECT_NE(Output("controller.txt").find("the rig's service ended its run"), std::string::npos)
      << Output("controller.txt");
  EXPECT_EQ(echo.Wait(10.0), 0) << Output("echo.txt");
  ExpectReadableRecording();
  auto read = riglog::ReadRigLog((dir_ / "echo.csv").string());
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_LT(read->time_s.back(), 100.0) << "the forged sample was recorded";
}

}  // namespace
}  // namespace mpdrig
