// The shadow model as a DDS client of a rig (`mpdrig shadow`): it subscribes to one rig's
// mpdrig_sensors (a virtual rig, a playback, the lab through a bridge), feeds every sample to a
// ShadowModel (model/analysis/shadow_model.h) and publishes
//   mpdrig_shadow_sensors - the model's channels at the rig's sample times (RigSensors, lab
//                           units, the rig's id; sensor QoS);
//   mpdrig_shadow_status  - its error over the sliding window, per channel and overall, its
//                           effects and parameters, the last change (status QoS);
// and takes mpdrig_shadow_command (effect on/off, set a parameter, reset, fit now, cancel the fit;
// reliable, keep all: a command is not state) addressed to its shadow id. Fit now runs on a
// worker thread (ShadowStatus.fit_state says "running: ...", then "done: ...", "failed: ..." or
// "cancelled"); a second one while it runs is refused. A bad
// command is refused and counted on the shadow's status; the shadow runs on. Optionally writes the
// error over time as CSV: time_s, error, <channel>_nrmse.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "model/analysis/shadow_model.h"
#include "model/common/status.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace mpdrig::service {

// The id of a shadow when none is given: the one shadow of a rig.
inline constexpr const char* kDefaultShadowId = "shadow";
// 1-64 characters of [A-Za-z0-9_.-]: it appears in commands, statuses and the dashboard's URLs.
Status CheckShadowId(const std::string& shadow_id);

struct ShadowServeOptions {
  std::string rig_id = "rig-1";
  // Which shadow of the rig this is: it takes only the model commands with this id, and its
  // status carries it (several shadows of one rig, e.g. two students' models).
  std::string shadow_id = kDefaultShadowId;
  dds_domainid_t domain = 0;
  // Cyclone's configuration of the domain; empty: the domain as this process already has it
  // (a test that runs a rig service beside the shadow).
  std::string dds_config = dds::LoopbackConfig();
  // Stop after this much of the rig's time has been shadowed (0: until stopped).
  double duration_s = 0.0;
  // Status (and a CSV row) every this much rig time.
  double status_period_s = 0.5;
  std::string log_path;  // the CSV ("" : none)
  // DDS Security: an identity directory of a class (deploy/security/make-class OUT/NAME) allowed
  // to read the rig and to use the shadow's topics; then every topic of the shadow (the rig's
  // sensors in, its own in and out) is in the rig's partition (RigPartition). "" : none.
  std::string security_dir;
  // "Fit now" (SHADOW_FIT_NOW): c, f1 and the active effects' strengths fitted on the rows of the
  // last fit_window_s (held for it), on a worker thread; the shadow runs on and applies the fit
  // when it is done. At most fit_max_iterations solver iterations.
  double fit_window_s = 180.0;
  int fit_max_iterations = 15;
};

class ShadowService {
 public:
  static Result<std::unique_ptr<ShadowService>> Create(RigParams params, ShadowOptions model,
                                                       const ShadowServeOptions& options);
  ~ShadowService();
  // Runs until `stop` or the duration. Fails only when the transport or the log file fails.
  Status Run(const std::atomic<bool>& stop);
  const ShadowModel& model() const;
  std::uint64_t samples() const;

 private:
  struct Impl;
  explicit ShadowService(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpdrig::service
