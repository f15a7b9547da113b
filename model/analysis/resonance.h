// The first resonance of bottom-hole pressure p(0) per piston position for a rig and a
// termination (termination.h), from the analytic response (9.2.13) where it represents the
// effects switched on, else from the simulated one (frequency_response.h).
//
// (9.2.13) with the effects it can hold (everything linear, lossless but for f1):
//   topside_compliance  a capacitance C at the outlet, beside the choke: A U(L) = i w C P(L) +
//                       P(L)/k_c (a tight choke: 1/k_c = 0; open: k_c = 0, the tubes see p_0), so
//                       the outlet impedance is  k = 1 / (1/k_c + i w C / A). With a tight choke
//                       and no friction the first pole solves tan(theta) = -r theta, theta = wL/c,
//                       r = C / C_pipe, C_pipe = A L / (rho c^2) (topside_compliance.cc).
//   hose_compliance     a capacitance C_h at the inlet: C_h i w P(0) = Q_0 - A U(0), Q_0 = -A_2 A
//   V_d
//                       (5.4.1), so with the pipe's input impedance Z_in = P(0)/U(0) of (9.2.13)
//                         P(0) = -A_2 V_d Z_in / (1 + i w C_h Z_in / A).
//                       Lossless: a closed outlet resonates where tan(theta) = -r_h theta, an open
//                       one where theta tan(theta) = 1/r_h, r_h = C_h / C_pipe.
//   gas_entrainment     the wave speed at the mean pressure p_m (no pump flow: the outlet
//                       pressure plus half the coil's rise), 1/(rho c_m^2) = 1/(rho c^2) +
//                       C_x(p_m), C_x = eps/(n p) - eps/K, eps = eps0 (p_ref/p)^(1/n)
//                       (8.3.5, 8.3.6).
//   piston_compressibility  the compartment's two volumes V_p/K and V_b/K and the clearance flow
//                       between them (5.4.3)-(5.4.5), linearised about rest: P(0) from a 2x2
//                       complex system (resonance.cc, CompartmentInletPressure). Without the
//                       clearance's inertance and resistance it is a capacitance (V_p + V_b)/K
//                       at the inlet, as hose_compliance.
//   pump_curve          nothing: the pump is off in every termination.
// Any other effect (unsteady or helical friction, the choke's inertia, a sensor lag, column
// separation) needs the simulated response.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "model/analysis/frequency_response.h"
#include "model/analysis/termination.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

enum class ResponseMethod { kAuto, kAnalytic, kSimulated };
std::string_view ResponseMethodName(ResponseMethod method);  // "auto", "analytic", "simulated"

// Whether the analytic response represents the effect called `effect_name`.
bool AnalyticRepresents(std::string_view effect_name);

// The effects of `params` the analytic response does not represent, comma separated; empty if
// it represents them all.
std::string EffectsOutsideAnalytic(const RigParams& params);

// (9.2.13) times s with the effects above: p(0) per piston position [Pa/m] at f > 0.
// `mean_pressure_pa` [Pa abs] sets gas_entrainment's wave speed.
std::complex<double> AnalyticBhpWithEffects(const RigParams& params, const ChokeSetting& choke,
                                            double pump_flow_m3ps, double mean_pressure_pa,
                                            double freq_hz);
std::vector<FrequencyPoint> AnalyticFrequencyResponseWithEffects(
    const RigParams& params, const ChokeSetting& choke, double pump_flow_m3ps,
    double mean_pressure_pa, const std::vector<double>& freqs_hz);

// The mean absolute pressure along the line with no flow: outlet pressure plus half the coil's
// rise (rho g h_c / 2 below the outlet on average).
double MeanLinePressurePa(const RigParams& params, double outlet_pressure_pa);

struct ResonanceOptions {
  ResponseMethod method = ResponseMethod::kAuto;
  SimulationOptions simulation;        // for the simulated response
  SimulatedResponseOptions simulated;  // amplitude, settling, outlet pressure (also p_m)
  double fmin_hz = 0.03;               // the first local maximum above fmin is the resonance
  double fmax_hz = 2.0;
  double scan_step_hz = 0.002;  // analytic scan before the golden-section refinement
  int simulated_points = 9;     // simulated scan over +-simulated_span of the guess
  double simulated_span = 0.2;
};

struct Resonance {
  double freq_hz = 0.0;
  double magnitude_pa_per_m = 0.0;
  ResponseMethod method = ResponseMethod::kAnalytic;  // what computed it
  int simulations = 0;                                // simulated frequencies spent
};

// The first resonance of the rig in `termination`. kAuto: analytic where EffectsOutsideAnalytic
// is empty for the terminated rig, else simulated; kAnalytic with an effect it does not represent
// is an error that names the effect. Simulated: a scan of simulated_points frequencies around the
// analytic resonance of the rig without those effects (shifted until the largest lies inside),
// then a parabola through log |H| at the largest and its neighbours, scanned again at a quarter
// of the step.
Result<Resonance> FirstResonance(const RigParams& params, Termination termination,
                                 const ResonanceOptions& options = {});

// The first local maximum of |H| above fmin in an analytic response of a terminated rig, refined
// by golden section to 1e-9 Hz; an error if |H| has none below fmax.
Result<Resonance> FirstAnalyticResonance(const RigParams& params, const ChokeSetting& choke,
                                         double pump_flow_m3ps, double mean_pressure_pa,
                                         const ResonanceOptions& options = {});

// The frequency of the largest point of a response and a parabola through log |H| there: the
// peak between the grid's points. The first or last point is returned as it is.
double PeakOfSampledResponse(const std::vector<FrequencyPoint>& points);

}  // namespace mpdrig
