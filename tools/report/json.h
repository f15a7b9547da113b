// JSON for every file the `mpdrig` commands write (compare, diagnose, fit, traveltime, freqresp):
// nlohmann-json (Debian's nlohmann-json3-dev), one rule for strings and numbers.
//   strings  RFC 8259 escaping: `"` and `\` escaped, control characters as \n, \t, ... or
//            \u00XX, other UTF-8 as it is; a byte that is not well-formed UTF-8 (a log path is
//            bytes) becomes U+FFFD instead of failing.
//   numbers  the shortest text that reads back the same double (an integral value without a
//            fraction: 600, not 600.0); NaN and infinities are null, JSON has neither.
// Objects keep the order their fields were added in (ordered_json): the documented order.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mpdrig::report {

using Json = nlohmann::ordered_json;

// A number as JSON: null for NaN and infinities, an integer for an integral value (below 2^53,
// where every integer is exact; -0 stays a double), else the double.
inline Json JsonNumber(double value) {
  if (!std::isfinite(value)) return nullptr;
  constexpr double kExactIntegers = 9007199254740992.0;  // 2^53
  if (value == std::trunc(value) && std::abs(value) < kExactIntegers &&
      !(value == 0.0 && std::signbit(value))) {
    return static_cast<std::int64_t>(value);
  }
  return value;
}

inline Json JsonNumbers(const std::vector<double>& values) {
  Json array = Json::array();
  for (double value : values) array.push_back(JsonNumber(value));
  return array;
}

// The text of `value` with a final newline: compact (indent < 0) or indented by `indent` spaces.
// (json.cc: the serializer is compiled once, not in every writer.)
std::string JsonText(const Json& value, int indent = -1);

}  // namespace mpdrig::report
