// Independent tasks (a diagnosis's candidates) spread over the machine's cores.
#pragma once

#include <functional>
#include <vector>

namespace mpdrig::cli {

// Runs the tasks on one thread per core (at most one per task); unless quiet, says on stderr when
// each is done ("diagnose: candidate 3 of 10 fitted").
void RunOnEveryCore(const std::vector<std::function<void()>>& tasks, bool quiet);

}  // namespace mpdrig::cli
