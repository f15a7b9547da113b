#include "model/pipe/pipe_solver.h"

#include <algorithm>
#include <cmath>

#include "model/pipe/characteristics_solver.h"
#include "model/pipe/mol_solver.h"

namespace mpdrig {

PipeConfig PipeConfig::FromParams(const RigParams& params, PipeModel model, int cells) {
  PipeConfig config;
  config.model = model;
  config.cells = cells;
  config.length_m = params.pipe_length_m;
  config.area_m2 = params.PipeAreaM2();
  config.wave_speed_mps = params.wave_speed_mps;
  config.density_kgpm3 = params.density_kgpm3;
  config.k_pa = params.QuasiLinearK();
  config.friction_f1_per_s = params.friction_f1_per_s;
  config.friction_f2_per_m = params.friction_f2_per_m;
  config.gravity_slope_mps2 = params.gravity_mps2 * params.SinInclination();
  config.choke_density_kgpm3 = params.choke_density_kgpm3;
  return config;
}

PipeSolver::PipeSolver(const PipeConfig& config, double p_bar_pa)
    : config_(config),
      law_(config.model, config.wave_speed_mps, config.density_kgpm3, config.k_pa, p_bar_pa),
      choke_(config.area_m2, config.choke_density_kgpm3),
      alpha_(config.cells + 1, 0.0),
      beta_(config.cells + 1, 0.0) {
  MPDRIG_CHECK(config.cells >= 2);
}

void PipeSolver::SetRestState(double outlet_pressure_pa) {
  const double c = config_.wave_speed_mps;
  const double dx = config_.dx_m();
  for (int i = 0; i <= config_.cells; ++i) {
    const double depth_below_outlet_m = config_.length_m - i * dx;
    double p;
    if (config_.model == PipeModel::kQuasiLinear) {
      // (6.5.3): p(x) = (k + p_l) exp(g sin(gamma) (L - x) / c^2) - k
      p = (config_.k_pa + outlet_pressure_pa) *
              std::exp(config_.gravity_slope_mps2 * depth_below_outlet_m / (c * c)) -
          config_.k_pa;
    } else {
      p = outlet_pressure_pa +
          config_.density_kgpm3 * config_.gravity_slope_mps2 * depth_below_outlet_m;
    }
    alpha_[i] = law_.Alpha(p, 0.0);
    beta_[i] = law_.Beta(p, 0.0);
  }
  OnStateReset();
}

void PipeSolver::SetState(const std::vector<double>& pressure_pa,
                          const std::vector<double>& velocity_mps) {
  MPDRIG_CHECK(pressure_pa.size() == alpha_.size() && velocity_mps.size() == alpha_.size());
  for (std::size_t i = 0; i < alpha_.size(); ++i) {
    alpha_[i] = law_.Alpha(pressure_pa[i], velocity_mps[i]);
    beta_[i] = law_.Beta(pressure_pa[i], velocity_mps[i]);
  }
  OnStateReset();
}

Status PipeSolver::SetExtensions(std::vector<const PipeExtension*> extensions) {
  source_extensions_.clear();
  inlet_closure_ = nullptr;
  outlet_closure_ = nullptr;
  compressibility_extensions_.clear();
  vapour_pressure_extension_ = nullptr;
  for (const PipeExtension* extension : extensions) {
    if (extension->adds_momentum_source()) {
      if (!supports_momentum_sources()) {
        return Status::Error("this pipe scheme takes no momentum sources (use characteristics)");
      }
      source_extensions_.push_back(extension);
    }
    if (extension->closes_inlet() || extension->closes_outlet()) {
      if (!supports_boundary_closures()) {
        return Status::Error("this pipe scheme takes no boundary closures (use characteristics)");
      }
    }
    if (extension->closes_inlet()) {
      if (inlet_closure_ != nullptr) return Status::Error("two effects close the pipe inlet");
      inlet_closure_ = extension;
    }
    if (extension->closes_outlet()) {
      if (outlet_closure_ != nullptr) return Status::Error("two effects close the pipe outlet");
      outlet_closure_ = extension;
    }
    if (extension->changes_compressibility()) {
      if (!supports_compressibility()) {
        return Status::Error(
            "this pipe scheme takes no pressure-dependent wave speed (use characteristics)");
      }
      compressibility_extensions_.push_back(extension);
    }
    if (extension->has_vapour_pressure()) {
      const PipeExtension::FreeGas gas = extension->CavityFreeGas();
      if (!supports_column_separation()) {
        return Status::Error(
            gas.void_fraction > 0.0
                ? "this pipe scheme takes no column separation, nor its discrete gas cavity model "
                  "(gas_void_fraction > 0): use --scheme characteristics"
                : "this pipe scheme takes no column separation (use characteristics)");
      }
      if (vapour_pressure_extension_ != nullptr) {
        return Status::Error("two effects set a vapour pressure");
      }
      if (!(extension->VapourPressurePa() > 0.0)) {
        return Status::Error("the vapour pressure must be above zero absolute");
      }
      if (gas.void_fraction > 0.0 && !(gas.reference_pressure_pa > extension->VapourPressurePa())) {
        return Status::Error(
            "the free gas's reference pressure (gas_reference_pressure_pa) must be above the "
            "vapour pressure");
      }
      if (gas.void_fraction > 0.0 && !(gas.weighting >= 0.5 && gas.weighting <= 1.0)) {
        return Status::Error("the gas cavities' weighting psi (gas_weighting) must be in [0.5, 1]");
      }
      vapour_pressure_extension_ = extension;
    }
  }
  source_explicit_.assign(source_extensions_.empty() ? 0 : config_.cells + 1, 0.0);
  source_implicit_.assign(source_explicit_.size(), 0.0);
  OnExtensionsChanged();
  return Status::Ok();
}

bool PipeSolver::EvaluateMomentumSources() {
  if (source_extensions_.empty()) return false;
  std::fill(source_explicit_.begin(), source_explicit_.end(), 0.0);
  std::fill(source_implicit_.begin(), source_implicit_.end(), 0.0);
  const PipeSnapshot snapshot{config_, law_, alpha_, beta_, time_step_s()};
  for (const PipeExtension* extension : source_extensions_) {
    extension->AddMomentumSource(snapshot, source_explicit_, source_implicit_);
  }
  return true;
}

void PipeSolver::Locate(double x_m, int* index, double* weight) const {
  const double s = std::clamp(x_m / config_.dx_m(), 0.0, static_cast<double>(config_.cells));
  int i = std::min(static_cast<int>(s), config_.cells - 1);
  *index = i;
  *weight = s - i;
}

double PipeSolver::PressureAt(double x_m) const {
  int i;
  double w;
  Locate(x_m, &i, &w);
  const double difference = (1.0 - w) * (alpha_[i] - beta_[i]) + w * (alpha_[i + 1] - beta_[i + 1]);
  return law_.PressureFromDifference(difference);
}

double PipeSolver::VelocityAt(double x_m) const {
  int i;
  double w;
  Locate(x_m, &i, &w);
  return law_.Velocity((1.0 - w) * alpha_[i] + w * alpha_[i + 1],
                       (1.0 - w) * beta_[i] + w * beta_[i + 1]);
}

double PipeSolver::StoredVolumeM3() const {
  // rho(p)/rho_ref - 1 = (p - p_ref)/(rho_ref c^2) (5.2.1); the constant p_ref drops out of
  // changes.
  const double scale =
      config_.area_m2 / (config_.density_kgpm3 * config_.wave_speed_mps * config_.wave_speed_mps);
  double sum = 0.0;
  for (int i = 0; i <= config_.cells; ++i) {
    const double weight = (i == 0 || i == config_.cells) ? 0.5 : 1.0;
    sum += weight * law_.Pressure(alpha_[i], beta_[i]);
  }
  return scale * sum * config_.dx_m();
}

void PipeSolver::CheckRange(RangeViolation* violation) const {
  if (violation == nullptr) return;
  // Every step: a plain minimum (vectorises). Only when the range is left, find where.
  const double* a = alpha_.data();
  const double* b = beta_.data();
  // Four independent running minima: an element-wise min vectorises, a scalar reduction would
  // not (floating-point reductions are not reassociated without fast-math).
  const int count = config_.cells + 1;
  double lanes[4] = {a[0] - b[0], a[0] - b[0], a[0] - b[0], a[0] - b[0]};
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    for (int k = 0; k < 4; ++k) lanes[k] = std::min(lanes[k], a[i + k] - b[i + k]);
  }
  for (; i < count; ++i) lanes[0] = std::min(lanes[0], a[i] - b[i]);
  CheckRange(violation, std::min(std::min(lanes[0], lanes[1]), std::min(lanes[2], lanes[3])));
}

void PipeSolver::CheckRange(RangeViolation* violation, double smallest) const {
  if (violation == nullptr || smallest > law_.ZeroPressureDifference()) return;
  const double* a = alpha_.data();
  const double* b = beta_.data();
  int worst = 0;
  for (int i = 1; i <= config_.cells; ++i) {
    if (a[i] - b[i] < a[worst] - b[worst]) worst = i;
  }
  violation->occurred = true;
  violation->min_pressure_pa = law_.PressureFromDifference(smallest);
  violation->position_m = worst * config_.dx_m();
}

Result<std::unique_ptr<PipeSolver>> MakePipeSolver(PipeScheme scheme, const PipeConfig& config,
                                                   double p_bar_pa) {
  if (config.cells < 2) return Status::Error("the pipe needs at least 2 cells");
  if (scheme == PipeScheme::kCharacteristics) {
    return std::unique_ptr<PipeSolver>(new CharacteristicsSolver(config, p_bar_pa));
  }
  auto solver = MolSolver::Create(config, p_bar_pa);
  if (!solver.ok()) return solver.status();
  return std::unique_ptr<PipeSolver>(std::move(solver).value());
}

}  // namespace mpdrig
