#include "tools/cli/freqresp_log.h"

#include <cstdio>
#include <sstream>

#include "model/riglog/rig_log.h"
#include "tools/cli/json_text.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

std::string ResponseJson(const EmpiricalResponse& r, const FreqrespLogArgs& args) {
  std::ostringstream out;
  out << "{\n  \"log\": " << JsonString(args.log_path) << ",\n";
  out << "  \"input\": \"piston_position\",\n";
  out << "  \"magnitude_unit\": \"Pa/m\",\n";
  out << "  \"sample_rate_hz\": " << JsonNumber(r.sample_rate_hz) << ",\n";
  out << "  \"segment_s\": " << JsonNumber(r.segment_s) << ",\n";
  out << "  \"segments\": " << r.segments << ",\n";
  out << "  \"df_hz\": " << JsonNumber(r.df_hz) << ",\n";
  out << "  \"min_coherence\": " << JsonNumber(args.response.min_coherence) << ",\n";
  out << "  \"channels\": [";
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    const ChannelResponse& ch = r.channels[c];
    out << (c ? "," : "") << "\n    {\"channel\": " << JsonString(ch.channel)
        << ",\n     \"peaks\": [";
    for (std::size_t k = 0; k < ch.peaks.size(); ++k) {
      const ResonancePeak& p = ch.peaks[k];
      out << (k ? ", " : "") << "{\"freq_hz\": " << JsonNumber(p.freq_hz)
          << ", \"uncertainty_hz\": " << JsonNumber(p.uncertainty_hz)
          << ", \"magnitude\": " << JsonNumber(p.magnitude)
          << ", \"coherence\": " << JsonNumber(p.coherence)
          << ", \"half_power_width_hz\": " << JsonNumber(p.half_power_width_hz) << "}";
    }
    out << "],\n     \"points\": [";
    for (std::size_t k = 0; k < ch.points.size(); ++k) {
      const EmpiricalPoint& p = ch.points[k];
      out << (k ? ", " : "") << "{\"freq_hz\": " << JsonNumber(p.freq_hz)
          << ", \"magnitude\": " << JsonNumber(p.magnitude)
          << ", \"phase_deg\": " << JsonNumber(p.phase_deg)
          << ", \"coherence\": " << JsonNumber(p.coherence) << "}";
    }
    out << "]}";
  }
  out << "\n  ]\n}\n";
  return out.str();
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
