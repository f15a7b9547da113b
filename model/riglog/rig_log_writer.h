// Streaming writer for rig-log v1 (docs/rig-log-format.md). Takes samples in SI with
// absolute pressure (channels.h) and writes each column in its own unit.
//
// Output, in this order:
//   # rig-log: 1
//   # key: value                        the metadata, in the given order (without `rig-log`)
//   # atmospheric_pressure_pa: 101325   only if the metadata has no such key (self-describing)
//   time_s,<columns...>                 time first, then the columns in the given order
//   <rows>                              '\n' line ends
// Numbers are the shortest text that reads back to the same double (std::to_chars), so a file
// written and read back gives the lab-unit values exactly and the SI values to round-off of the
// unit conversion. NaN is written as an empty field.
//
// Refused (a Status naming the file and the line that would have been written): a metadata key
// that is not IsMetadataKey, a value with a line break, `rig-log` other than 1, a bad
// `atmospheric_pressure_pa`, a column whose name does not match channel + unit or fails
// ParseColumnName, a `time_s` column among `columns`, a channel twice, a row of the wrong
// length, a non-finite or non-increasing time, an infinite value (also after conversion).
#pragma once

#include <cstdint>
#include <memory>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/channels.h"

namespace mpdrig::riglog {

class RigLogWriter {
 public:
  // Creates (truncates) `path`; "-" writes to standard output. `columns` excludes time: time_s is
  // always the first column. Gauge columns convert with metadata `atmospheric_pressure_pa`
  // (default 101325 Pa).
  static Result<RigLogWriter> Open(const std::string& path, Metadata metadata,
                                   std::vector<ColumnSpec> columns);
  // Writes to `out`, which must outlive the writer; `name` is used in error messages.
  static Result<RigLogWriter> ToStream(std::ostream* out, std::string name, Metadata metadata,
                                       std::vector<ColumnSpec> columns);

  RigLogWriter(RigLogWriter&&) noexcept;
  RigLogWriter& operator=(RigLogWriter&&) noexcept;
  // Closes if Close was not called; a write error is then lost, so call Close.
  ~RigLogWriter();

  const std::string& path() const;
  double atmospheric_pressure_pa() const;
  const std::vector<ColumnSpec>& columns() const;  // excluding time

  // One sample: values_si[i] belongs to columns()[i]; NaN = not measured.
  Status WriteRow(double time_s, std::span<const double> values_si);
  // Flushes and closes; reports any write error. Further WriteRow calls fail.
  Status Close();

 private:
  struct State;
  explicit RigLogWriter(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace mpdrig::riglog
