// rig_echo: prints or records what a rig publishes, as a rig log (rig-log-format.md), so any DDS
// recording of a rig (virtual or physical) is a file the comparison tools read. A client: it
// speaks only the DDS topics, through the client library (clients/client/rig_client.h: QoS,
// security, the lost-rig rule), and never links model/.
//
//   rig_echo --rig rig-1 --out run.csv            # until Ctrl-C
//   rig_echo --rig rig-1 --samples 6000 --out -   # 6000 samples to stdout
//   rig_echo --samples 10000 --timing --out /dev/null  # sensor period jitter as received
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "clients/client/rig_client.h"
#include "clients/rig_watch.h"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

// Columns in the wire's own lab units, so values are written as they arrive.
constexpr const char* kHeader =
    "time_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,P1_barg,P2_barg,PT1_barg,"
    "PT2_barg,PT3_barg,PT4_barg,PT5_barg,PT6_barg,PT7_barg,PT8_barg,PT9_barg,PT10_barg,C2_barg,"
    "FT1_lpm,FT3_lpm,FT4_lpm";

void WriteRow(std::ostream& out, const mpdrig::client::Sensors& s) {
  char line[1024];
  int n = std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", s.time_s,
                        s.piston_position_m, s.choke_position_deg, s.FT2_lpm, s.C1_barg, s.P1_barg,
                        s.P2_barg);
  for (double pt : s.PT_barg) n += std::snprintf(line + n, sizeof line - n, ",%.17g", pt);
  std::snprintf(line + n, sizeof line - n, ",%.17g,%.17g,%.17g,%.17g\n", s.C2_barg, s.FT1_lpm,
                s.FT3_lpm, s.FT4_lpm);
  out << line;
}

// Inter-arrival statistics of the received samples against the nominal period (the median):
// what a controller subscribed to the rig sees of its sensor clock.
void PrintTiming(const char* what, const std::vector<double>& arrival_s) {
  if (arrival_s.size() < 3) return;
  std::vector<double> periods;
  for (std::size_t i = 1; i < arrival_s.size(); ++i)
    periods.push_back(arrival_s[i] - arrival_s[i - 1]);
  std::vector<double> sorted = periods;
  std::sort(sorted.begin(), sorted.end());
  const double nominal = sorted[sorted.size() / 2];
  std::vector<double> jitter;
  for (double p : periods) jitter.push_back(std::fabs(p - nominal));
  std::sort(jitter.begin(), jitter.end());
  auto quantile = [&](double q) {
    return jitter[static_cast<std::size_t>(q * (jitter.size() - 1))];
  };
  std::fprintf(stderr,
               "rig_echo: %s: %zu periods, median %.3f ms; |period - median|: p50 %.3f ms, "
               "p99 %.3f ms, max %.3f ms\n",
               what, periods.size(), 1e3 * nominal, 1e3 * quantile(0.5), 1e3 * quantile(0.99),
               1e3 * jitter.back());
}

// The header's atmosphere [Pa], exact for any value a rig log can give (12 significant digits).
std::string FormatAtmosphere(double pa) {
  char text[32];
  std::snprintf(text, sizeof text, "%.12g", pa);
  return text;
}

int Fail(const mpdrig::Status& status) {
  std::fprintf(stderr, "rig_echo: %s\n", status.message().c_str());
  return 1;
}

struct Recorded {
  long written = 0;
  // Samples the rig published that never arrived (gaps in sample_counter: the reader fell behind
  // a real-time rig's keep-last writer, e.g. rig_echo was stopped or starved), in how many gaps,
  // and the longest gap in rig time with where it began.
  std::uint64_t lost = 0;
  long gaps = 0;
  double longest_gap_s = 0.0, longest_gap_at_s = 0.0;
  std::vector<double> published_s, received_s;  // --timing
  std::string error;  // why the recording stopped early, if not Ctrl-C or a lost rig
};

// Writes every sample in order until `max_samples` (0: no limit), Ctrl-C, the rig's loss (the
// samples from before it included) or, before the first sample, the timeout.
Recorded Record(mpdrig::client::Rig& rig, std::ostream& out, long max_samples, bool timing,
                const mpdrig::client::Rig::Interrupt& interrupt) {
  Recorded r;
  double previous_time = -1e300;
  std::optional<std::uint64_t> previous_counter;
  while (!g_stop && (max_samples == 0 || r.written < max_samples)) {
    auto s = rig.Next(interrupt);
    if (!s.ok()) {
      using mpdrig::client::Failure;
      if (rig.last_failure() != Failure::kInterrupted && rig.last_failure() != Failure::kLost) {
        r.error = s.status().message();
      }
      break;
    }
    // Only increasing times (a rig log's time is strictly increasing).
    if (!(s->time_s > previous_time)) continue;
    // A hole in the recording is marked where it is (a comment line, which every reader of the
    // format skips) and counted: the rows on either side are not neighbours in time.
    if (previous_counter && s->sample_counter > *previous_counter + 1) {
      const std::uint64_t missing = s->sample_counter - *previous_counter - 1;
      char line[256];
      std::snprintf(line, sizeof line,
                    "# lost: %llu samples between time_s %.17g and %.17g (sample_counter %llu to "
                    "%llu did not arrive)\n",
                    static_cast<unsigned long long>(missing), previous_time, s->time_s,
                    static_cast<unsigned long long>(*previous_counter + 1),
                    static_cast<unsigned long long>(s->sample_counter - 1));
      out << line;
      r.lost += missing;
      ++r.gaps;
      if (s->time_s - previous_time > r.longest_gap_s) {
        r.longest_gap_s = s->time_s - previous_time;
        r.longest_gap_at_s = previous_time;
      }
    }
    previous_counter = s->sample_counter;
    WriteRow(out, *s);
    if (timing) {
      r.published_s.push_back(s->published_s);
      r.received_s.push_back(s->received_s);
    }
    previous_time = s->time_s;
    ++r.written;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("rig_echo - record what a rig publishes on DDS as a rig log (rig-log-format.md)");
  std::string rig_id = "rig-1";
  std::string out_path = "-";
  int domain = 0;
  long max_samples = 0;
  double timeout_s = 0.0;
  std::string dds_config;
  std::string security;
  bool timing = false;
  app.add_flag("--timing", timing, "report the sensor period jitter as received (stderr)");
  app.add_option("--rig", rig_id, "rig id to record")->capture_default_str();
  app.add_option("--out", out_path, "rig log to write ('-' for stdout)")->capture_default_str();
  app.add_option("--domain", domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  app.add_option("--samples", max_samples, "stop after this many samples (0: until Ctrl-C)");
  app.add_option("--timeout", timeout_s,
                 "give up after this many seconds without a sample (0: wait): before the first, "
                 "exit 1; after it, the rig is lost (exit 3)");
  app.footer(
      "The rig is lost when its time or sample counter goes back (the service restarted), its\n"
      "sensor writer leaves (the service exited, or crashed and its lease ran out), or no sample\n"
      "comes for --timeout s: rig_echo says why, keeps the rows recorded so far and exits 3.\n"
      "A service that ends its run as asked (a stop, --duration, a playback's last row) says so\n"
      "before it goes: the recording is then complete (exit 0). Samples the rig sent that never\n"
      "arrived (this reader fell behind) are marked '# lost: ...' in the log and counted.");
  app.add_option("--dds-config", dds_config, "Cyclone DDS XML (default: loopback only)");
  app.add_option("--security", security,
                 "DDS Security: an identity directory of a class (deploy/security/make-class OUT "
                 "NAME: OUT/NAME) allowed to read the rig; the rig's topics are then in "
                 "partition rig.<rig id>. Refuses an invalid directory, saying why");
  CLI11_PARSE(app, argc, argv);
  if (!(timeout_s >= 0.0 && timeout_s <= 86400.0)) {
    std::fprintf(stderr, "rig_echo: --timeout must be 0..86400 s\n");
    return 2;
  }

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  const mpdrig::client::Rig::Interrupt interrupt = [] { return g_stop.load(); };
  mpdrig::client::RigOptions options;
  options.rig_id = rig_id;
  options.domain = domain;
  options.dds_config = dds_config;
  options.timeout_s = timeout_s;  // 0: wait for ever, and silence never loses the rig
  options.security_dir = security;
  options.keep_every_sample = true;  // a recording should not drop samples the rig sent
  options.read_estimates = false;
  options.read_profiles = false;
  auto rig = mpdrig::client::Rig::Connect(options, interrupt);
  if (!rig.ok()) return Fail(rig.status());

  // The rig's atmosphere, from its status: the samples' gauge pressures are relative to it, so the
  // log says it and converts back to the same absolute pressures (a playback's log may have its
  // own).
  auto status = (*rig)->LatestStatus(interrupt);
  if (!status.ok()) return Fail(status.status());

  std::ofstream file;
  std::ostream* out = &std::cout;
  if (out_path != "-") {
    file.open(out_path);
    if (!file) return Fail(mpdrig::Status::Error(out_path + ": cannot write"));
    out = &file;
  }
  *out << "# rig-log: 1\n# source: rig_echo, rig " << rig_id << ", DDS domain " << domain
       << "\n# atmospheric_pressure_pa: " << FormatAtmosphere(status->atmospheric_pressure_pa)
       << "\n"
       << kHeader << "\n";
  const Recorded recorded = Record(**rig, *out, max_samples, timing, interrupt);
  out->flush();
  if (!*out) return Fail(mpdrig::Status::Error(out_path + ": write failed"));
  std::fprintf(stderr, "rig_echo: %ld samples of %s recorded\n", recorded.written, rig_id.c_str());
  if (recorded.lost > 0) {
    std::fprintf(stderr,
                 "rig_echo: %llu samples lost in %ld gaps (marked '# lost:' in the log), the "
                 "longest %.3f s after rig time %.3f s: this reader fell behind the rig (stopped, "
                 "or starved of CPU); the rows around a gap are not neighbours in time\n",
                 static_cast<unsigned long long>(recorded.lost), recorded.gaps,
                 recorded.longest_gap_s, recorded.longest_gap_at_s);
  }
  if ((*rig)->lost() && (*rig)->ended()) {
    // The service ended its run as asked: the recording is complete, not cut short.
    std::fprintf(stderr, "rig_echo: rig %s: %s; the recording is complete\n", rig_id.c_str(),
                 (*rig)->lost()->c_str());
    return recorded.written > 0 ? 0 : 1;
  }
  if (const auto& lost = (*rig)->lost()) {
    // A lost rig (clients/rig_watch.h) ends the recording: the file keeps what came before, on
    // whole rows, and the exit status says the recording did not end as asked.
    std::fprintf(stderr, "rig_echo: rig %s lost: %s; the recording ends there\n", rig_id.c_str(),
                 lost->c_str());
    return mpdrig::clients::kExitRigLost;
  }
  if (!recorded.error.empty()) std::fprintf(stderr, "rig_echo: %s\n", recorded.error.c_str());
  if (timing) {
    PrintTiming("published (source timestamps)", recorded.published_s);
    PrintTiming("received (arrival at this reader)", recorded.received_s);
  }
  return recorded.written > 0 && recorded.error.empty() ? 0 : 1;
}
