#include "model/sim/sensor_noise.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <vector>

#include "model/common/units.h"
#include "model/riglog/channels.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {
namespace {

constexpr std::string_view kKeys = "pressure, flow, piston, choke, scale";

enum class Kind { kNone, kPressure, kFlow, kPiston, kChoke };

Kind KindOf(Channel channel) {
  switch (riglog::QuantityOf(channel)) {
    case riglog::Quantity::kPressure:
      return Kind::kPressure;
    case riglog::Quantity::kFlow:
      return Kind::kFlow;
    case riglog::Quantity::kPosition:
      return Kind::kPiston;
    case riglog::Quantity::kChokeOpening:
      return Kind::kChoke;
    case riglog::Quantity::kTime:
      break;
  }
  return Kind::kNone;
}

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view Trim(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front())))
    text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
    text.remove_suffix(1);
  return text;
}

std::string Quoted(std::string_view text) { return riglog::QuoteForMessage(text); }

// A unit a value may carry and its factor to the field's unit.
struct UnitFactor {
  std::string_view name;
  double factor;
};

// Reads a number at the front of `text`; the rest (the unit) is left in `text`.
Result<double> TakeNumber(std::string_view* text, std::string_view token) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text->data(), text->data() + text->size(), value);
  if (error != std::errc() || end == text->data()) {
    return Status::Error("sensor noise: " + Quoted(token) + ": not a number");
  }
  if (!std::isfinite(value)) {
    return Status::Error("sensor noise: " + Quoted(token) + ": not a finite number");
  }
  if (value < 0.0) {
    return Status::Error("sensor noise: " + Quoted(token) + ": negative (a standard deviation)");
  }
  text->remove_prefix(static_cast<std::size_t>(end - text->data()));
  return value;
}

// A number with one of `units` (0 may go without).
Result<double> ParseQuantity(std::string_view value_text, std::string_view token,
                             std::initializer_list<UnitFactor> units) {
  std::string_view rest = value_text;
  auto number = TakeNumber(&rest, token);
  if (!number.ok()) return number.status();
  const std::string unit = Lower(Trim(rest));
  std::string names;
  for (const UnitFactor& u : units) {
    if (unit == u.name) return *number * u.factor;
    names += (names.empty() ? "" : ", ") + std::string(u.name);
  }
  if (unit.empty() && *number == 0.0) return 0.0;
  return Status::Error("sensor noise: " + Quoted(token) +
                       (unit.empty() ? ": needs a unit" : ": unknown unit " + Quoted(rest)) +
                       "; units: " + names);
}

// Terms joined by '+': N% (of the reading) or N lpm / N m3ps.
Status ParseFlow(std::string_view value_text, std::string_view token, SensorNoise* noise) {
  noise->flow_fraction = 0.0;
  noise->flow_m3ps = 0.0;
  std::string_view rest = value_text;
  while (true) {
    auto number = TakeNumber(&rest, token);
    if (!number.ok()) return number.status();
    // The unit runs to the next '+' (a '+' inside the number, 1e+2, was taken by from_chars).
    const std::size_t plus = rest.find('+');
    const std::string unit = Lower(Trim(rest.substr(0, plus)));
    if (unit == "%") {
      noise->flow_fraction += *number / 100.0;
    } else if (unit == "lpm") {
      noise->flow_m3ps += units::LpmToM3ps(*number);
    } else if (unit == "m3ps") {
      noise->flow_m3ps += *number;
    } else if (!(unit.empty() && *number == 0.0)) {
      return Status::Error("sensor noise: " + Quoted(token) +
                           (unit.empty() ? ": a term needs a unit"
                                         : ": unknown unit " + Quoted(rest.substr(0, plus))) +
                           "; flow terms: N% (of the reading), N lpm, N m3ps, joined by '+'");
    }
    if (plus == std::string_view::npos) return Status::Ok();
    rest = Trim(rest.substr(plus + 1));
  }
}

std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

SensorNoise SensorNoise::Lab() {
  // Thesis Table 4.1.1; the same expressions as ParseSensorNoise, so "lab" and its text form
  // give the same doubles.
  SensorNoise lab;
  lab.pressure_pa = 0.024 * units::kPaPerBar;  // 0.15 % of 16 bar
  lab.flow_fraction = 2.0 / 100.0;
  lab.flow_m3ps = units::LpmToM3ps(0.05);
  lab.piston_m = 0.5 * 1e-3;
  lab.choke_deg = 0.1;
  return lab;
}

bool SensorNoise::IsNone() const { return *this == None(); }

Status SensorNoise::Validate() const {
  const std::pair<const char*, double> fields[] = {{"pressure_pa", pressure_pa},
                                                   {"flow_fraction", flow_fraction},
                                                   {"flow_m3ps", flow_m3ps},
                                                   {"piston_m", piston_m},
                                                   {"choke_deg", choke_deg}};
  for (const auto& [name, value] : fields) {
    if (!(std::isfinite(value) && value >= 0.0)) {
      const std::string shown = std::isnan(value)   ? "NaN"
                                : std::isinf(value) ? "infinite"
                                                    : riglog::FormatNumber(value);
      return Status::Error(std::string("sensor noise: ") + name + " is " + shown +
                           "; a standard deviation must be finite and >= 0");
    }
  }
  return Status::Ok();
}

std::string SensorNoise::ToSpec() const {
  if (IsNone()) return "none";
  if (*this == Lab()) return "lab";
  return "pressure=" + riglog::FormatNumber(pressure_pa / units::kPaPerBar) +
         "bar,flow=" + riglog::FormatNumber(flow_fraction * 100.0) + "%+" +
         riglog::FormatNumber(units::M3psToLpm(flow_m3ps)) +
         "lpm,piston=" + riglog::FormatNumber(piston_m * 1e3) +
         "mm,choke=" + riglog::FormatNumber(choke_deg) + "deg";
}

double SensorNoise::SigmaFor(Channel channel, double value_si) const {
  switch (KindOf(channel)) {
    case Kind::kPressure:
      return pressure_pa;
    case Kind::kFlow:
      return flow_fraction * std::abs(value_si) + flow_m3ps;
    case Kind::kPiston:
      return piston_m;
    case Kind::kChoke:
      return units::ChokeDegToFrac(choke_deg);
    case Kind::kNone:
      break;
  }
  return 0.0;
}

std::string SensorNoisePresetNames() { return "none, lab"; }

Result<SensorNoise> ParseSensorNoise(std::string_view text) {
  const std::string valid = "; presets: " + SensorNoisePresetNames() +
                            "; keys: " + std::string(kKeys) +
                            " (e.g. pressure=0.024bar,flow=2%+0.05lpm,piston=0.5mm,choke=0.1deg)";
  if (Trim(text).empty()) return Status::Error("sensor noise: empty" + valid);
  SensorNoise noise;
  double scale = 1.0;
  std::vector<std::string> seen;
  bool first = true;
  std::string_view rest = text;
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view token = Trim(rest.substr(0, comma));
    const std::size_t equals = token.find('=');
    if (token.empty()) return Status::Error("sensor noise: empty item in " + Quoted(text) + valid);
    if (equals == std::string_view::npos) {
      const std::string name = Lower(token);
      if (name != "none" && name != "lab") {
        return Status::Error("sensor noise: unknown preset " + Quoted(token) + valid);
      }
      if (!first) {
        return Status::Error("sensor noise: preset " + Quoted(token) + " must come first");
      }
      noise = name == "lab" ? SensorNoise::Lab() : SensorNoise::None();
    } else {
      const std::string key = Lower(Trim(token.substr(0, equals)));
      const std::string_view value = Trim(token.substr(equals + 1));
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
        return Status::Error("sensor noise: " + Quoted(token) + ": key given twice");
      }
      seen.push_back(key);
      Result<double> parsed = 0.0;
      if (key == "pressure") {
        parsed = ParseQuantity(value, token,
                               {{"bar", units::kPaPerBar},
                                {"mbar", 1e-3 * units::kPaPerBar},
                                {"pa", 1.0},
                                {"kpa", 1e3}});
        if (parsed.ok()) noise.pressure_pa = *parsed;
      } else if (key == "flow") {
        MPDRIG_RETURN_IF_ERROR(ParseFlow(value, token, &noise));
      } else if (key == "piston") {
        parsed = ParseQuantity(value, token, {{"m", 1.0}, {"mm", 1e-3}, {"um", 1e-6}});
        if (parsed.ok()) noise.piston_m = *parsed;
      } else if (key == "choke") {
        parsed = ParseQuantity(value, token, {{"deg", 1.0}});
        if (parsed.ok()) noise.choke_deg = *parsed;
      } else if (key == "scale") {
        std::string_view number_text = value;
        parsed = TakeNumber(&number_text, token);
        if (parsed.ok() && !Trim(number_text).empty()) {
          parsed = Status::Error("sensor noise: " + Quoted(token) + ": scale is a plain number");
        }
        if (parsed.ok()) scale = *parsed;
      } else {
        return Status::Error("sensor noise: unknown key " + Quoted(token.substr(0, equals)) +
                             " in " + Quoted(token) + "; valid keys: " + std::string(kKeys));
      }
      if (!parsed.ok()) return parsed.status();
    }
    first = false;
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  noise.pressure_pa *= scale;
  noise.flow_fraction *= scale;
  noise.flow_m3ps *= scale;
  noise.piston_m *= scale;
  noise.choke_deg *= scale;
  MPDRIG_RETURN_IF_ERROR(noise.Validate());
  return noise;
}

std::uint64_t MixSeed(std::uint64_t seed, std::string_view name) {
  std::uint64_t hash = 0xcbf29ce484222325ULL;  // FNV-1a
  for (char c : name) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return SplitMix64(SplitMix64(seed) ^ hash);
}

double SensorNoiseApplier::Stream::Uniform() {
  return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
}

double SensorNoiseApplier::Stream::Normal() {
  // Box-Muller: two independent standard normals from two uniforms; u1 in (0, 1] keeps the
  // logarithm finite.
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - Uniform();
  const double u2 = Uniform();
  const double radius = std::sqrt(-2.0 * std::log(u1));
  const double angle = 2.0 * std::numbers::pi * u2;
  spare_ = radius * std::sin(angle);
  has_spare_ = true;
  return radius * std::cos(angle);
}

SensorNoiseApplier::SensorNoiseApplier(const SensorNoise& noise, std::uint64_t seed)
    : noise_(noise), seed_(seed) {
  MPDRIG_CHECK(noise.Validate().ok());
  streams_.reserve(kChannelCount);
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    streams_.emplace_back(MixSeed(seed, riglog::ChannelName(static_cast<Channel>(i))));
  }
}

double SensorNoiseApplier::Measure(Channel channel, double value_si) {
  bool noisy = false;
  switch (KindOf(channel)) {
    case Kind::kPressure:
      noisy = noise_.pressure_pa > 0.0;
      break;
    case Kind::kFlow:
      noisy = noise_.flow_fraction > 0.0 || noise_.flow_m3ps > 0.0;
      break;
    case Kind::kPiston:
      noisy = noise_.piston_m > 0.0;
      break;
    case Kind::kChoke:
      noisy = noise_.choke_deg > 0.0;
      break;
    case Kind::kNone:
      break;
  }
  if (!noisy) return value_si;
  const double n = streams_[Index(channel)].Normal();
  if (std::isnan(value_si)) return value_si;
  return value_si + noise_.SigmaFor(channel, value_si) * n;
}

void SensorNoiseApplier::MeasureColumn(Channel channel, std::span<double> values_si) {
  for (double& value : values_si) value = Measure(channel, value);
}

void SensorNoiseApplier::MeasureSample(RigSample* sample) {
  for (std::size_t i = 0; i < kChannelCount; ++i) {
    const Channel channel = static_cast<Channel>(i);
    if (channel == Channel::kTime) continue;
    sample->values[i] = Measure(channel, sample->values[i]);
  }
}

}  // namespace mpdrig
