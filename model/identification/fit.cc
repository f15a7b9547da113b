// Bounded nonlinear least squares of rig parameters against a rig log (fit.h).
//
// Problem: minimise 1/2 sum r(x)^2 over x in [lower, upper], r the window's normalised residuals
// (fit.h), x the parameters. The model is a black box: every residual vector is one full replay
// of the log (ReplayModel), cut to the window.
// Numerics:
//   - the solver sees z = x / s, s a typical scale per parameter (|initial|, or the bound range
//     when the start is 0), so wave speed (~1e3 m/s) and choke leak (~1e-7 m^2) are both O(1);
//   - Jacobian by forward differences (p replays) inside Ceres, central differences (2p) at the
//     optimum for the covariance; the step is FitOptions::relative_step of max(|z|, 1% of the
//     range), flipped inwards at a bound;
//   - the residuals of the last few points are cached: Ceres evaluates a trial point's cost, then
//     (once accepted) its Jacobian, and the replay at the centre is not repeated;
//   - a replay that fails (e.g. leaves the model's range) returns false: Ceres treats the step as
//     infeasible and shrinks the trust region.
// Single threaded (num_threads = 1), no wall clock: Ceres's time limit is left at its default.
#include "model/identification/fit.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <optional>
#include <sstream>

#include <ceres/ceres.h>
#include <Eigen/Dense>

#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"
#include "model/signal/input_reconstruction.h"

namespace mpdrig {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Condition limit of the column-scaled J^T J: directions below it are unidentifiable.
constexpr double kSingularRatio = 1.0e-12;
// A parameter whose difference step changes the residual vector by less than this share of its
// norm has no influence (bit-identical replays give 0; round-off alone stays far below).
constexpr double kNoInfluence = 1.0e-9;

// One compared channel's samples inside the window and its normalisation.
struct WindowChannel {
  std::size_t index = 0;             // into log.channels
  std::vector<std::size_t> samples;  // measured samples in the window
  double variation = 0.0;            // ||y - mean(y)|| over those samples
  // The residuals' divisor: variation sqrt(C), or sigma sqrt(N C) (ChannelWeighting).
  double scale = 0.0;
};

std::vector<WindowChannel> WindowChannels(const MeasuredLog& log, double begin_s, double end_s,
                                          ChannelWeighting weighting) {
  const std::vector<double>& time = log.time_s();
  std::vector<WindowChannel> channels;
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    const std::vector<double>& y = log.channels[c].values_si;
    WindowChannel channel;
    channel.index = c;
    double sum = 0.0;
    for (std::size_t n = 0; n < time.size(); ++n) {
      if (time[n] < begin_s || time[n] > end_s || !std::isfinite(y[n])) continue;
      channel.samples.push_back(n);
      sum += y[n];
    }
    if (channel.samples.empty()) continue;
    const double mean = sum / static_cast<double>(channel.samples.size());
    double sst = 0.0;
    for (std::size_t n : channel.samples) sst += (y[n] - mean) * (y[n] - mean);
    if (!(sst > 0.0)) continue;  // constant: NRMSE undefined, nothing to fit
    channel.variation = std::sqrt(sst);
    channel.scale = channel.variation;
    if (weighting == ChannelWeighting::kNoise) {
      std::vector<double> values;
      for (std::size_t n : channel.samples) values.push_back(y[n]);
      const double count = static_cast<double>(channel.samples.size());
      const double sigma =
          std::max(WhiteNoiseSigma(values), 1e-3 * channel.variation / std::sqrt(count));
      channel.scale = sigma * std::sqrt(count);
    }
    channels.push_back(std::move(channel));
  }
  const double root_count = std::sqrt(static_cast<double>(channels.size()));
  for (WindowChannel& channel : channels) channel.scale *= root_count;
  return channels;
}

// The residual function r(z): parameters in scaled form, one replay per new point.
class ReplayResiduals {
 public:
  ReplayResiduals(const MeasuredLog& log, const RigParams& start, std::vector<std::string> keys,
                  std::vector<double> scales, const FitOptions& options,
                  std::vector<WindowChannel> channels)
      : log_(log),
        start_(start),
        keys_(std::move(keys)),
        scales_(std::move(scales)),
        options_(options),
        channels_(std::move(channels)) {
    for (const WindowChannel& channel : channels_) residual_count_ += channel.samples.size();
  }

  int residual_count() const { return static_cast<int>(residual_count_); }
  int parameter_count() const { return static_cast<int>(keys_.size()); }
  int replays() const { return replays_; }
  const std::string& last_failure() const { return last_failure_; }

  // The rig parameters at scaled point z.
  Result<RigParams> ParamsAt(const double* z) const {
    RigParams params = start_;
    for (std::size_t j = 0; j < keys_.size(); ++j) {
      MPDRIG_RETURN_IF_ERROR(SetParamValue(&params, keys_[j], z[j] * scales_[j]));
    }
    return params;
  }

  // r(z) into `residuals` (residual_count() values); false if the replay fails.
  bool Evaluate(const double* z, double* residuals) {
    const std::vector<double> point(z, z + keys_.size());
    for (const CacheEntry& entry : cache_) {
      if (entry.z == point) {
        if (!entry.ok) return false;
        std::copy(entry.residuals.begin(), entry.residuals.end(), residuals);
        return true;
      }
    }
    CacheEntry entry;
    entry.z = point;
    entry.ok = Replay(z, &entry.residuals);
    if (entry.ok) std::copy(entry.residuals.begin(), entry.residuals.end(), residuals);
    const bool ok = entry.ok;
    cache_.push_front(std::move(entry));
    if (cache_.size() > 2 * keys_.size() + 4) cache_.pop_back();
    return ok;
  }

  // Mean NRMSE over the channels from a residual vector: NRMSE_c = sqrt(C sum_n r_cn^2).
  double Error(const double* residuals) const {
    if (channels_.empty()) return kNaN;
    const double count = static_cast<double>(channels_.size());
    double total = 0.0;
    std::size_t offset = 0;
    for (const WindowChannel& channel : channels_) {
      double sum = 0.0;
      for (std::size_t n = 0; n < channel.samples.size(); ++n) {
        sum += residuals[offset + n] * residuals[offset + n];
      }
      offset += channel.samples.size();
      total += std::sqrt(sum) * channel.scale / channel.variation;  // the channel's NRMSE
    }
    return total / count;
  }

  // The solver's current point is where it last asked for a Jacobian: remember its error.
  void MarkCurrent(const double* residuals) { current_error_ = Error(residuals); }
  double current_error() const { return current_error_; }

 private:
  struct CacheEntry {
    std::vector<double> z;
    std::vector<double> residuals;
    bool ok = false;
  };

  bool Replay(const double* z, std::vector<double>* residuals) {
    auto params = ParamsAt(z);
    if (!params.ok()) {
      last_failure_ = params.status().message();
      return false;
    }
    ++replays_;
    auto traces = ReplayModel(log_, *params, options_.simulation, options_.replay);
    if (!traces.ok()) {
      last_failure_ = traces.status().message();
      return false;
    }
    residuals->resize(residual_count_);
    std::size_t offset = 0;
    for (const WindowChannel& channel : channels_) {
      const std::vector<double>& y = log_.channels[channel.index].values_si;
      const std::vector<double>& yhat = traces->values_si[channel.index];
      for (std::size_t n : channel.samples) {
        const double r = (yhat[n] - y[n]) / channel.scale;
        if (!std::isfinite(r)) {
          last_failure_ = "the model gave a non-finite value";
          return false;
        }
        (*residuals)[offset++] = r;
      }
    }
    return true;
  }

  const MeasuredLog& log_;
  RigParams start_;
  std::vector<std::string> keys_;
  std::vector<double> scales_;
  const FitOptions& options_;
  std::vector<WindowChannel> channels_;
  std::size_t residual_count_ = 0;
  int replays_ = 0;
  std::deque<CacheEntry> cache_;
  std::string last_failure_;
  double current_error_ = kNaN;
};

// Finite-difference step for scaled parameter j at z (sign: inwards at the upper bound).
double Step(double relative_step, double z, double lower, double upper) {
  const double h = relative_step * std::max(std::abs(z), 0.01 * (upper - lower));
  return z + h <= upper ? h : -h;
}

// Ceres's view of the residuals: one parameter block of size p, m residuals, Jacobian by forward
// or central differences (row-major m x p).
class ReplayCost final : public ceres::CostFunction {
 public:
  ReplayCost(ReplayResiduals* residuals, std::vector<double> lower, std::vector<double> upper,
             double relative_step, bool central)
      : residuals_(residuals),
        lower_(std::move(lower)),
        upper_(std::move(upper)),
        relative_step_(relative_step),
        central_(central) {
    set_num_residuals(residuals->residual_count());
    mutable_parameter_block_sizes()->push_back(residuals->parameter_count());
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* z = parameters[0];
    if (!residuals_->Evaluate(z, residuals)) return false;
    if (jacobians == nullptr || jacobians[0] == nullptr) return true;
    residuals_->MarkCurrent(residuals);
    const int m = num_residuals();
    const int p = residuals_->parameter_count();
    std::vector<double> shifted(z, z + p);
    std::vector<double> plus(m), minus(m);
    for (int j = 0; j < p; ++j) {
      const double h = Step(relative_step_, z[j], lower_[j], upper_[j]);
      if (central_) {
        // Central where both sides are inside the bounds, else one-sided (inwards).
        const double hc = std::abs(h);
        const double up = std::min(z[j] + hc, upper_[j]);
        const double down = std::max(z[j] - hc, lower_[j]);
        shifted[j] = up;
        if (up == z[j]) {
          std::copy(residuals, residuals + m, plus.begin());
        } else if (!residuals_->Evaluate(shifted.data(), plus.data())) {
          return false;
        }
        shifted[j] = down;
        if (down == z[j]) {
          std::copy(residuals, residuals + m, minus.begin());
        } else if (!residuals_->Evaluate(shifted.data(), minus.data())) {
          return false;
        }
        const double width = up - down;
        for (int i = 0; i < m; ++i) jacobians[0][i * p + j] = (plus[i] - minus[i]) / width;
      } else {
        shifted[j] = z[j] + h;
        if (!residuals_->Evaluate(shifted.data(), plus.data())) return false;
        const double step = shifted[j] - z[j];  // the representable step
        for (int i = 0; i < m; ++i) jacobians[0][i * p + j] = (plus[i] - residuals[i]) / step;
      }
      shifted[j] = z[j];
    }
    return true;
  }

 private:
  ReplayResiduals* residuals_;
  std::vector<double> lower_, upper_;
  double relative_step_;
  bool central_;
};

class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const ReplayResiduals& residuals,
                   const std::function<void(int, double)>& progress,
                   const std::function<bool()>& cancelled)
      : residuals_(residuals), progress_(progress), cancelled_(cancelled) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (progress_) progress_(summary.iteration, residuals_.current_error());
    if (cancelled_ && cancelled_()) {
      was_cancelled_ = true;
      return ceres::SOLVER_ABORT;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool was_cancelled() const { return was_cancelled_; }

 private:
  const ReplayResiduals& residuals_;
  const std::function<void(int, double)>& progress_;
  const std::function<bool()>& cancelled_;
  bool was_cancelled_ = false;
};

// --- FitParameters's steps ------------------------------------------------------------------

// The parameters as the solver sees them: z = x / scale, with the bounds in the same form.
struct ScaledParameters {
  std::vector<double> scale, z, lower, upper;
  std::size_t size() const { return z.size(); }
};

// Checks each parameter (given once, known, bounds finite, ordered and settable) and scales it:
// its value in `start` clamped into the bounds is written into result->params (which starts as
// `start`) and result->initial, its key into result->keys. The scale is |initial|, or the bound
// range when the start is 0.
Result<ScaledParameters> ScaleParameters(const RigParams& start,
                                         const std::vector<FitParameter>& parameters,
                                         FitResult* result) {
  const std::size_t p = parameters.size();
  ScaledParameters x{std::vector<double>(p), std::vector<double>(p), std::vector<double>(p),
                     std::vector<double>(p)};
  for (std::size_t j = 0; j < p; ++j) {
    const FitParameter& parameter = parameters[j];
    for (std::size_t k = 0; k < j; ++k) {
      if (parameters[k].key == parameter.key) {
        return Status::Error("parameter '" + parameter.key + "' is given twice");
      }
    }
    auto value = GetParamValue(start, parameter.key);
    if (!value.ok()) return value.status();
    if (!std::isfinite(parameter.lower) || !std::isfinite(parameter.upper) ||
        !(parameter.lower < parameter.upper)) {
      std::ostringstream out;
      out << parameter.key << ": bounds [" << parameter.lower << ", " << parameter.upper
          << "] must be finite with lower < upper";
      return Status::Error(out.str());
    }
    // The bounds must be settable: inside the parameter tables' bounds.
    MPDRIG_RETURN_IF_ERROR(SetParamValue(&result->params, parameter.key, parameter.lower));
    MPDRIG_RETURN_IF_ERROR(SetParamValue(&result->params, parameter.key, parameter.upper));
    const double initial = std::clamp(*value, parameter.lower, parameter.upper);
    MPDRIG_RETURN_IF_ERROR(SetParamValue(&result->params, parameter.key, initial));
    result->keys.push_back(parameter.key);
    result->initial.push_back(initial);
    x.scale[j] = initial != 0.0 ? std::abs(initial) : parameter.upper - parameter.lower;
    x.z[j] = initial / x.scale[j];
    x.lower[j] = parameter.lower / x.scale[j];
    x.upper[j] = parameter.upper / x.scale[j];
  }
  return x;
}

// Which parameters to hold: those whose difference step at the start moves the residuals `r0`
// by less than kNoInfluence of their norm. Such a parameter is held at its start value and
// reported so (FitResult::held), rather than returned as if it had been estimated. E.g. the
// choke leak is the floor of the choke characteristic (G = max(G_table, leak), 9.4): with the
// choke open it changes nothing, and its estimate would only be its start value. Holding it also
// keeps the Levenberg-Marquardt step away from a zero Jacobian column, which only Ceres's tiny
// minimum diagonal regularises. The probes use ReplayCost's forward steps, so Ceres's first
// Jacobian finds them in the cache.
std::vector<bool> HeldParameters(ReplayResiduals* residuals, const ScaledParameters& x,
                                 const std::vector<double>& r0, double relative_step) {
  const std::size_t p = x.size();
  const int m = static_cast<int>(r0.size());
  std::vector<bool> held(p, false);
  const double reference = Eigen::Map<const Eigen::VectorXd>(r0.data(), m).norm();
  std::vector<double> shifted = x.z, probe(m);
  for (std::size_t j = 0; j < p; ++j) {
    shifted[j] = x.z[j] + Step(relative_step, x.z[j], x.lower[j], x.upper[j]);
    if (residuals->Evaluate(shifted.data(), probe.data())) {
      double change = 0.0;
      for (int i = 0; i < m; ++i) change += (probe[i] - r0[i]) * (probe[i] - r0[i]);
      held[j] = std::sqrt(change) <= kNoInfluence * reference;
    }
    shifted[j] = x.z[j];
  }
  return held;
}

// Trust region, Levenberg-Marquardt, dense QR, one thread, silent unless options.solver_log.
ceres::Solver::Options SolverOptions(const FitOptions& options) {
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  // Steps below a tenth of the difference step are below what the derivatives resolve.
  solver.parameter_tolerance = 0.1 * options.relative_step;
  // With bounds, Ceres runs a projected Armijo line search on every step. Its default cubic
  // interpolation asks for the gradient at each trial point, a whole Jacobian (p replays) here;
  // quadratic interpolation needs only costs, and a few contractions are enough (measured: about
  // half the replays per fit).
  solver.line_search_interpolation_type = ceres::QUADRATIC;
  solver.max_num_line_search_step_size_iterations = 4;
  solver.num_threads = 1;
  solver.logging_type = options.solver_log ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  solver.minimizer_progress_to_stdout = options.solver_log;
  return solver;
}

// Runs Ceres from x->z, which it moves in place, with the parameters of result->held fixed at
// their start; the solver's report, iterations and convergence into *result. Where every
// parameter is held there is nothing to solve.
Status RunSolver(ReplayResiduals* residuals, const FitOptions& options, ScaledParameters* x,
                 FitResult* result) {
  const std::size_t p = x->size();
  std::vector<int> held_indices;
  for (std::size_t j = 0; j < p; ++j) {
    if (result->held[j]) held_indices.push_back(static_cast<int>(j));
  }
  // Ceres owns the cost function (default ownership) and reads/writes z in place.
  ceres::Problem problem;
  problem.AddResidualBlock(new ReplayCost(residuals, x->lower, x->upper, options.relative_step,
                                          options.central_differences),
                           nullptr, x->z.data());
  if (!held_indices.empty() && held_indices.size() < p) {
    problem.SetManifold(x->z.data(), new ceres::SubsetManifold(static_cast<int>(p), held_indices));
  }
  for (std::size_t j = 0; j < p; ++j) {
    problem.SetParameterLowerBound(x->z.data(), static_cast<int>(j), x->lower[j]);
    problem.SetParameterUpperBound(x->z.data(), static_cast<int>(j), x->upper[j]);
  }
  ceres::Solver::Options solver = SolverOptions(options);
  ProgressCallback callback(*residuals, options.progress, options.cancelled);
  solver.callbacks.push_back(&callback);
  std::string options_error;
  if (!solver.IsValid(&options_error)) return Status::Error("solver options: " + options_error);
  ceres::Solver::Summary summary;
  if (held_indices.size() < p) {
    ceres::Solve(solver, &problem, &summary);
    result->solver_report = summary.BriefReport();
  } else {
    summary.termination_type = ceres::CONVERGENCE;
    result->solver_report = "no parameter moves the residuals: all held at their start values";
  }
  if (callback.was_cancelled()) return Status::Error(kFitCancelled);
  if (summary.termination_type == ceres::FAILURE) {
    return Status::Error("the solver failed: " + summary.message +
                         (residuals->last_failure().empty()
                              ? std::string()
                              : " (last model failure: " + residuals->last_failure() + ")"));
  }
  result->iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  result->converged = summary.termination_type == ceres::CONVERGENCE;
  return Status::Ok();
}

// The central-difference Jacobian of the residuals at x.z (scaled parameters; one-sided where
// a bound is within the step), or nullopt where a replay fails.
std::optional<Eigen::MatrixXd> CentralJacobian(ReplayResiduals* residuals,
                                               const ScaledParameters& x, double relative_step) {
  const std::size_t p = x.size();
  const int m = residuals->residual_count();
  Eigen::MatrixXd jacobian(m, p);
  std::vector<double> plus(m), minus(m);
  for (std::size_t j = 0; j < p; ++j) {
    const double h = std::abs(Step(relative_step, x.z[j], x.lower[j], x.upper[j]));
    std::vector<double> z_plus = x.z, z_minus = x.z;
    z_plus[j] = std::min(x.z[j] + h, x.upper[j]);
    z_minus[j] = std::max(x.z[j] - h, x.lower[j]);
    if (!residuals->Evaluate(z_plus.data(), plus.data()) ||
        !residuals->Evaluate(z_minus.data(), minus.data())) {
      return std::nullopt;
    }
    const double width = z_plus[j] - z_minus[j];
    for (int i = 0; i < m; ++i) jacobian(i, j) = (plus[i] - minus[i]) / width;
  }
  return jacobian;
}

// Standard errors and correlations from the Jacobian at the optimum (scaled parameters) and the
// residuals r there: cov_z = s^2 (J^T J)^-1, s^2 = ||r||^2 / (m - p); cov_x = S cov_z S,
// S = diag(scales). A parameter in a null direction of J^T J keeps NaN.
void StandardErrors(const Eigen::MatrixXd& jacobian, double residual_square_sum,
                    const std::vector<double>& scales, FitResult* result) {
  const std::size_t p = scales.size();
  const auto m = static_cast<int>(jacobian.rows());
  const double s2 = residual_square_sum / static_cast<double>(m - static_cast<int>(p));
  const Eigen::MatrixXd jtj = jacobian.transpose() * jacobian;
  // Column scaling to unit diagonal, so the condition test sees the shape, not the units.
  Eigen::VectorXd d = jtj.diagonal().cwiseSqrt();
  std::vector<bool> identifiable(p, true);
  for (std::size_t j = 0; j < p; ++j) identifiable[j] = d(j) > 0.0;
  for (std::size_t j = 0; j < p; ++j) {
    if (!identifiable[j]) d(j) = 1.0;
  }
  const Eigen::MatrixXd normalised = d.asDiagonal().inverse() * jtj * d.asDiagonal().inverse();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normalised);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const double largest = values.maxCoeff();
  Eigen::MatrixXd inverse = Eigen::MatrixXd::Zero(p, p);
  for (std::size_t k = 0; k < p; ++k) {
    const Eigen::VectorXd v = eigen.eigenvectors().col(k);
    if (values(k) > kSingularRatio * largest) {
      inverse += v * v.transpose() / values(k);
    } else {
      // A null direction: every parameter it involves is not identifiable on its own.
      for (std::size_t j = 0; j < p; ++j) {
        if (std::abs(v(j)) > 1.0e-3) identifiable[j] = false;
      }
    }
  }
  const Eigen::MatrixXd cov_z = s2 * d.asDiagonal().inverse() * inverse * d.asDiagonal().inverse();
  for (std::size_t i = 0; i < p; ++i) {
    if (!identifiable[i]) continue;
    result->standard_errors[i] = std::sqrt(cov_z(i, i)) * scales[i];
    for (std::size_t j = 0; j < p; ++j) {
      if (i == j || !identifiable[j]) continue;
      result->correlation[i][j] = cov_z(i, j) / std::sqrt(cov_z(i, i) * cov_z(j, j));
    }
  }
}

// Covariance from the central-difference Jacobian at the optimum x.z, residuals r there: the
// standard errors and correlations into *result, NaN where the Jacobian's replays fail.
void EstimateCovariance(ReplayResiduals* residuals, const ScaledParameters& x,
                        double residual_square_sum, double relative_step, FitResult* result) {
  const std::optional<Eigen::MatrixXd> jacobian = CentralJacobian(residuals, x, relative_step);
  if (jacobian) StandardErrors(*jacobian, residual_square_sum, x.scale, result);
}

// No covariance yet: standard errors NaN, correlations NaN off the diagonal.
void NoCovariance(std::size_t p, FitResult* result) {
  result->standard_errors.assign(p, kNaN);
  result->correlation.assign(p, std::vector<double>(p, kNaN));
  for (std::size_t j = 0; j < p; ++j) result->correlation[j][j] = 1.0;
}

}  // namespace

Status FitOptions::Validate() const {
  if (!(window_begin_s < window_end_s)) {
    return Status::Error("fit window is empty: begin must be before end");
  }
  if (max_iterations < 0) return Status::Error("max_iterations must be >= 0");
  if (!(relative_step > 0.0 && relative_step < 0.1)) {
    return Status::Error("relative_step must be in (0, 0.1)");
  }
  return simulation.Validate();
}

Result<FitParameter> DefaultFitParameter(std::string_view key) {
  auto found = FindParamByKey(key);
  if (!found.ok()) return found.status();
  const auto [lower, upper] = found->FitRange();
  return FitParameter{std::string(key), lower, upper};
}

Result<FitResult> FitParameters(const MeasuredLog& log, const RigParams& start,
                                const std::vector<FitParameter>& parameters,
                                const FitOptions& options) {
  if (parameters.empty()) return Status::Error("no parameter to fit");
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(start));

  FitResult result;
  result.params = start;
  auto scaled = ScaleParameters(start, parameters, &result);
  if (!scaled.ok()) return scaled.status();
  ScaledParameters& x = *scaled;
  const std::size_t p = x.size();

  std::vector<WindowChannel> channels =
      WindowChannels(log, options.window_begin_s, options.window_end_s, options.weighting);
  if (channels.empty()) {
    return Status::Error("no measured channel varies inside the fit window: nothing to fit");
  }
  ReplayResiduals residuals(log, result.params, result.keys, x.scale, options, std::move(channels));
  const int m = residuals.residual_count();
  if (m <= static_cast<int>(p)) {
    return Status::Error("the fit window has " + std::to_string(m) + " measured samples for " +
                         std::to_string(p) + " parameters");
  }
  std::vector<double> r0(m);
  if (!residuals.Evaluate(x.z.data(), r0.data())) {
    return Status::Error("the model fails at the start values: " + residuals.last_failure());
  }
  result.error_before = residuals.Error(r0.data());

  result.held = HeldParameters(&residuals, x, r0, options.relative_step);
  MPDRIG_RETURN_IF_ERROR(RunSolver(&residuals, options, &x, &result));

  std::vector<double> r(m);
  if (!residuals.Evaluate(x.z.data(), r.data())) {
    return Status::Error("the model fails at the estimate: " + residuals.last_failure());
  }
  result.error_after = residuals.Error(r.data());
  for (std::size_t j = 0; j < p; ++j) {
    const double estimate =
        std::clamp(x.z[j] * x.scale[j], parameters[j].lower, parameters[j].upper);
    result.estimates.push_back(estimate);
    MPDRIG_RETURN_IF_ERROR(SetParamValue(&result.params, result.keys[j], estimate));
  }
  result.scaled_estimates = x.z;
  result.residual_square_sum = Eigen::Map<const Eigen::VectorXd>(r.data(), m).squaredNorm();
  NoCovariance(p, &result);
  if (options.standard_errors) {
    EstimateCovariance(&residuals, x, result.residual_square_sum, options.relative_step, &result);
  }
  result.replays = residuals.replays();
  return result;
}

Status EstimateStandardErrors(const MeasuredLog& log, const std::vector<FitParameter>& parameters,
                              const FitOptions& options, FitResult* fit) {
  const std::size_t p = parameters.size();
  if (fit->keys.size() != p || fit->scaled_estimates.size() != p) {
    return Status::Error("standard errors: not the fit of these parameters");
  }
  // The fit's scaling again: from its start values (ScaleParameters).
  FitResult scratch;
  scratch.params = fit->params;
  for (std::size_t j = 0; j < p; ++j) {
    if (parameters[j].key != fit->keys[j]) {
      return Status::Error("standard errors: not the fit of these parameters");
    }
    MPDRIG_RETURN_IF_ERROR(SetParamValue(&scratch.params, fit->keys[j], fit->initial[j]));
  }
  const RigParams start = scratch.params;
  auto scaled = ScaleParameters(start, parameters, &scratch);
  if (!scaled.ok()) return scaled.status();
  ScaledParameters& x = *scaled;
  x.z = fit->scaled_estimates;
  ReplayResiduals residuals(
      log, scratch.params, scratch.keys, x.scale, options,
      WindowChannels(log, options.window_begin_s, options.window_end_s, options.weighting));
  NoCovariance(p, fit);
  EstimateCovariance(&residuals, x, fit->residual_square_sum, options.relative_step, fit);
  fit->replays += residuals.replays();
  return Status::Ok();
}

Result<FitResult> FitParametersAndInputLevels(MeasuredLog* log, const RigParams& start,
                                              const std::vector<FitParameter>& parameters,
                                              FitOptions options) {
  auto first = FitParameters(*log, start, parameters, options);
  if (!first.ok()) return first;
  if (options.cancelled && options.cancelled()) return Status::Error(kFitCancelled);
  // The start chosen at the start values (ChooseReplayStart) may be one that absorbed their error
  // (a measured state fitted under a wrong wave speed): chosen again at the fitted parameters.
  bool start_changed = false;
  if (options.replay.choose_warmup && options.replay.profile) {
    ReplayOptions again = options.replay;
    MPDRIG_RETURN_IF_ERROR(ChooseReplayStart(*log, first->params, options.simulation, &again));
    start_changed = true;
    options.replay = again;
  }
  const ReplayOptions& replay = options.replay;
  bool levels_changed = false;
  InputLevelCorrection levels;
  if (replay.reconstruct_inputs && replay.estimate_levels &&
      !log->reconstruction.levels.applied()) {
    auto estimate = EstimateInputLevels(*log, first->params, options.simulation, replay);
    if (!estimate.ok()) return estimate.status();
    levels = *estimate;
    levels_changed = levels.applied();
  }
  if (!start_changed && !levels_changed) return first;
  if (levels_changed) {
    ApplyInputLevels(levels, log);
    ApplyInputLevels(levels, &options.replay);
  }
  auto second = FitParameters(*log, first->params, parameters, options);
  if (!second.ok()) {
    return second.status().Within("refitting on the start and input levels estimated at the fit");
  }
  second->initial = first->initial;  // the user's start, not the second fit's
  second->error_before = first->error_before;
  second->iterations += first->iterations;
  second->replays += first->replays + 3;
  if (levels_changed) second->input_levels = levels;
  return second;
}

}  // namespace mpdrig
