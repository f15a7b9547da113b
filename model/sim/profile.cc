#include "model/sim/profile.h"

#include <charconv>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>
#include <vector>

namespace mpdrig {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

class ConstantProfile final : public Profile {
 public:
  explicit ConstantProfile(double value) : value_(value) {}
  double ValueAt(double) const override { return value_; }
  std::string Describe() const override { return "constant " + std::to_string(value_); }

 private:
  double value_;
};

class SineProfile final : public Profile {
 public:
  SineProfile(double mean, double amplitude, double freq_hz, double phase_rad)
      : mean_(mean), amplitude_(amplitude), freq_hz_(freq_hz), phase_rad_(phase_rad) {}
  double ValueAt(double t) const override {
    return mean_ + amplitude_ * std::sin(kTwoPi * freq_hz_ * t + phase_rad_);
  }
  std::string Describe() const override {
    std::ostringstream out;
    out << "sine, amplitude " << amplitude_ << ", " << freq_hz_ << " Hz, mean " << mean_;
    return out.str();
  }

 private:
  double mean_, amplitude_, freq_hz_, phase_rad_;
};

class SweepProfile final : public Profile {
 public:
  SweepProfile(double mean, double amplitude, double f0_hz, double f1_hz, double duration_s)
      : mean_(mean), amplitude_(amplitude), f0_(f0_hz), f1_(f1_hz), duration_s_(duration_s) {}
  double ValueAt(double t) const override {
    const double tc = std::min(std::max(t, 0.0), duration_s_);
    // Instantaneous frequency rises linearly from f0 to f1 over the duration, then stays at f1.
    double phase = kTwoPi * (f0_ * tc + 0.5 * (f1_ - f0_) * tc * tc / duration_s_);
    if (t > duration_s_) phase += kTwoPi * f1_ * (t - duration_s_);
    return mean_ + amplitude_ * std::sin(phase);
  }
  std::string Describe() const override {
    std::ostringstream out;
    out << "sweep, amplitude " << amplitude_ << ", " << f0_ << " -> " << f1_ << " Hz over "
        << duration_s_ << " s";
    return out.str();
  }

 private:
  double mean_, amplitude_, f0_, f1_, duration_s_;
};

class StepProfile final : public Profile {
 public:
  StepProfile(double mean, double amplitude, double t0_s, double rise_s)
      : mean_(mean), amplitude_(amplitude), t0_s_(t0_s), rise_s_(rise_s) {}
  double ValueAt(double t) const override {
    if (t <= t0_s_) return mean_;
    if (rise_s_ <= 0.0 || t >= t0_s_ + rise_s_) return mean_ + amplitude_;
    return mean_ + amplitude_ * (t - t0_s_) / rise_s_;
  }
  std::string Describe() const override {
    std::ostringstream out;
    out << "step of " << amplitude_ << " at " << t0_s_ << " s (rise " << rise_s_ << " s)";
    return out.str();
  }

 private:
  double mean_, amplitude_, t0_s_, rise_s_;
};

Result<double> ParseNumber(std::string_view text, std::string_view what) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() ||
      !std::isfinite(value)) {
    return Status::Error(std::string(what) + ": '" + std::string(text) +
                         "' is not a finite number");
  }
  return value;
}

// Parses "k1=v1,k2=v2" against the allowed keys; `required` must all be present.
Result<std::map<std::string, double>> ParseKeys(std::string_view body, std::string_view kind,
                                                const std::vector<std::string>& required,
                                                const std::vector<std::string>& optional) {
  std::map<std::string, double> values;
  auto allowed = [&](const std::string& key) {
    for (const auto& k : required)
      if (k == key) return true;
    for (const auto& k : optional)
      if (k == key) return true;
    return false;
  };
  auto usage = [&]() {
    std::string text = std::string(kind) + " takes ";
    for (std::size_t i = 0; i < required.size(); ++i) text += (i ? "," : "") + required[i] + "=..";
    for (const auto& k : optional) text += ",[" + k + "=..]";
    return text;
  };
  bool more = !body.empty();
  while (more) {
    const std::size_t comma = body.find(',');
    const std::string_view item = body.substr(0, comma);
    more = comma != std::string_view::npos;  // a trailing comma leaves an empty item: an error
    body = more ? body.substr(comma + 1) : std::string_view();
    const std::size_t equals = item.find('=');
    if (equals == std::string_view::npos) {
      return Status::Error("'" + std::string(item) + "' is not key=value; " + usage());
    }
    const std::string key(item.substr(0, equals));
    if (!allowed(key)) return Status::Error("unknown key '" + key + "'; " + usage());
    if (values.count(key)) return Status::Error("key '" + key + "' given twice");
    auto value = ParseNumber(item.substr(equals + 1), key);
    if (!value.ok()) return value.status();
    values[key] = *value;
  }
  for (const auto& key : required) {
    if (!values.count(key)) return Status::Error("missing key '" + key + "'; " + usage());
  }
  return values;
}

}  // namespace

Result<std::unique_ptr<Profile>> ParseProfile(std::string_view spec, std::string_view unit,
                                              double default_duration_s) {
  const std::string u(unit);
  const std::size_t colon = spec.find(':');
  const std::string_view kind = spec.substr(0, colon);
  const std::string_view body =
      colon == std::string_view::npos ? std::string_view() : spec.substr(colon + 1);
  const std::string amp = "amp_" + u;
  const std::string mean = "mean_" + u;

  if (colon == std::string_view::npos) {
    auto value = ParseNumber(spec, "profile");
    if (!value.ok()) {
      return Status::Error("'" + std::string(spec) +
                           "' is neither a number nor a profile (sine:..., sweep:..., step:...)");
    }
    return std::unique_ptr<Profile>(new ConstantProfile(*value));
  }
  if (kind == "sine") {
    auto keys = ParseKeys(body, "sine", {amp, "freq_hz"}, {mean, "phase_deg"});
    if (!keys.ok()) return keys.status();
    auto& k = *keys;
    if (k["freq_hz"] < 0.0) return Status::Error("sine: freq_hz must be >= 0");
    return std::unique_ptr<Profile>(
        new SineProfile(k[mean], k[amp], k["freq_hz"], k["phase_deg"] * std::numbers::pi / 180.0));
  }
  if (kind == "sweep") {
    auto keys = ParseKeys(body, "sweep", {amp, "f0_hz", "f1_hz"}, {mean, "duration_s"});
    if (!keys.ok()) return keys.status();
    auto& k = *keys;
    const double duration = k.count("duration_s") ? k["duration_s"] : default_duration_s;
    if (!(duration > 0.0)) return Status::Error("sweep: duration_s must be > 0");
    if (k["f0_hz"] < 0.0 || k["f1_hz"] < 0.0)
      return Status::Error("sweep: frequencies must be >= 0");
    return std::unique_ptr<Profile>(
        new SweepProfile(k[mean], k[amp], k["f0_hz"], k["f1_hz"], duration));
  }
  if (kind == "step") {
    auto keys = ParseKeys(body, "step", {amp, "t_s"}, {mean, "rise_s"});
    if (!keys.ok()) return keys.status();
    auto& k = *keys;
    if (k["rise_s"] < 0.0) return Status::Error("step: rise_s must be >= 0");
    return std::unique_ptr<Profile>(new StepProfile(k[mean], k[amp], k["t_s"], k["rise_s"]));
  }
  return Status::Error("unknown profile '" + std::string(kind) +
                       "'; valid: sine, sweep, step, or a number");
}

}  // namespace mpdrig
