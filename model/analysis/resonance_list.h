// Resonances measured on the rig as data: a CSV file, one line per termination (termination.h),
//   configuration,frequency_hz,uncertainty_hz
//   choke-closed,0.44,0.01
//   choke-open,0.25,0.01
//   closed-at-pipe-end,0.49,0.01
// The header is exactly that line. Lines starting with '#' and empty lines are skipped. Each data
// line: a termination name, the first resonance [Hz] (finite, > 0) and its standard uncertainty
// [Hz] (finite, > 0); a termination at most once. A bad line is rejected with
// `file:line:column: message`, the column (1-based) where the bad field starts.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "model/analysis/termination.h"
#include "model/common/status.h"

namespace mpdrig {

struct MeasuredResonance {
  Termination configuration = Termination::kChokeClosed;
  double frequency_hz = 0.0;
  double uncertainty_hz = 0.0;
  int line = 0;  // in its file
};

inline constexpr std::string_view kResonanceListHeader =
    "configuration,frequency_hz,uncertainty_hz";

// Parses `text`; errors are prefixed with `source` ("file:line:column: ...").
Result<std::vector<MeasuredResonance>> ParseResonanceList(std::string_view text,
                                                          const std::string& source);
Result<std::vector<MeasuredResonance>> ReadResonanceList(const std::string& path);

}  // namespace mpdrig
