// The dashboard's JSON (its API and the refusals; api_json.h has the small answers without the
// library's header), written with nlohmann-json: the library and the string rule of every JSON
// mpdrig writes. Strings are escaped as RFC 8259 says, and a byte that is not well-formed UTF-8
// (a rig id a client sent as `?rig=%ff`) becomes U+FFFD, so the JSON stays valid for the
// browser. A measured value is rounded to 7 significant digits (more than a chart or a readout
// shows, and a third of the bytes); NaN and infinities (a channel "not measured", an error still
// warming up) become null, which the page draws as a gap: JSON has no NaN. Counters and sequence
// numbers are integers, exact.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mpdrig::dashboard {

using Json = nlohmann::ordered_json;

// A measured value: null, or the double nearest its 7 significant digits (written as those
// digits, an integral one without a fraction: 13, not 13.0).
inline Json JsonNumber(double value) {
  if (!std::isfinite(value)) return nullptr;
  // to_chars and from_chars: correctly rounded both ways, and faster than printf and strtod.
  char digits[32];
  const auto printed =
      std::to_chars(digits, digits + sizeof digits, value, std::chars_format::general, 7);
  double rounded = 0.0;
  std::from_chars(digits, printed.ptr, rounded);
  if (rounded == std::trunc(rounded) && std::abs(rounded) < 9007199254740992.0 &&  // 2^53
      !(rounded == 0.0 && std::signbit(rounded))) {
    return static_cast<std::int64_t>(rounded);
  }
  return rounded;
}

inline Json JsonNumbers(const std::vector<double>& values) {
  Json array = Json::array();
  for (double value : values) array.push_back(JsonNumber(value));
  return array;
}

// The compact text of `value` (json_out.cc: the serializer compiled once).
std::string JsonText(const Json& value);

}  // namespace mpdrig::dashboard
