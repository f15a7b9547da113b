#include "model/identification/resonance_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <ceres/ceres.h>
#include <Eigen/Dense>

#include "model/effects/param_by_key.h"

namespace mpdrig {
namespace {

class ResonanceModel {
 public:
  ResonanceModel(const std::vector<MeasuredResonance>& measured, const RigParams& start,
                 const std::vector<FitParameter>& parameters, const ResonanceFitOptions& options)
      : measured_(measured), start_(start), parameters_(parameters), options_(options) {}

  RigParams ParamsAt(const double* z) const {
    RigParams params = start_;
    for (std::size_t j = 0; j < parameters_.size(); ++j) {
      const FitParameter& p = parameters_[j];
      const double value = p.lower + std::clamp(z[j], 0.0, 1.0) * (p.upper - p.lower);
      const Status set = SetParamValue(&params, p.key, value);
      MPDRIG_CHECK(set.ok());
    }
    return params;
  }

  // The model's first resonance in every configuration; false if one cannot be computed.
  bool Resonances(const RigParams& params, std::vector<Resonance>* out) const {
    out->clear();
    for (const MeasuredResonance& m : measured_) {
      auto resonance = FirstResonance(params, m.configuration, options_.resonance);
      ++evaluations_;
      if (!resonance.ok()) {
        last_error_ = resonance.status().message();
        return false;
      }
      out->push_back(*resonance);
    }
    return true;
  }

  bool Residuals(const double* z, double* r, bool* simulated) const {
    std::vector<Resonance> resonances;
    if (!Resonances(ParamsAt(z), &resonances)) return false;
    for (std::size_t i = 0; i < measured_.size(); ++i) {
      r[i] = (resonances[i].freq_hz - measured_[i].frequency_hz) / measured_[i].uncertainty_hz;
      if (resonances[i].method == ResponseMethod::kSimulated) *simulated = true;
    }
    return true;
  }

  // Central differences (one-sided at a bound) of the residuals in the mapped parameters.
  bool Jacobian(const double* z, Eigen::MatrixXd* jacobian) const {
    const std::size_t p = parameters_.size(), m = measured_.size();
    std::vector<double> base(m), plus(m), minus(m);
    bool simulated = false;
    if (!Residuals(z, base.data(), &simulated)) return false;
    const double h = simulated ? options_.simulated_step : options_.analytic_step;
    jacobian->resize(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(p));
    std::vector<double> shifted(z, z + p);
    for (std::size_t j = 0; j < p; ++j) {
      const double hi = std::min(1.0, z[j] + h), lo = std::max(0.0, z[j] - h);
      shifted[j] = hi;
      bool ignored = false;
      if (!Residuals(shifted.data(), plus.data(), &ignored)) return false;
      shifted[j] = lo;
      if (!Residuals(shifted.data(), minus.data(), &ignored)) return false;
      shifted[j] = z[j];
      for (std::size_t i = 0; i < m; ++i) {
        (*jacobian)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
            (plus[i] - minus[i]) / (hi - lo);
      }
    }
    return true;
  }

  std::size_t size() const { return measured_.size(); }
  int evaluations() const { return evaluations_; }
  const std::string& last_error() const { return last_error_; }

 private:
  const std::vector<MeasuredResonance>& measured_;
  const RigParams& start_;
  const std::vector<FitParameter>& parameters_;
  const ResonanceFitOptions& options_;
  mutable int evaluations_ = 0;
  mutable std::string last_error_;
};

class ResonanceCost final : public ceres::CostFunction {
 public:
  explicit ResonanceCost(const ResonanceModel& model, int parameters) : model_(model) {
    set_num_residuals(static_cast<int>(model.size()));
    mutable_parameter_block_sizes()->push_back(parameters);
  }
  bool Evaluate(double const* const* z, double* residuals, double** jacobians) const override {
    bool simulated = false;
    if (!model_.Residuals(z[0], residuals, &simulated)) return false;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::MatrixXd j;
      if (!model_.Jacobian(z[0], &j)) return false;
      // Ceres: row-major, residual by parameter.
      for (Eigen::Index r = 0; r < j.rows(); ++r) {
        for (Eigen::Index c = 0; c < j.cols(); ++c) jacobians[0][r * j.cols() + c] = j(r, c);
      }
    }
    return true;
  }

 private:
  const ResonanceModel& model_;
};

double SumOfSquares(const std::vector<double>& r) {
  double sum = 0.0;
  for (double v : r) sum += v * v;
  return sum;
}

}  // namespace

Result<ResonanceFitResult> FitResonances(const std::vector<MeasuredResonance>& measured,
                                         const RigParams& start,
                                         const std::vector<FitParameter>& parameters,
                                         const ResonanceFitOptions& options) {
  if (measured.empty()) return Status::Error("no measured resonance to fit");
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(start));
  ResonanceFitResult result;
  result.params = start;
  std::vector<double> z;
  for (const FitParameter& p : parameters) {
    for (const std::string& key : result.keys) {
      if (key == p.key) return Status::Error("parameter '" + p.key + "' given twice");
    }
    if (!(p.lower < p.upper)) return Status::Error(p.key + ": lower bound must be below upper");
    auto value = GetParamValue(start, p.key);
    if (!value.ok()) return value.status();
    const double clamped = std::clamp(*value, p.lower, p.upper);
    result.keys.push_back(p.key);
    result.lower.push_back(p.lower);
    result.upper.push_back(p.upper);
    result.initial.push_back(*value);
    z.push_back((clamped - p.lower) / (p.upper - p.lower));
  }
  const std::size_t np = parameters.size();
  ResonanceModel model(measured, start, parameters, options);

  std::vector<Resonance> before;
  if (!model.Resonances(start, &before)) {
    return Status::Error("at the start parameters: " + model.last_error());
  }
  std::vector<double> r(measured.size());
  for (std::size_t i = 0; i < measured.size(); ++i) {
    r[i] = (before[i].freq_hz - measured[i].frequency_hz) / measured[i].uncertainty_hz;
  }
  result.chi2_before = SumOfSquares(r);

  if (np > 0) {
    ceres::Problem problem;
    problem.AddResidualBlock(new ResonanceCost(model, static_cast<int>(np)), nullptr, z.data());
    for (std::size_t j = 0; j < np; ++j) {
      problem.SetParameterLowerBound(z.data(), static_cast<int>(j), 0.0);
      problem.SetParameterUpperBound(z.data(), static_cast<int>(j), 1.0);
    }
    ceres::Solver::Options solver;
    solver.minimizer_type = ceres::TRUST_REGION;
    solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    solver.linear_solver_type = ceres::DENSE_QR;
    solver.max_num_iterations = options.max_iterations;
    solver.function_tolerance = 1e-10;
    solver.parameter_tolerance = 1e-10;
    solver.gradient_tolerance = 1e-12;
    solver.num_threads = 1;
    solver.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    if (summary.termination_type == ceres::FAILURE) {
      return Status::Error("the resonance fit failed: " + summary.message +
                           (model.last_error().empty() ? "" : " (" + model.last_error() + ")"));
    }
    result.converged = summary.termination_type == ceres::CONVERGENCE;
    result.iterations = static_cast<int>(summary.iterations.size()) - 1;
    result.solver_report = summary.BriefReport();
  } else {
    result.converged = true;
  }

  result.params = model.ParamsAt(z.data());
  for (std::size_t j = 0; j < np; ++j) {
    auto value = GetParamValue(result.params, parameters[j].key);
    MPDRIG_CHECK(value.ok());
    result.estimates.push_back(*value);
  }
  std::vector<Resonance> after;
  if (!model.Resonances(result.params, &after)) {
    return Status::Error("at the estimates: " + model.last_error());
  }
  for (std::size_t i = 0; i < measured.size(); ++i) {
    ResonanceFitConfiguration c;
    c.configuration = measured[i].configuration;
    c.measured_hz = measured[i].frequency_hz;
    c.uncertainty_hz = measured[i].uncertainty_hz;
    c.base_model_hz = before[i].freq_hz;
    c.model_hz = after[i].freq_hz;
    c.method = after[i].method;
    r[i] = (c.model_hz - c.measured_hz) / c.uncertainty_hz;
    result.max_error_hz = std::max(result.max_error_hz, std::fabs(c.model_hz - c.measured_hz));
    result.configurations.push_back(c);
  }
  result.chi2_after = SumOfSquares(r);

  // Standard errors from J at the estimates.
  result.standard_errors.assign(np, std::numeric_limits<double>::quiet_NaN());
  Eigen::MatrixXd jacobian;
  if (np > 0 && model.Jacobian(z.data(), &jacobian)) {
    const Eigen::MatrixXd jtj = jacobian.transpose() * jacobian;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(jtj);
    const auto& s = svd.singularValues();
    const bool regular = s.size() > 0 && s(s.size() - 1) > 1e-10 * s(0) && s(0) > 0.0;
    if (regular) {
      const Eigen::MatrixXd cov = jtj.inverse();
      for (std::size_t j = 0; j < np; ++j) {
        result.standard_errors[j] =
            std::sqrt(cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j))) *
            (parameters[j].upper - parameters[j].lower);
      }
    }
  }
  result.evaluations = model.evaluations();
  return result;
}

}  // namespace mpdrig
