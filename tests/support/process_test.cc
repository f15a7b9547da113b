// The test helper ChildProcess (tests/support/process.h) with /bin/sh as the child: exit codes and
// signals as the shell reports them, a wait that times out, a child that ignores SIGTERM stopped
// and reaped by the destructor, the environment it is given, its output in a file or a pipe, and
// which descriptors it inherits (the DDS domain claim, not another child's pipe).
#include "tests/support/process.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/shell.h"
#include "tests/support/test_domain.h"

namespace mpdrig::testing {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Whether `pid` is a child of this process still to be reaped (an exited one not yet waited for
// counts too).
bool IsUnreapedChild(pid_t pid) {
  int status = 0;
  return ::waitpid(pid, &status, WNOHANG) >= 0 || errno != ECHILD;
}

// The targets of the descriptors process `pid` has open.
std::vector<std::string> OpenFiles(pid_t pid) {
  std::vector<std::string> targets;
  for (const auto& entry :
       std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/fd")) {
    std::error_code error;
    const auto target = std::filesystem::read_symlink(entry.path(), error);
    if (!error) targets.push_back(target.string());
  }
  return targets;
}

bool Contains(const std::vector<std::string>& list, const std::string& item) {
  return std::find(list.begin(), list.end(), item) != list.end();
}

TEST(ChildProcess, ReportsTheExitCodeOrTheSignalAsTheShellDoes) {
  ChildProcess exits({"/bin/sh", "-c", "exit 7"});
  ASSERT_TRUE(exits.started()) << exits.error();
  EXPECT_EQ(exits.Wait(30.0), 7);
  EXPECT_EQ(exits.pid(), -1) << "reaped";
  EXPECT_EQ(exits.Wait(), 7) << "the status stays";
  EXPECT_FALSE(exits.Signal(SIGTERM)) << "no signal to a reaped pid";

  ChildProcess killed({"/bin/sh", "-c", "kill -KILL $$"});
  ASSERT_TRUE(killed.started());
  EXPECT_EQ(killed.Wait(30.0), 128 + SIGKILL);
}

TEST(ChildProcess, ProgramThatDoesNotExistIsNotStartedAndSaysWhy) {
  ChildProcess missing({"/nonexistent/program", "--flag"});
  EXPECT_FALSE(missing.started());
  EXPECT_NE(missing.error().find("/nonexistent/program"), std::string::npos) << missing.error();
  EXPECT_EQ(missing.Wait(1.0), ChildProcess::kNoExit);
  EXPECT_FALSE(missing.Signal(SIGTERM));
}

TEST(ChildProcess, WaitReturnsAtItsTimeoutAndLeavesTheChildRunning) {
  ChildProcess sleeper({"/bin/sleep", "30"});
  ASSERT_TRUE(sleeper.started()) << sleeper.error();
  const auto start = Clock::now();
  EXPECT_EQ(sleeper.Wait(0.3), ChildProcess::kNoExit);
  const double waited_s = SecondsSince(start);
  EXPECT_GE(waited_s, 0.3);
  EXPECT_LT(waited_s, 5.0) << "far below the child's 30 s";
  EXPECT_TRUE(IsUnreapedChild(sleeper.pid()));
  EXPECT_TRUE(sleeper.Signal(SIGTERM));
  EXPECT_EQ(sleeper.Wait(30.0), 128 + SIGTERM);
}

TEST(ChildProcess, StopEndsAChildThatIgnoresItsSignalWithSigkill) {
  ChildOptions options;
  options.out = Output::Capture();
  ChildProcess stubborn({"/bin/sh", "-c", "trap '' TERM; echo ready; exec sleep 30"}, options);
  ASSERT_TRUE(stubborn.started());
  for (int i = 0; i < 3000 && stubborn.out().empty(); ++i) stubborn.Wait(0.01);
  ASSERT_EQ(stubborn.out(), "ready\n");
  const auto start = Clock::now();
  EXPECT_EQ(stubborn.Stop(SIGTERM, 0.5), 128 + SIGKILL);
  EXPECT_GE(SecondsSince(start), 0.5) << "SIGTERM first, SIGKILL after the grace";
}

TEST(ChildProcess, DestructorStopsAndReapsAChildThatIgnoresSigterm) {
  pid_t pid = -1;
  {
    ChildOptions options;
    options.out = Output::Capture();
    options.stop_grace_s = 0.5;
    ChildProcess stubborn({"/bin/sh", "-c", "trap '' TERM; echo ready; exec sleep 30"}, options);
    ASSERT_TRUE(stubborn.started());
    pid = stubborn.pid();
    for (int i = 0; i < 3000 && stubborn.out().empty(); ++i) stubborn.Wait(0.01);
    ASSERT_EQ(stubborn.out(), "ready\n");
    // It does ignore SIGTERM: still running after it.
    ASSERT_TRUE(stubborn.Signal(SIGTERM));
    EXPECT_EQ(stubborn.Wait(0.3), ChildProcess::kNoExit);
  }
  EXPECT_FALSE(IsUnreapedChild(pid)) << "the destructor left pid " << pid << " behind";
  EXPECT_NE(::kill(pid, 0), 0) << "pid " << pid << " still exists";
}

TEST(ChildProcess, ChildSeesItsExtraVariablesOverThisProcesssEnvironment) {
  ASSERT_EQ(::setenv("MPDRIG_PROCESS_TEST_KEPT", "inherited", 1), 0);
  ASSERT_EQ(::setenv("MPDRIG_PROCESS_TEST_REPLACED", "old", 1), 0);
  ChildOptions options;
  options.env = {"MPDRIG_PROCESS_TEST_REPLACED=new", "MPDRIG_PROCESS_TEST_ADDED=added"};
  options.out = Output::Capture();
  ChildProcess child({"/bin/sh", "-c",
                      "printf '%s %s %s' \"$MPDRIG_PROCESS_TEST_KEPT\" "
                      "\"$MPDRIG_PROCESS_TEST_REPLACED\" \"$MPDRIG_PROCESS_TEST_ADDED\""},
                     options);
  ASSERT_TRUE(child.started());
  EXPECT_EQ(child.Wait(30.0), 0);
  EXPECT_EQ(child.out(), "inherited new added");
  ChildProcess count({"/bin/sh", "-c", "env | grep -c '^MPDRIG_PROCESS_TEST_REPLACED='"}, options);
  EXPECT_EQ(count.Wait(30.0), 0);
  EXPECT_EQ(count.out(), "1\n") << "a replaced variable is there once";
  ::unsetenv("MPDRIG_PROCESS_TEST_KEPT");
  ::unsetenv("MPDRIG_PROCESS_TEST_REPLACED");
}

TEST(ChildProcess, OutputGoesToAFileOrIsCaptured) {
  const std::filesystem::path dir = TestTempDir("process_test_");
  const std::string script = "echo out; echo err >&2";
  {
    ChildOptions options;
    options.out = Output::File((dir / "both.txt").string());
    options.err = Output::SameAsStdout();
    ChildProcess child({"/bin/sh", "-c", script}, options);
    EXPECT_EQ(child.Wait(30.0), 0);
    EXPECT_EQ(ReadFile(dir / "both.txt"), "out\nerr\n");
  }
  {
    ChildOptions options;
    options.out = Output::Capture();
    options.err = Output::Capture();
    ChildProcess child({"/bin/sh", "-c", script}, options);
    EXPECT_EQ(child.Wait(30.0), 0);
    EXPECT_EQ(child.out(), "out\n");
    EXPECT_EQ(child.err(), "err\n");
  }
  {
    ChildOptions options;
    options.out = Output::Discard();
    options.err = Output::File((dir / "err.txt").string());
    ChildProcess child({"/bin/sh", "-c", script}, options);
    EXPECT_EQ(child.Wait(30.0), 0);
    EXPECT_EQ(ReadFile(dir / "err.txt"), "err\n");
  }
  // More than a pipe holds: Wait reads while it waits, so the child never blocks on it.
  ChildOptions options;
  options.out = Output::Capture();
  ChildProcess large({"/bin/sh", "-c", "head -c 1000000 /dev/zero"}, options);
  EXPECT_EQ(large.Wait(30.0), 0);
  EXPECT_EQ(large.out().size(), 1000000u);
  std::filesystem::remove_all(dir);
}

// The DDS domain claim reaches the child (so an orphaned service keeps its domain); one child's
// capture pipe does not reach another child.
TEST(ChildProcess, ChildInheritsTheDomainClaimButNoOtherChildsPipe) {
  const int domain = ClaimTestDomain();
  ASSERT_GT(domain, 0);
  const std::string lock = std::filesystem::temp_directory_path().string() +
                           "/mpdrig-test-dds-domain-" + std::to_string(domain) + ".lock";
  ChildOptions captured;
  captured.out = Output::Capture();
  ChildProcess first({"/bin/sleep", "30"}, captured);
  ChildProcess second({"/bin/sleep", "30"});
  ASSERT_TRUE(first.started() && second.started());
  const std::vector<std::string> first_files = OpenFiles(first.pid());
  const std::vector<std::string> second_files = OpenFiles(second.pid());
  EXPECT_TRUE(Contains(first_files, lock)) << lock;
  EXPECT_TRUE(Contains(second_files, lock)) << lock;
  const auto pipe = std::filesystem::read_symlink("/proc/" + std::to_string(first.pid()) + "/fd/1");
  ASSERT_EQ(pipe.string().rfind("pipe:", 0), 0u) << pipe;
  EXPECT_FALSE(Contains(second_files, pipe.string())) << "the second child holds " << pipe;
}

}  // namespace
}  // namespace mpdrig::testing
