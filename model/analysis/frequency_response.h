// Frequency response from piston position to bottom-hole pressure p(0) (thesis 9.2).
//
// Analytic (9.2.13), the linear model (7.0.1-7.0.2) with linear friction f1 and the linearised
// outlet boundary P(L) = k U(L) (design.md: k = 0 wide open, k -> infinity closed):
//   P(0)/V_d = -A_2 Z (Z sinh(kappa L) + k cosh(kappa L)) / (Z cosh(kappa L) + k sinh(kappa L)),
//   kappa = sqrt(s (s + f1)) / c   (9.2.11),   Z = rho c^2 kappa / s,   A_2 = (A_d - A_d2) / A,
// multiplied by s for the piston position. Without friction the open choke resonates at
// (2n+1) c/(4L) (9.3.2) and the closed one at n c/(2L) (9.3.4).
//
// Simulated: the full simulator driven by a small piston sine at each frequency, run until the
// transients have decayed (rate f1/2), then the fundamental of p(0) over whole periods divided by
// that of the piston position.
#pragma once

#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// The choke as the frequency response sees it.
struct ChokeSetting {
  enum class Kind { kClosed, kOpen, kOpening };
  Kind kind = Kind::kClosed;
  double opening_frac = 0.0;  // for kOpening
  static ChokeSetting Closed() { return {Kind::kClosed, 0.0}; }
  static ChokeSetting Open() { return {Kind::kOpen, 1.0}; }
  static ChokeSetting Opening(double frac) { return {Kind::kOpening, frac}; }
  std::string Describe() const;
};

struct FrequencyPoint {
  double freq_hz = 0.0;
  double magnitude_pa_per_m = 0.0;
  double phase_deg = 0.0;
};

// k of the linearised choke P(L) = k U(L) [Pa s/m]: infinity for closed, 0 for open; for an
// opening, the slope of (5.3.2) at the steady pump flow: k = 2 rho_L A q_b / G(u_c)^2.
double LinearizedOutletImpedance(const RigParams& params, const ChokeSetting& choke,
                                 double pump_flow_m3ps);

// (9.2.13) times s: p(0) per piston position [Pa/m], complex, at f > 0.
std::complex<double> AnalyticBhpPerPistonPosition(const RigParams& params, double k_pa_s_per_m,
                                                  double freq_hz);

std::vector<FrequencyPoint> AnalyticFrequencyResponse(const RigParams& params,
                                                      const ChokeSetting& choke,
                                                      double pump_flow_m3ps,
                                                      const std::vector<double>& freqs_hz);

struct SimulatedResponseOptions {
  double amplitude_m = 0.001;  // small: the analytic model is linear
  double settle_decay = 7.0;   // run e^{settle_decay} transient decays (rate f1/2) first
  int min_settle_periods = 3;
  int measure_periods = 4;
  int samples_per_period = 64;
  double outlet_pressure_pa = 5.0e5;  // keeps absolute pressure positive
};

Result<std::vector<FrequencyPoint>> SimulatedFrequencyResponse(
    const RigParams& params, const SimulationOptions& sim_options, const ChokeSetting& choke,
    double pump_flow_m3ps, const std::vector<double>& freqs_hz,
    const SimulatedResponseOptions& options = {},
    const std::function<void(int done, int total)>& progress = {});

// n frequencies from fmin to fmax, evenly spaced (linear) or geometric (log).
std::vector<double> FrequencyGrid(double fmin_hz, double fmax_hz, int count, bool logarithmic);

// Phases continued across +-180 deg jumps, so a curve reads smoothly.
void UnwrapPhase(std::vector<FrequencyPoint>* points);

}  // namespace mpdrig
