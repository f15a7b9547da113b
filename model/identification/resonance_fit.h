// Fitting in the frequency domain: shared parameters (the wave speed, effect parameters such as
// topside_compliance.compliance_m3_per_pa, hose_compliance.compliance_m3_per_pa,
// gas_entrainment.void_fraction) adjusted so that the model's first resonance in each
// termination (termination.h) matches the measured one (resonance_list.h):
//   minimise sum_i r_i^2,   r_i = (f_model(theta; termination_i) - f_i) / u_i,
// f_i and u_i the measured resonance and its standard uncertainty. f_model is FirstResonance
// (resonance.h): the analytic response (9.2.13) where it holds the effects switched on, else the
// simulated response. Solved by Ceres (Levenberg-Marquardt with the parameters' bounds), on
// parameters mapped to [0, 1] over their bounds; the Jacobian by central differences of f_model
// (one-sided at a bound). Standard errors: cov = (J^T J)^-1 in the mapped parameters (the
// residuals are already in units of their uncertainty), NaN where J^T J is singular (more
// parameters than the resonances determine).
#pragma once

#include <string>
#include <vector>

#include "model/analysis/resonance.h"
#include "model/analysis/resonance_list.h"
#include "model/common/status.h"
#include "model/identification/fit.h"
#include "model/params/rig_params.h"

namespace mpdrig {

struct ResonanceFitOptions {
  ResonanceOptions resonance;  // method, simulation, outlet pressure
  int max_iterations = 50;
  // Central-difference step in the mapped parameter ([0, 1] over the bounds): the analytic
  // resonance is refined to 1e-9 Hz, the simulated one is a parabola through a scan (smooth only
  // to about 1e-5 Hz), so it takes a larger step.
  double analytic_step = 1.0e-5;
  double simulated_step = 3.0e-3;
};

struct ResonanceFitConfiguration {
  Termination configuration = Termination::kChokeClosed;
  double measured_hz = 0.0;
  double uncertainty_hz = 0.0;
  double base_model_hz = 0.0;                         // at the start parameters
  double model_hz = 0.0;                              // at the estimates
  ResponseMethod method = ResponseMethod::kAnalytic;  // what computed model_hz
};

struct ResonanceFitResult {
  RigParams params;  // start params with the estimates written in
  std::vector<std::string> keys;
  std::vector<double> lower, upper;
  std::vector<double> initial;
  std::vector<double> estimates;
  std::vector<double> standard_errors;
  std::vector<ResonanceFitConfiguration> configurations;
  double chi2_before = 0.0;  // sum r_i^2 at the start and at the estimates
  double chi2_after = 0.0;
  double max_error_hz = 0.0;  // max |model - measured| at the estimates
  int iterations = 0;
  int evaluations = 0;  // resonances computed
  bool converged = false;
  std::string solver_report;
};

// Fits `parameters` (bounds as given) from `start`; with no parameter, evaluates the start.
Result<ResonanceFitResult> FitResonances(const std::vector<MeasuredResonance>& measured,
                                         const RigParams& start,
                                         const std::vector<FitParameter>& parameters,
                                         const ResonanceFitOptions& options = {});

}  // namespace mpdrig
