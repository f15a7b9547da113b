// mpdrig freqresp --from-log: the empirical frequency response of a measured log
// (model/analysis/empirical_response.h) as a table, JSON and CSV.
#pragma once

#include <string>

#include "model/analysis/empirical_response.h"
#include "model/riglog/rig_log_reader.h"

namespace mpdrig::cli {

struct FreqrespLogArgs {
  std::string log_path;
  std::string json_path;  // empty: none; "-": stdout
  std::string csv_path;
  // Appends the first resonance of `resonance_channel` as a line of a resonance list
  // (model/analysis/resonance_list.h) for `termination`, the line end the log was recorded in.
  std::string resonance_list_path;
  std::string resonance_channel = "PT1";
  std::string termination;
  riglog::ReadOptions read;
  EmpiricalResponseOptions response;
};

int RunFreqrespFromLog(const FreqrespLogArgs& args);

}  // namespace mpdrig::cli
