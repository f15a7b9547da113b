#include "model/analysis/log_replay.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Dense>

#include "model/analysis/log_stream.h"

namespace mpdrig {

Result<ModelTraces> ReplayModel(const MeasuredLog& log, const RigParams& params,
                                const SimulationOptions& sim_options, const ReplayOptions& replay,
                                const CompareProgress& progress) {
  const std::vector<double>& times = log.time_s();
  if (times.size() < 2) return Status::Error(log.path + ": needs at least 2 samples");
  if (log.channels.size() > kComparedChannelCount) {
    return Status::Error(log.path + ": more channels than P1 P2 PT1..PT10 C2 FT1 FT3 FT4");
  }
  // Keep only the compared channels of each sample.
  ModelTraces traces;
  traces.values_si.assign(log.channels.size(), {});
  for (auto& values : traces.values_si) values.reserve(times.size());
  PercentProgress percent(progress, "simulate", static_cast<long>(times.size()));
  // The reconstruction made at loading; a log put together by hand gets one here.
  const MeasuredLog* replayed = &log;
  MeasuredLog reconstructed;
  if (replay.reconstruct_inputs && log.reconstructed_inputs.time_s.size() != times.size()) {
    reconstructed = log;
    ReconstructInputs(&reconstructed);
    replayed = &reconstructed;
  }
  traces.inputs_reconstructed = replay.reconstruct_inputs;
  traces.warmup = replay.warmup;
  RowPipeline pipeline(
      PipelineSmoothingS(replay), ReplaySetup{params, sim_options, times.back(), replay.warmup},
      [&](const PipelineSample& sample) {
        for (std::size_t i = 0; i < log.channels.size(); ++i) {
          traces.values_si[i].push_back(sample.model->values[Index(log.channels[i].channel)]);
        }
        percent.Done(sample.index + 1);
      });
  MemoryRowSource source(
      *replayed, replay.reconstruct_inputs ? InputView::kReconstructed : InputView::kMeasured);
  MPDRIG_RETURN_IF_ERROR(RunPipeline(&source, &pipeline));
  const RigSampler* sampler = pipeline.sampler();
  MPDRIG_CHECK(sampler != nullptr);
  traces.time_step_s = sampler->simulator().time_step_s();
  traces.steps = sampler->steps();
  traces.first_range_event = sampler->simulator().first_range_event();
  return traces;
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
  log->reconstructed_inputs = ReconstructInputColumns(log->inputs, log->reconstruction);
}

void ApplyInputLevels(const InputLevelCorrection& levels, ReplayOptions* replay) {
  if (!replay->warmup) return;
  // The warm-up holds the levels the log starts with (tau = -1).
  const double start_s = levels.center_s - levels.half_span_s;
  RigInputs& warm = replay->warmup->levels;
  warm.choke_opening_frac = std::clamp(warm.choke_opening_frac + levels.ChokeAt(start_s), 0.0, 1.0);
  warm.pump_flow_m3ps = std::max(0.0, warm.pump_flow_m3ps + levels.PumpAt(start_s));
}

Status PrepareLogReplay(MeasuredLog* log, const RigParams& params,
                        const SimulationOptions& sim_options, ReplayOptions* replay,
                        InputLevels levels) {
  if (replay->choose_warmup) {
    auto warmup = ChooseWarmup(*log, params, sim_options, *replay);
    if (!warmup.ok()) return warmup.status();
    replay->warmup = *warmup;
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
