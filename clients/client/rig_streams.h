// Read-only streams of the rigs on a domain, for a dashboard or a monitor that shows many rigs
// at once through one participant: each rig's sensors, the observer's estimates, the pressure
// profiles and the status, and a shadow model's sensors and status (shadow_client.h). It sends
// nothing, so it holds no rig back and needs no right to command.
//
//   auto streams = client::RigStreams::Open(participant, {.rigs = {}});   // every rig
//   streams->Take({.sensors = [](const std::string& rig, const client::Sensors& s) { ... }});
//
// Without security it reads every rig of the domain (or only those named); with security each
// named rig's topics in its partition (Participant::ScopeOf), and the permissions decide.
// Readers keep each topic's documented QoS (service/dds/topics.h): the sensor streams the newest
// 8 samples per rig, so a reader that falls behind loses old samples, never holds the rig back.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "clients/client/participant.h"
#include "clients/client/rig_client.h"
#include "clients/client/shadow_client.h"
#include "model/common/status.h"

namespace mpdrig::client {

struct StreamOptions {
  std::vector<std::string> rigs;     // only these rigs; empty: every rig (not with security)
  std::string shadow_id = "shadow";  // whose shadow status is taken; other shadows' are left out
};

class RigStreams {
 public:
  // What Take hands out, each with its rig's id; an unset one is not read.
  struct Visitor {
    std::function<void(const std::string& rig_id, const Sensors&)> sensors;
    std::function<void(const std::string& rig_id, const Estimate&)> estimate;
    std::function<void(const std::string& rig_id, const Profile&)> profile;
    std::function<void(const std::string& rig_id, const RigStatus&)> status;
    std::function<void(const std::string& rig_id, const Sensors&)> shadow_sensors;
    std::function<void(const ShadowStatus&)> shadow_status;
  };
  struct Taken {
    std::uint64_t samples = 0;  // valid samples taken (of every rig, wanted or not)
    std::string error;          // the last topic that failed, if any; the others were taken
  };

  static Result<std::unique_ptr<RigStreams>> Open(const std::shared_ptr<Participant>& participant,
                                                  const StreamOptions& options);
  ~RigStreams();
  RigStreams(const RigStreams&) = delete;
  RigStreams& operator=(const RigStreams&) = delete;

  // Takes every sample that has arrived, topic by topic in the Visitor's order, without waiting.
  Taken Take(const Visitor& visitor);

 private:
  struct Dds;
  explicit RigStreams(const StreamOptions& options);
  bool Wanted(const char* rig_id) const;

  StreamOptions options_;
  std::unique_ptr<Dds> dds_;
};

}  // namespace mpdrig::client
