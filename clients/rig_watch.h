// How a client notices that the rig it talks to is gone or is no longer the same run, and the
// rule it then follows (docs/service.md, "When the rig is lost"). The rig is lost when
//   - its time or its sample counter goes back: the service restarted and runs a new rig from
//     t = 0 (a controller's integrator, set point and adaptation, or a recording's time axis,
//     belong to the old run). A restart is a new sensor writer that keeps sending: a stray
//     sample of another writer is ignored, not taken for one;
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

  // What to do with one sample.
  enum class Verdict { kAccept, kIgnore, kLost };

  // One sample of the watched rig, from the DDS writer `writer` (its publication handle). The
  // first writer heard is the rig's. A sample from another writer is ignored (counted in
  // ignored()): without DDS Security anyone on the domain can write one, and a stranger's single
  // sample (counter 1e9, time 1e6) is no evidence that the service restarted. Only when another
  // writer has sent kSamplesToSwitch samples in a row, with none from the rig's writer between,
  // is it the rig's writer now: a restarted service. If its clock is behind the old one's, the
  // rig is lost (`why` says so); else the rig goes on (the same run, e.g. a standby service).
  // A sample of the rig's own writer whose clock went back is lost too.
  Verdict Sample(std::uint64_t counter, double time_s, std::uint64_t writer, std::string* why) {
    if (seen_ && writer != writer_) {
      if (writer != candidate_) {
        candidate_ = writer;
        candidate_samples_ = 0;
        candidate_first_time_s_ = time_s;
        candidate_first_counter_ = counter;
      }
      if (++candidate_samples_ < kSamplesToSwitch) {
        ++ignored_;
        return Verdict::kIgnore;
      }
      // The new writer's first sample is the one to compare with the old run's last.
      const double old_time_s = time_s_;
      const std::uint64_t old_counter = counter_;
      writer_ = writer;
      candidate_ = 0;
      if (candidate_first_time_s_ < old_time_s || candidate_first_counter_ < old_counter) {
        *why = WentBack(old_time_s, candidate_first_time_s_, candidate_first_counter_, old_counter);
        return Verdict::kLost;
      }
    } else if (seen_ && (time_s < time_s_ || counter < counter_)) {
      *why = WentBack(time_s_, time_s, counter, counter_);
      return Verdict::kLost;
    }
    if (writer == writer_) candidate_ = 0;  // the rig's writer spoke: no switch under way
    seen_ = true;
    writer_ = writer;
    time_s_ = time_s;
    counter_ = counter;
    return Verdict::kAccept;
  }

  // The rig's writer (a DDS publication handle; 0 before the first sample): the one whose leaving
  // means the rig's service left (Check's `writer_matched`).
  std::uint64_t writer() const { return writer_; }
  // Samples of other writers that Sample ignored.
  std::uint64_t ignored() const { return ignored_; }

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

  // Samples in a row from another writer that make it the rig's (a restarted service): at the
  // lab's 100 Hz 50 ms, far below any client's timeout.
  static constexpr int kSamplesToSwitch = 5;

 private:
  static std::string WentBack(double from_s, double to_s, std::uint64_t counter,
                              std::uint64_t after) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "rig time went back from %.3f s to %.3f s (sample %llu after %llu): the "
                  "service restarted",
                  from_s, to_s, static_cast<unsigned long long>(counter),
                  static_cast<unsigned long long>(after));
    return text;
  }

  double timeout_s_;
  bool seen_ = false;
  double time_s_ = 0.0;
  std::uint64_t counter_ = 0;
  std::uint64_t writer_ = 0;  // the rig's writer: the one whose samples are taken
  // Another writer that has sent samples since the rig's writer last did, and what it sent first.
  std::uint64_t candidate_ = 0;
  int candidate_samples_ = 0;
  double candidate_first_time_s_ = 0.0;
  std::uint64_t candidate_first_counter_ = 0;
  std::uint64_t ignored_ = 0;
};

}  // namespace mpdrig::clients
