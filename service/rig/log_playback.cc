#include "service/rig/log_playback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace mpdrig::service {

Result<std::shared_ptr<LogPlayback>> LogPlayback::Open(const std::string& path, bool loop,
                                                       const riglog::ReadOptions& read) {
  MPDRIG_RETURN_IF_ERROR(read.Validate());
  std::shared_ptr<LogPlayback> playback(new LogPlayback());
  playback->path_ = path;
  playback->loop_ = loop;
  playback->read_options_ = read;
  MPDRIG_RETURN_IF_ERROR(playback->Reopen());
  playback->atmospheric_pa_ = playback->reader_->atmospheric_pressure_pa();
  playback->column_of_.assign(kChannelCount, -1);
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    const auto channel = static_cast<Channel>(i);
    auto column = playback->reader_->FindColumn(riglog::ChannelName(channel));
    if (column) {
      playback->column_of_[i] = static_cast<long>(*column);
      if (channel != Channel::kTime) playback->present_.push_back(channel);
    } else {
      playback->absent_.push_back(channel);
    }
  }
  // The pace: the median interval of the first rows (a log of one row plays at 100 Hz, the
  // lab's rate, since it has no interval of its own).
  while (playback->ahead_.size() < kPeriodRows) {
    auto more = playback->ReadRow();
    if (!more.ok()) return more.status();
    if (!*more) break;
  }
  if (playback->ahead_.empty()) return Status::Error(path + ": the log has no samples to play");
  playback->first_time_s_ = playback->ahead_.front().time_s;
  std::vector<double> intervals;
  for (std::size_t i = 1; i < playback->ahead_.size(); ++i) {
    intervals.push_back(playback->ahead_[i].time_s - playback->ahead_[i - 1].time_s);
  }
  if (intervals.empty()) {
    playback->period_s_ = 0.01;
  } else {
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
    playback->period_s_ = intervals[intervals.size() / 2];
  }
  return playback;
}

Status LogPlayback::Reopen() {
  auto reader = riglog::RigLogReader::Open(path_, read_options_);
  if (!reader.ok()) return reader.status();
  reader_.emplace(std::move(reader).value());
  file_done_ = false;
  return Status::Ok();
}

Result<bool> LogPlayback::ReadRow() {
  if (file_done_) return false;
  auto more = reader_->Next(&values_);
  if (!more.ok()) return more.status();
  if (!*more) {
    file_done_ = true;
    return false;
  }
  RigSample sample;
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    const long column = column_of_[i];
    sample.values[i] = column >= 0 ? values_[static_cast<std::size_t>(column)]
                                   : std::numeric_limits<double>::quiet_NaN();
  }
  sample.values[Index(Channel::kTime)] += time_offset_s_;
  sample.time_s = sample.values[Index(Channel::kTime)];
  last_time_s_ = values_[static_cast<std::size_t>(column_of_[Index(Channel::kTime)])];
  ahead_.push_back(std::move(sample));
  return true;
}

Result<RigSample> LogPlayback::Next(std::size_t pressure_points) {
  if (!failed_.ok()) return failed_;
  auto row = NextRow(pressure_points);
  if (!row.ok() && !finished_) failed_ = row.status();
  return row;
}

Result<RigSample> LogPlayback::NextRow(std::size_t pressure_points) {
  if (finished_) {
    return Status::Error("the playback of " + path_ + " has ended (" +
                         std::to_string(rows_played_) + " rows played)");
  }
  if (ahead_.empty()) {
    auto more = ReadRow();
    if (!more.ok()) return more.status();
    if (!*more) {
      // Only a log that loops gets here with rows to come: the end is seen one row early below.
      return Status::Error(path_ + ": no rows left to play");
    }
  }
  RigSample sample = std::move(ahead_.front());
  ahead_.pop_front();
  sample.pressure_at_positions_pa.assign(pressure_points, std::numeric_limits<double>::quiet_NaN());
  ++rows_played_;
  // Look one row ahead so the end is known when the last row goes out. A bad row there ends
  // the playback at the next call: this row, which is good, still goes out.
  if (ahead_.empty()) {
    auto more = ReadRow();
    if (!more.ok()) {
      failed_ = more.status();
      return sample;
    }
    if (!*more) {
      ++passes_;
      if (loop_) {
        // The next pass continues the clock: one period after this pass's last row.
        time_offset_s_ += last_time_s_ - first_time_s_ + period_s_;
        Status reopened = Reopen();
        auto first = reopened.ok() ? ReadRow() : Result<bool>(reopened);
        if (!first.ok()) {
          failed_ = first.status();
        } else if (!*first) {
          failed_ = Status::Error(path_ + ": the log became empty while looping");
        }
      } else {
        finished_ = true;
      }
    }
  }
  return sample;
}

std::string LogPlayback::Describe() const {
  std::ostringstream out;
  out << path_ << " (" << rows_played_ << " rows played";
  if (loop_) out << ", " << passes_ << " passes, looping";
  out << "; not measured:";
  bool any = false;
  for (Channel channel : absent_) {
    if (channel == Channel::kTime) continue;
    out << (any ? ", " : " ") << riglog::ChannelName(channel);
    any = true;
  }
  if (!any) out << " none";
  out << ")";
  return out.str();
}

}  // namespace mpdrig::service
