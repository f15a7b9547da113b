#include "tools/cli/parallel_tasks.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <limits>
#include <numeric>
#include <thread>

namespace mpdrig::cli {

LongestFirstRunner::LongestFirstRunner(unsigned workers, bool quiet)
    : workers_(workers > 0 ? workers : std::max(1u, std::thread::hardware_concurrency())),
      quiet_(quiet) {}

std::vector<std::size_t> LongestFirstRunner::Order(const std::vector<Task>& tasks) const {
  std::vector<double> seconds(tasks.size(), std::numeric_limits<double>::infinity());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      if (auto known = seconds_.find(tasks[i].kind); known != seconds_.end()) {
        seconds[i] = known->second;
      }
    }
  }
  std::vector<std::size_t> order(tasks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return seconds[a] > seconds[b]; });
  return order;
}

void LongestFirstRunner::Run(const std::vector<Task>& tasks) {
  const std::vector<std::size_t> order = Order(tasks);
  std::atomic<std::size_t> next{0}, done{0};
  const unsigned workers = std::min<unsigned>(workers_, static_cast<unsigned>(tasks.size()));
  const auto work = [&] {
    for (std::size_t k = next++; k < order.size(); k = next++) {
      const Task& task = tasks[order[k]];
      const auto started = std::chrono::steady_clock::now();
      task.run();
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        seconds_[task.kind] = seconds;
      }
      const std::size_t finished = ++done;
      if (!quiet_) {
        std::fprintf(stderr, "diagnose: %s done in %.1f s (%zu of %zu)\n", task.kind.c_str(),
                     seconds, finished, tasks.size());
      }
    }
  };
  std::vector<std::thread> threads;
  for (unsigned w = 1; w < workers; ++w) threads.emplace_back(work);
  work();  // the calling thread is one of the workers
  for (std::thread& thread : threads) thread.join();
}

TaskRunner LongestFirstRunner::Shared(unsigned workers, bool quiet) {
  auto runner = std::make_shared<LongestFirstRunner>(workers, quiet);
  return [runner](const std::vector<Task>& tasks) { runner->Run(tasks); };
}

}  // namespace mpdrig::cli
