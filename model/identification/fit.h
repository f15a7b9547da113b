// Parameter identification against a rig log (the thesis's chapter 8-9 tuning,
// automated): bounded nonlinear least squares of any base or effect parameter.
//
// Residuals: for every compared channel c present in the log (ComparedChannels(), P1 P2
// PT1..PT10 C2 FT1 FT3 FT4) and every measured sample n inside the fit window,
//   r_cn = (yhat_cn - y_cn) / ||y_c - mean(y_c)|| / sqrt(C)
// (norms and mean over the channel's measured samples in the window, C the channels with a
// non-constant measurement there), i.e. each channel's residual normalised by its own variation,
// so that sum_n r_cn^2 = NRMSE_c^2 / C and every channel weighs the same whatever its unit (the
// compare metric, compare.h): the cost is the mean squared NRMSE.
// Solved by Ceres (trust region, Levenberg-Marquardt) with box bounds, on parameters scaled by
// their start values; derivatives by finite differences of full replays (the model is a black box
// to the solver): forward inside the solver, central at the optimum for the covariance.
// Standard errors: from the Jacobian J at the optimum, cov = s^2 (J^T J)^-1 with
// s^2 = ||r||^2 / (m - p) rescaled to the unnormalised residuals (Gauss-Newton / Ceres
// Covariance); correlation = cov_ij / sqrt(cov_ii cov_jj).
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/analysis/window_error.h"  // WindowError: the error fit reports
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// One parameter to fit: a base key of ParamTable() ("wave_speed_mps") or an effect's
// "EFFECT.KEY" ("unsteady_friction.k"; the effect must be switched on in the start params).
struct FitParameter {
  std::string key;
  double lower = 0.0;  // bounds; DefaultFitParameter() takes them from the parameter tables
  double upper = 0.0;
};

// The parameter `key` with search bounds (FindParamByKey's fit range, model/effects/
// param_by_key.h): the effect registry's bounds for an effect parameter; for a base parameter a
// plausible tuning range around the thesis value (e.g. wave speed 300..1500 m/s, f1 0..5 1/s,
// choke leak 0..1e-5 m^2), never wider than ParamTable()'s bounds. Values in a RigParams are
// read and set by key with GetParamValue and SetParamValue (param_by_key.h).
Result<FitParameter> DefaultFitParameter(std::string_view key);

// How the channels weigh in the cost.
enum class ChannelWeighting {
  // Each channel's residual over its own variation, ||y - mean(y)||: the cost is compare's mean
  // squared NRMSE, every channel counts the same whatever its unit or noise.
  kVariation,
  // Each channel's residual over its white-noise level (sigma from the second differences of its
  // measurement in the window, floored at 1e-3 of its variation per sample): the maximum-
  // likelihood weighting for white measurement noise, where a quiet channel counts more.
  kNoise,
};

// The message of a fit ended by FitOptions::cancelled.
inline constexpr const char* kFitCancelled = "cancelled";

struct FitOptions {
  SimulationOptions simulation;  // cells etc.; choke input is forced to kMeasured (ReplayModel)
  ReplayOptions replay;
  ChannelWeighting weighting = ChannelWeighting::kVariation;
  // Only samples with time in [window_begin_s, window_end_s] enter the residuals (the replay
  // always starts at the log's start). diagnose fits on the first part and scores on the rest.
  double window_begin_s = -std::numeric_limits<double>::infinity();
  double window_end_s = std::numeric_limits<double>::infinity();
  int max_iterations = 30;
  double function_tolerance = 1e-6;  // relative change of the cost that stops the solver
  // Finite-difference step, relative to max(|x|, 1% of the bound range). Larger than the usual
  // sqrt(eps): the replay is piecewise smooth in the parameters (its time step dt = dx / c moves
  // against the log's sample times), and a step below ~1e-4 sees that texture, not the slope.
  double relative_step = 1.0e-3;
  // false: forward differences inside the solver (p replays per Jacobian); true: central (2p).
  // The covariance at the optimum always uses central differences.
  bool central_differences = false;
  // false: no covariance at the optimum (standard errors and correlations NaN, none of its 2p
  // replays); EstimateStandardErrors adds it later to the fit that is kept, with the same
  // numbers (diagnose fits from several starts and keeps one).
  bool standard_errors = true;
  // Called after each solver iteration: iteration number and current error (mean NRMSE).
  std::function<void(int iteration, double error)> progress;
  // Asked after each solver iteration (and between the two fits of FitParametersAndInputLevels):
  // true ends the fit with the error kFitCancelled, its estimates dropped (the shadow's "cancel
  // fit": the model holds no thread, its caller decides when to ask).
  std::function<bool()> cancelled;
  // Prints Ceres's per-iteration table to stdout (trust region ratio, step, radius): the way to
  // see why a fit stops. The command line sets it from MPDRIG_CERES_LOG; the model reads no
  // environment.
  bool solver_log = false;

  // The window is not empty, max_iterations >= 0, relative_step in (0, 0.1), the simulation
  // options valid; else an error that says which.
  [[nodiscard]] Status Validate() const;
};

struct FitResult {
  RigParams params;               // start params with the estimates written in
  std::vector<std::string> keys;  // in the order of the parameters given
  std::vector<double> initial;    // start values
  std::vector<double> estimates;
  std::vector<double> standard_errors;  // NaN where J^T J is singular (unidentifiable)
  // True where the parameter did not move the residuals at the start (relative change below
  // kNoInfluence for its difference step): it was held at its start value, not fitted.
  std::vector<bool> held;
  std::vector<std::vector<double>> correlation;  // keys.size() squared
  double error_before = 0.0;  // mean NRMSE over compared channels on the window (compare's error)
  double error_after = 0.0;
  int iterations = 0;
  int replays = 0;  // model runs spent
  bool converged = false;
  std::string solver_report;  // Ceres's brief report
  // FitParametersAndInputLevels: the levels estimated at the first fit's parameters.
  InputLevelCorrection input_levels;
  // What EstimateStandardErrors needs: the optimum as the solver scaled it (x / scale) and the
  // squared norm of the normalised residuals there.
  std::vector<double> scaled_estimates;
  double residual_square_sum = 0.0;
};

// Fits `parameters` starting from `start` (its values are the initial guesses, clamped into the
// bounds). A replay that fails (e.g. leaves the model's range) counts as an infeasible step.
Result<FitResult> FitParameters(const MeasuredLog& log, const RigParams& start,
                                const std::vector<FitParameter>& parameters,
                                const FitOptions& options = {});

// The standard errors and correlations of `fit` (FitParameters's, with the same log, parameters
// and options but FitOptions::standard_errors false), as FitParameters would have given them:
// the central-difference Jacobian at its optimum (2p replays, added to fit->replays).
Status EstimateStandardErrors(const MeasuredLog& log, const std::vector<FitParameter>& parameters,
                              const FitOptions& options, FitResult* fit);

// What `mpdrig fit` runs: FitParameters on the log as reconstructed, then the choke's and FT2's
// levels estimated at the fitted parameters (EstimateInputLevels; at the start values a wrong
// parameter would pass for a level error) and applied to *log, then FitParameters again from the
// first fit's estimates. A measured start (ReplayOptions::profile, ChooseReplayStart) is chosen
// again at the first fit's estimates before the levels: at the start values it may have absorbed
// their error. Where options.replay does not reconstruct or estimate levels, or *log already has
// levels, and the start is not a measured one, FitParameters alone. replays and iterations count
// both fits, error_before is the first fit's.
Result<FitResult> FitParametersAndInputLevels(MeasuredLog* log, const RigParams& start,
                                              const std::vector<FitParameter>& parameters,
                                              FitOptions options = {});

}  // namespace mpdrig
