#include "tools/cli/freqresp_log.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "model/analysis/resonance_list.h"
#include "model/analysis/termination.h"
#include "model/riglog/rig_log.h"
#include "tools/cli/model_options.h"
#include "tools/report/json.h"

namespace mpdrig::cli {
namespace {

using report::Json;
using report::JsonNumber;
using report::JsonText;

std::string ResponseJson(const EmpiricalResponse& r, const FreqrespLogArgs& args) {
  Json channels = Json::array();
  for (const ChannelResponse& ch : r.channels) {
    Json peaks = Json::array();
    for (const ResonancePeak& p : ch.peaks) {
      peaks.push_back({{"freq_hz", JsonNumber(p.freq_hz)},
                       {"uncertainty_hz", JsonNumber(p.uncertainty_hz)},
                       {"magnitude", JsonNumber(p.magnitude)},
                       {"coherence", JsonNumber(p.coherence)},
                       {"half_power_width_hz", JsonNumber(p.half_power_width_hz)}});
    }
    Json points = Json::array();
    for (const EmpiricalPoint& p : ch.points) {
      points.push_back({{"freq_hz", JsonNumber(p.freq_hz)},
                        {"magnitude", JsonNumber(p.magnitude)},
                        {"phase_deg", JsonNumber(p.phase_deg)},
                        {"coherence", JsonNumber(p.coherence)}});
    }
    channels.push_back({{"channel", ch.channel}, {"peaks", peaks}, {"points", points}});
  }
  const Json json = {{"log", args.log_path},
                     {"input", "piston_position"},
                     {"magnitude_unit", "Pa/m"},
                     {"sample_rate_hz", JsonNumber(r.sample_rate_hz)},
                     {"segment_s", JsonNumber(r.segment_s)},
                     {"segments", r.segments},
                     {"df_hz", JsonNumber(r.df_hz)},
                     {"min_coherence", JsonNumber(args.response.min_coherence)},
                     {"channels", channels}};
  return JsonText(json, 2);
}

std::string ResponseCsv(const EmpiricalResponse& r) {
  std::ostringstream out;
  out.precision(10);
  out << "channel,freq_hz,magnitude_pa_per_m,phase_deg,coherence\n";
  for (const ChannelResponse& ch : r.channels) {
    for (const EmpiricalPoint& p : ch.points) {
      out << ch.channel << "," << p.freq_hz << "," << p.magnitude << "," << p.phase_deg << ","
          << p.coherence << "\n";
    }
  }
  return out.str();
}

// The first peak of the chosen channel as one more line of the resonance list: the header if the
// file is new or empty; the whole list is parsed before it is written, so a termination given
// twice or a damaged file is refused with its line, and the file is left as it was.
Status AppendResonance(const EmpiricalResponse& response, const FreqrespLogArgs& args) {
  if (args.termination.empty()) {
    return Status::Error(
        "--resonance-list needs --termination: the line end the log was "
        "recorded in (" +
        TerminationNames() + ")");
  }
  auto termination = ParseTermination(args.termination);
  if (!termination.ok()) return termination.status().Within("--termination");
  const ChannelResponse* channel = nullptr;
  for (const ChannelResponse& c : response.channels) {
    if (c.channel == args.resonance_channel) channel = &c;
  }
  if (channel == nullptr) {
    return Status::Error("--resonance-channel " + args.resonance_channel +
                         ": the log has no such pressure channel");
  }
  if (channel->peaks.empty()) {
    return Status::Error("--resonance-list: " + args.resonance_channel +
                         " has no resonance peak (gamma^2 >= --min-coherence, standing out of "
                         "its valleys): sweep through it with the choke and the pump held");
  }
  std::string text;
  if (std::ifstream in(args.resonance_list_path); in) {
    std::ostringstream existing;
    existing << in.rdbuf();
    text = existing.str();
  }
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    text = std::string(kResonanceListHeader) + "\n";
  } else if (text.back() != '\n') {
    text += '\n';
  }
  const ResonancePeak& peak = channel->peaks.front();
  char line[160];
  std::snprintf(line, sizeof line, "%s,%.6g,%.3g\n", args.termination.c_str(), peak.freq_hz,
                peak.uncertainty_hz);
  text += line;
  auto parsed = ParseResonanceList(text, args.resonance_list_path);
  if (!parsed.ok()) return parsed.status();
  MPDRIG_RETURN_IF_ERROR(WriteText(args.resonance_list_path, text));
  std::fprintf(stderr, "freqresp: %s first resonance %.4f +- %.4f Hz (%s) -> %s\n",
               args.resonance_channel.c_str(), peak.freq_hz, peak.uncertainty_hz,
               args.termination.c_str(), args.resonance_list_path.c_str());
  return Status::Ok();
}

}  // namespace

int RunFreqrespFromLog(const FreqrespLogArgs& args) {
  const std::string name = "freqresp";
  auto log = riglog::ReadRigLog(args.log_path, args.read);
  if (!log.ok()) return Fail(name, log.status());
  auto response = EstimateEmpiricalResponse(*log, args.response);
  if (!response.ok()) return Fail(name, response.status().Within(args.log_path));
  if (!args.json_path.empty()) {
    Status written = WriteText(args.json_path, ResponseJson(*response, args));
    if (!written.ok()) return Fail(name, written);
  }
  if (!args.csv_path.empty()) {
    Status written = WriteText(args.csv_path, ResponseCsv(*response));
    if (!written.ok()) return Fail(name, written);
  }
  if (!args.resonance_list_path.empty()) {
    const Status appended = AppendResonance(*response, args);
    if (!appended.ok()) return Fail(name, appended);
  }
  if (args.json_path == "-" || args.csv_path == "-") return 0;
  std::printf(
      "%s: piston_position -> pressure, %d Welch segments of %.1f s (df %.4f Hz), %.4g Hz\n",
      args.log_path.c_str(), response->segments, response->segment_s, response->df_hz,
      response->sample_rate_hz);
  std::printf("%-8s  %s\n", "channel", "resonances [Hz] (gamma^2 >= min_coherence)");
  for (const ChannelResponse& ch : response->channels) {
    std::printf("%-8s ", ch.channel.c_str());
    if (ch.peaks.empty()) std::printf(" none");
    for (const ResonancePeak& p : ch.peaks) {
      std::printf("  %.4f +- %.4f (gamma^2 %.2f)", p.freq_hz, p.uncertainty_hz, p.coherence);
    }
    std::printf("\n");
  }
  return 0;
}

}  // namespace mpdrig::cli
