// mpdrig_command_latency: time from writing a command to the first sensor sample that reflects
// it, as a controller sees it, against a running `mpdrig serve --clock realtime`. It toggles the
// pump between two flows and waits for FT2 (an input: the next sample shows it, rig_host.h) to
// read the new value. Each latency is a wait for the next tick (up to one sensor period), the
// service's tick, and two DDS one-way trips (command in, sample out); bench/command_latency.sh
// runs it beside ddsperf's round trip.
//
//   mpdrig_command_latency --domain 9 --rig rig-1 --count 2000
//   mpdrig_command_latency --domain 9 --rig rig-1 --security class/rig-1   # DDS Security
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/dds/topics.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "mpdrig_command_latency: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("mpdrig_command_latency - pump command to the first FT2 sample that shows it");
  int domain = 0;
  std::string rig_id = "rig-1";
  int count = 1000;
  double low_lpm = 5.0, high_lpm = 6.0;
  app.add_option("--domain", domain, "DDS domain id")->capture_default_str();
  app.add_option("--rig", rig_id, "rig id")->capture_default_str();
  app.add_option("--count", count, "commands to time")->check(CLI::Range(10, 1000000));
  std::string security;
  app.add_option("--security", security,
                 "DDS Security identity directory (deploy/security/make-class OUT NAME: OUT/NAME)");
  CLI11_PARSE(app, argc, argv);

  using namespace mpdrig;
  auto created = dds::Domain::Create(domain, dds::LoopbackConfig());
  if (!created.ok()) return Fail(created.status().message());
  auto scope = dds::CreateClientScope(domain, security, rig_id);
  if (!scope.ok()) return Fail(scope.status().message());
  const dds_entity_t p = scope->participant.handle();
  auto sensors_topic = dds::CreateTopic(p, dds::topics::kSensors);
  auto pump_topic = dds::CreateTopic(p, dds::topics::kPumpCommand);
  if (!sensors_topic.ok() || !pump_topic.ok()) return Fail("cannot create topics");
  auto sensors = dds::Reader<mpdrig_RigSensors>::Create(scope->sub(), sensors_topic->handle(),
                                                        dds::SensorQos());
  auto pump = dds::Writer<mpdrig_PumpCommand>::Create(scope->pub(), pump_topic->handle(),
                                                      dds::CommandQos());
  if (!sensors.ok() || !pump.ok()) return Fail("cannot create the reader or the writer");

  // Waits for the first sample whose FT2 is `flow_lpm`; seconds since `since`, or -1 on timeout.
  using Clock = std::chrono::steady_clock;
  auto wait_for = [&](double flow_lpm, Clock::time_point since) -> double {
    for (;;) {
      auto ready = sensors->Wait(DDS_SECS(2));
      if (!ready.ok() || !*ready) return -1.0;
      bool seen = false;
      (void)sensors->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
        if (rig_id == s.rig_id && std::fabs(s.FT2_lpm - flow_lpm) < 1e-9) seen = true;
      });
      if (seen) return std::chrono::duration<double>(Clock::now() - since).count();
    }
  };
  mpdrig_PumpCommand command{rig_id.data(), low_lpm};
  // Warm-up: discovery, and the first command in force.
  for (int attempt = 0;; ++attempt) {
    if (attempt > 20)
      return Fail("no rig '" + rig_id + "' answering on domain " + std::to_string(domain));
    if (!pump->Write(command).ok()) return Fail("dds_write");
    if (wait_for(low_lpm, Clock::now()) >= 0.0) break;
  }

  std::vector<double> latency_s;
  const std::clock_t cpu_started = std::clock();
  const Clock::time_point wall_started = Clock::now();
  std::mt19937 random(12345);
  // Commands at random phases of the sensor period: 5-15 ms apart.
  std::uniform_int_distribution<int> gap_us(5000, 15000);
  for (int i = 0; i < count; ++i) {
    command.flow_lpm = (i % 2 == 0) ? high_lpm : low_lpm;
    dds_sleepfor(DDS_USECS(gap_us(random)));
    const Clock::time_point written = Clock::now();
    if (!pump->Write(command).ok()) return Fail("dds_write");
    const double seconds = wait_for(command.flow_lpm, written);
    if (seconds < 0.0) return Fail("no sample showed command " + std::to_string(i));
    latency_s.push_back(seconds);
  }
  const double cpu_s = static_cast<double>(std::clock() - cpu_started) / CLOCKS_PER_SEC;
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_started).count();
  std::sort(latency_s.begin(), latency_s.end());
  auto quantile = [&](double q) {
    return 1e3 * latency_s[static_cast<std::size_t>(q * (latency_s.size() - 1))];
  };
  std::printf(
      "command->sensor latency (pump command -> FT2), %zu commands: p50 %.3f ms, p90 %.3f ms, "
      "p99 %.3f ms, max %.3f ms; probe CPU %.1f%% of one core (%s)\n",
      latency_s.size(), quantile(0.5), quantile(0.9), quantile(0.99), 1e3 * latency_s.back(),
      100.0 * cpu_s / wall_s, security.empty() ? "no security" : "DDS Security");
  return 0;
}
