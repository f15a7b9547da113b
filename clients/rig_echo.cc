// rig_echo: prints or records what a rig publishes, as a rig log (rig-log-format.md), so any DDS
// recording of a rig (virtual or physical) is a file the comparison tools read. A client: it
// speaks only the DDS topics and never links model/.
//
//   rig_echo --rig rig-1 --out run.csv            # until Ctrl-C
//   rig_echo --rig rig-1 --samples 6000 --out -   # 6000 samples to stdout
//   rig_echo --samples 10000 --timing --out /dev/null  # sensor period jitter as received
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "clients/rig_watch.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"

namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

// Columns in the wire's own lab units, so values are written as they arrive.
constexpr const char* kHeader =
    "time_s,piston_position_m,choke_position_deg,FT2_lpm,C1_barg,P1_barg,P2_barg,PT1_barg,"
    "PT2_barg,PT3_barg,PT4_barg,PT5_barg,PT6_barg,PT7_barg,PT8_barg,PT9_barg,PT10_barg,C2_barg,"
    "FT1_lpm,FT3_lpm,FT4_lpm";

void WriteRow(std::ostream& out, const mpdrig_RigSensors& s) {
  char line[1024];
  int n = std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g",
                        s.sim_time_s, s.piston_position_m, s.choke_position_deg, s.FT2_lpm,
                        s.C1_barg, s.P1_barg, s.P2_barg);
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

int Fail(const mpdrig::Status& status) {
  std::fprintf(stderr, "rig_echo: %s\n", status.message().c_str());
  return 1;
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
      "comes for --timeout s: rig_echo says why, keeps the rows recorded so far and exits 3.");
  app.add_option("--dds-config", dds_config, "Cyclone DDS XML (default: loopback only)");
  app.add_option("--security", security,
                 "DDS Security: an identity directory of a class (deploy/security/make-class OUT "
                 "NAME: OUT/NAME) allowed to read the rig; the rig's topics are then in "
                 "partition rig.<rig id>. Refuses an invalid directory, saying why");
  CLI11_PARSE(app, argc, argv);

  auto created = mpdrig::dds::Domain::Create(
      domain, dds_config.empty() ? mpdrig::dds::LoopbackConfig() : dds_config);
  if (!created.ok()) return Fail(created.status());
  // With --security the rig's topics are in its partition (make-class's permissions name it).
  auto scope = mpdrig::dds::CreateClientScope(domain, security, rig_id);
  if (!scope.ok()) return Fail(scope.status());
  auto topic = mpdrig::dds::CreateTopic(scope->participant.handle(), &mpdrig_RigSensors_desc,
                                        "mpdrig_sensors");
  if (!topic.ok()) return Fail(topic.status());
  // Keep all: a recording should not drop samples the rig sent.
  auto reader = mpdrig::dds::Reader<mpdrig_RigSensors>::Create(scope->sub(), topic->handle(),
                                                               mpdrig::dds::SensorQos(true));
  if (!reader.ok()) return Fail(reader.status());

  std::ofstream file;
  std::ostream* out = &std::cout;
  if (out_path != "-") {
    file.open(out_path);
    if (!file) return Fail(mpdrig::Status::Error(out_path + ": cannot write"));
    out = &file;
  }
  *out << "# rig-log: 1\n# source: rig_echo, rig " << rig_id << ", DDS domain " << domain
       << "\n# atmospheric_pressure_pa: 101325\n"
       << kHeader << "\n";

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  long written = 0;
  std::vector<double> arrival_s, source_s;
  const auto started = std::chrono::steady_clock::now();
  double previous_time = -1e300;
  // A lost rig (clients/rig_watch.h) ends the recording: the file keeps what came before, on
  // whole rows, and the exit status says the recording did not end as asked.
  mpdrig::clients::RigWatch watch(timeout_s);
  std::optional<std::string> lost;
  auto last_sample = std::chrono::steady_clock::now();
  auto take = [&]() -> mpdrig::Status {
    auto taken = reader->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t& info) {
      if (rig_id != s.rig_id || lost) return;
      lost = watch.Sample(s.sample_counter, s.sim_time_s);
      if (lost) return;
      last_sample = std::chrono::steady_clock::now();
      // Only increasing times (a rig log's time is strictly increasing).
      if (!(s.sim_time_s > previous_time)) return;
      if (max_samples != 0 && written >= max_samples) return;
      WriteRow(*out, s);
      if (timing) {
        arrival_s.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
        source_s.push_back(1e-9 * static_cast<double>(info.source_timestamp));
      }
      previous_time = s.sim_time_s;
      ++written;
    });
    return taken.status();
  };
  while (!g_stop && !lost && (max_samples == 0 || written < max_samples)) {
    auto ready = reader->Wait(DDS_MSECS(100));
    if (!ready.ok()) return Fail(ready.status());
    if (*ready) {
      const mpdrig::Status taken = take();
      if (!taken.ok()) return Fail(taken);
    }
    if (lost) break;
    const double idle_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - last_sample).count();
    dds_subscription_matched_status_t matched{};
    dds_get_subscription_matched_status(reader->handle(), &matched);
    lost = watch.Check(idle_s, matched.current_count > 0);
    if (lost) {
      // What the departed writer sent before it went is in the reader already: keep it.
      const std::optional<std::string> why = lost;
      lost.reset();
      const mpdrig::Status taken = take();
      if (!taken.ok()) return Fail(taken);
      if (!lost) lost = why;
      break;
    }
    if (!watch.seen() && timeout_s > 0.0 && idle_s >= timeout_s) break;  // no rig: exit 1
  }
  out->flush();
  if (!*out) return Fail(mpdrig::Status::Error(out_path + ": write failed"));
  std::fprintf(stderr, "rig_echo: %ld samples of %s recorded\n", written, rig_id.c_str());
  if (lost) {
    std::fprintf(stderr, "rig_echo: rig %s lost: %s; the recording ends there\n", rig_id.c_str(),
                 lost->c_str());
    return mpdrig::clients::kExitRigLost;
  }
  if (timing) {
    PrintTiming("published (source timestamps)", source_s);
    PrintTiming("received (arrival at this reader)", arrival_s);
  }
  return written > 0 ? 0 : 1;
}
