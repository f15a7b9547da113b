// Column separation told apart from free gas by what the log shows (cavity_evidence.h): pressures
// held on a floor and ended by a collapse's jump.
#include "model/identification/cavity_evidence.h"

#include <cstdio>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "model/identification/synthetic_log.h"
#include "model/sim/sensor_noise.h"

namespace mpdrig {
namespace {

struct Logged {
  CavityEvidence evidence;
  MeasuredLog log;
};

Logged EvidenceOf(const std::string& effect, std::uint64_t seed, bool lab_noise, int cells,
                  double duration_s = 40.0, double rate_hz = 50.0) {
  SyntheticLogOptions options;
  options.seed = seed;
  options.duration_s = duration_s;
  options.rate_hz = rate_hz;
  options.cells = cells;
  options.low_pressure = true;
  if (effect != "none") options.hidden_effects = {effect};
  if (lab_noise) options.sensor_noise = SensorNoise::Lab();
  auto synthetic = MakeSyntheticLog(options);
  EXPECT_TRUE(synthetic.ok()) << synthetic.status().message();
  auto log = MeasuredLogFromRigLog(synthetic->log, "synthetic");
  EXPECT_TRUE(log.ok()) << log.status().message();
  Logged out{FindPressureFloors(*log), *log};
  std::printf("%s seed %d %s cells %d: %d holds on %zu channels at %.0f Pa (%s)\n", effect.c_str(),
              static_cast<int>(seed), lab_noise ? "lab" : "quiet", cells, out.evidence.holds,
              out.evidence.floors.size(), out.evidence.level_pa, synthetic->description.c_str());
  for (const ChannelFloor& floor : out.evidence.floors) {
    std::printf("  %s: sigma %.0f Pa, level %.0f Pa,",
                std::string(ChannelName(floor.channel)).c_str(), floor.noise_pa, floor.level_pa);
    for (const PressureHold& hold : floor.holds) {
      std::printf(" %.2f-%.2f s @%.0f (+%.0f)", hold.start_s, hold.end_s, hold.level_pa,
                  hold.rise_pa);
    }
    std::printf("\n");
  }
  return out;
}

TEST(CavityEvidence, Explore) {
  const char* e = std::getenv("EFFECT");
  const int seeds = std::getenv("SEEDS") ? std::atoi(std::getenv("SEEDS")) : 3;
  const int cells = std::getenv("CELLS") ? std::atoi(std::getenv("CELLS")) : 50;
  const bool lab = std::getenv("QUIET") == nullptr;
  const double duration = std::getenv("DUR") ? std::atof(std::getenv("DUR")) : 40.0;
  const double rate = std::getenv("RATE") ? std::atof(std::getenv("RATE")) : 50.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    EvidenceOf(e ? e : "column_separation", seed, lab, cells, duration, rate);
  }
}

}  // namespace
}  // namespace mpdrig
