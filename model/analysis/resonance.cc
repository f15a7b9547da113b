#include "model/analysis/resonance.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "model/effects/effect.h"

namespace mpdrig {
namespace {

using Complex = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// An effect's resolved parameter value (its default where the setting gives none).
double EffectValue(const EffectSetting& setting, std::string_view key) {
  const EffectInfo* info = FindEffectInfo(setting.name);
  MPDRIG_CHECK(info != nullptr);
  auto values = ResolveEffectValues(*info, setting);
  MPDRIG_CHECK(values.ok());
  for (std::size_t i = 0; i < info->params.size(); ++i) {
    if (info->params[i].key == key) return (*values)[i];
  }
  MPDRIG_CHECK(false);
  return 0.0;
}

// gas_entrainment's wave speed at p (its header, (8.3.5)-(8.3.6)).
double GasWaveSpeed(const RigParams& params, const EffectSetting& gas, double pressure_pa) {
  const double c = params.wave_speed_mps, rho = params.density_kgpm3;
  const double bulk = rho * c * c;
  const double eps0 = EffectValue(gas, "void_fraction");
  const double p_ref = EffectValue(gas, "reference_pressure_pa");
  const double n = EffectValue(gas, "polytropic_index");
  const double p = std::max(pressure_pa, 1e-300);
  const double eps = eps0 * std::pow(p_ref / p, 1.0 / n);
  const double extra = std::max(0.0, eps / (n * p) - eps / bulk);
  return 1.0 / std::sqrt(rho * (1.0 / bulk + extra));
}

double CircleArea(double diameter_m) { return 0.25 * std::numbers::pi * diameter_m * diameter_m; }

// piston_compressibility's (5.4.3)-(5.4.5) linearised about rest (q_d = 0, where the quadratic
// clearance friction has no slope; rho g h is constant and drops out), with X = 1, V_d = s:
//   s C_p P_p = Q_d + V_d (A_b - A_d) - A U(0) - s C_h P_p      C_p = V_p / K (+ a hose beside it)
//   s C_b P_b = -Q_d - V_d (A_b - A_d2)                          C_b = V_b / K
//   (s M + r_1) Q_d = P_b - P_p                                  r_1 = |f_d1| / (A_b - A_d2)
// and the pipe P_p = Z_in U(0). Multiplying the first by Z_in keeps it finite where Z_in is.
// Rigid (K -> inf) it is (9.2.5): A U(0) = -V_d (A_d - A_d2). Without clearance resistance and
// inertance the two volumes are one capacitance (V_p + V_b)/K at the inlet, like hose_compliance.
struct Compartment {
  Compartment(const RigParams& params, const EffectSetting& effect) {
    const double bulk = EffectValue(effect, "bulk_modulus_pa");
    c_above = EffectValue(effect, "volume_above_m3") / bulk;
    c_below = EffectValue(effect, "volume_below_m3") / bulk;
    inertance = EffectValue(effect, "inertance_kg_per_m4");
    const double bha = CircleArea(EffectValue(effect, "bha_diameter_m"));
    face_above = bha - CircleArea(params.upper_rod_diameter_m);
    // The effect's floor for a BHA no wider than its lower rod (piston_compressibility.cc).
    face_below = std::max(bha - CircleArea(params.lower_rod_diameter_m), 1e-3 * bha);
    r1 = std::fabs(params.piston_friction_fd1_pa_s_per_m) / face_below;
  }

  // P(0) per piston position.
  Complex InletPressure(double hose_compliance, double area, Complex s, Complex z_in) const {
    const Complex v_d = s;
    const Complex zq = s * inertance + r1;
    if (std::abs(zq) == 0.0) {
      const double total = c_above + c_below + hose_compliance;
      return z_in * v_d * (face_above - face_below) / (area + s * total * z_in);
    }
    const Complex g = 1.0 / zq;
    const Complex a11 = z_in * (s * (c_above + hose_compliance) + g) + area, a12 = -z_in * g;
    const Complex a21 = -g, a22 = s * c_below + g;
    const Complex b1 = z_in * v_d * face_above, b2 = -v_d * face_below;
    return (b1 * a22 - a12 * b2) / (a11 * a22 - a12 * a21);
  }

  double c_above, c_below, inertance, face_above, face_below, r1;
};

// The line as the analytic response sees it, every effect's values resolved once: a frequency
// then costs only the complex arithmetic of (9.2.13) (a resonance takes a few hundred).
class AnalyticLine {
 public:
  AnalyticLine(const RigParams& params, const ChokeSetting& choke, double pump_flow_m3ps,
               double mean_pressure_pa)
      : c_(params.wave_speed_mps),
        rho_(params.density_kgpm3),
        length_(params.pipe_length_m),
        area_(params.PipeAreaM2()),
        a2_(params.PistonDisplacementAreaM2() / params.PipeAreaM2()),
        f1_(params.friction_f1_per_s),
        k_choke_(LinearizedOutletImpedance(params, choke, pump_flow_m3ps)) {
    for (const EffectSetting& effect : params.effects) {
      if (effect.name == "piston_compressibility") {
        compartment_.emplace(params, effect);
      } else if (effect.name == "topside_compliance") {
        outlet_compliance_ += EffectValue(effect, "compliance_m3_per_pa");
      } else if (effect.name == "hose_compliance") {
        inlet_compliance_ += EffectValue(effect, "compliance_m3_per_pa");
      } else if (effect.name == "gas_entrainment") {
        c_ = GasWaveSpeed(params, effect, mean_pressure_pa);
      }
    }
  }

  // (9.2.13) times s with the effects: p(0) per piston position [Pa/m].
  Complex At(double freq_hz) const {
    const Complex s(0.0, kTwoPi * freq_hz);
    const Complex kappa = std::sqrt(s * (s + f1_)) / c_;  // (9.2.11)
    const Complex z = rho_ * c_ * c_ * kappa / s;
    const Complex sh = std::sinh(kappa * length_), ch = std::cosh(kappa * length_);
    // Outlet admittance U(L)/P(L) = 1/k_c + s C / A: the choke and the tubes side by side.
    const Complex admittance = (std::isinf(k_choke_) ? Complex(0.0) : Complex(1.0 / k_choke_)) +
                               s * outlet_compliance_ / area_;
    Complex z_in;  // P(0) / U(0)
    if (k_choke_ == 0.0) {
      z_in = z * sh / ch;  // P(L) = 0: the open choke holds the outlet, the tubes see nothing
    } else {
      // (9.2.13) with k = 1/admittance, written so that a closed end (admittance 0) is exact.
      z_in = z * (z * admittance * sh + ch) / (z * admittance * ch + sh);
    }
    if (compartment_) return compartment_->InletPressure(inlet_compliance_, area_, s, z_in);
    // Inlet: A U(0) = Q_0 - s C_h P(0), Q_0/A = -A_2 V_d (9.2.5), V_d = s X.
    const Complex p0_per_vd = -a2_ * z_in / (1.0 + s * inlet_compliance_ * z_in / area_);
    return p0_per_vd * s;
  }
  double Magnitude(double freq_hz) const { return std::abs(At(freq_hz)); }

 private:
  double c_, rho_, length_, area_, a2_, f1_, k_choke_;
  double outlet_compliance_ = 0.0, inlet_compliance_ = 0.0;
  std::optional<Compartment> compartment_;
};

}  // namespace

bool AnalyticRepresents(std::string_view name) {
  return name == "topside_compliance" || name == "hose_compliance" || name == "gas_entrainment" ||
         name == "piston_compressibility" || name == "pump_curve";
}

std::string_view ResponseMethodName(ResponseMethod method) {
  switch (method) {
    case ResponseMethod::kAuto:
      return "auto";
    case ResponseMethod::kAnalytic:
      return "analytic";
    case ResponseMethod::kSimulated:
      return "simulated";
  }
  return "?";
}

std::string EffectsOutsideAnalytic(const RigParams& params) {
  std::string names;
  for (const EffectSetting& effect : params.effects) {
    if (AnalyticRepresents(effect.name)) continue;
    if (!names.empty()) names += ", ";
    names += effect.name;
  }
  return names;
}

double MeanLinePressurePa(const RigParams& params, double outlet_pressure_pa) {
  return outlet_pressure_pa +
         0.5 * params.density_kgpm3 * params.gravity_mps2 * params.pipe_elevation_gain_m;
}

Complex AnalyticBhpWithEffects(const RigParams& params, const ChokeSetting& choke,
                               double pump_flow_m3ps, double mean_pressure_pa, double freq_hz) {
  return AnalyticLine(params, choke, pump_flow_m3ps, mean_pressure_pa).At(freq_hz);
}

std::vector<FrequencyPoint> AnalyticFrequencyResponseWithEffects(
    const RigParams& params, const ChokeSetting& choke, double pump_flow_m3ps,
    double mean_pressure_pa, const std::vector<double>& freqs_hz) {
  const AnalyticLine line(params, choke, pump_flow_m3ps, mean_pressure_pa);
  std::vector<FrequencyPoint> points;
  for (double f : freqs_hz) {
    const Complex h = line.At(f);
    points.push_back({f, std::abs(h), std::arg(h) * 180.0 / std::numbers::pi});
  }
  UnwrapPhase(&points);
  return points;
}

Result<Resonance> FirstAnalyticResonance(const RigParams& params, const ChokeSetting& choke,
                                         double pump_flow_m3ps, double mean_pressure_pa,
                                         const ResonanceOptions& options) {
  const AnalyticLine line(params, choke, pump_flow_m3ps, mean_pressure_pa);
  const double step = options.scan_step_hz;
  double f_prev = options.fmin_hz;
  double m_prev = line.Magnitude(f_prev);
  double f = f_prev + step;
  double m = line.Magnitude(f);
  for (; f + step <= options.fmax_hz; f += step) {
    const double m_next = line.Magnitude(f + step);
    if (m > m_prev && m >= m_next) {
      // Golden section on [f - step, f + step], where |H| is unimodal.
      double a = f - step, b = f + step;
      const double g = 0.5 * (std::sqrt(5.0) - 1.0);
      double x1 = b - g * (b - a), x2 = a + g * (b - a);
      double m1 = line.Magnitude(x1);
      double m2 = line.Magnitude(x2);
      while (b - a > 1e-9) {
        if (m1 < m2) {
          a = x1, x1 = x2, m1 = m2;
          x2 = a + g * (b - a);
          m2 = line.Magnitude(x2);
        } else {
          b = x2, x2 = x1, m2 = m1;
          x1 = b - g * (b - a);
          m1 = line.Magnitude(x1);
        }
      }
      const double peak = 0.5 * (a + b);
      return Resonance{peak, line.Magnitude(peak), ResponseMethod::kAnalytic, 0};
    }
    m_prev = m, m = m_next;
  }
  return Status::Error("the analytic response has no resonance between " +
                       std::to_string(options.fmin_hz) + " and " + std::to_string(options.fmax_hz) +
                       " Hz");
}

double PeakOfSampledResponse(const std::vector<FrequencyPoint>& points) {
  MPDRIG_CHECK(!points.empty());
  std::size_t best = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].magnitude_pa_per_m > points[best].magnitude_pa_per_m) best = i;
  }
  if (best == 0 || best + 1 == points.size()) return points[best].freq_hz;
  // Parabola through (f, log |H|) at the three points (they need not be evenly spaced).
  const double x0 = points[best - 1].freq_hz, x1 = points[best].freq_hz,
               x2 = points[best + 1].freq_hz;
  const double y0 = std::log(points[best - 1].magnitude_pa_per_m),
               y1 = std::log(points[best].magnitude_pa_per_m),
               y2 = std::log(points[best + 1].magnitude_pa_per_m);
  const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1);
  const double curvature = (d12 - d01) / (x2 - x0);  // y'' / 2
  if (!(curvature < 0.0)) return x1;
  // y = y1 + d (x - x1) + curvature (x - x1)^2 around x1, d the slope there.
  const double slope = d01 + curvature * (x1 - x0);
  return std::clamp(x1 - slope / (2.0 * curvature), x0, x2);
}

Result<Resonance> FirstResonance(const RigParams& params, Termination termination,
                                 const ResonanceOptions& options) {
  const TerminatedRig rig = ApplyTermination(params, termination);
  const double p_m = MeanLinePressurePa(rig.params, options.simulated.outlet_pressure_pa);
  const std::string outside = EffectsOutsideAnalytic(rig.params);
  ResponseMethod method = options.method;
  if (method == ResponseMethod::kAuto) {
    method = outside.empty() ? ResponseMethod::kAnalytic : ResponseMethod::kSimulated;
  }
  if (method == ResponseMethod::kAnalytic) {
    if (!outside.empty()) {
      return Status::Error("the analytic response (9.2.13) does not represent " + outside +
                           ": use the simulated one");
    }
    return FirstAnalyticResonance(rig.params, rig.choke, rig.pump_flow_m3ps, p_m, options);
  }

  // The guess: the analytic resonance of the rig without the effects it cannot hold.
  RigParams covered = rig.params;
  std::erase_if(covered.effects,
                [](const EffectSetting& e) { return !AnalyticRepresents(e.name); });
  auto guess = FirstAnalyticResonance(covered, rig.choke, rig.pump_flow_m3ps, p_m, options);
  if (!guess.ok()) return guess.status().Within("the simulated resonance's first guess");
  Resonance result;
  result.method = ResponseMethod::kSimulated;
  const int n = std::max(3, options.simulated_points);
  double centre = guess->freq_hz;
  double step = 2.0 * options.simulated_span * centre / (n - 1);
  auto scan = [&](double middle, double spacing) -> Result<std::vector<FrequencyPoint>> {
    std::vector<double> freqs;
    for (int i = 0; i < n; ++i) {
      const double f = middle + (i - (n - 1) / 2.0) * spacing;
      if (f > 0.0) freqs.push_back(f);
    }
    result.simulations += static_cast<int>(freqs.size());
    return SimulatedFrequencyResponse(rig.params, options.simulation, rig.choke, rig.pump_flow_m3ps,
                                      freqs, options.simulated);
  };
  std::vector<FrequencyPoint> points;
  for (int shift = 0;; ++shift) {
    auto scanned = scan(centre, step);
    if (!scanned.ok()) return scanned.status();
    points = *scanned;
    const auto largest = std::max_element(points.begin(), points.end(), [](auto& a, auto& b) {
      return a.magnitude_pa_per_m < b.magnitude_pa_per_m;
    });
    const bool inside = largest != points.begin() && largest + 1 != points.end();
    if (inside) {
      centre = largest->freq_hz;
      break;
    }
    if (shift == 4) {
      return Status::Error("no simulated resonance within " +
                           std::to_string(points.front().freq_hz) + ".." +
                           std::to_string(points.back().freq_hz) + " Hz");
    }
    centre = largest->freq_hz + (largest == points.begin() ? -1.0 : 1.0) * 0.5 * (n - 1) * step;
  }
  // A finer scan across the largest point's neighbours, then the parabola.
  auto fine = scan(centre, step / 4.0);
  if (!fine.ok()) return fine.status();
  result.freq_hz = PeakOfSampledResponse(*fine);
  result.magnitude_pa_per_m = 0.0;
  for (const FrequencyPoint& p : *fine) {
    result.magnitude_pa_per_m = std::max(result.magnitude_pa_per_m, p.magnitude_pa_per_m);
  }
  return result;
}

}  // namespace mpdrig
