// Within(seconds, done): polls `done` every 5 ms until it holds or `seconds` have passed, for
// conditions no waitset can wait on (a match count, a status another process reports).
// Header-only.
#pragma once

#include <chrono>
#include <functional>
#include <thread>

namespace mpdrig::testing {

inline bool Within(double seconds, const std::function<bool()>& done) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done();
}

}  // namespace mpdrig::testing
