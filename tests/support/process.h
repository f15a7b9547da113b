// A child process for tests (header-only). ChildProcess starts a program with arguments and extra
// environment variables, sends its stdout and stderr where the test wants them (inherited,
// discarded, into a file, or captured in memory through a pipe), waits for it with a timeout and
// signals it. When it goes out of scope it stops the child: its stop signal (SIGTERM unless
// chosen otherwise), SIGKILL after a grace period, then reaps it; so a test that fails or returns
// early leaves no process behind.
//
// Descriptors this process holds without O_CLOEXEC are inherited, on purpose: the DDS domain claim
// of tests/support/test_domain.h is one, so a `mpdrig serve` that outlives a crashed test (whose
// destructors never ran) keeps the domain claimed until it is gone too. The helper's own pipe ends
// are O_CLOEXEC, so no child holds another child's pipe open (its reader would never see EOF).
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

extern char** environ;

namespace mpdrig::testing {

// Where one of a child's output streams goes.
struct Output {
  enum class Kind { kInherit, kDiscard, kFile, kCapture, kStdout };
  Kind kind = Kind::kInherit;
  std::string path;  // kFile: created, or truncated if it exists

  static Output Inherit() { return {}; }
  static Output Discard() { return {Kind::kDiscard, ""}; }
  static Output File(std::string path) { return {Kind::kFile, std::move(path)}; }
  // Read while Wait or Stop runs, and by out()/err(). A child that writes more than a pipe holds
  // (64 KiB) while the test does none of these waits for it: large outputs belong in a file.
  static Output Capture() { return {Kind::kCapture, ""}; }
  // For stderr: wherever stdout goes (the shell's 2>&1).
  static Output SameAsStdout() { return {Kind::kStdout, ""}; }
};

struct ChildOptions {
  std::vector<std::string> env;  // "NAME=value", over (or added to) this process's environment
  Output out;
  Output err;
  int stop_signal = SIGTERM;  // what Stop() and the destructor send first
  double stop_grace_s = 5.0;  // then SIGKILL

  // stdout and stderr discarded.
  static ChildOptions Quiet() {
    ChildOptions options;
    options.out = Output::Discard();
    options.err = Output::Discard();
    return options;
  }
  // stdout and stderr together into the file at `path` (as `> path 2>&1`).
  static ChildOptions Log(std::string path) {
    ChildOptions options;
    options.out = Output::File(std::move(path));
    options.err = Output::SameAsStdout();
    return options;
  }
  // stdout inherited, stderr to `err`.
  static ChildOptions Stderr(Output err) {
    ChildOptions options;
    options.err = std::move(err);
    return options;
  }
};

class ChildProcess {
 public:
  // What Wait returns for a child still running at the timeout (or never started).
  static constexpr int kNoExit = -1;
  static constexpr double kForever = std::numeric_limits<double>::infinity();

  // args[0] is the program's path (no PATH search).
  explicit ChildProcess(std::vector<std::string> args, ChildOptions options = {})
      : options_(std::move(options)) {
    Start(std::move(args));
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() {
    Stop();
    CloseCaptures();
  }

  bool started() const { return started_; }
  const std::string& error() const { return error_; }  // why it did not start
  pid_t pid() const { return pid_; }                   // -1 once reaped

  // Sends `signal` to the child unless it has been reaped (whose pid may belong to another
  // process by now). False if it was not sent.
  bool Signal(int signal) { return pid_ > 0 && ::kill(pid_, signal) == 0; }

  // Waits up to `timeout_s` for the child to exit: its exit code, 128 + the signal that ended it
  // (as the shell reports it), or kNoExit if it is still running (it is left running).
  int Wait(double timeout_s = kForever) {
    const auto start = std::chrono::steady_clock::now();
    while (pid_ > 0) {
      // Nothing to drain and no deadline: block until it exits, seen at once.
      const bool block = timeout_s == kForever && read_ends_[0] < 0 && read_ends_[1] < 0;
      if (Reap(block ? 0 : WNOHANG)) break;
      const double left_s =
          timeout_s -
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left_s <= 0.0) return kNoExit;
      // Waiting on the capture pipes keeps them drained; 10 ms bounds how late an exit is seen.
      PollCaptures(left_s < 0.01 ? left_s : 0.01);
    }
    return status_;
  }

  // Stops the child: `signal`, then SIGKILL if it has not exited after `grace_s`; reaps it and
  // returns its status as Wait does. A child already reaped: its status.
  int Stop(int signal, double grace_s) {
    if (pid_ <= 0) return status_;
    if (signal != SIGKILL) {
      Signal(signal);
      Signal(SIGCONT);  // a child a test stopped (SIGSTOP) handles it too
      if (Wait(grace_s) != kNoExit) return status_;
    }
    Signal(SIGKILL);
    return Wait();
  }
  int Stop() { return Stop(options_.stop_signal, options_.stop_grace_s); }
  // SIGKILL at once, as a crash would end it, and reaped.
  int Kill() { return Stop(SIGKILL, 0.0); }

  // What the child wrote so far to a stream captured with Output::Capture().
  const std::string& out() {
    Drain();
    return captured_[0];
  }
  const std::string& err() {
    Drain();
    return captured_[1];
  }

 private:
  void Start(std::vector<std::string> args) {
    if (args.empty()) {
      error_ = "no program given";
      return;
    }
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);

    std::vector<std::string> env_strings;
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string entry = *e;
      const std::size_t eq = entry.find('=');
      const std::string name = entry.substr(0, eq == std::string::npos ? entry.size() : eq + 1);
      bool overridden = false;
      for (const std::string& o : options_.env) overridden = overridden || o.rfind(name, 0) == 0;
      if (!overridden) env_strings.push_back(entry);
    }
    env_strings.insert(env_strings.end(), options_.env.begin(), options_.env.end());
    std::vector<char*> envp;
    for (std::string& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    int write_ends[2] = {-1, -1};
    bool ok = Redirect(&actions, 1, options_.out, &read_ends_[0], &write_ends[0]) &&
              Redirect(&actions, 2, options_.err, &read_ends_[1], &write_ends[1]);
    // The child gets default handling of the signals Stop sends even if this process ignores
    // them (a shell starts background jobs with SIGINT ignored), and no blocked signals.
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    sigset_t defaults, none;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    if (options_.stop_signal != SIGKILL) sigaddset(&defaults, options_.stop_signal);
    sigemptyset(&none);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setsigmask(&attributes, &none);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
    if (!ok && error_.empty()) error_ = "cannot set up the output of " + args[0];
    if (ok) {
      const int spawned =
          posix_spawn(&pid_, argv[0], &actions, &attributes, argv.data(), envp.data());
      if (spawned != 0) {
        pid_ = -1;
        error_ = "cannot start " + args[0] + ": " + std::strerror(spawned);
      }
    }
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    for (int fd : write_ends) {
      if (fd >= 0) ::close(fd);
    }
    started_ = pid_ > 0;
    if (!started_) CloseCaptures();
  }

  // Adds the file action that sends descriptor `fd` to `output`.
  bool Redirect(posix_spawn_file_actions_t* actions, int fd, const Output& output, int* read_end,
                int* write_end) {
    switch (output.kind) {
      case Output::Kind::kInherit:
        return true;
      case Output::Kind::kDiscard:
        return posix_spawn_file_actions_addopen(actions, fd, "/dev/null", O_WRONLY, 0) == 0;
      case Output::Kind::kFile:
        return posix_spawn_file_actions_addopen(actions, fd, output.path.c_str(),
                                                O_WRONLY | O_CREAT | O_TRUNC, 0644) == 0;
      case Output::Kind::kStdout:
        return posix_spawn_file_actions_adddup2(actions, 1, fd) == 0;
      case Output::Kind::kCapture: {
        int ends[2];
        if (::pipe2(ends, O_CLOEXEC | O_NONBLOCK) != 0) {
          error_ = std::string("pipe: ") + std::strerror(errno);
          return false;
        }
        // The write end blocks in the child like any stdout; dup2 clears O_CLOEXEC on `fd`.
        ::fcntl(ends[1], F_SETFL, ::fcntl(ends[1], F_GETFL) & ~O_NONBLOCK);
        *read_end = ends[0];
        *write_end = ends[1];
        return posix_spawn_file_actions_adddup2(actions, ends[1], fd) == 0;
      }
    }
    return false;
  }

  // Reaps the child if it has exited; true then.
  bool Reap(int flags) {
    int status = 0;
    pid_t done;
    do {
      done = ::waitpid(pid_, &status, flags);
    } while (done < 0 && errno == EINTR);
    if (done < 0) {  // not ours to wait for any more (reaped elsewhere): nothing to report
      pid_ = -1;
      return true;
    }
    if (done != pid_) return false;
    pid_ = -1;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    Drain();  // what it wrote before it exited is still in the pipes
    return true;
  }

  // Waits up to `timeout_s` for output on the capture pipes (or just waits, without any) and
  // reads what is there.
  void PollCaptures(double timeout_s) {
    pollfd fds[2];
    nfds_t n = 0;
    for (int fd : read_ends_) {
      if (fd >= 0) fds[n++] = {fd, POLLIN, 0};
    }
    ::poll(fds, n, static_cast<int>(timeout_s * 1000.0) + 1);
    Drain();
  }

  void Drain() {
    char buffer[4096];
    for (int i = 0; i < 2; ++i) {
      while (read_ends_[i] >= 0) {
        const ssize_t n = ::read(read_ends_[i], buffer, sizeof buffer);
        if (n > 0) {
          captured_[i].append(buffer, static_cast<std::size_t>(n));
        } else if (n == 0) {  // every writer has closed it
          ::close(read_ends_[i]);
          read_ends_[i] = -1;
        } else if (errno != EINTR) {
          break;  // EAGAIN: nothing more for now
        }
      }
    }
  }

  void CloseCaptures() {
    for (int& fd : read_ends_) {
      if (fd >= 0) ::close(fd);
      fd = -1;
    }
  }

  ChildOptions options_;
  bool started_ = false;
  std::string error_;
  pid_t pid_ = -1;
  int status_ = kNoExit;
  int read_ends_[2] = {-1, -1};  // stdout, stderr when captured
  std::string captured_[2];
};

}  // namespace mpdrig::testing
