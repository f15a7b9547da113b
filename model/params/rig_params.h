// Rig parameters: one typed structure with the thesis's tuned values as defaults.
//
// Sources: Table 8.1.1 (heave generator with BHA1), Table 8.1.2 (copper pipe), Table 8.4.1 (choke
// characteristic) with the leak of Table 9.4.1, Table 9.4.1 (tuned wave speed and pipe friction),
// section 8.2 (piston friction). SI units, absolute pressures; every name carries its unit.
//
// Every scalar is described once, in the table returned by ParamTable(): key, unit, meaning,
// bounds. The config file (rig_config.proto), `--set key=value` and `mpdrig params` all go
// through that table, so a key cannot exist in one place and not in another.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "model/common/status.h"
#include "model/params/rig_layout.h"

namespace mpdrig {

// One point of the choke characteristic G(u_c): q_c = G sqrt((p_c - p_0)/rho_L), thesis (5.3.2).
struct ChokePoint {
  double opening_frac;  // u_c in [0, 1]; 1 = 90 deg, fully open
  double g_m2;          // flow coefficient G [m^2]
};

// A physical effect switched on (model/effects/): its registry name and the parameters
// given explicitly; the others keep the effect's defaults. The effect registry checks names and
// bounds (ValidateEffects in model/effects/effect.h) before anything is simulated.
struct EffectSetting {
  std::string name;
  std::vector<std::pair<std::string, double>> values;  // key -> value, in the order given

  // The value set for `key`, or nullptr.
  const double* Find(std::string_view key) const;
  // Gives `key` the value `value`: replaces the value set for it, else appends it. Keys and
  // bounds are the registry's to check (ValidateEffects).
  void Set(std::string_view key, double value);
};

struct RigParams {
  // --- Copper pipe, Table 8.1.2 and Table 9.4.1 -------------------------------------------------
  double pipe_length_m = 900.0;             // L
  double pipe_inner_radius_m = 0.008;       // r_p (16 mm bore)
  double pipe_elevation_gain_m = 2.3;       // coil height h_c: outlet is 2.3 m above inlet
  double wave_speed_mps = 850.0;            // c, tuned (9.4.1); 1173 measured (8.3.2)
  double density_kgpm3 = 998.0;             // rho_ref at p_ref, (5.2.1)
  double reference_pressure_pa = 101325.0;  // p_ref, (5.2.1)
  double friction_f1_per_s = 0.15;  // linear pipe friction f1: f(u) = f1 u + f2 u|u| (8.6.8)
  double friction_f2_per_m = 0.63;  // quadratic pipe friction f2
  double gravity_mps2 = 9.81;       // g

  // --- Choke, section 8.4, Table 8.4.1, Table 9.4.1 ----------------------------------------------
  double choke_leak_m2 = 6.0e-7;             // floor of G: G = max(G_table(u_c), leak) (9.4)
  double choke_density_kgpm3 = 998.0;        // rho_L in (5.3.2)
  double choke_time_constant_s = 0.1;        // first-order actuator lag (5.3)
  double choke_rate_limit_frac_per_s = 1.0;  // 0 -> 90 deg in about 1 s (8.4, Fig. 8.4.3)
  std::vector<ChokePoint> choke_characteristic = DefaultChokeCharacteristic();

  // --- Heave generator (piston / BHA), Table 8.1.1 and section 8.2 -------------------------------
  double upper_rod_diameter_m = 0.025;                  // drill string above the BHA, area A_d
  double lower_rod_diameter_m = 0.022;                  // rod below the BHA, area A_d2
  double compartment_height_m = 1.7;                    // h in (5.4.2)
  double piston_friction_fd1_pa_s_per_m = -43840.0;     // f_d1 (8.2.1)
  double piston_friction_fd2_pa_s2_per_m2 = -410400.0;  // f_d2 (8.2.1)

  // --- Surroundings ----------------------------------------------------------------------------
  double atmospheric_pressure_pa = 101325.0;  // converts the lab's gauge pressures

  // --- What sits at the ends of the pipe (rig_layout.h): the NTNU rig unless the config says
  // otherwise (a reservoir and a valve). Not a scalar of ParamTable(): not fitted, not --set.
  RigLayout layout;

  // --- Physical effects beyond the thesis's model, in the order given (model/effects/) ----------
  std::vector<EffectSetting> effects;

  // Derived quantities (thesis symbols).
  double PipeAreaM2() const;                // A = pi r_p^2
  double PistonDisplacementAreaM2() const;  // A_d - A_d2 (5.4.1, 8.6.1)
  double SinInclination() const;            // sin(gamma) = elevation gain / L
  // k = c^2 rho_ref - p_ref in (5.2.3); k + p = c^2 rho(p).
  double QuasiLinearK() const;

  // Checks every value against the bounds of ParamTable() and the characteristic's shape.
  Status Validate() const;
  // The characteristic's point `index`: in range, and after the point before it (Validate's check
  // of one point, for a config loader that knows where the point was written).
  Status ValidateChokePoint(std::size_t index) const;

  static std::vector<ChokePoint> DefaultChokeCharacteristic();

  // The setting of effect `name`, or nullptr when it is not switched on.
  EffectSetting* FindEffect(std::string_view name);
  const EffectSetting* FindEffect(std::string_view name) const;
};

// One scalar parameter: the single place its key, unit, meaning and bounds are written.
struct ParamInfo {
  std::string_view key;
  std::string_view unit;
  std::string_view description;
  double RigParams::*member;
  double min_value;  // inclusive
  double max_value;  // inclusive
  // The range `mpdrig fit` searches by default where the thesis gives a plausible tuning range
  // (Tables 9.4.1, 8.2.1, 8.3.2); none (fit_min == fit_max): a factor of 3 either way around the
  // thesis value. Within [min_value, max_value].
  double fit_min = 0.0;
  double fit_max = 0.0;

  // The value in `params`.
  double Get(const RigParams& params) const { return params.*member; }
  // Sets the value in `params` if it is within the bounds (CheckInRange: NaN and infinities are
  // outside); else the error, and `params` unchanged.
  Status Set(RigParams* params, double value) const;
  // The range fit searches by default: [fit_min, fit_max] where given, else a factor of 3 either
  // way around the thesis value (the bounds for a thesis value of 0); within the bounds.
  std::pair<double, double> FitRange() const;
};

std::span<const ParamInfo> ParamTable();
const ParamInfo* FindParam(std::string_view key);
// FindParam, or the error for an unknown key, which lists the valid ones: "unknown parameter
// 'wave_speed'; valid keys: pipe_length_m, ...", then ", or `other_keys`" where the caller takes
// other keys too (an effect's "EFFECT.KEY").
Result<const ParamInfo*> LookUpParam(std::string_view key, std::string_view other_keys = {});

// Ok when min_value <= value <= max_value, else "key = value unit is outside [min, max]" (NaN
// and infinities are outside): the one wording of a bound check, for the table and effects.
Status CheckInRange(std::string_view key, double value, std::string_view unit, double min_value,
                    double max_value);

// Sets one parameter from its key and a text value (`--set wave_speed_mps=1100`). An unknown key
// lists the valid ones; a NaN, an unparsable number or a value outside the bounds is an error.
// An effect's parameter is "EFFECT.KEY" (`--set unsteady_friction.k=0.02`); the effect must be
// switched on, and its key and bounds are checked by the effect registry (ValidateEffects).
Status SetParam(RigParams* params, std::string_view key, std::string_view value_text);
// Parses "key=value" and calls SetParam.
Status ApplyOverride(RigParams* params, std::string_view assignment);

}  // namespace mpdrig
