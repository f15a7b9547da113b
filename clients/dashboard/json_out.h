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

// The length of the well-formed UTF-8 sequence (RFC 3629: no overlong forms, no surrogates,
// nothing above U+10FFFF) that starts text[i], or 0 if none does.
inline std::size_t Utf8SequenceLength(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return 1;
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xbf;  // the range of the second byte
  if (b0 >= 0xc2 && b0 <= 0xdf) {
    n = 2;
  } else if (b0 >= 0xe0 && b0 <= 0xef) {
    n = 3;
    if (b0 == 0xe0) lo = 0xa0;  // overlong
    if (b0 == 0xed) hi = 0x9f;  // surrogates
  } else if (b0 >= 0xf0 && b0 <= 0xf4) {
    n = 4;
    if (b0 == 0xf0) lo = 0x90;  // overlong
    if (b0 == 0xf4) hi = 0x8f;  // above U+10FFFF
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  if (byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xbf) return 0;
  }
  return n;
}

// A JSON string of `text`; a byte that is not part of well-formed UTF-8 (e.g. a rig id a client
// sent as `?rig=%ff`) becomes U+FFFD, so the JSON stays valid for the browser.
inline void AppendString(std::string* out, std::string_view text) {
  *out += '"';
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (static_cast<unsigned char>(c) >= 0x80) {
      const std::size_t n = Utf8SequenceLength(text, i);
      if (n == 0) {
        *out += "\\ufffd";
      } else {
        out->append(text.substr(i, n));
        i += n - 1;
      }
      continue;
    }
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
