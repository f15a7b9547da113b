// Independent pieces of work a model function hands to its caller (design.md: the model has no
// threads; the command line runs them on every core).
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace mpdrig {

struct Task {
  // What the work is, named the same for the same work in a later call of the same function
  // ("candidate gas_entrainment", "polish hose_compliance"): a runner may start first what took
  // longest before, which shortens the wall time of tasks spread over cores (the longest job
  // last leaves the other cores idle). A task's result never depends on the order.
  std::string kind;
  std::function<void()> run;
};

// Runs every task to completion, in any order and on any threads. The tasks share nothing
// mutable; each writes only its own result.
using TaskRunner = std::function<void(const std::vector<Task>&)>;

// Each task in turn, on the calling thread (what a model function does without a runner).
inline void RunInTurn(const std::vector<Task>& tasks) {
  for (const Task& task : tasks) task.run();
}

}  // namespace mpdrig
