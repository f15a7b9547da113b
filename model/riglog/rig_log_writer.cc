#include "model/riglog/rig_log_writer.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <utility>

#include "model/common/units.h"

namespace mpdrig::riglog {
namespace {

bool HasOuterBlank(std::string_view s) {
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  return !s.empty() && (blank(s.front()) || blank(s.back()));
}

struct CheckedHead {
  Metadata metadata;  // without `rig-log`
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;
  bool has_atmosphere_key = false;
};

// Validates metadata and columns before anything is written, so a refused call leaves no file.
Result<CheckedHead> CheckHead(const std::string& path, Metadata metadata,
                              const std::vector<ColumnSpec>& columns) {
  CheckedHead head;
  bool has_version_key = false;
  for (auto& [key, value] : metadata) {
    if (!IsMetadataKey(key)) {
      return Status::Error(path + ": metadata key " + QuoteForMessage(key) +
                           " is not a key (a letter, then letters, digits, '_', '-', '.')");
    }
    if (value.find_first_of("\r\n") != std::string::npos) {
      return Status::Error(path + ": metadata " + QuoteForMessage(key) +
                           ": the value contains a line break");
    }
    if (HasOuterBlank(value)) {
      return Status::Error(path + ": metadata " + QuoteForMessage(key) +
                           ": the value starts or ends with a blank, which a reader drops");
    }
    if (key == kVersionKey) {
      if (has_version_key) return Status::Error(path + ": duplicate metadata key 'rig-log'");
      has_version_key = true;
      if (value != kFormatVersion) {
        return Status::Error(path + ": metadata 'rig-log' is " + QuoteForMessage(value) +
                             "; this writer writes version 1");
      }
      continue;  // written first, by the writer itself
    }
    if (key == kAtmosphericPressureKey) {
      if (head.has_atmosphere_key) {
        return Status::Error(path + ": duplicate metadata key 'atmospheric_pressure_pa'");
      }
      head.has_atmosphere_key = true;
      Result<double> pa = ParseAtmosphericPressure(value);
      if (!pa.ok()) return Status::Error(path + ": metadata " + pa.status().message());
      head.atmospheric_pressure_pa = *pa;
    }
    head.metadata.emplace_back(std::move(key), std::move(value));
  }

  for (std::size_t i = 0; i < columns.size(); ++i) {
    const ColumnSpec& column = columns[i];
    Result<ColumnSpec> parsed = ParseColumnName(column.name);
    if (!parsed.ok()) return Status::Error(path + ": " + parsed.status().message());
    if (*parsed != column) {
      return Status::Error(path + ": column " + QuoteForMessage(column.name) +
                           " does not match its channel " + QuoteForMessage(column.channel) +
                           " and unit " + QuoteForMessage(UnitSuffix(column.unit)));
    }
    if (column.channel == ChannelName(Channel::kTime)) {
      return Status::Error(path +
                           ": column 'time_s' must not be listed; time is WriteRow's "
                           "time_s argument and always the first column");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (columns[j].channel == column.channel) {
        return Status::Error(path + ": duplicate channel " + QuoteForMessage(column.channel) +
                             " (columns " + QuoteForMessage(columns[j].name) + " and " +
                             QuoteForMessage(column.name) + ")");
      }
    }
  }
  return head;
}

// Any double, for messages.
std::string Describe(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return FormatNumber(value);
}

}  // namespace

struct RigLogWriter::State {
  std::unique_ptr<std::ofstream> owned;
  std::ostream* out = nullptr;
  std::string path;
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;
  std::vector<ColumnSpec> columns;
  std::int64_t lines_written = 0;
  double last_time_s = 0.0;
  bool has_row = false;
  bool closed = false;
  std::string row;

  Status ErrorOnNextLine(const std::string& message) const {
    return Status::Error(path + ":" + std::to_string(lines_written + 1) + ": " + message);
  }

  Status WriteLine(const std::string& text) {
    out->write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!out->good()) return ErrorOnNextLine("write error");
    ++lines_written;
    return Status::Ok();
  }

  Status WriteHead(const CheckedHead& head) {
    MPDRIG_RETURN_IF_ERROR(WriteLine("# rig-log: 1\n"));
    for (const auto& [key, value] : head.metadata) {
      MPDRIG_RETURN_IF_ERROR(
          WriteLine("# " + key + ":" + (value.empty() ? "" : " ") + value + "\n"));
    }
    if (!head.has_atmosphere_key) {
      MPDRIG_RETURN_IF_ERROR(WriteLine(
          "# atmospheric_pressure_pa: " + FormatNumber(head.atmospheric_pressure_pa) + "\n"));
    }
    std::string header = TimeColumn().name;
    for (const ColumnSpec& column : columns) header += "," + column.name;
    return WriteLine(header + "\n");
  }

  Status WriteRow(double time_s, std::span<const double> values_si) {
    if (closed) return Status::Error(path + ": WriteRow after Close");
    if (values_si.size() != columns.size()) {
      return ErrorOnNextLine("row has " + std::to_string(values_si.size()) + " values for " +
                             std::to_string(columns.size()) + " columns");
    }
    if (!std::isfinite(time_s)) {
      return ErrorOnNextLine("time_s " + Describe(time_s) + " is not finite");
    }
    if (has_row && !(time_s > last_time_s)) {
      return ErrorOnNextLine("time_s " + FormatNumber(time_s) + " is not after the previous " +
                             FormatNumber(last_time_s) + "; time must be strictly increasing");
    }
    row.clear();
    AppendNumber(time_s, &row);
    for (std::size_t i = 0; i < columns.size(); ++i) {
      row += ',';
      const double value_si = values_si[i];
      if (std::isnan(value_si)) continue;
      const double value = FromSi(columns[i].unit, value_si, atmospheric_pressure_pa);
      if (!std::isfinite(value)) {
        return ErrorOnNextLine(columns[i].name + ": value " + Describe(value_si) +
                               " (SI) is not finite in " +
                               std::string(UnitSuffix(columns[i].unit)));
      }
      AppendNumber(value, &row);
    }
    row += '\n';
    MPDRIG_RETURN_IF_ERROR(WriteLine(row));
    last_time_s = time_s;
    has_row = true;
    return Status::Ok();
  }

  Status Close() {
    if (closed) return Status::Ok();
    closed = true;
    out->flush();
    bool failed = !out->good();
    if (owned != nullptr) {
      owned->close();
      failed = failed || owned->fail();
    }
    if (failed) return Status::Error(path + ": write error on close");
    return Status::Ok();
  }
};

RigLogWriter::RigLogWriter(std::unique_ptr<State> state) : state_(std::move(state)) {}
RigLogWriter::RigLogWriter(RigLogWriter&&) noexcept = default;
RigLogWriter& RigLogWriter::operator=(RigLogWriter&& other) noexcept {
  if (this != &other) {
    if (state_ != nullptr) (void)state_->Close();
    state_ = std::move(other.state_);
  }
  return *this;
}
RigLogWriter::~RigLogWriter() {
  if (state_ != nullptr) (void)state_->Close();
}

Result<RigLogWriter> RigLogWriter::Open(const std::string& path, Metadata metadata,
                                        std::vector<ColumnSpec> columns) {
  if (path == "-") return ToStream(&std::cout, "<stdout>", std::move(metadata), std::move(columns));
  Result<CheckedHead> head = CheckHead(path, std::move(metadata), columns);
  if (!head.ok()) return head.status();
  errno = 0;
  auto file = std::make_unique<std::ofstream>(path, std::ios::binary | std::ios::trunc);
  if (!file->is_open()) {
    const int saved = errno;
    return Status::Error(path + ": cannot open for writing" +
                         (saved != 0 ? std::string(": ") + std::strerror(saved) : std::string()));
  }
  auto state = std::make_unique<State>();
  state->out = file.get();
  state->owned = std::move(file);
  state->path = path;
  state->atmospheric_pressure_pa = head->atmospheric_pressure_pa;
  state->columns = std::move(columns);
  MPDRIG_RETURN_IF_ERROR(state->WriteHead(*head));
  return RigLogWriter(std::move(state));
}

Result<RigLogWriter> RigLogWriter::ToStream(std::ostream* out, std::string name, Metadata metadata,
                                            std::vector<ColumnSpec> columns) {
  MPDRIG_CHECK(out != nullptr);
  Result<CheckedHead> head = CheckHead(name, std::move(metadata), columns);
  if (!head.ok()) return head.status();
  auto state = std::make_unique<State>();
  state->out = out;
  state->path = std::move(name);
  state->atmospheric_pressure_pa = head->atmospheric_pressure_pa;
  state->columns = std::move(columns);
  MPDRIG_RETURN_IF_ERROR(state->WriteHead(*head));
  return RigLogWriter(std::move(state));
}

const std::string& RigLogWriter::path() const { return state_->path; }
double RigLogWriter::atmospheric_pressure_pa() const { return state_->atmospheric_pressure_pa; }
const std::vector<ColumnSpec>& RigLogWriter::columns() const { return state_->columns; }

Status RigLogWriter::WriteRow(double time_s, std::span<const double> values_si) {
  return state_->WriteRow(time_s, values_si);
}

Status RigLogWriter::Close() { return state_->Close(); }

}  // namespace mpdrig::riglog
