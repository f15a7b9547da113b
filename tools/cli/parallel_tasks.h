// Independent tasks (a diagnosis's candidates) spread over the machine's cores.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "model/common/tasks.h"

namespace mpdrig::cli {

// Runs tasks on one thread per core (at most one per task), the longest first: it remembers how
// long each kind of task took (Task::kind) and starts a call's tasks in the order of those times,
// longest first, kinds it has not seen before them in the order given. A diagnosis's rounds
// repeat the same kinds, and one candidate can cost five times another (the free gas model's):
// started last, it leaves the other core idle while it runs. The order changes no result.
class LongestFirstRunner {
 public:
  // `workers` threads at most (0: one per core); unless quiet, says on stderr when each task is
  // done and how long it took ("diagnose: candidate gas_entrainment done in 4.8 s (3 of 10)").
  explicit LongestFirstRunner(unsigned workers = 0, bool quiet = true);

  void Run(const std::vector<Task>& tasks);
  // As a model function's runner (DiagnoseOptions::run_tasks): shares this runner's memory.
  static TaskRunner Shared(unsigned workers, bool quiet);

  // The order Run starts `tasks` in: indices into it.
  std::vector<std::size_t> Order(const std::vector<Task>& tasks) const;

 private:
  unsigned workers_;
  bool quiet_;
  mutable std::mutex mutex_;
  std::unordered_map<std::string, double> seconds_;  // the last time of each kind
};

}  // namespace mpdrig::cli
