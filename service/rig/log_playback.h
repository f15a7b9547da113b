// A recorded rig log (rig-log-format.md) as a rig's sensors: `mpdrig serve --playback LOG`. Rows
// come out one at a time, in order, every one of them, read from the file as they are needed
// (bounded memory: an hour at 1 kHz is not held). A channel the log lacks, or leaves empty on a
// row, comes out as NaN: "not measured", as the log format says, never filled in. With `loop`
// the log starts again after its last row, its times shifted so the rig's clock keeps rising by
// one sample period across the seam.
//
// The sensor period is the median interval of the log's first kPeriodRows rows: the rig is
// paced (realtime, fast, lockstep) by that period, one row per tick, so a log sampled unevenly
// plays each row in one period while its samples keep their own times.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::service {

class LogPlayback {
 public:
  static constexpr std::size_t kPeriodRows = 1000;

  // Reads the header and the first rows. Errors name the file, line and column. `read` limits
  // the log's time axis (the gap between two rows, `serve --max-gap-s`), as for every reader.
  static Result<std::shared_ptr<LogPlayback>> Open(const std::string& path, bool loop,
                                                   const riglog::ReadOptions& read = {});

  const std::string& path() const { return path_; }
  double period_s() const { return period_s_; }
  double atmospheric_pressure_pa() const { return atmospheric_pa_; }
  bool loop() const { return loop_; }
  // The lab channels the log has (measured on at least its header), and those it lacks.
  const std::vector<Channel>& present() const { return present_; }
  const std::vector<Channel>& absent() const { return absent_; }
  // Rows handed out so far (over every pass when looping), and whole passes completed.
  std::uint64_t rows_played() const { return rows_played_; }
  std::uint64_t passes() const { return passes_; }
  // True once the last row of a log that does not loop has gone out.
  bool finished() const { return finished_; }
  // The error that ended the playback (a bad row further on in the file), or OK.
  const Status& failed() const { return failed_; }

  // The next row as a sample (SI, absolute pressure; NaN where not measured), with
  // `pressure_points` NaN pressures along the pipe (a log has only PT1..PT10: the profile is not
  // measured between them). An error at the end of a log that does not loop, or when the file
  // turns out bad further on (its path, line and column): then the playback has failed for
  // good (failed(); the reader stays failed, so no row after a bad one is ever played).
  Result<RigSample> Next(std::size_t pressure_points);

  // "run.csv (12000 rows so far; not measured: P1, FT4)".
  std::string Describe() const;

 private:
  LogPlayback() = default;
  Status Reopen();
  Result<RigSample> NextRow(std::size_t pressure_points);  // Next, before it records a failure
  Result<bool> ReadRow();  // appends to ahead_; false at the end of the file

  std::string path_;
  bool loop_ = false;
  riglog::ReadOptions read_options_;
  std::optional<riglog::RigLogReader> reader_;
  double atmospheric_pa_ = 0.0;
  double period_s_ = 0.0;
  std::vector<Channel> present_, absent_;
  // The reader's column of each Channel (by Index), or -1.
  std::vector<long> column_of_;
  std::deque<RigSample> ahead_;  // read, not yet handed out
  std::vector<double> values_;
  double first_time_s_ = 0.0;   // of the log (each pass starts there)
  double last_time_s_ = 0.0;    // of the pass being read
  double time_offset_s_ = 0.0;  // added to the file's times in this pass
  std::uint64_t rows_played_ = 0, passes_ = 0;
  bool file_done_ = false;
  bool finished_ = false;
  Status failed_ = Status::Ok();
};

}  // namespace mpdrig::service
