// How a client notices that the rig it talks to is gone or is no longer the same run, and the
// rule it then follows (docs/service.md, "When the rig is lost"). The rig is lost when
//   - its time or its sample counter goes back: the service restarted and runs a new rig from
//     t = 0 (a controller's integrator, set point and adaptation, or a recording's time axis,
//     belong to the old run);
//   - after the first sample, none comes for `timeout_s` of wall time: the service died, was
//     stopped, or the network is gone;
//   - the rig's sensor writer has left (the service exited; after a crash, once its participant
//     lease has run out).
// The client then says why on stderr and exits with kExitRigLost: it never carries its state over
// to another run, and never ends as if its job were done. Header-only: clients link no model code.
#pragma once

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

namespace mpdrig::clients {

// The exit code of a client whose rig was lost (1 is a failure to start, 2 a usage error).
inline constexpr int kExitRigLost = 3;

class RigWatch {
 public:
  explicit RigWatch(double timeout_s) : timeout_s_(timeout_s) {}

  // One sample of the watched rig. Returns why the rig is lost if its clock went back.
  std::optional<std::string> Sample(std::uint64_t counter, double time_s) {
    std::optional<std::string> lost;
    if (seen_ && (time_s < time_s_ || counter < counter_)) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "rig time went back from %.3f s to %.3f s (sample %llu after %llu): the "
                    "service restarted",
                    time_s_, time_s, static_cast<unsigned long long>(counter),
                    static_cast<unsigned long long>(counter_));
      lost = text;
    }
    seen_ = true;
    time_s_ = time_s;
    counter_ = counter;
    return lost;
  }

  // `idle_s` of wall time without a sample, and whether the rig's sensor writer is still matched.
  // Returns why the rig is lost, if it is (only once a sample has been seen: before that the
  // client is still waiting for the rig to appear).
  std::optional<std::string> Check(double idle_s, bool writer_matched) const {
    if (!seen_) return std::nullopt;
    char text[200];
    if (!writer_matched) {
      std::snprintf(text, sizeof text,
                    "the rig's service left (its sensor writer is gone) at rig time %.3f s",
                    time_s_);
      return std::string(text);
    }
    if (timeout_s_ > 0.0 && idle_s > timeout_s_) {
      std::snprintf(text, sizeof text, "no sample for %.1f s after rig time %.3f s", idle_s,
                    time_s_);
      return std::string(text);
    }
    return std::nullopt;
  }

  bool seen() const { return seen_; }

 private:
  double timeout_s_;
  bool seen_ = false;
  double time_s_ = 0.0;
  std::uint64_t counter_ = 0;
};

}  // namespace mpdrig::clients
