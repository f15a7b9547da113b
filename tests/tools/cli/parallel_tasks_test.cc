// The command line's task runner (tools/cli/parallel_tasks.h): every task once, whatever the
// threads, and a call's tasks started longest first by what the same kinds took before.
#include "tools/cli/parallel_tasks.h"

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig::cli {
namespace {

TEST(LongestFirstRunner, RunsEveryTaskOnceOnAnyNumberOfWorkers) {
  for (unsigned workers : {1u, 2u, 5u}) {
    for (std::size_t count : {0u, 1u, 3u, 17u}) {
      LongestFirstRunner runner(workers);
      std::vector<std::atomic<int>> runs(count);
      std::vector<Task> tasks;
      for (std::size_t i = 0; i < count; ++i) {
        tasks.push_back({"task " + std::to_string(i % 4), [&runs, i] { ++runs[i]; }});
      }
      runner.Run(tasks);
      runner.Run(tasks);  // the second call with the kinds' times known
      for (std::size_t i = 0; i < count; ++i) {
        EXPECT_EQ(runs[i].load(), 2) << "task " << i << " of " << count << ", " << workers;
      }
    }
  }
}

TEST(LongestFirstRunner, StartsWhatTookLongestBeforeFirstAndNewKindsBeforeThem) {
  // One worker: the order started is the order run. The sleeps are far apart (0, 40, 200 ms), so
  // a loaded machine cannot swap their times.
  LongestFirstRunner runner(1);
  std::mutex lock;
  std::vector<std::string> started;
  const auto task = [&](const std::string& kind, int milliseconds) {
    return Task{kind, [&, kind, milliseconds] {
                  {
                    std::lock_guard<std::mutex> guard(lock);
                    started.push_back(kind);
                  }
                  std::this_thread::sleep_for(std::chrono::milliseconds(milliseconds));
                }};
  };
  runner.Run({task("quick", 0), task("slow", 200), task("middle", 40)});
  EXPECT_EQ(started, (std::vector<std::string>{"quick", "slow", "middle"}));  // nothing known
  started.clear();
  const std::vector<Task> again = {task("quick", 0), task("middle", 0), task("new", 0),
                                   task("slow", 0)};
  const std::vector<std::size_t> order = runner.Order(again);
  EXPECT_EQ(order, (std::vector<std::size_t>{2, 3, 1, 0}));
  runner.Run(again);
  EXPECT_EQ(started, (std::vector<std::string>{"new", "slow", "middle", "quick"}));
  // Each kind keeps its last time: "slow" took about nothing just now, and 200 ms once more.
  runner.Run({task("quick", 0), task("slow", 200)});
  EXPECT_EQ(runner.Order({task("quick", 0), task("slow", 0)}), (std::vector<std::size_t>{1, 0}));
}

}  // namespace
}  // namespace mpdrig::cli
