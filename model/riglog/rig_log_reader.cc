#include "model/riglog/rig_log_reader.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <utility>

#include "model/common/units.h"

namespace mpdrig::riglog {
namespace {

// Reads are chunked; a line may not exceed kMaxLineBytes, so memory stays bounded even for a
// binary file without line ends.
constexpr std::size_t kChunkBytes = 1 << 16;
constexpr std::size_t kMaxLineBytes = 1 << 20;
constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";

// 1-based character column of byte `offset` in `line`: UTF-8 continuation bytes (10xxxxxx) do not
// start a character.
std::int64_t ColumnOf(std::string_view line, std::size_t offset) {
  std::int64_t column = 1;
  for (std::size_t i = 0; i < offset && i < line.size(); ++i) {
    if ((static_cast<unsigned char>(line[i]) & 0xC0) != 0x80) ++column;
  }
  return column;
}

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

// A time difference for a message: 6 significant digits (the sum of two written times carries
// rounding noise in its last digits).
std::string FormatGap(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", seconds);
  return text;
}

struct MetadataLine {
  std::string_view key;
  std::string_view value;
  std::size_t value_offset = 0;  // byte offset of the value in the line
};

// `# key: value` -> key and trimmed value; nullopt for a plain comment.
std::optional<MetadataLine> ParseMetadataLine(std::string_view line) {
  std::size_t i = 1;  // past '#'
  while (i < line.size() && IsBlank(line[i])) ++i;
  const std::size_t colon = line.find(':', i);
  if (colon == std::string_view::npos) return std::nullopt;
  const std::string_view key = line.substr(i, colon - i);
  if (!IsMetadataKey(key)) return std::nullopt;
  std::size_t begin = colon + 1;
  while (begin < line.size() && IsBlank(line[begin])) ++begin;
  std::size_t end = line.size();
  while (end > begin && IsBlank(line[end - 1])) --end;
  return MetadataLine{key, line.substr(begin, end - begin), begin};
}

}  // namespace

struct RigLogReader::State {
  std::unique_ptr<std::istream> owned;
  std::istream* in = nullptr;
  std::string path;

  std::string buffer;  // unread input starts at buffer_pos
  std::size_t buffer_pos = 0;
  bool input_exhausted = false;
  std::int64_t line_number = 0;

  Metadata metadata;
  double atmospheric_pressure_pa = units::kStandardAtmospherePa;
  std::vector<ColumnSpec> columns;
  std::size_t time_index = 0;

  ReadOptions options;
  double last_time_s = 0.0;
  std::int64_t last_time_line = 0;  // 0: no sample yet
  std::int64_t pending_empty_line = 0;
  std::int64_t samples_read = 0;
  bool finished = false;
  Status failure = Status::Ok();

  Status ErrorAt(std::int64_t line, std::int64_t column, const std::string& message) const {
    return Status::Error(path + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                         message);
  }

  // Next line without its line end, valid until the next call. False at the end of the input.
  Result<bool> ReadLine(std::string_view* line) {
    std::size_t scan_from = buffer_pos;
    for (;;) {
      const std::size_t newline = buffer.find('\n', scan_from);
      if (newline != std::string::npos) {
        *line = std::string_view(buffer).substr(buffer_pos, newline - buffer_pos);
        buffer_pos = newline + 1;
        break;
      }
      if (buffer.size() - buffer_pos > kMaxLineBytes) {
        return ErrorAt(line_number + 1, 1,
                       "line longer than " + std::to_string(kMaxLineBytes) + " bytes");
      }
      if (input_exhausted) {
        if (buffer_pos == buffer.size()) return false;
        *line = std::string_view(buffer).substr(buffer_pos);
        buffer_pos = buffer.size();
        break;
      }
      buffer.erase(0, buffer_pos);
      buffer_pos = 0;
      const std::size_t kept = buffer.size();
      scan_from = kept;
      buffer.resize(kept + kChunkBytes);
      in->read(buffer.data() + kept, static_cast<std::streamsize>(kChunkBytes));
      const auto got = static_cast<std::size_t>(in->gcount());
      buffer.resize(kept + got);
      if (in->bad()) return ErrorAt(line_number + 1, 1, "read error");
      if (in->eof() || got == 0) input_exhausted = true;
    }
    ++line_number;
    if (!line->empty() && line->back() == '\r') line->remove_suffix(1);
    if (line_number == 1 && line->substr(0, kUtf8Bom.size()) == kUtf8Bom) {
      line->remove_prefix(kUtf8Bom.size());
    }
    if (line->size() > kMaxLineBytes) {
      return ErrorAt(line_number, 1,
                     "line longer than " + std::to_string(kMaxLineBytes) + " bytes");
    }
    return true;
  }

  // Reads metadata and header.
  Status ReadHead() {
    std::int64_t version_line = 0;
    std::int64_t atmosphere_line = 0;
    std::string_view line;
    for (;;) {
      Result<bool> got = ReadLine(&line);
      if (!got.ok()) return got.status();
      if (!*got) {
        return ErrorAt(line_number + 1, 1,
                       "no header line: expected column names such as 'time_s,piston_position_m'");
      }
      if (line.empty()) {
        return ErrorAt(line_number, 1,
                       "empty line before the header; the first line that is not a comment must "
                       "be the header");
      }
      if (line[0] != '#') break;
      const std::optional<MetadataLine> entry = ParseMetadataLine(line);
      if (!entry.has_value()) continue;
      const std::int64_t value_column = ColumnOf(line, entry->value_offset);
      if (entry->key == kVersionKey) {
        if (version_line != 0) {
          return ErrorAt(line_number, 1,
                         "duplicate metadata key 'rig-log' (first on line " +
                             std::to_string(version_line) + ")");
        }
        version_line = line_number;
        if (entry->value != kFormatVersion) {
          return ErrorAt(line_number, value_column,
                         "unsupported rig-log version " + QuoteForMessage(entry->value) +
                             "; this reader reads version 1");
        }
      } else if (entry->key == kAtmosphericPressureKey) {
        if (atmosphere_line != 0) {
          return ErrorAt(line_number, 1,
                         "duplicate metadata key 'atmospheric_pressure_pa' (first on line " +
                             std::to_string(atmosphere_line) + ")");
        }
        atmosphere_line = line_number;
        Result<double> pa = ParseAtmosphericPressure(entry->value);
        if (!pa.ok()) return ErrorAt(line_number, value_column, pa.status().message());
        atmospheric_pressure_pa = *pa;
      }
      metadata.emplace_back(std::string(entry->key), std::string(entry->value));
    }
    return ParseHeader(line);
  }

  Status ParseHeader(std::string_view line) {
    std::vector<std::int64_t> column_positions;
    std::size_t start = 0;
    for (;;) {
      const std::size_t comma = std::min(line.find(',', start), line.size());
      const std::string_view name = line.substr(start, comma - start);
      const std::int64_t position = ColumnOf(line, start);
      Result<ColumnSpec> column = ParseColumnName(name);
      if (!column.ok()) return ErrorAt(line_number, position, column.status().message());
      for (std::size_t j = 0; j < columns.size(); ++j) {
        if (columns[j].channel != column->channel) continue;
        if (columns[j].name == column->name) {
          return ErrorAt(line_number, position,
                         "duplicate column " + QuoteForMessage(name) + " (also at column " +
                             std::to_string(column_positions[j]) + ")");
        }
        return ErrorAt(line_number, position,
                       "duplicate channel " + QuoteForMessage(column->channel) + ": column " +
                           QuoteForMessage(name) + " and column " +
                           QuoteForMessage(columns[j].name) + " at column " +
                           std::to_string(column_positions[j]));
      }
      columns.push_back(std::move(column).value());
      column_positions.push_back(position);
      if (comma == line.size()) break;
      start = comma + 1;
    }
    const ColumnSpec time = TimeColumn();
    const auto found = std::find(columns.begin(), columns.end(), time);
    if (found == columns.end()) {
      return ErrorAt(line_number, 1, "missing required column 'time_s' (sample time in seconds)");
    }
    time_index = static_cast<std::size_t>(found - columns.begin());
    return Status::Ok();
  }

  Result<bool> Next(std::vector<double>* values_si) {
    std::string_view line;
    for (;;) {
      Result<bool> got = ReadLine(&line);
      if (!got.ok()) return got.status();
      if (!*got) return false;
      if (line.empty()) {
        if (pending_empty_line == 0) pending_empty_line = line_number;
        continue;
      }
      if (line[0] == '#') continue;
      break;
    }
    if (pending_empty_line != 0) {
      return ErrorAt(pending_empty_line, 1,
                     "empty line inside the data (followed by a sample on line " +
                         std::to_string(line_number) +
                         "); empty lines are allowed only at the end of the file");
    }

    const std::size_t expected = columns.size();
    const std::size_t found =
        1 + static_cast<std::size_t>(std::count(line.begin(), line.end(), ','));
    if (found != expected) {
      std::size_t offset = line.size();  // too few: point just past the last field
      if (found > expected) {            // too many: point at the first extra field
        offset = 0;
        for (std::size_t commas = 0; commas < expected; ++offset) {
          if (line[offset] == ',') ++commas;
        }
      }
      return ErrorAt(line_number, ColumnOf(line, offset),
                     "expected " + std::to_string(expected) + " fields as in the header, found " +
                         std::to_string(found));
    }

    values_si->resize(expected);
    std::size_t start = 0;
    for (std::size_t i = 0; i < expected; ++i) {
      const std::size_t comma = std::min(line.find(',', start), line.size());
      const std::string_view field = line.substr(start, comma - start);
      const ColumnSpec& column = columns[i];
      Result<double> value = ParseSampleField(field);
      if (!value.ok()) {
        return ErrorAt(line_number, ColumnOf(line, start),
                       column.name + ": " + value.status().message());
      }
      if (i == time_index) {
        if (std::isnan(*value)) {
          return ErrorAt(line_number, ColumnOf(line, start),
                         column.name + ": " +
                             (field.empty() ? std::string("empty")
                                            : QuoteForMessage(field) + " is not a time") +
                             "; every sample needs a time");
        }
        if (last_time_line != 0 && !(*value > last_time_s)) {
          return ErrorAt(line_number, ColumnOf(line, start),
                         column.name + ": " + FormatNumber(*value) +
                             " is not after the previous sample's " + FormatNumber(last_time_s) +
                             " (line " + std::to_string(last_time_line) +
                             "); time must be strictly increasing");
        }
        if (last_time_line != 0 && !(*value - last_time_s <= options.max_gap_s)) {
          return ErrorAt(line_number, ColumnOf(line, start),
                         column.name + ": " + FormatNumber(*value) + " is " +
                             FormatGap(*value - last_time_s) + " s after the previous sample's " +
                             FormatNumber(last_time_s) + " (line " +
                             std::to_string(last_time_line) + "), a gap longer than " +
                             FormatGap(options.max_gap_s) +
                             " s (an interrupted recording or a wrong time; a longer gap limit "
                             "admits it if it is real)");
        }
        if (last_time_line != 0 && !(*value - last_time_s >= options.min_step_s)) {
          return ErrorAt(line_number, ColumnOf(line, start),
                         column.name + ": " + FormatNumber(*value) + " is only " +
                             FormatGap(*value - last_time_s) + " s after the previous sample's " +
                             FormatNumber(last_time_s) + " (line " +
                             std::to_string(last_time_line) + "); time steps must be at least " +
                             FormatGap(options.min_step_s) + " s");
        }
        last_time_s = *value;
        last_time_line = line_number;
      }
      (*values_si)[i] = ToSi(column.unit, *value, atmospheric_pressure_pa);
      if (i != time_index) {
        Status in_range =
            CheckPhysicalRange(column, *value, (*values_si)[i], atmospheric_pressure_pa);
        if (!in_range.ok()) return ErrorAt(line_number, ColumnOf(line, start), in_range.message());
      }
      start = comma + 1;
    }
    ++samples_read;
    return true;
  }
};

RigLogReader::RigLogReader(std::unique_ptr<State> state) : state_(std::move(state)) {}
RigLogReader::RigLogReader(RigLogReader&&) noexcept = default;
RigLogReader& RigLogReader::operator=(RigLogReader&&) noexcept = default;
RigLogReader::~RigLogReader() = default;

Status ReadOptions::Validate() const {
  if (!(min_step_s > 0.0) || !(max_gap_s > min_step_s)) {
    return Status::Error("time limits of a rig log: need max gap " + FormatGap(max_gap_s) +
                         " s > min step " + FormatGap(min_step_s) + " s > 0");
  }
  return Status::Ok();
}

Result<RigLogReader> RigLogReader::Open(const std::string& path, const ReadOptions& options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  if (path == "-") {
    auto state = std::make_unique<State>();
    state->in = &std::cin;
    state->path = "<stdin>";
    state->options = options;
    MPDRIG_RETURN_IF_ERROR(state->ReadHead());
    return RigLogReader(std::move(state));
  }
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return Status::Error(path + ": cannot read: is a directory");
  }
  errno = 0;
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!file->is_open()) {
    const int saved = errno;
    return Status::Error(path + ": cannot open for reading" +
                         (saved != 0 ? std::string(": ") + std::strerror(saved) : std::string()));
  }
  return FromStream(std::move(file), path, options);
}

Result<RigLogReader> RigLogReader::FromStream(std::unique_ptr<std::istream> in, std::string name,
                                              const ReadOptions& options) {
  MPDRIG_CHECK(in != nullptr);
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  auto state = std::make_unique<State>();
  state->options = options;
  state->in = in.get();
  state->owned = std::move(in);
  state->path = std::move(name);
  MPDRIG_RETURN_IF_ERROR(state->ReadHead());
  return RigLogReader(std::move(state));
}

const std::string& RigLogReader::path() const { return state_->path; }
const Metadata& RigLogReader::metadata() const { return state_->metadata; }
double RigLogReader::atmospheric_pressure_pa() const { return state_->atmospheric_pressure_pa; }
const std::vector<ColumnSpec>& RigLogReader::columns() const { return state_->columns; }
std::size_t RigLogReader::time_index() const { return state_->time_index; }
std::int64_t RigLogReader::line_number() const { return state_->line_number; }
std::int64_t RigLogReader::samples_read() const { return state_->samples_read; }

std::optional<std::size_t> RigLogReader::FindColumn(std::string_view channel) const {
  const std::vector<ColumnSpec>& columns = state_->columns;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i].channel == channel) return i;
  }
  return std::nullopt;
}

Result<bool> RigLogReader::Next(std::vector<double>* values_si) {
  MPDRIG_CHECK(values_si != nullptr);
  State& state = *state_;
  if (!state.failure.ok()) return state.failure;
  if (state.finished) return false;
  Result<bool> result = state.Next(values_si);
  if (!result.ok()) {
    state.failure = result.status();
  } else if (!*result) {
    state.finished = true;
  }
  return result;
}

}  // namespace mpdrig::riglog
