// The lab's sensor noise: what the rig's transmitters, flow meters and position feedbacks add to
// the true value, so that a simulated log or a virtual rig reads like the physical one.
//
// Model: white (independent from sample to sample at the logging or sensor rate), Gaussian, zero
// mean, per channel kind; the reading is y = x + sigma(x) n with n ~ N(0, 1):
//   pressure  P1 P2 PT1..PT10 C1 C2     sigma = pressure_pa
//   flow      FT1 FT2 FT3 FT4           sigma = flow_fraction |x| + flow_m3ps
//   piston    piston_position           sigma = piston_m
//   choke     choke_position            sigma = choke_deg (the model's opening is deg / 90)
// The preset `lab` is thesis Table 4.1.1 (section 4.1.2) read as one standard deviation:
//   pressure transmitters (UNIK 5000 / PTX 1400): +-0.15 % of 0-16 bar  -> 0.024 bar
//   turbine flow meters (Parker DFT990): +-2 % of reading, plus 0.05 L/min near zero flow
//   piston position 0.5 mm and choke position feedback 0.1 deg (not in the table: the issue's
//   reading of the lab's position feedbacks).
// Not modelled: the back-pressure pump's vibration on the pipe's pressure sensors (section
// 4.1.1): the thesis gives neither its size nor its spectrum, only that it is there while the
// pump runs and that the lab low-pass filtered it away. Sensor dynamics (a transmitter's lag) are
// an effect of the catalogue (sensor_lag), not noise.
//
// Text form (`--sensor-noise SPEC`), comma separated, case-insensitive units:
//   none | lab                                        a preset
//   pressure=0.024bar,flow=2%+0.05lpm,piston=0.5mm,choke=0.1deg
//   lab,pressure=0,scale=0.5                          a preset first, then changes to it
// Keys: pressure (bar, mbar, pa, kpa), flow (terms joined by '+': N% of reading, N lpm or
// N m3ps), piston (m, mm, um), choke (deg), scale (a factor on everything, applied last). A key
// that is not given is 0, or the preset's value. 0 needs no unit. Negative, NaN and infinite
// values are refused; an error names the bad token and lists the valid keys or units.
//
// Applying it (SensorNoiseApplier): std::mt19937_64 with the Gaussian written out (Box-Muller),
// so a seed gives the same numbers with any standard library, and one independent stream per
// channel, seeded from (seed, channel name): a channel's noise does not depend on which other
// channels are measured or in which order they are read.
#pragma once

#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/common/status.h"
#include "model/core/rig_channels.h"

namespace mpdrig {

struct RigSample;

// Standard deviations per channel kind, SI except the choke (deg, as its feedback reads).
struct SensorNoise {
  double pressure_pa = 0.0;
  double flow_fraction = 0.0;  // of the reading's magnitude
  double flow_m3ps = 0.0;      // added to the relative part
  double piston_m = 0.0;
  double choke_deg = 0.0;

  static SensorNoise None() { return {}; }
  static SensorNoise Lab();

  bool IsNone() const;
  // Every value finite and >= 0; the error names the first field that is not.
  Status Validate() const;
  // "none", "lab", or the full text form, which ParseSensorNoise reads back.
  std::string ToSpec() const;
  // The standard deviation of a reading of `channel` whose true value is `value_si` (SI with
  // absolute pressure, choke as a fraction); 0 for time and channels without noise.
  double SigmaFor(Channel channel, double value_si) const;

  bool operator==(const SensorNoise&) const = default;
};

// "none, lab"
std::string SensorNoisePresetNames();
// Parses the text form above. The error quotes the bad token and lists what is valid there.
Result<SensorNoise> ParseSensorNoise(std::string_view text);

// A seed for one of several independent users of one seed (e.g. one rig of a service): mixes
// `name` into `seed` (FNV-1a and SplitMix64), so the streams do not overlap in practice.
std::uint64_t MixSeed(std::uint64_t seed, std::string_view name);

// Adds the noise of a SensorNoise to readings, reproducibly for a seed. Not thread-safe (each
// channel's stream advances by one draw per reading); copy it to branch a stream.
class SensorNoiseApplier {
 public:
  SensorNoiseApplier(const SensorNoise& noise, std::uint64_t seed);

  const SensorNoise& noise() const { return noise_; }
  std::uint64_t seed() const { return seed_; }

  // The reading of `channel` for the true value `value_si`. A channel kind without noise returns
  // the value unchanged (bitwise) and draws nothing; otherwise one draw of that channel's stream,
  // also for a NaN value (not measured), which stays NaN.
  double Measure(Channel channel, double value_si);
  // Measure() on every value, in order.
  void MeasureColumn(Channel channel, std::span<double> values_si);
  // Measure() on every channel of a sample except time. The sample's extra pressure outputs
  // along the pipe (pressure_at_positions_pa) are the model's, not sensors: left as they are.
  void MeasureSample(RigSample* sample);

 private:
  // One channel's standard normal draws: mt19937_64, 53-bit uniforms, Box-Muller in pairs.
  class Stream {
   public:
    explicit Stream(std::uint64_t seed) : engine_(seed) {}
    double Normal();

   private:
    double Uniform();  // in [0, 1)
    std::mt19937_64 engine_;
    double spare_ = 0.0;
    bool has_spare_ = false;
  };

  SensorNoise noise_;
  std::uint64_t seed_;
  std::vector<Stream> streams_;  // indexed by Channel
};

}  // namespace mpdrig
