#include "model/analysis/log_replay.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include <Eigen/Dense>

#include "model/analysis/log_stream.h"
#include "model/analysis/window_error.h"
#include "model/boundary/piston.h"

namespace mpdrig {

namespace {

// The replay ReplayModel and ReplayWindowError share: `on_sample` gets every sample the pipeline
// hands out (it may stop the pipeline, RowPipeline::RequestStop), and `traces` (if not null) the
// start and the solver's step and range event.
Status RunReplay(const MeasuredLog& log, const RigParams& params,
                 const SimulationOptions& sim_options, const ReplayOptions& replay,
                 const std::function<void(const PipelineSample&, RowPipeline*)>& on_sample,
                 ModelTraces* traces) {
  const std::vector<double>& times = log.time_s();
  if (times.size() < 2) return Status::Error(log.path + ": needs at least 2 samples");
  if (log.channels.size() > kComparedChannelCount) {
    return Status::Error(log.path + ": more channels than P1 P2 PT1..PT10 C2 FT1 FT3 FT4");
  }
  // The reconstruction made at loading; a log put together by hand gets one here.
  const MeasuredLog* replayed = &log;
  MeasuredLog reconstructed;
  if (replay.reconstruct_inputs && log.reconstructed_inputs.time_s.size() != times.size()) {
    reconstructed = log;
    ReconstructInputs(&reconstructed);
    replayed = &reconstructed;
  }
  RowPipeline* self = nullptr;
  RowPipeline pipeline(
      PipelineSmoothingS(replay),
      ReplaySetup{params, sim_options, times.back(), replay.warmup, replay.profile},
      [&](const PipelineSample& sample) { on_sample(sample, self); });
  self = &pipeline;
  MemoryRowSource source(
      *replayed, replay.reconstruct_inputs ? InputView::kReconstructed : InputView::kMeasured);
  MPDRIG_RETURN_IF_ERROR(RunPipeline(&source, &pipeline));
  if (traces != nullptr) {
    traces->inputs_reconstructed = replay.reconstruct_inputs;
    traces->warmup = replay.warmup;
    traces->profile = replay.profile;
    const RigSampler* sampler = pipeline.sampler();
    MPDRIG_CHECK(sampler != nullptr);
    traces->time_step_s = sampler->simulator().time_step_s();
    traces->steps = sampler->steps();
    traces->first_range_event = sampler->simulator().first_range_event();
  }
  return Status::Ok();
}

}  // namespace

Result<ModelTraces> ReplayModel(const MeasuredLog& log, const RigParams& params,
                                const SimulationOptions& sim_options, const ReplayOptions& replay,
                                const CompareProgress& progress) {
  // Keep only the compared channels of each sample.
  ModelTraces traces;
  traces.values_si.assign(log.channels.size(), {});
  for (auto& values : traces.values_si) values.reserve(log.time_s().size());
  PercentProgress percent(progress, "simulate", static_cast<long>(log.time_s().size()));
  MPDRIG_RETURN_IF_ERROR(RunReplay(
      log, params, sim_options, replay,
      [&](const PipelineSample& sample, RowPipeline*) {
        for (std::size_t i = 0; i < log.channels.size(); ++i) {
          traces.values_si[i].push_back(sample.model->values[Index(log.channels[i].channel)]);
        }
        percent.Done(sample.index + 1);
      },
      &traces));
  return traces;
}

Result<std::optional<double>> ReplayWindowError(const MeasuredLog& log, const RigParams& params,
                                                const SimulationOptions& sim_options,
                                                const ReplayOptions& replay, double begin_s,
                                                double end_s, double stop_above) {
  return ReplayWindowError(log, params, sim_options, replay, MeasureWindow(log, begin_s, end_s),
                           stop_above);
}

Result<std::optional<double>> ReplayWindowError(const MeasuredLog& log, const RigParams& params,
                                                const SimulationOptions& sim_options,
                                                const ReplayOptions& replay,
                                                const WindowReference& reference,
                                                double stop_above) {
  const double end_s = reference.end_s;
  WindowErrorAccumulator error(log, reference);
  std::vector<double> values(log.channels.size());
  bool stopped = false;
  MPDRIG_RETURN_IF_ERROR(RunReplay(
      log, params, sim_options, replay,
      [&](const PipelineSample& sample, RowPipeline* pipeline) {
        for (std::size_t i = 0; i < log.channels.size(); ++i) {
          values[i] = sample.model->values[Index(log.channels[i].channel)];
        }
        error.Add(static_cast<std::size_t>(sample.index), values.data());
        // Past the window nothing more counts.
        if (sample.row->time_s >= end_s) pipeline->RequestStop();
        // Not at every sample: 16 square roots each. Every 16th is soon enough.
        if (sample.index % 16 == 15 && error.LowerBound() > stop_above) {
          stopped = true;
          pipeline->RequestStop();
        }
      },
      nullptr));
  if (stopped) return std::optional<double>();
  return std::optional<double>(error.Error());
}

namespace {

bool IsPressure(Channel channel) {
  return channel != Channel::kFT1 && channel != Channel::kFT3 && channel != Channel::kFT4;
}

}  // namespace

Result<std::optional<PeriodicWarmup>> ChooseWarmup(const MeasuredLog& log, const RigParams& params,
                                                   const SimulationOptions& sim_options,
                                                   const ReplayOptions& replay) {
  const std::optional<PeriodicWarmup> candidate =
      PlanPeriodicWarmup(log.inputs, replay.reconstruct_inputs);
  if (!candidate) return std::optional<PeriodicWarmup>{};
  const MeasuredLog cut = MeasuredLogUntil(log, log.time_s().front() + 2.0 * candidate->period_s);
  double error[2] = {0.0, 0.0};
  for (int warm = 0; warm < 2; ++warm) {
    ReplayOptions start = replay;
    start.warmup = warm ? candidate : std::nullopt;
    auto traces = ReplayModel(cut, params, sim_options, start);
    if (!traces.ok()) {
      // A start that leaves the model's range (or fails) is not chosen; if both do, the replay
      // itself will say why.
      error[warm] = std::numeric_limits<double>::infinity();
      continue;
    }
    for (std::size_t c = 0; c < cut.channels.size(); ++c) {
      if (!IsPressure(cut.channels[c].channel)) continue;
      for (std::size_t i = 0; i < cut.time_s().size(); ++i) {
        const double d = traces->values_si[c][i] - cut.channels[c].values_si[i];
        if (std::isfinite(d)) error[warm] += d * d;
      }
    }
  }
  return error[1] < error[0] ? candidate : std::nullopt;
}

namespace {

// Where along the pipe a channel measures the pressure, as a fraction of its length: P2 = p(0),
// PTk at (k - 1)/9, C2 = p(L) (design.md). None for P1 (below the piston) and the flows.
std::optional<double> PipeFraction(Channel channel) {
  if (channel == Channel::kP2) return 0.0;
  if (channel == Channel::kC2) return 1.0;
  const int k = static_cast<int>(Index(channel)) - static_cast<int>(Index(Channel::kPT1));
  if (k >= 0 && k < kPipeTransmitterCount) {
    return static_cast<double>(k) / (kPipeTransmitterCount - 1);
  }
  return std::nullopt;
}

// Value and slope at t[0] of the least-squares quadratic through the finite samples with
// t - t[0] <= window_s. None with fewer than 6 of them.
std::optional<Eigen::Vector2d> QuadraticAtStart(const std::vector<double>& t,
                                                const std::vector<double>& y, double window_s) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d projection = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t i = 0; i < t.size() && t[i] - t[0] <= window_s; ++i) {
    if (!std::isfinite(y[i])) continue;
    const double tau = (t[i] - t[0]) / window_s;
    const Eigen::Vector3d b(1.0, tau, tau * tau);
    normal += b * b.transpose();
    projection += b * y[i];
    ++count;
  }
  if (count < 6) return std::nullopt;
  const Eigen::Vector3d c = normal.ldlt().solve(projection);
  if (!c.allFinite()) return std::nullopt;
  return Eigen::Vector2d(c(0), c(1) / window_s);
}

// y at `fraction` from the (fraction, y) points sorted by fraction: linear between them, held
// beyond the ends.
double InterpolateAlong(const std::vector<std::pair<double, double>>& points, double fraction) {
  if (fraction <= points.front().first) return points.front().second;
  for (std::size_t k = 1; k < points.size(); ++k) {
    if (fraction <= points[k].first) {
      return InterpolateLinear(fraction, points[k - 1].first, points[k - 1].second, points[k].first,
                               points[k].second);
    }
  }
  return points.back().second;
}

// The first guess of the pipe's state at t0 from the measurements there (EstimatePipeProfile);
// none with fewer than two pipe pressure channels at distinct places.
std::optional<PipeProfile> ProfileAtStart(const MeasuredLog& log, const RigParams& params,
                                          const SimulationOptions& sim_options,
                                          const ReplayOptions& replay, double window_s) {
  const std::vector<double>& t = log.time_s();
  // p and dp/dt at each measured place (channels at one place averaged).
  std::vector<std::pair<double, Eigen::Vector3d>> places;  // fraction, (sum p, sum dp/dt, count)
  for (const MeasuredChannel& channel : log.channels) {
    const auto fraction = PipeFraction(channel.channel);
    if (!fraction) continue;
    const auto start = QuadraticAtStart(t, channel.values_si, window_s);
    if (!start) continue;
    auto place = std::find_if(places.begin(), places.end(),
                              [&](const auto& p) { return p.first == *fraction; });
    if (place == places.end()) {
      places.emplace_back(*fraction, Eigen::Vector3d::Zero());
      place = places.end() - 1;
    }
    place->second += Eigen::Vector3d((*start)(0), (*start)(1), 1.0);
  }
  if (places.size() < 2) return std::nullopt;
  std::sort(places.begin(), places.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::pair<double, double>> pressure, rate;
  for (const auto& [fraction, sums] : places) {
    pressure.emplace_back(fraction, sums(0) / sums(2));
    rate.emplace_back(fraction, sums(1) / sums(2));
  }
  // The piston's velocity at t0 from the piston position the replay is fed.
  const std::vector<double> piston =
      replay.reconstruct_inputs && log.reconstructed_inputs.time_s.size() == t.size()
          ? log.reconstructed_inputs.piston_position_m
          : SmoothedPistonPosition(log.inputs, replay.piston_smoothing_s);
  const auto piston_start = QuadraticAtStart(t, piston, window_s);
  if (!piston_start) return std::nullopt;
  PipeProfile profile;
  profile.piston_velocity_mps = (*piston_start)(1);
  const double inlet_velocity_mps =
      PistonBoundary(params).InletVelocityMps(profile.piston_velocity_mps);
  // Continuity (thesis 6.1.1 with rho(p) of 5.2.1): dp/dt = -(k + p) du/dx (quasi-linear), -rho c^2
  // du/dx (linear), the convective u dp/dx left out (u / c < 1e-3): u integrated from the inlet by
  // the trapezoid over the profile's points.
  const double k_pa = params.QuasiLinearK();
  const double rho_c2 = params.density_kgpm3 * params.wave_speed_mps * params.wave_speed_mps;
  const double dx_m = params.pipe_length_m / (kProfilePoints - 1);
  double previous_rate = 0.0;
  for (int k = 0; k < kProfilePoints; ++k) {
    const double fraction = static_cast<double>(k) / (kProfilePoints - 1);
    const double p = InterpolateAlong(pressure, fraction);
    const double stiffness = sim_options.model == PipeModel::kLinear ? rho_c2 : k_pa + p;
    const double du_dx = -InterpolateAlong(rate, fraction) / stiffness;
    profile.pressure_pa.push_back(p);
    profile.velocity_mps.push_back(k == 0 ? inlet_velocity_mps
                                          : profile.velocity_mps.back() +
                                                0.5 * dx_m * (previous_rate + du_dx));
    previous_rate = du_dx;
  }
  return profile;
}

// The measured minus the model's pressures over the pressure channels (every sample, channel by
// channel; NaN where either is not finite). None if the replay fails.
std::optional<Eigen::VectorXd> PressureError(const MeasuredLog& cut, const RigParams& params,
                                             const SimulationOptions& sim_options,
                                             const ReplayOptions& replay) {
  auto traces = ReplayModel(cut, params, sim_options, replay);
  if (!traces.ok()) return std::nullopt;
  std::vector<double> error;
  for (std::size_t c = 0; c < cut.channels.size(); ++c) {
    if (!IsPressure(cut.channels[c].channel)) continue;
    for (std::size_t i = 0; i < cut.time_s().size(); ++i) {
      error.push_back(cut.channels[c].values_si[i] - traces->values_si[c][i]);
    }
  }
  return Eigen::Map<const Eigen::VectorXd>(error.data(), static_cast<Eigen::Index>(error.size()));
}

// The sum of the finite squares of `error`.
double SquaredError(const Eigen::VectorXd& error) {
  double sum = 0.0;
  for (double e : error) {
    if (std::isfinite(e)) sum += e * e;
  }
  return sum;
}

// The median over the channels of each one's squared error (`error` is PressureError's, `samples`
// per channel). A wrong start is a state of the whole pipe and its transient reaches every channel;
// a sensor's offset or delay, which a start fitted to the pressures would partly absorb, is one
// channel's: the median leaves it out.
double MedianChannelSquaredError(const Eigen::VectorXd& error, std::size_t samples) {
  std::vector<double> channels;
  for (Eigen::Index first = 0; first + static_cast<Eigen::Index>(samples) <= error.size();
       first += static_cast<Eigen::Index>(samples)) {
    channels.push_back(SquaredError(error.segment(first, static_cast<Eigen::Index>(samples))));
  }
  if (channels.empty()) return 0.0;
  std::sort(channels.begin(), channels.end());
  const std::size_t n = channels.size();
  return n % 2 == 1 ? channels[n / 2] : 0.5 * (channels[n / 2 - 1] + channels[n / 2]);
}

}  // namespace

Result<std::optional<PipeProfile>> EstimatePipeProfile(const MeasuredLog& log,
                                                       const RigParams& params,
                                                       const SimulationOptions& sim_options,
                                                       const ReplayOptions& replay) {
  const std::vector<double>& t = log.time_s();
  if (t.size() < 2) return std::optional<PipeProfile>{};
  const double travel_s = params.pipe_length_m / params.wave_speed_mps;
  auto guess =
      ProfileAtStart(log, params, sim_options, replay, kProfileWindowTravelTimes * travel_s);
  if (!guess) return std::optional<PipeProfile>{};
  const MeasuredLog cut = MeasuredLogUntil(log, t.front() + kProfileFitTravelTimes * travel_s);
  ReplayOptions start = replay;
  start.warmup.reset();
  start.profile = guess;
  const auto base = PressureError(cut, params, sim_options, start);
  if (!base) return std::optional<PipeProfile>{};
  // The Jacobian of the model's pressures in the profile's values, by forward differences of a
  // step well inside the model's linear range and well above its rounding: 0.01 bar, and the
  // velocity that carries it in a wave (Joukowsky, dp = rho c du).
  const double step_pa = 1.0e3;
  const double step_mps = step_pa / (params.density_kgpm3 * params.wave_speed_mps);
  constexpr int kParameters = 2 * kProfilePoints;
  const auto value = [](PipeProfile& profile, int j) -> double& {
    return j < kProfilePoints ? profile.pressure_pa[j] : profile.velocity_mps[j - kProfilePoints];
  };
  const auto scale = [&](int j) { return j < kProfilePoints ? step_pa : step_mps; };
  Eigen::MatrixXd jacobian(base->size(), kParameters);
  for (int j = 0; j < kParameters; ++j) {
    ReplayOptions nudged = start;
    value(*nudged.profile, j) += scale(j);
    const auto error = PressureError(cut, params, sim_options, nudged);
    if (!error || error->size() != base->size()) return std::optional<PipeProfile>{};
    // d(model)/d(value / scale) = -(d error).
    jacobian.col(j) = *base - *error;
  }
  // Least squares over the finite residuals, in the scaled values; a ridge far below the
  // normal matrix's scale keeps a profile point no channel sees (too few transmitters) at its
  // guess.
  const auto solve = [&](const Eigen::VectorXd& error) -> Eigen::VectorXd {
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(kParameters, kParameters);
    Eigen::VectorXd projection = Eigen::VectorXd::Zero(kParameters);
    for (Eigen::Index i = 0; i < error.size(); ++i) {
      if (!std::isfinite(error(i)) || !jacobian.row(i).allFinite()) continue;
      normal += jacobian.row(i).transpose() * jacobian.row(i);
      projection += jacobian.row(i).transpose() * error(i);
    }
    normal.diagonal().array() += 1e-9 * std::max(normal.diagonal().maxCoeff(), 1e-300);
    return normal.ldlt().solve(projection);
  };
  // The model is linear in its initial state to first order: two chord steps (one Jacobian),
  // each kept only if the error falls.
  PipeProfile best = *guess;
  double best_error = SquaredError(*base);
  Eigen::VectorXd error = *base;
  for (int iteration = 0; iteration < 2; ++iteration) {
    const Eigen::VectorXd delta = solve(error);
    if (!delta.allFinite()) break;
    ReplayOptions trial = start;
    for (int j = 0; j < kParameters; ++j)
      value(*trial.profile, j) = value(best, j) + delta(j) * scale(j);
    const auto trial_error = PressureError(cut, params, sim_options, trial);
    if (!trial_error) break;
    const double squared = SquaredError(*trial_error);
    if (!(squared < best_error)) break;
    best = *trial.profile;
    best_error = squared;
    error = *trial_error;
  }
  return std::optional<PipeProfile>{best};
}

namespace {

// The mean of the steady state's pressures (5.3.2) over the log's pressure channels at `inputs`.
std::optional<double> SteadyMeanPressurePa(const MeasuredLog& log, const RigParams& params,
                                           SimulationOptions options, const RigInputs& inputs) {
  options.choke_input = ChokeInput::kMeasured;
  auto simulator = RigSimulator::Create(params, options, inputs);
  if (!simulator.ok()) return std::nullopt;
  const RigSample sample = simulator->Sample();
  double sum = 0.0;
  int count = 0;
  for (const MeasuredChannel& channel : log.channels) {
    if (!IsPressure(channel.channel)) continue;
    sum += sample[channel.channel];
    ++count;
  }
  if (count == 0 || !std::isfinite(sum)) return std::nullopt;
  return sum / count;
}

// The level correction over the log's first n samples with its priors and nothing applied. The
// mean of N samples of white noise errs by sigma / sqrt(N) (a flat stretch's reconstruction by
// about that over its windows, the head's mean level over the head); at the ends a one-sided
// local linear fit over W samples errs by 2 sigma / sqrt(W), which is what a trend over the head
// picks up.
InputLevelCorrection LevelPriors(const InputReconstruction& plan, const std::vector<double>& t,
                                 std::size_t n) {
  InputLevelCorrection levels;
  levels.center_s = 0.5 * (t.front() + t[n - 1]);
  levels.half_span_s = 0.5 * (t[n - 1] - t.front());
  const double sqrt_n = std::sqrt(static_cast<double>(n));
  const double sqrt_w = std::sqrt(static_cast<double>(
      std::clamp<long>(plan.level_max_half_width_samples, 1, static_cast<long>(n))));
  levels.choke_sigma_frac = plan.choke_noise_frac / sqrt_n;
  levels.pump_sigma_m3ps = plan.pump_noise_m3ps / sqrt_n;
  levels.choke_trend_sigma_frac = 2.0 * plan.choke_noise_frac / sqrt_w;
  levels.pump_trend_sigma_m3ps = 2.0 * plan.pump_noise_m3ps / sqrt_w;
  return levels;
}

// The input the replay is perturbed in to learn the pipe's answer to a level change, and the
// steady law's sensitivities of the mean pressure to both levels [Pa per unit of each].
struct LevelCarrier {
  double s_choke = 0.0, s_pump = 0.0;
  bool pump = false;  // FT2 carries; else the choke
  double step = 0.0;  // the perturbation, in the carrier's unit
  double sensitivity() const { return pump ? s_pump : s_choke; }
};

// Both levels act through the choke's steady law, so the pipe answers a change of either with
// the same dynamics (the pipe's mean level settles with its compliance times the choke's
// resistance, about 17 s on the lab's rig, so a level error at the start weighs on the whole
// head): their steady sensitivities at the head's mean inputs give the ratio, and the carrier is
// the input whose prior moves the pressure more. None where neither moves it.
std::optional<LevelCarrier> ChooseLevelCarrier(const MeasuredLog& head, std::size_t n,
                                               const RigParams& params,
                                               const SimulationOptions& sim_options,
                                               const InputLevelCorrection& levels) {
  const InputReconstruction& plan = head.reconstruction;
  RigInputs mean{0.0, 0.0, 0.0};
  const LogInputColumns& in = head.reconstructed_inputs;
  for (std::size_t i = 0; i < n; ++i) {
    mean.choke_opening_frac += in.choke_opening_frac[i] / n;
    mean.pump_flow_m3ps += in.pump_flow_m3ps[i] / n;
    mean.outlet_pressure_pa += in.outlet_pressure_pa[i] / n;
  }
  const auto sensitivity = [&](double RigInputs::*level, double step) -> double {
    RigInputs up = mean, down = mean;
    up.*level += step;
    down.*level = std::max(0.0, down.*level - step);
    const double span = up.*level - down.*level;
    const auto p_up = SteadyMeanPressurePa(head, params, sim_options, up);
    const auto p_down = SteadyMeanPressurePa(head, params, sim_options, down);
    if (!p_up || !p_down || !(span > 0.0)) return 0.0;
    const double s = (*p_up - *p_down) / span;
    return std::isfinite(s) ? s : 0.0;
  };
  // Steps well inside the steady law's smooth range and well above its rounding.
  const double pump_step = std::max(1.0e-2 * mean.pump_flow_m3ps, units::LpmToM3ps(0.05));
  const double choke_step = 2.0e-3;
  LevelCarrier carrier;
  carrier.s_choke =
      plan.choke_noise_frac > 0.0 ? sensitivity(&RigInputs::choke_opening_frac, choke_step) : 0.0;
  carrier.s_pump =
      plan.pump_noise_m3ps > 0.0 ? sensitivity(&RigInputs::pump_flow_m3ps, pump_step) : 0.0;
  carrier.pump = std::abs(carrier.s_pump) * levels.pump_sigma_m3ps >=
                 std::abs(carrier.s_choke) * levels.choke_sigma_frac;
  if (carrier.sensitivity() == 0.0) return std::nullopt;
  carrier.step = carrier.pump ? pump_step : choke_step;
  return carrier;
}

// The replay's answer (per unit of the carrier) to a constant [0] and to a trend [1] in the
// carrier, start and warm-up included, at every sample of the pressure channels (channel by
// channel, n each). None if a perturbed replay fails.
std::optional<std::array<std::vector<double>, 2>> CarrierAnswers(
    const MeasuredLog& head, std::size_t n, const RigParams& params,
    const SimulationOptions& sim_options, const ReplayOptions& replay,
    const InputLevelCorrection& levels, const LevelCarrier& carrier, const ModelTraces& base,
    const std::vector<std::size_t>& pressures) {
  std::array<std::vector<double>, 2> answer;
  for (int basis = 0; basis < 2; ++basis) {
    InputLevelCorrection nudge = levels;
    (carrier.pump ? (basis == 0 ? nudge.pump_offset_m3ps : nudge.pump_trend_m3ps)
                  : (basis == 0 ? nudge.choke_offset_frac : nudge.choke_trend_frac)) = carrier.step;
    MeasuredLog nudged = head;
    ReplayOptions nudged_replay = replay;
    ApplyInputLevels(nudge, &nudged);
    ApplyInputLevels(nudge, &nudged_replay);
    auto traces = ReplayModel(nudged, params, sim_options, nudged_replay);
    if (!traces.ok()) return std::nullopt;
    for (std::size_t c : pressures) {
      for (std::size_t i = 0; i < n; ++i) {
        answer[basis].push_back((traces->values_si[c][i] - base.values_si[c][i]) / carrier.step);
      }
    }
  }
  return answer;
}

// measured - model at every sample of the pressure channels, ordered as CarrierAnswers.
std::vector<double> PressureResidual(const MeasuredLog& head, std::size_t n,
                                     const ModelTraces& base,
                                     const std::vector<std::size_t>& pressures) {
  std::vector<double> residual;
  for (std::size_t c : pressures) {
    for (std::size_t i = 0; i < n; ++i) {
      residual.push_back(head.channels[c].values_si[i] - base.values_si[c][i]);
    }
  }
  return residual;
}

// The residual's least squares on the two answers, z in the carrier's units (constant, trend),
// over the samples where all three are finite, with its covariance from the residual's spread
// (white residual). None if the answers do not determine z or too few samples remain.
struct AnswerFit {
  Eigen::Vector2d z;
  Eigen::Matrix2d covariance;
};
std::optional<AnswerFit> FitAnswers(const std::vector<double>& residual,
                                    const std::array<std::vector<double>, 2>& answer) {
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d projection = Eigen::Vector2d::Zero();
  for (std::size_t j = 0; j < residual.size(); ++j) {
    const double r = residual[j];
    if (!std::isfinite(r) || !std::isfinite(answer[0][j]) || !std::isfinite(answer[1][j])) {
      continue;
    }
    const Eigen::Vector2d u(answer[0][j], answer[1][j]);
    normal += u * u.transpose();
    projection += u * r;
  }
  if (!(normal.determinant() > 0.0)) return std::nullopt;
  AnswerFit fit;
  fit.z = normal.ldlt().solve(projection);
  double sum_sq = 0.0;
  long count = 0;
  for (std::size_t j = 0; j < residual.size(); ++j) {
    const double e = residual[j] - fit.z(0) * answer[0][j] - fit.z(1) * answer[1][j];
    if (!std::isfinite(e)) continue;
    sum_sq += e * e;
    ++count;
  }
  if (count < 16) return std::nullopt;
  fit.covariance = sum_sq / (count - 2) * normal.inverse();
  return fit;
}

// Maximum a posteriori split of the fit over x = (choke, pump) x (constant, trend): z = B x + e,
// with the carrier's units; x ~ N(0, P), e ~ N(0, Cov): x = P B' (B P B' + Cov)^-1 z, each term
// clipped to kMaxLevelOffsetSigmas of its prior. Sets the offsets and trends of `levels` and
// returns B x, the part of z they apply; none if x is not finite.
std::optional<Eigen::Vector2d> SplitLevels(const AnswerFit& fit, const LevelCarrier& carrier,
                                           InputLevelCorrection* levels) {
  const double s_carrier = carrier.sensitivity();
  const double k_choke = carrier.s_choke / s_carrier, k_pump = carrier.s_pump / s_carrier;
  Eigen::Matrix<double, 2, 4> mix = Eigen::Matrix<double, 2, 4>::Zero();
  mix(0, 0) = k_choke;
  mix(0, 1) = k_pump;
  mix(1, 2) = k_choke;
  mix(1, 3) = k_pump;
  const Eigen::Vector4d sigma(levels->choke_sigma_frac, levels->pump_sigma_m3ps,
                              levels->choke_trend_sigma_frac, levels->pump_trend_sigma_m3ps);
  const Eigen::Matrix4d prior = sigma.cwiseProduct(sigma).asDiagonal();
  const Eigen::Matrix2d innovation = mix * prior * mix.transpose() + fit.covariance;
  Eigen::Vector4d x = prior * mix.transpose() * innovation.ldlt().solve(fit.z);
  for (int i = 0; i < 4; ++i) {
    const double bound = kMaxLevelOffsetSigmas * sigma(i);
    if (!std::isfinite(x(i))) return std::nullopt;
    if (std::abs(x(i)) > bound) levels->at_bound = true;
    x(i) = std::clamp(x(i), -bound, bound);
  }
  levels->choke_offset_frac = x(0);
  levels->pump_offset_m3ps = x(1);
  levels->choke_trend_frac = x(2);
  levels->pump_trend_m3ps = x(3);
  return Eigen::Vector2d(mix * x);
}

// The residual's mean and trend (at tau = 1) over the pressure samples, before and after the
// correction (the after as the answers predict, `applied` of them).
void ResidualMeanAndTrend(const std::vector<double>& residual,
                          const std::array<std::vector<double>, 2>& answer,
                          const Eigen::Vector2d& applied, const std::vector<double>& t,
                          std::size_t n, InputLevelCorrection* levels) {
  Eigen::Matrix2d basis_normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d before = Eigen::Vector2d::Zero(), after = Eigen::Vector2d::Zero();
  for (std::size_t j = 0; j < residual.size(); ++j) {
    const double r = residual[j];
    const double r_after = r - applied(0) * answer[0][j] - applied(1) * answer[1][j];
    if (!std::isfinite(r_after)) continue;
    const Eigen::Vector2d b(1.0, levels->Tau(t[j % n]));
    basis_normal += b * b.transpose();
    before += b * r;
    after += b * r_after;
  }
  if (basis_normal.determinant() > 0.0) {
    const Eigen::Vector2d mb = basis_normal.ldlt().solve(before);
    const Eigen::Vector2d ma = basis_normal.ldlt().solve(after);
    levels->residual_before_pa = mb(0);
    levels->residual_trend_before_pa = mb(1);
    levels->residual_after_pa = ma(0);
    levels->residual_trend_after_pa = ma(1);
  }
}

}  // namespace

Result<InputLevelCorrection> EstimateInputLevels(const MeasuredLog& log, const RigParams& params,
                                                 const SimulationOptions& sim_options,
                                                 const ReplayOptions& replay) {
  InputLevelCorrection none;
  if (!replay.reconstruct_inputs || !replay.estimate_levels) return none;
  const std::vector<double>& t = log.time_s();
  const std::size_t n = std::min(t.size(), kReconstructionPlanSamples);
  if (n < 16) return none;
  const MeasuredLog head = n < t.size() ? MeasuredLogUntil(log, t[n - 1]) : log;
  const InputReconstruction& plan = head.reconstruction;
  if (head.reconstructed_inputs.time_s.size() != n || plan.levels.applied()) return none;
  InputLevelCorrection levels = LevelPriors(plan, t, n);
  if (plan.choke_noise_frac == 0.0 && plan.pump_noise_m3ps == 0.0) return none;
  std::vector<std::size_t> pressures;
  for (std::size_t c = 0; c < head.channels.size(); ++c) {
    if (IsPressure(head.channels[c].channel)) pressures.push_back(c);
  }
  if (pressures.empty()) return none;
  auto base = ReplayModel(head, params, sim_options, replay);
  if (!base.ok()) return none;
  const auto carrier = ChooseLevelCarrier(head, n, params, sim_options, levels);
  if (!carrier) return none;
  const auto answer =
      CarrierAnswers(head, n, params, sim_options, replay, levels, *carrier, *base, pressures);
  if (!answer) return none;
  const std::vector<double> residual = PressureResidual(head, n, *base, pressures);
  const auto fit = FitAnswers(residual, *answer);
  if (!fit) return none;
  const auto applied = SplitLevels(*fit, *carrier, &levels);
  if (!applied) return none;
  ResidualMeanAndTrend(residual, *answer, *applied, t, n, &levels);
  return levels;
}

void ApplyInputLevels(const InputLevelCorrection& levels, MeasuredLog* log) {
  log->reconstruction.levels = levels;
  ReconstructWithLevels(log);
}

void ApplyInputLevels(const InputLevelCorrection& levels, ReplayOptions* replay) {
  if (!replay->warmup) return;
  // The warm-up holds the levels the log starts with (tau = -1).
  const double start_s = levels.center_s - levels.half_span_s;
  RigInputs& warm = replay->warmup->levels;
  warm.choke_opening_frac = std::clamp(warm.choke_opening_frac + levels.ChokeAt(start_s), 0.0, 1.0);
  warm.pump_flow_m3ps = std::max(0.0, warm.pump_flow_m3ps + levels.PumpAt(start_s));
}

Status ChooseReplayStart(const MeasuredLog& log, const RigParams& params,
                         const SimulationOptions& sim_options, ReplayOptions* replay) {
  replay->warmup.reset();
  replay->profile.reset();
  const std::optional<PeriodicWarmup> warmup =
      PlanPeriodicWarmup(log.inputs, replay->reconstruct_inputs);
  auto profile = EstimatePipeProfile(log, params, sim_options, *replay);
  if (!profile.ok()) return profile.status();
  if (!warmup && !*profile) return Status::Ok();
  const double travel_s = params.pipe_length_m / params.wave_speed_mps;
  const double window_s =
      std::max(warmup ? 2.0 * warmup->period_s : 0.0, kStartChoiceTravelTimes * travel_s);
  const MeasuredLog cut = MeasuredLogUntil(log, log.time_s().front() + window_s);

  // Steady, warm-up, measured: the first with the smallest error (a tie keeps the simpler start).
  double best = std::numeric_limits<double>::infinity();
  ReplayOptions chosen = *replay;
  for (int kind = 0; kind < 3; ++kind) {
    ReplayOptions start = *replay;
    if (kind == 1 && !warmup) continue;
    if (kind == 2 && !*profile) continue;
    if (kind == 1) start.warmup = warmup;
    if (kind == 2) start.profile = **profile;
    const auto error = PressureError(cut, params, sim_options, start);
    if (!error) continue;  // a start that leaves the model's range is not chosen
    const double squared = MedianChannelSquaredError(*error, cut.time_s().size());
    if (squared < best) {
      best = squared;
      chosen = start;
    }
  }
  *replay = chosen;
  return Status::Ok();
}

Status PrepareLogReplay(MeasuredLog* log, const RigParams& params,
                        const SimulationOptions& sim_options, ReplayOptions* replay,
                        InputLevels levels) {
  if (replay->choose_warmup) {
    MPDRIG_RETURN_IF_ERROR(ChooseReplayStart(*log, params, sim_options, replay));
  }
  if (levels == InputLevels::kWithTheseParams && replay->reconstruct_inputs &&
      replay->estimate_levels) {
    auto estimate = EstimateInputLevels(*log, params, sim_options, *replay);
    if (!estimate.ok()) return estimate.status();
    ApplyInputLevels(*estimate, log);
    ApplyInputLevels(*estimate, replay);
  }
  return Status::Ok();
}

}  // namespace mpdrig
