#include "model/analysis/measured_log.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

#include "model/analysis/log_stream.h"

namespace mpdrig {
namespace {

// A column of unknown length read in fixed-size chunks: no vector doubling (which would hold up to
// twice every column while reading), and one contiguous copy per column at the end.
class ChunkedColumn {
 public:
  void Push(double value) {
    if (chunks_.empty() || chunks_.back().size() == kChunk) {
      chunks_.emplace_back();
      chunks_.back().reserve(kChunk);
    }
    chunks_.back().push_back(value);
  }
  std::vector<double> Release() {
    std::size_t total = 0;
    for (const auto& chunk : chunks_) total += chunk.size();
    std::vector<double> out;
    out.reserve(total);
    for (auto& chunk : chunks_) {
      out.insert(out.end(), chunk.begin(), chunk.end());
      std::vector<double>().swap(chunk);
    }
    chunks_.clear();
    return out;
  }

 private:
  static constexpr std::size_t kChunk = 1 << 16;
  std::vector<std::vector<double>> chunks_;
};

}  // namespace

std::vector<Channel> ComparedChannels() {
  std::vector<Channel> channels = {Channel::kP1, Channel::kP2};
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    channels.push_back(static_cast<Channel>(static_cast<int>(Channel::kPT1) + k));
  }
  channels.insert(channels.end(), {Channel::kC2, Channel::kFT1, Channel::kFT3, Channel::kFT4});
  return channels;
}

std::optional<double> PipePositionM(Channel channel) {
  constexpr double kSpacingM = 100.0;
  const int k = static_cast<int>(channel) - static_cast<int>(Channel::kPT1);
  if (k < 0 || k >= kPipeTransmitterCount) return std::nullopt;
  return kSpacingM * k;
}

namespace {

Status CheckMeasuredLog(MeasuredLog* log) {
  if (log->inputs.time_s.size() < 4) {
    return Status::Error(log->path + ": needs at least 4 samples to compare");
  }
  // Keep only channels with at least one measured sample.
  std::erase_if(log->channels, [](const MeasuredChannel& channel) {
    return std::none_of(channel.values_si.begin(), channel.values_si.end(),
                        [](double v) { return std::isfinite(v); });
  });
  if (log->channels.empty()) {
    return Status::Error(log->path +
                         ": no measured channel to compare (P1 P2 PT1..PT10 C2 FT1 FT3 FT4)");
  }
  const std::vector<Channel> order = ComparedChannels();
  auto rank = [&](Channel channel) { return std::find(order.begin(), order.end(), channel); };
  std::sort(log->channels.begin(), log->channels.end(),
            [&](const MeasuredChannel& a, const MeasuredChannel& b) {
              return rank(a.channel) < rank(b.channel);
            });
  ReconstructInputs(log);
  return Status::Ok();
}

}  // namespace

void ReconstructInputs(MeasuredLog* log) {
  log->reconstruction = PlanInputReconstruction(log->inputs);
  log->smoothed_inputs.reset();
  ReconstructWithLevels(log);
}

void ReconstructWithLevels(MeasuredLog* log) {
  const std::uint64_t fingerprint = SmoothingFingerprint(log->inputs, log->reconstruction);
  if (log->smoothed_inputs == nullptr || log->smoothed_inputs->fingerprint != fingerprint) {
    log->smoothed_inputs = std::make_shared<const MeasuredLog::Smoothed>(
        MeasuredLog::Smoothed{fingerprint, SmoothInputColumns(log->inputs, log->reconstruction)});
  }
  log->reconstructed_inputs =
      WithInputLevels(log->smoothed_inputs->columns, log->reconstruction.levels);
}

Result<MeasuredLog> LoadMeasuredLog(const std::string& path, const CompareProgress& progress,
                                    const riglog::ReadOptions& read) {
  auto source = FileRowSource::Open(path, progress, read);
  if (!source.ok()) return source.status();
  MeasuredLog log;
  log.path = path;
  log.metadata = (*source)->metadata();
  log.atmospheric_pressure_pa = (*source)->atmospheric_pressure_pa();
  const std::vector<SourceChannel>& channels = (*source)->channels();
  for (const SourceChannel& channel : channels) {
    log.channels.push_back({channel.channel, channel.unit, {}});
  }
  // time, the four inputs, then the compared channels
  std::vector<ChunkedColumn> columns(5 + channels.size());
  LogRow row;
  while (true) {
    auto more = (*source)->Next(&row);
    if (!more.ok()) return more.status();
    if (!*more) break;
    columns[0].Push(row.time_s);
    columns[1].Push(row.piston_position_m);
    columns[2].Push(row.choke_opening_frac);
    columns[3].Push(row.pump_flow_m3ps);
    columns[4].Push(row.outlet_pressure_pa);
    for (std::size_t i = 0; i < channels.size(); ++i) columns[5 + i].Push(row.measured_si[i]);
  }
  log.inputs.time_s = columns[0].Release();
  log.inputs.piston_position_m = columns[1].Release();
  log.inputs.choke_opening_frac = columns[2].Release();
  log.inputs.pump_flow_m3ps = columns[3].Release();
  log.inputs.outlet_pressure_pa = columns[4].Release();
  for (std::size_t i = 0; i < channels.size(); ++i) {
    log.channels[i].values_si = columns[5 + i].Release();
  }
  MPDRIG_RETURN_IF_ERROR(CheckMeasuredLog(&log));
  return log;
}

Result<MeasuredLog> MeasuredLogFromRigLog(const riglog::RigLog& rig_log, const std::string& path) {
  MeasuredLog log;
  log.path = path;
  log.metadata = rig_log.metadata;
  log.atmospheric_pressure_pa = rig_log.atmospheric_pressure_pa;
  auto inputs = InputColumnsFromLog(rig_log, path);
  if (!inputs.ok()) return inputs.status();
  log.inputs = std::move(inputs).value();
  for (Channel channel : ComparedChannels()) {
    if (auto column = rig_log.FindColumn(riglog::ChannelName(channel))) {
      log.channels.push_back({channel, rig_log.columns[*column].unit, rig_log.values_si[*column]});
    }
  }
  MPDRIG_RETURN_IF_ERROR(CheckMeasuredLog(&log));
  return log;
}

MeasuredLog MeasuredLogUntil(const MeasuredLog& log, double t_end) {
  const std::vector<double>& t = log.time_s();
  const auto n = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), t_end) - t.begin());
  const auto head = [n](const std::vector<double>& v) {
    return std::vector<double>(v.begin(),
                               v.begin() + static_cast<std::ptrdiff_t>(std::min(n, v.size())));
  };
  const auto head_columns = [&](const LogInputColumns& c) {
    return LogInputColumns{head(c.time_s), head(c.piston_position_m), head(c.choke_opening_frac),
                           head(c.pump_flow_m3ps), head(c.outlet_pressure_pa)};
  };
  MeasuredLog cut;
  cut.path = log.path;
  cut.metadata = log.metadata;
  cut.atmospheric_pressure_pa = log.atmospheric_pressure_pa;
  cut.inputs = head_columns(log.inputs);
  cut.reconstructed_inputs = head_columns(log.reconstructed_inputs);
  cut.reconstruction = log.reconstruction;
  for (const MeasuredChannel& channel : log.channels) {
    cut.channels.push_back({channel.channel, channel.unit, head(channel.values_si)});
  }
  return cut;
}

}  // namespace mpdrig
