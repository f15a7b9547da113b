#include "model/params/rig_params.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <sstream>

namespace mpdrig {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Bounds are physical plausibility limits, not tuning ranges: they catch unit mistakes
// (a wave speed in km/s, a radius in mm) without forbidding experiments. The last two numbers,
// where given, are the tuning range `fit` searches (ParamInfo::fit_min, fit_max).
const ParamInfo kParams[] = {
    {"pipe_length_m", "m", "copper pipe length L (Table 8.1.2)", &RigParams::pipe_length_m, 1.0,
     1.0e5},
    {"pipe_inner_radius_m", "m", "copper pipe inner radius r_p (Table 8.1.2)",
     &RigParams::pipe_inner_radius_m, 1.0e-4, 1.0},
    {"pipe_elevation_gain_m", "m",
     "height of the outlet above the inlet (coil height, Table 8.1.2)",
     &RigParams::pipe_elevation_gain_m, -1.0e4, 1.0e4},
    {"wave_speed_mps", "m/s", "speed of sound c (tuned 850, Table 9.4.1)",
     &RigParams::wave_speed_mps, 10.0, 5000.0, 300.0, 1500.0},
    {"density_kgpm3", "kg/m^3", "water density rho_ref at p_ref (5.2.1)", &RigParams::density_kgpm3,
     100.0, 5000.0, 900.0, 1100.0},
    {"reference_pressure_pa", "Pa", "reference pressure p_ref of (5.2.1), absolute",
     &RigParams::reference_pressure_pa, 0.0, 1.0e8},
    {"friction_f1_per_s", "1/s", "linear pipe friction f1 in f(u) = f1 u + f2 u|u| (8.6.8, 9.4.1)",
     &RigParams::friction_f1_per_s, 0.0, 1.0e3, 0.0, 5.0},
    {"friction_f2_per_m", "1/m", "quadratic pipe friction f2 in f(u) = f1 u + f2 u|u| (8.6.8)",
     &RigParams::friction_f2_per_m, 0.0, 1.0e4, 0.0, 10.0},
    {"gravity_mps2", "m/s^2", "gravitational acceleration g", &RigParams::gravity_mps2, 0.0, 100.0},
    {"choke_leak_m2", "m^2", "choke leak: floor of the characteristic G (Table 9.4.1)",
     &RigParams::choke_leak_m2, 0.0, 1.0e-2, 0.0, 1.0e-5},
    {"choke_density_kgpm3", "kg/m^3", "fluid density at the choke rho_L (5.3.2)",
     &RigParams::choke_density_kgpm3, 100.0, 5000.0, 900.0, 1100.0},
    {"choke_time_constant_s", "s", "choke actuator first-order time constant (5.3)",
     &RigParams::choke_time_constant_s, 0.0, 100.0},
    {"choke_rate_limit_frac_per_s", "1/s",
     "choke actuator rate limit, fraction of full opening per second (8.4: 0-90 deg in ~1 s)",
     &RigParams::choke_rate_limit_frac_per_s, 1.0e-3, 1.0e3},
    {"upper_rod_diameter_m", "m", "drill string (upper rod) diameter, area A_d (Table 8.1.1)",
     &RigParams::upper_rod_diameter_m, 0.0, 1.0},
    {"lower_rod_diameter_m", "m", "lower rod diameter, area A_d2 (Table 8.1.1)",
     &RigParams::lower_rod_diameter_m, 0.0, 1.0},
    {"compartment_height_m", "m", "heave generator compartment height h (5.4.2, Table 8.1.1)",
     &RigParams::compartment_height_m, 0.0, 100.0},
    {"piston_friction_fd1_pa_s_per_m", "Pa s/m", "piston pressure drop, linear term f_d1 (8.2.1)",
     &RigParams::piston_friction_fd1_pa_s_per_m, -1.0e9, 1.0e9, -5.0e5, 5.0e5},
    {"piston_friction_fd2_pa_s2_per_m2", "Pa s^2/m^2",
     "piston pressure drop, quadratic term f_d2 (8.2.1)",
     &RigParams::piston_friction_fd2_pa_s2_per_m2, -1.0e10, 1.0e10, -5.0e6, 5.0e6},
    {"atmospheric_pressure_pa", "Pa", "atmospheric pressure (gauge <-> absolute)",
     &RigParams::atmospheric_pressure_pa, 1.0e4, 2.0e5},
};

}  // namespace

std::vector<ChokePoint> RigParams::DefaultChokeCharacteristic() {
  // Table 8.4.1: opening [deg] -> G [m^2]. The zero values at 0 and 15 deg are replaced by the
  // leak at evaluation time (design.md convention), not here, so the table stays the thesis's.
  const double deg[] = {0, 15, 20, 25, 28, 31, 40, 50, 60, 70, 80, 90};
  const double g[] = {0,       0,      2.2e-7,  8e-7,    2.5e-6,  4.5e-6,
                      1.19e-5, 2.3e-5, 3.69e-5, 5.76e-5, 8.66e-5, 1.03e-4};
  std::vector<ChokePoint> points;
  for (int i = 0; i < 12; ++i) points.push_back({deg[i] / 90.0, g[i]});
  return points;
}

double RigParams::PipeAreaM2() const {
  return std::numbers::pi * pipe_inner_radius_m * pipe_inner_radius_m;
}

double RigParams::PistonDisplacementAreaM2() const {
  const double a_upper = std::numbers::pi * 0.25 * upper_rod_diameter_m * upper_rod_diameter_m;
  const double a_lower = std::numbers::pi * 0.25 * lower_rod_diameter_m * lower_rod_diameter_m;
  return a_upper - a_lower;
}

double RigParams::SinInclination() const { return pipe_elevation_gain_m / pipe_length_m; }

double RigParams::QuasiLinearK() const {
  return wave_speed_mps * wave_speed_mps * density_kgpm3 - reference_pressure_pa;
}

Status RigParams::Validate() const {
  for (const ParamInfo& info : kParams) {
    const double value = this->*info.member;
    if (!std::isfinite(value)) {
      return Status::Error(std::string(info.key) + " is not a finite number");
    }
    MPDRIG_RETURN_IF_ERROR(
        CheckInRange(info.key, value, info.unit, info.min_value, info.max_value));
  }
  // The piston displaces (A_d - A_d2) per metre (5.4.1): an upper rod no thicker than the lower
  // one would make the heave push fluid the wrong way, or not at all.
  if (!(upper_rod_diameter_m > lower_rod_diameter_m)) {
    std::ostringstream out;
    out << "upper_rod_diameter_m = " << upper_rod_diameter_m
        << " m must exceed lower_rod_diameter_m = " << lower_rod_diameter_m
        << " m: the piston displaces the difference of the rods' areas (thesis 5.4.1)";
    return Status::Error(out.str());
  }
  if (std::abs(pipe_elevation_gain_m) > pipe_length_m) {
    return Status::Error(
        "pipe_elevation_gain_m exceeds pipe_length_m: the pipe cannot rise more "
        "than its length");
  }
  if (choke_characteristic.size() < 2) {
    return Status::Error("choke characteristic needs at least 2 points");
  }
  for (std::size_t i = 0; i < choke_characteristic.size(); ++i) {
    MPDRIG_RETURN_IF_ERROR(ValidateChokePoint(i));
  }
  return layout.Validate();
}

Status RigParams::ValidateChokePoint(std::size_t index) const {
  MPDRIG_CHECK(index < choke_characteristic.size());
  const ChokePoint& point = choke_characteristic[index];
  if (!std::isfinite(point.opening_frac) || !std::isfinite(point.g_m2) || point.g_m2 < 0.0 ||
      point.opening_frac < 0.0 || point.opening_frac > 1.0) {
    return Status::Error("choke characteristic point " + std::to_string(index) +
                         ": opening must be in [0, 90] deg and G >= 0 m^2");
  }
  if (index > 0 && point.opening_frac <= choke_characteristic[index - 1].opening_frac) {
    return Status::Error("choke characteristic point " + std::to_string(index) +
                         ": openings must be strictly increasing");
  }
  return Status::Ok();
}

Status ParamInfo::Set(RigParams* params, double value) const {
  MPDRIG_RETURN_IF_ERROR(CheckInRange(key, value, unit, min_value, max_value));
  params->*member = value;
  return Status::Ok();
}

std::pair<double, double> ParamInfo::FitRange() const {
  double lower = fit_min, upper = fit_max;
  if (!(fit_min < fit_max)) {
    lower = min_value, upper = max_value;
    // A factor of 3 either way around the thesis value (the sign kept), or the table's bounds.
    const double value = RigParams{}.*member;
    if (value != 0.0) {
      lower = value > 0.0 ? value / 3.0 : value * 3.0;
      upper = value > 0.0 ? value * 3.0 : value / 3.0;
    }
  }
  return {std::max(lower, min_value), std::min(upper, max_value)};
}

std::span<const ParamInfo> ParamTable() { return kParams; }

const ParamInfo* FindParam(std::string_view key) {
  for (const ParamInfo& info : kParams) {
    if (info.key == key) return &info;
  }
  return nullptr;
}

Result<const ParamInfo*> LookUpParam(std::string_view key, std::string_view other_keys) {
  if (const ParamInfo* info = FindParam(key)) return info;
  std::string keys;
  for (const ParamInfo& info : kParams) {
    if (!keys.empty()) keys += ", ";
    keys += info.key;
  }
  if (!other_keys.empty()) keys += ", or " + std::string(other_keys);
  return Status::Error("unknown parameter '" + std::string(key) + "'; valid keys: " + keys);
}

const double* EffectSetting::Find(std::string_view key) const {
  for (const auto& [name, value] : values) {
    if (name == key) return &value;
  }
  return nullptr;
}

void EffectSetting::Set(std::string_view key, double value) {
  for (auto& [name, existing] : values) {
    if (name == key) {
      existing = value;
      return;
    }
  }
  values.emplace_back(std::string(key), value);
}

EffectSetting* RigParams::FindEffect(std::string_view name) {
  for (EffectSetting& effect : effects) {
    if (effect.name == name) return &effect;
  }
  return nullptr;
}

const EffectSetting* RigParams::FindEffect(std::string_view name) const {
  return const_cast<RigParams*>(this)->FindEffect(name);
}

namespace {

// A finite number, or an error naming `key` and its unit.
Result<double> ParseNumber(std::string_view key, std::string_view value_text,
                           std::string_view unit) {
  double value = 0.0;
  // from_chars takes no leading '+'; a user may well write one.
  if (value_text.size() > 1 && value_text.front() == '+' && value_text[1] != '-') {
    value_text.remove_prefix(1);
  }
  const char* first = value_text.data();
  const char* last = value_text.data() + value_text.size();
  const auto [end, error] = std::from_chars(first, last, value);
  if (error != std::errc() || end != last || value_text.empty()) {
    return Status::Error(std::string(key) + ": '" + std::string(value_text) +
                         "' is not a number (units: " + std::string(unit) + ")");
  }
  if (!std::isfinite(value)) {
    return Status::Error(std::string(key) + ": value must be finite, got '" +
                         std::string(value_text) + "'");
  }
  return value;
}

// "EFFECT.KEY": bounds and key names are the registry's to check (ValidateEffects).
Status SetEffectParam(RigParams* params, std::string_view key, std::string_view value_text) {
  const std::size_t dot = key.find('.');
  const std::string_view effect_name = key.substr(0, dot);
  const std::string_view param = key.substr(dot + 1);
  EffectSetting* effect = params->FindEffect(effect_name);
  if (effect == nullptr) {
    return Status::Error(std::string(key) + ": effect '" + std::string(effect_name) +
                         "' is not switched on");
  }
  auto value = ParseNumber(key, value_text, "see `mpdrig effects`");
  if (!value.ok()) return value.status();
  effect->Set(param, *value);
  return Status::Ok();
}

}  // namespace

Status CheckInRange(std::string_view key, double value, std::string_view unit, double min_value,
                    double max_value) {
  if (std::isfinite(value) && value >= min_value && value <= max_value) return Status::Ok();
  std::ostringstream out;
  out << key << " = " << value << " " << unit << " is outside [" << min_value << ", " << max_value
      << "]";
  return Status::Error(out.str());
}

Status SetParam(RigParams* params, std::string_view key, std::string_view value_text) {
  if (key.find('.') != std::string_view::npos) return SetEffectParam(params, key, value_text);
  auto info = LookUpParam(key);
  if (!info.ok()) return info.status();
  auto value = ParseNumber(key, value_text, (*info)->unit);
  if (!value.ok()) return value.status();
  return (*info)->Set(params, *value);
}

Status ApplyOverride(RigParams* params, std::string_view assignment) {
  const std::size_t equals = assignment.find('=');
  if (equals == std::string_view::npos) {
    return Status::Error("expected key=value, got '" + std::string(assignment) + "'");
  }
  return SetParam(params, assignment.substr(0, equals), assignment.substr(equals + 1));
}

}  // namespace mpdrig
