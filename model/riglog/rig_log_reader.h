// Streaming reader for rig-log v1 (docs/rig-log-format.md), in bounded memory: an hour of
// 1 kHz samples is read one line at a time. Samples come out in SI with absolute pressure
// (channels.h): time s, position m, choke opening fraction 0..1, flow m^3/s, pressure Pa abs.
//
// What is accepted, and where the format leaves room:
//   - UTF-8 text, ',' separated, '\n' or '\r\n' line ends (mixed is fine; a last line without a
//     line end is fine). A UTF-8 byte-order mark at the very start is skipped.
//   - A line whose FIRST character is '#' is a comment, anywhere in the file. Before the header,
//     `# key: value` (key: a letter then letters, digits, '_', '-', '.'; see IsMetadataKey) is
//     metadata, kept in file order; other comments are dropped. After the header, `# key: value`
//     lines are plain comments.
//   - `# rig-log: V` with V other than `1` is rejected; without the line the file is read as v1.
//     `rig-log` and `atmospheric_pressure_pa` may each appear once. `atmospheric_pressure_pa`
//     must be a number of Pa in [1e4, 1e6] (catches a value given in bar); default 101325.
//   - The first line that is not a comment is the header, so an empty line before the header is
//     an error. Header checks: every column `<channel>_<unit>` with a known unit suffix
//     (case-sensitive); a known channel in a unit of its quantity; no channel twice (`PT1_barg`
//     and `PT1_bara` count as duplicates); `time_s` present (any position). No quoting, spaces,
//     tabs or control characters in names.
//   - Empty lines are allowed only at the end of the file (trailing). An empty line followed by
//     another sample is an error that points at the empty line.
//   - Sample fields: see ParseSampleField. No surrounding spaces, no quotes, no `inf`. Empty or
//     `nan` is NaN. Field count must equal the header's.
//   - `time_s` must be a number (not empty, not nan) and strictly increasing, by at least
//     ReadOptions::min_step_s and at most ReadOptions::max_gap_s from one sample to the next.
//   - Every other value must lie in its quantity's physical range (PhysicalRangeOf, channels.h):
//     `PT1_barg=1e308` or `choke_position_deg=-50` is an error, not infinity or a replayed -50 deg.
//
// Every error is `path:line:column: message`, 1-based, the column being the character (UTF-8
// code point) position where the offending field or header column starts, e.g.
//   run.csv:57:23: PT1_barg: 'abc' is not a number
// After an error the reader stays failed: Next returns the same error again.
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/channels.h"

namespace mpdrig::riglog {

// Limits on a log's time axis beyond the format, against bad input. Every tool replays the model
// over a log's whole time span, so one wild time value (1e308, or a clock jump of a day) would make
// it run for hours; a gap is also where a recording was interrupted, and the replay would hold the
// inputs across it as if the rig had. Time steps far below any sensor period are a unit slip
// (ms written as s) or a broken clock, and give empty metrics.
struct ReadOptions {
  // The longest step from one sample's time to the next [s]; a longer one is an error at the
  // later sample. Default 10 s: 1000 sample periods of the lab's 100 Hz, longer than the rig's
  // slowest dynamics (the ~7 s filling time constant), shorter than a replay a user waits for
  // without noticing. Infinity: no limit.
  double max_gap_s = 10.0;
  // The shortest step [s]: 1 us, ten times finer than `mpdrig simulate`'s highest rate.
  double min_step_s = 1.0e-6;

  Status Validate() const;  // max_gap_s > min_step_s > 0, neither NaN
};

class RigLogReader {
 public:
  // Opens `path` ("-" reads standard input) and reads the metadata and the header.
  static Result<RigLogReader> Open(const std::string& path, const ReadOptions& options = {});
  // Reads from `in`; `name` is used as the path in error messages.
  static Result<RigLogReader> FromStream(std::unique_ptr<std::istream> in, std::string name,
                                         const ReadOptions& options = {});

  RigLogReader(RigLogReader&&) noexcept;
  RigLogReader& operator=(RigLogReader&&) noexcept;
  ~RigLogReader();

  const std::string& path() const;
  const Metadata& metadata() const;
  double atmospheric_pressure_pa() const;
  // All columns in file order, including time_s.
  const std::vector<ColumnSpec>& columns() const;
  // Index of time_s in columns().
  std::size_t time_index() const;
  // Index in columns() of the column of `channel` (e.g. "PT1", "time", "BHP_est").
  std::optional<std::size_t> FindColumn(std::string_view channel) const;

  // Reads the next sample into `values_si` (resized to columns().size(), file order, SI with
  // absolute pressure, NaN where not measured). Returns false at the end of the file, or an error
  // naming the file, line and column.
  Result<bool> Next(std::vector<double>* values_si);

  // 1-based line number of the last line read (the header after Open, then the last sample).
  std::int64_t line_number() const;
  // Samples returned so far.
  std::int64_t samples_read() const;

 private:
  struct State;
  explicit RigLogReader(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace mpdrig::riglog
