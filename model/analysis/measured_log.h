// A measured rig log in memory, as the comparison, fit and diagnose use it: time, the four inputs
// (as measured and reconstructed under their noise) and the compared channels, nothing else of
// the file.
//
// One of the two ways into a comparison (compare.h): LoadMeasuredLog keeps the log in memory, so
// that ReplayModel (log_replay.h) and CompareTraces (compare.h) can run on it many times, as fit
// and diagnose do to fit and screen effects. The other, CompareLog, streams the file
// (log_stream.h) and keeps nothing of it.
//
// Units: SI with absolute pressure (Pa, m^3/s, m, opening fraction); MeasuredChannel::unit keeps
// each channel's unit in the log, for the edges (JSON, HTML).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"
#include "model/common/units.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/log_inputs.h"

namespace mpdrig {

// The measured channels a comparison looks at (not the inputs): P1 P2 PT1..PT10 C2 FT1 FT3 FT4.
std::vector<Channel> ComparedChannels();
// x [m] of PTk along the lab's pipe (0, 100, ..., 900, rig-log-format.md); nullopt otherwise.
std::optional<double> PipePositionM(Channel channel);

// "stage" names the part of the work ("read", "replay", "simulate", "analyse"); fraction in
// [0, 1], or minus a sample count where the total is unknown (reading standard input).
using CompareProgress = std::function<void(std::string_view stage, double fraction)>;

struct MeasuredChannel {
  Channel channel = Channel::kP1;
  riglog::Unit unit = riglog::Unit::kBarg;  // the log's unit, for the edges
  std::vector<double> values_si;            // NaN where not measured
};

// What a comparison needs from a log. Memory: 8 bytes per sample for time, each input and each
// compared channel present, and for time and the four inputs twice more (reconstructed, and
// smoothed before the levels); nothing else of the file is kept.
struct MeasuredLog {
  std::string path;
  riglog::Metadata metadata;
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;
  LogInputColumns inputs;  // as measured; time_s lives here
  // The inputs reconstructed under their noise (log_inputs.h), what a replay feeds the model by
  // default, and how: made when the log is loaded.
  LogInputColumns reconstructed_inputs;
  InputReconstruction reconstruction;
  // `inputs` smoothed as `reconstruction` says, before its levels (SmoothInputColumns), and the
  // SmoothingFingerprint it was made for: ApplyInputLevels adds other levels to it without
  // smoothing again (a diagnosis tries levels per candidate; the smoothing was 15 % of it).
  // Copies of the log share it; a log whose inputs or plan changed since smooths again, and a
  // log cut by MeasuredLogUntil has none (its inputs end earlier, so their smoothing near the end
  // differs).
  struct Smoothed {
    std::uint64_t fingerprint = 0;
    LogInputColumns columns;
  };
  std::shared_ptr<const Smoothed> smoothed_inputs;
  // Present (at least one sample measured), in the order of ComparedChannels().
  std::vector<MeasuredChannel> channels;
  const std::vector<double>& time_s() const { return inputs.time_s; }
};

// Streams `path` (RigLogReader): errors are `path:line:column: message`. Refuses a log without
// piston_position or choke_position (or with an unmeasured input sample), fewer than 4 samples,
// or no compared channel.
Result<MeasuredLog> LoadMeasuredLog(const std::string& path, const CompareProgress& progress = {},
                                    const riglog::ReadOptions& read = {});
// The same from a log already in memory (tests, tools that build logs).
Result<MeasuredLog> MeasuredLogFromRigLog(const riglog::RigLog& log, const std::string& path);
// The samples of `log` with t <= t_end; the reconstructed inputs are the whole log's, cut (a
// replay of the head sees what a replay of the whole log sees there).
MeasuredLog MeasuredLogUntil(const MeasuredLog& log, double t_end);

// Plans and makes log->reconstructed_inputs from log->inputs (both loaders do it; call it again
// after changing the inputs by hand).
void ReconstructInputs(MeasuredLog* log);
// log->reconstructed_inputs again from log->inputs and log->reconstruction (its levels changed):
// the smoothing reused where log->smoothed_inputs holds it for these inputs and plan.
void ReconstructWithLevels(MeasuredLog* log);

}  // namespace mpdrig
