// A whole rig log in memory (docs/rig-log-format.md), for tools that want the table:
// column-major vectors in SI with absolute pressure (channels.h). For long logs that need not be
// held at once, use RigLogReader / RigLogWriter directly; ReadRigLog and WriteRigLog are thin
// loops around them and accept and refuse exactly the same files (see rig_log_reader.h).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"
#include "model/common/units.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log_reader.h"

namespace mpdrig::riglog {

struct RigLog {
  // `# key: value` lines before the header, in file order (including `rig-log` when present).
  Metadata metadata;
  // Used to convert gauge columns; WriteRigLog writes it as metadata if the key is absent there.
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;
  std::vector<double> time_s;
  // Columns without time, in file order; the unit is what the file has (or will have): values
  // are SI regardless.
  std::vector<ColumnSpec> columns;
  // values_si[column][row], NaN where not measured.
  std::vector<std::vector<double>> values_si;

  std::size_t num_rows() const { return time_s.size(); }
  // Index into `columns` of the column of `channel` ("PT1", "BHP_est"); not for time.
  std::optional<std::size_t> FindColumn(std::string_view channel) const;
  // SI values of `channel`; "time" gives time_s. nullptr if absent.
  const std::vector<double>* Find(std::string_view channel) const;
  const std::vector<double>* Find(Channel channel) const;

  // Appends a column; refuses a duplicate channel, a time column, an inconsistent ColumnSpec or
  // a length other than num_rows().
  Status AddColumn(ColumnSpec column, std::vector<double> values_si);
};

// Reads a whole file ("-": standard input). Errors as RigLogReader: `path:line:column: message`;
// `options`: the limits on the time axis (rig_log_reader.h).
Result<RigLog> ReadRigLog(const std::string& path, const ReadOptions& options = {});

// Writes `log` ("-": standard output) with RigLogWriter. Refuses a log whose vectors disagree in
// length, or whose metadata `atmospheric_pressure_pa` disagrees with log.atmospheric_pressure_pa.
Status WriteRigLog(const RigLog& log, const std::string& path);

}  // namespace mpdrig::riglog
