// A minimal JSON writer for the dashboard's snapshots: numbers, strings and arrays appended to
// one string. NaN and infinities (a channel "not measured", an error still warming up) become
// null, which the page draws as a gap: JSON has no NaN.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace mpdrig::dashboard {

inline void AppendNumber(std::string* out, double value) {
  if (!std::isfinite(value)) {
    *out += "null";
    return;
  }
  char buffer[32];
  // 7 significant digits: more than a chart or a readout shows, and a third of the bytes.
  const int n = std::snprintf(buffer, sizeof buffer, "%.7g", value);
  out->append(buffer, static_cast<std::size_t>(n));
}

inline void AppendString(std::string* out, std::string_view text) {
  *out += '"';
  for (const char c : text) {
    switch (c) {
      case '"':
        *out += "\\\"";
        break;
      case '\\':
        *out += "\\\\";
        break;
      case '\n':
        *out += "\\n";
        break;
      case '\r':
        *out += "\\r";
        break;
      case '\t':
        *out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(c));
          *out += buffer;
        } else {
          *out += c;
        }
    }
  }
  *out += '"';
}

inline void AppendNumbers(std::string* out, const std::vector<double>& values) {
  *out += '[';
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) *out += ',';
    AppendNumber(out, values[i]);
  }
  *out += ']';
}

inline void AppendStrings(std::string* out, const std::vector<std::string>& values) {
  *out += '[';
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) *out += ',';
    AppendString(out, values[i]);
  }
  *out += ']';
}

// `"key":` for an object member (the caller writes the commas).
inline void AppendKey(std::string* out, std::string_view key) {
  AppendString(out, key);
  *out += ':';
}

}  // namespace mpdrig::dashboard
