// The dashboard's view of the rigs on a DDS domain: it reads the topics of idl/mpdrig.idl (the
// rigs' sensors, the observer's estimate, the pressure profile, the rig status, and a shadow
// model's sensors and status), keeps the newest of each per rig plus a thinned history for the
// charts, and writes the shadow's model commands. On the client library (clients/client:
// RigStreams and Shadow handles through one Participant for every rig shown). Only the topics:
// it works the same against a virtual rig, a playback or the lab's rig behind a bridge.
//
// Two rules keep it cheap:
//   - Watched only: the DDS participant and its readers exist only while a browser asks (a
//     request within the last `idle_s`); when nobody watches they are deleted, so the service's
//     writers have no reader to send to and the dashboard costs the rig nothing.
//   - Thinned: a browser draws at most ~20 frames a second, so the readers are drained once per
//     frame (`frame_hz`), not woken per sample (10 rigs at 100 Hz would be thousands of wakeups
//     a second for nothing), and each frame adds at most one point per series to the history.
//     Sensor readers keep the newest 8 samples per rig, as the project's sensor QoS does: a
//     dashboard that falls behind loses old samples, never holds the rig back.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "model/common/status.h"

namespace mpdrig::dashboard {

struct FeedOptions {
  int domain = 0;
  std::string dds_config;         // Cyclone XML (inline); empty: loopback only
  std::vector<std::string> rigs;  // the rigs to show; empty: every rig that reports a status
  // DDS Security: a class's identity directory (deploy/security/make-class OUT NAME: OUT/NAME).
  // The feed then reads, and switches the shadow of, the one rig in `rigs`, in its partition
  // rig.<rig id>, as the other clients do; empty: no security.
  std::string security_dir;
  // Which shadow of each rig to show and command (`mpdrig shadow --shadow-id`); the others'
  // statuses are left out. Their model channels share the rig's one shadow-sensors instance.
  std::string shadow_id = "shadow";
  double idle_s = 5.0;       // close DDS this long after the last request
  double frame_hz = 20.0;    // drains (and history points) per second
  double history_s = 120.0;  // rig time of history kept per rig
};

// Counters for the measurements (GET /api/health): is DDS open, how often it opened, samples.
struct FeedHealth {
  bool open = false;
  std::uint64_t sessions_opened = 0;
  std::uint64_t samples_taken = 0;
  std::uint64_t frames = 0;
  std::string error;  // why DDS could not be opened, if it could not
};

class RigFeed {
 public:
  // Configures the domain (no participant yet: nothing on the wire) and starts the drain thread.
  static Result<std::unique_ptr<RigFeed>> Create(const FeedOptions& options);
  ~RigFeed();
  RigFeed(const RigFeed&) = delete;
  RigFeed& operator=(const RigFeed&) = delete;

  // A browser is watching: opens DDS if it is closed and keeps it open for `idle_s`.
  void Touch();

  // {"rigs":[...], "dds":"open"|"opening"|"closed", ...} for the rig selector.
  std::string RigsJson() const;
  // One rig's newest values and its history points newer than `since` (a sequence number the
  // previous answer gave; 0: all of it). Unknown rig: an object that says so.
  std::string StateJson(const std::string& rig_id, std::uint64_t since) const;
  FeedHealth Health() const;

  // Writes a ShadowCommand (action: effect_on, effect_off, set, reset, fit_now) for `rig_id`
  // and returns its command_id, which the shadow's status names once it has taken it. Fails
  // with a reason a user understands when no shadow of the rig is listening.
  Result<std::uint64_t> SendShadowCommand(const std::string& rig_id, const std::string& action,
                                          const std::string& argument);

  struct Session;  // the DDS entities of one watched period (rig_feed.cc)
  struct RigView;  // everything held about one rig (rig_feed.cc)

 private:
  explicit RigFeed(const FeedOptions& options);
  void Run();
  void Drain();             // takes every topic into the views (mu_ held)
  void AddHistoryPoints();  // after Drain: each fresh series its newest point (mu_ held)
  RigView& View(const std::string& rig_id);

  FeedOptions options_;
  struct DomainHolder;
  std::unique_ptr<DomainHolder> domain_;

  mutable std::mutex mu_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::chrono::steady_clock::time_point last_touch_{};
  bool touched_ = false;
  std::unique_ptr<Session> session_;
  std::map<std::string, std::unique_ptr<RigView>> views_;
  std::uint64_t next_seq_ = 1;
  FeedHealth health_;
  std::thread thread_;
};

}  // namespace mpdrig::dashboard
