#include "model/analysis/resonance_list.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace mpdrig {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

Status At(const std::string& source, int line, std::size_t column, const std::string& message) {
  return Status::Error(source + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                       message);
}

}  // namespace

Result<std::vector<MeasuredResonance>> ParseResonanceList(std::string_view text,
                                                          const std::string& source) {
  std::vector<MeasuredResonance> list;
  bool header_seen = false;
  int line_number = 0;
  std::size_t position = 0;
  while (position <= text.size()) {
    const std::size_t end = std::min(text.find('\n', position), text.size());
    std::string_view line = text.substr(position, end - position);
    position = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') {
      if (end == text.size()) break;
      continue;
    }
    if (!header_seen) {
      if (trimmed != kResonanceListHeader) {
        return At(source, line_number, 1,
                  "expected the header '" + std::string(kResonanceListHeader) + "', got '" +
                      std::string(trimmed) + "'");
      }
      header_seen = true;
      if (end == text.size()) break;
      continue;
    }
    // Split into fields, remembering where each starts (1-based column).
    std::vector<std::pair<std::string_view, std::size_t>> fields;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = line.find(',', start);
      const std::size_t stop = comma == std::string_view::npos ? line.size() : comma;
      fields.emplace_back(line.substr(start, stop - start), start + 1);
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    if (fields.size() != 3) {
      return At(source, line_number, fields.size() > 3 ? fields[3].second - 1 : line.size() + 1,
                "expected 3 fields (configuration,frequency_hz,uncertainty_hz), got " +
                    std::to_string(fields.size()));
    }
    MeasuredResonance entry;
    entry.line = line_number;
    auto termination = ParseTermination(Trim(fields[0].first));
    if (!termination.ok())
      return At(source, line_number, fields[0].second, termination.status().message());
    entry.configuration = *termination;
    for (int f = 1; f <= 2; ++f) {
      const std::string_view field = Trim(fields[f].first);
      double value = 0.0;
      const auto [ptr, error] = std::from_chars(field.data(), field.data() + field.size(), value);
      const char* what = f == 1 ? "frequency_hz" : "uncertainty_hz";
      if (field.empty() || error != std::errc() || ptr != field.data() + field.size() ||
          !std::isfinite(value)) {
        return At(source, line_number, fields[f].second,
                  std::string(what) + ": '" + std::string(field) + "' is not a finite number");
      }
      if (!(value > 0.0)) {
        return At(source, line_number, fields[f].second,
                  std::string(what) + " must be > 0, got " + std::string(field));
      }
      (f == 1 ? entry.frequency_hz : entry.uncertainty_hz) = value;
    }
    for (const MeasuredResonance& other : list) {
      if (other.configuration == entry.configuration) {
        return At(source, line_number, fields[0].second,
                  "configuration '" + std::string(TerminationName(entry.configuration)) +
                      "' again (first on line " + std::to_string(other.line) + ")");
      }
    }
    list.push_back(entry);
    if (end == text.size()) break;
  }
  if (!header_seen) return At(source, line_number, 1, "empty: no header");
  if (list.empty()) return At(source, line_number, 1, "no resonance after the header");
  return list;
}

Result<std::vector<MeasuredResonance>> ReadResonanceList(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return Status::Error(path + ": cannot read");
  std::ostringstream text;
  text << file.rdbuf();
  return ParseResonanceList(text.str(), path);
}

}  // namespace mpdrig
