#include "tools/cli/parallel_tasks.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <thread>

namespace mpdrig::cli {

void RunOnEveryCore(const std::vector<std::function<void()>>& tasks, bool quiet) {
  std::atomic<std::size_t> next{0}, done{0};
  const unsigned workers = std::max(1u, std::min<unsigned>(std::thread::hardware_concurrency(),
                                                           static_cast<unsigned>(tasks.size())));
  std::vector<std::thread> threads;
  for (unsigned w = 0; w < workers; ++w) {
    threads.emplace_back([&] {
      for (std::size_t i = next++; i < tasks.size(); i = next++) {
        tasks[i]();
        const std::size_t finished = ++done;
        if (!quiet) {
          std::fprintf(stderr, "diagnose: candidate %zu of %zu fitted\n", finished, tasks.size());
        }
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
}

}  // namespace mpdrig::cli
