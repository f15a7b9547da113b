#include "model/sim/log_inputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <sstream>

#include <Eigen/Dense>
#include <utility>

#include "model/common/units.h"
#include "model/signal/input_reconstruction.h"
#include "model/signal/smoothing.h"
#include "model/signal/spectrum.h"

namespace mpdrig {
namespace {

// A log column that must be finite on every row.
Result<std::vector<double>> RequireFinite(const riglog::RigLog& log, std::string_view channel,
                                          const std::string& path) {
  const std::vector<double>* values = log.Find(channel);
  if (values == nullptr) {
    return Status::Error(path + ": required input column '" + std::string(channel) +
                         "_<unit>' is missing");
  }
  for (std::size_t row = 0; row < values->size(); ++row) {
    if (!std::isfinite((*values)[row])) {
      std::ostringstream out;
      out << path << ": input " << channel << " is not measured (empty or nan) at data row "
          << row + 1 << " (time_s = " << log.time_s[row] << "); the model needs every input sample";
      return Status::Error(out.str());
    }
  }
  return *values;
}

// The input columns behind the time functions, interpolated linearly (as PiecewiseLinear) with
// one shared time vector and a remembered bracket: the simulator asks for increasing times, so
// the search is O(1) amortised instead of a binary search per call.
class SharedInputs {
 public:
  SharedInputs(LogInputColumns columns, std::vector<double> smoothed_piston_m)
      : columns_(std::move(columns)), piston_m_(std::move(smoothed_piston_m)) {}

  double At(const std::vector<double>& values, double t) const {
    const std::vector<double>& time = columns_.time_s;
    if (t <= time.front()) return values.front();
    if (t >= time.back()) return values.back();
    std::size_t j = hint_;
    if (!(j > 0 && j < time.size() && time[j - 1] <= t && t < time[j])) {
      j = static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), t) - time.begin());
      hint_ = j;
    }
    return InterpolateLinear(t, time[j - 1], values[j - 1], time[j], values[j]);
  }
  double Piston(double t) const { return At(piston_m_, t); }
  RigInputs Rig(double t) const {
    RigInputs in;
    in.choke_opening_frac = At(columns_.choke_opening_frac, t);
    in.pump_flow_m3ps = At(columns_.pump_flow_m3ps, t);
    in.outlet_pressure_pa = At(columns_.outlet_pressure_pa, t);
    return in;
  }

 private:
  LogInputColumns columns_;
  std::vector<double> piston_m_;
  mutable std::size_t hint_ = 0;  // a search cache only: the values do not depend on it
};

}  // namespace

void InitialInputs::Add(double time_s, const RigInputs& row) {
  if (count_ == 0) first_time_s_ = time_s;
  if (time_s > first_time_s_ + kInitialInputWindowS) return;
  sum_.choke_opening_frac += row.choke_opening_frac;
  sum_.pump_flow_m3ps += row.pump_flow_m3ps;
  sum_.outlet_pressure_pa += row.outlet_pressure_pa;
  ++count_;
}

RigInputs InitialInputs::Mean() const {
  MPDRIG_CHECK(count_ > 0);
  const double n = static_cast<double>(count_);
  return {sum_.choke_opening_frac / n, sum_.pump_flow_m3ps / n, sum_.outlet_pressure_pa / n};
}

Result<LogInputColumns> InputColumnsFromLog(const riglog::RigLog& log, const std::string& path) {
  LogInputColumns columns;
  auto piston = RequireFinite(log, "piston_position", path);
  if (!piston.ok()) return piston.status();
  auto choke = RequireFinite(log, "choke_position", path);
  if (!choke.ok()) return choke.status();
  const std::size_t n = log.num_rows();
  columns.time_s = log.time_s;
  columns.piston_position_m = std::move(piston).value();
  columns.choke_opening_frac = std::move(choke).value();
  // Optional inputs: absent means the documented default; present means measured everywhere.
  columns.pump_flow_m3ps.assign(n, 0.0);
  columns.outlet_pressure_pa.assign(n, log.atmospheric_pressure_pa);
  if (log.Find("FT2") != nullptr) {
    auto values = RequireFinite(log, "FT2", path);
    if (!values.ok()) return values.status();
    columns.pump_flow_m3ps = std::move(values).value();
  }
  if (log.Find("C1") != nullptr) {
    auto values = RequireFinite(log, "C1", path);
    if (!values.ok()) return values.status();
    columns.outlet_pressure_pa = std::move(values).value();
  }
  return columns;
}

namespace {

double MedianInterval(const std::vector<double>& time_s) {
  if (time_s.size() < 2) return 0.0;
  std::vector<double> dt(time_s.size() - 1);
  for (std::size_t i = 0; i + 1 < time_s.size(); ++i) dt[i] = time_s[i + 1] - time_s[i];
  const auto middle = dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2);
  std::nth_element(dt.begin(), middle, dt.end());
  return *middle;
}

std::vector<double> Head(const std::vector<double>& values, std::size_t n) {
  return {values.begin(), values.begin() + static_cast<std::ptrdiff_t>(n)};
}

}  // namespace

std::string InputReconstruction::Describe() const {
  std::ostringstream out;
  out.precision(3);
  out << "inputs reconstructed (noise estimated from the log): piston " << piston_noise_m * 1e3
      << " mm, band " << piston_band_hz << " Hz, window +-" << piston_half_width_s << " s; choke "
      << units::ChokeFracToDeg(choke_noise_frac) << " deg; FT2 "
      << units::M3psToLpm(pump_noise_m3ps) << " L/min; C1 " << outlet_noise_pa * 1e-5
      << " bar; steps kept, windows up to +-" << level_max_half_width_samples << " samples";
  return out.str();
}

InputReconstruction PlanInputReconstruction(const LogInputColumns& columns) {
  const std::size_t n = std::min(columns.time_s.size(), kReconstructionPlanSamples);
  InputReconstruction plan;
  plan.sample_interval_s = MedianInterval(Head(columns.time_s, n));
  if (n < 16 || !(plan.sample_interval_s > 0.0))
    return plan;  // too short to tell noise from signal
  plan.piston_noise_m = WhiteNoiseSigma(Head(columns.piston_position_m, n));
  plan.choke_noise_frac = WhiteNoiseSigma(Head(columns.choke_opening_frac, n));
  plan.pump_noise_m3ps = WhiteNoiseSigma(Head(columns.pump_flow_m3ps, n));
  plan.outlet_noise_pa = WhiteNoiseSigma(Head(columns.outlet_pressure_pa, n));
  // Windows double: the first power of two that spans kMaxLevelHalfWidthS, within the cap.
  plan.level_max_half_width_samples = 2;
  while (plan.level_max_half_width_samples < kMaxLevelHalfWidthSamples &&
         static_cast<double>(plan.level_max_half_width_samples) * plan.sample_interval_s <
             kMaxLevelHalfWidthS) {
    plan.level_max_half_width_samples *= 2;
  }
  if (plan.piston_noise_m > 0.0) {
    plan.piston_band_hz = HighestSignalFrequencyHz(Head(columns.piston_position_m, n),
                                                   plan.sample_interval_s, plan.piston_noise_m);
    const double half_width_s = std::min(BandLimitedHalfWidthS(plan.piston_band_hz),
                                         kMaxPistonHalfWidthSamples * plan.sample_interval_s);
    // Below two sample intervals a tricube window holds too few points to smooth anything.
    plan.piston_half_width_s = half_width_s >= 2.0 * plan.sample_interval_s ? half_width_s : 0.0;
  }
  return plan;
}

double InputLevelCorrection::Tau(double t) const {
  if (!(half_span_s > 0.0)) return 0.0;
  return std::clamp((t - center_s) / half_span_s, -1.0, 1.0);
}

std::string InputLevelCorrection::Describe() const {
  std::ostringstream out;
  out.precision(3);
  const double k = kMaxLevelOffsetSigmas;
  out << "input levels from the measured pressures: choke " << std::showpos
      << units::ChokeFracToDeg(choke_offset_frac) << " deg"
      << " (trend " << units::ChokeFracToDeg(choke_trend_frac) << "), FT2 "
      << units::M3psToLpm(pump_offset_m3ps) << " L/min (trend " << units::M3psToLpm(pump_trend_m3ps)
      << ")" << std::noshowpos << "; the noise allows +-"
      << units::ChokeFracToDeg(k * choke_sigma_frac) << " ("
      << units::ChokeFracToDeg(k * choke_trend_sigma_frac) << ") deg, +-"
      << units::M3psToLpm(k * pump_sigma_m3ps) << " ("
      << units::M3psToLpm(k * pump_trend_sigma_m3ps) << ") L/min; pressure residual "
      << residual_before_pa * 1e-5 << " -> " << residual_after_pa * 1e-5 << " bar, trend "
      << residual_trend_before_pa * 1e-5 << " -> " << residual_trend_after_pa * 1e-5 << " bar";
  if (at_bound) out << " (at the bound: the rest is the model's)";
  return out.str();
}

namespace {

// The smoothing of a block (ReconstructInputBlock without the levels).
LogInputColumns SmoothInputBlock(const LogInputColumns& block, const LevelInputSums& sums,
                                 long first_index, const InputReconstruction& plan) {
  LogInputColumns out;
  out.time_s = block.time_s;
  out.piston_position_m =
      SmoothBandLimited(block.time_s, block.piston_position_m, plan.piston_half_width_s);
  auto keeping_steps = [&](const std::vector<double>& values,
                           const std::vector<RunningSum>& level_sums, double sigma) {
    StepKeepingOptions options;
    options.sigma = sigma;
    options.max_half_width_samples = plan.level_max_half_width_samples;
    return SmoothKeepingSteps(values, level_sums, first_index, options);
  };
  out.choke_opening_frac =
      keeping_steps(block.choke_opening_frac, sums.choke, plan.choke_noise_frac);
  out.pump_flow_m3ps = keeping_steps(block.pump_flow_m3ps, sums.pump, plan.pump_noise_m3ps);
  out.outlet_pressure_pa =
      keeping_steps(block.outlet_pressure_pa, sums.outlet, plan.outlet_noise_pa);
  return out;
}

LevelInputSums LevelSumsOf(const LogInputColumns& columns) {
  LevelInputSums sums;
  auto build = [](const std::vector<double>& values, std::vector<RunningSum>* out) {
    RunningSums running;
    out->reserve(values.size() + 1);
    for (double y : values) out->push_back(running.Push(y));
    out->push_back(running.Next());
  };
  build(columns.choke_opening_frac, &sums.choke);
  build(columns.pump_flow_m3ps, &sums.pump);
  build(columns.outlet_pressure_pa, &sums.outlet);
  return sums;
}

}  // namespace

LogInputColumns WithInputLevels(LogInputColumns smoothed, const InputLevelCorrection& levels) {
  if (!levels.applied()) return smoothed;
  for (std::size_t i = 0; i < smoothed.time_s.size(); ++i) {
    const double t = smoothed.time_s[i];
    smoothed.choke_opening_frac[i] =
        std::clamp(smoothed.choke_opening_frac[i] + levels.ChokeAt(t), 0.0, 1.0);
    smoothed.pump_flow_m3ps[i] = std::max(0.0, smoothed.pump_flow_m3ps[i] + levels.PumpAt(t));
  }
  return smoothed;
}

LogInputColumns ReconstructInputBlock(const LogInputColumns& block, const LevelInputSums& sums,
                                      long first_index, const InputReconstruction& plan) {
  return WithInputLevels(SmoothInputBlock(block, sums, first_index, plan), plan.levels);
}

LogInputColumns SmoothInputColumns(const LogInputColumns& columns,
                                   const InputReconstruction& plan) {
  return SmoothInputBlock(columns, LevelSumsOf(columns), 0, plan);
}

LogInputColumns ReconstructInputColumns(const LogInputColumns& columns,
                                        const InputReconstruction& plan) {
  return WithInputLevels(SmoothInputColumns(columns, plan), plan.levels);
}

std::uint64_t SmoothingFingerprint(const LogInputColumns& columns,
                                   const InputReconstruction& plan) {
  // FNV-1a over 64-bit words, each mixed first (splitmix64's finaliser) so that every bit of a
  // value reaches every bit of the hash.
  std::uint64_t hash = 14695981039346656037ull;
  const auto add = [&hash](double value) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof(bits));
    bits ^= bits >> 30;
    bits *= 0xbf58476d1ce4e5b9ull;
    bits ^= bits >> 27;
    bits *= 0x94d049bb133111ebull;
    bits ^= bits >> 31;
    hash = (hash ^ bits) * 1099511628211ull;
  };
  for (const std::vector<double>* column :
       {&columns.time_s, &columns.piston_position_m, &columns.choke_opening_frac,
        &columns.pump_flow_m3ps, &columns.outlet_pressure_pa}) {
    add(static_cast<double>(column->size()));
    for (double value : *column) add(value);
  }
  // What the smoothing reads of the plan (SmoothInputBlock).
  for (double value :
       {plan.piston_half_width_s, plan.choke_noise_frac, plan.pump_noise_m3ps, plan.outlet_noise_pa,
        static_cast<double>(plan.level_max_half_width_samples)}) {
    add(value);
  }
  return hash;
}

namespace {

// The columns' rows with t <= t_end.
LogInputColumns RowsUntil(const LogInputColumns& columns, double t_end) {
  std::size_t n = 0;
  while (n < columns.time_s.size() && columns.time_s[n] <= t_end) ++n;
  return {Head(columns.time_s, n), Head(columns.piston_position_m, n),
          Head(columns.choke_opening_frac, n), Head(columns.pump_flow_m3ps, n),
          Head(columns.outlet_pressure_pa, n)};
}

// The period of the largest line of the piston's spectrum (Hann window, zero-padded 4x), among
// periods up to kMaxWarmupPeriodS; 0 if there is none.
double DominantPeriodS(const std::vector<double>& position, double dt_s) {
  const std::size_t n = position.size();
  double mean = 0.0;
  for (double x : position) mean += x;
  mean /= static_cast<double>(n);
  const std::vector<double> window = HannWindow(n);
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = (position[i] - mean) * window[i];
  const std::size_t size = FastFftSize(4 * n);
  const std::vector<std::complex<double>> spectrum = RealDft(x, size);
  const double df = 1.0 / (static_cast<double>(size) * dt_s);
  const auto first = static_cast<std::size_t>(std::ceil(1.0 / (kMaxWarmupPeriodS * df)));
  std::size_t best = 0;
  for (std::size_t k = std::max<std::size_t>(first, 1); k < spectrum.size(); ++k) {
    if (best == 0 || std::norm(spectrum[k]) > std::norm(spectrum[best])) best = k;
  }
  return best == 0 ? 0.0 : 1.0 / (static_cast<double>(best) * df);
}

// RMS over the samples in [t0, t0 + period] of values(t) - values(t + period).
double PeriodicityError(const std::vector<double>& time_s, const std::vector<double>& values,
                        double period_s) {
  const PiecewiseLinear later(time_s, values);
  double sum = 0.0;
  long count = 0;
  for (std::size_t i = 0; i < time_s.size() && time_s[i] <= time_s[0] + period_s; ++i) {
    const double d = values[i] - later(time_s[i] + period_s);
    sum += d * d, ++count;
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

double StandardDeviation(const std::vector<double>& values) {
  double mean = 0.0, sq = 0.0;
  for (double v : values) mean += v;
  mean /= static_cast<double>(values.size());
  for (double v : values) sq += (v - mean) * (v - mean);
  return std::sqrt(sq / static_cast<double>(values.size()));
}

// The warm-up's excitation: a Fourier series of kWarmupHarmonics harmonics of `period_s` fitted by
// least squares to the piston over the whole periods `part` holds (up to kWarmupFitPeriods), the
// other inputs at their means there. Repeating the measured period itself would repeat its noise
// as a periodic forcing, which the pipe's resonances pick up.
PeriodicWarmup FitPeriodicExcitation(const LogInputColumns& part, double period_s) {
  const double t0 = part.time_s.front();
  const double periods =
      std::min<double>(kWarmupFitPeriods, std::floor((part.time_s.back() - t0) / period_s));
  const LogInputColumns fitted = RowsUntil(part, t0 + periods * period_s);
  const auto n = static_cast<Eigen::Index>(fitted.time_s.size());
  constexpr int kColumns = 1 + 2 * kWarmupHarmonics;
  Eigen::MatrixXd design(n, kColumns);
  Eigen::VectorXd position(n);
  const double w = 2.0 * std::numbers::pi / period_s;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = fitted.time_s[static_cast<std::size_t>(i)] - t0;
    design(i, 0) = 1.0;
    for (int k = 1; k <= kWarmupHarmonics; ++k) {
      design(i, 2 * k - 1) = std::cos(k * w * t);
      design(i, 2 * k) = std::sin(k * w * t);
    }
    position(i) = fitted.piston_position_m[static_cast<std::size_t>(i)];
  }
  const Eigen::VectorXd coefficients = design.colPivHouseholderQr().solve(position);
  PeriodicWarmup warmup;
  warmup.period_s = period_s;
  warmup.duration_s = kReplayWarmupS;
  warmup.mean_m = coefficients(0);
  for (int k = 1; k <= kWarmupHarmonics; ++k) {
    warmup.cos_m.push_back(coefficients(2 * k - 1));
    warmup.sin_m.push_back(coefficients(2 * k));
  }
  const auto mean = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  warmup.levels.choke_opening_frac = mean(fitted.choke_opening_frac);
  warmup.levels.pump_flow_m3ps = mean(fitted.pump_flow_m3ps);
  warmup.levels.outlet_pressure_pa = mean(fitted.outlet_pressure_pa);
  return warmup;
}

}  // namespace

std::optional<PeriodicWarmup> PlanPeriodicWarmup(const LogInputColumns& columns, bool reconstruct) {
  const std::size_t n = std::min(columns.time_s.size(), kReconstructionPlanSamples);
  if (n < 64) return std::nullopt;
  const double dt = MedianInterval(Head(columns.time_s, n));
  if (!(dt > 0.0)) return std::nullopt;
  const double rough_period_s = DominantPeriodS(Head(columns.piston_position_m, n), dt);
  const double t0 = columns.time_s[0];
  // The refinement looks up to 5 % beyond two periods.
  const double needed_s = 2.0 * 1.05 * rough_period_s;
  if (!(rough_period_s > 0.0) || columns.time_s[n - 1] - t0 < needed_s) return std::nullopt;
  const InputReconstruction plan = PlanInputReconstruction(columns);
  // The checks need two periods; the fit takes up to kWarmupFitPeriods.
  const double span_s = std::max(needed_s, kWarmupFitPeriods * 1.05 * rough_period_s);
  LogInputColumns part = RowsUntil(columns, t0 + span_s + plan.piston_half_width_s);
  if (reconstruct) part = ReconstructInputColumns(part, plan);
  part = RowsUntil(part, t0 + span_s);

  // Least squares on the piston's own repetition: a scan over +-5 %, then a parabola through the
  // best point and its neighbours (the period must be right to a fraction of a sample: each
  // wrap of the warm-up would otherwise put a velocity step into the pipe).
  constexpr int kScan = 100;
  auto period_at = [&](int k) { return rough_period_s * (0.95 + 0.1 * k / kScan); };
  std::vector<double> error(kScan + 1);
  int best = 0;
  for (int k = 0; k <= kScan; ++k) {
    error[k] = PeriodicityError(part.time_s, part.piston_position_m, period_at(k));
    if (error[k] < error[best]) best = k;
  }
  double period_s = period_at(best);
  if (best > 0 && best < kScan) {
    const double a = error[best - 1] * error[best - 1], b = error[best] * error[best],
                 c = error[best + 1] * error[best + 1];
    const double curvature = a - 2.0 * b + c;
    if (curvature > 0.0) period_s += 0.5 * (a - c) / curvature * (period_at(1) - period_at(0));
  }
  const LogInputColumns two_periods = RowsUntil(part, t0 + 2.0 * period_s);
  const double piston_std = StandardDeviation(two_periods.piston_position_m);
  if (!(piston_std > 10.0 * plan.piston_noise_m) || piston_std == 0.0) return std::nullopt;
  if (PeriodicityError(part.time_s, part.piston_position_m, period_s) >
      0.05 * piston_std + 3.0 * std::sqrt(2.0) * plan.piston_noise_m) {
    return std::nullopt;
  }
  const auto repeats = [&](const std::vector<double>& values, double noise) {
    const double scale = std::fabs(values.front()) + 1.0;
    return PeriodicityError(part.time_s, values, period_s) <=
           3.0 * std::sqrt(2.0) * noise + 1e-9 * scale;
  };
  if (!repeats(part.choke_opening_frac, plan.choke_noise_frac) ||
      !repeats(part.pump_flow_m3ps, plan.pump_noise_m3ps) ||
      !repeats(part.outlet_pressure_pa, plan.outlet_noise_pa)) {
    return std::nullopt;
  }
  return FitPeriodicExcitation(part, period_s);
}

std::vector<double> SmoothedPistonPosition(const LogInputColumns& columns, double smoothing_s) {
  return SmoothLocalQuadratic(columns.time_s, columns.piston_position_m, smoothing_s);
}

Result<InputSignals> SignalsFromColumns(LogInputColumns columns, const std::string& path,
                                        const InputReplayOptions& options,
                                        const InputReconstruction* plan) {
  const std::size_t n = columns.time_s.size();
  if (n < 2) return Status::Error(path + ": needs at least 2 samples");
  MPDRIG_CHECK(columns.piston_position_m.size() == n && columns.choke_opening_frac.size() == n &&
               columns.pump_flow_m3ps.size() == n && columns.outlet_pressure_pa.size() == n);
  double smoothing_s = options.piston_smoothing_s;
  if (options.reconstruct_inputs) {
    columns = ReconstructInputColumns(columns,
                                      plan != nullptr ? *plan : PlanInputReconstruction(columns));
    smoothing_s = 0.0;  // the reconstruction has smoothed the piston
  }
  std::vector<double> smoothed = SmoothedPistonPosition(columns, smoothing_s);
  // As RowPipeline (compare's replay): the mean over the first kInitialInputWindowS.
  InitialInputs initial;
  for (std::size_t i = 0; i < n; ++i) {
    if (columns.time_s[i] > columns.time_s[0] + kInitialInputWindowS) break;
    initial.Add(columns.time_s[i], {columns.choke_opening_frac[i], columns.pump_flow_m3ps[i],
                                    columns.outlet_pressure_pa[i]});
  }
  auto shared = std::make_shared<SharedInputs>(std::move(columns), std::move(smoothed));
  InputSignals signals;
  signals.piston_position_m = [shared](double t) { return shared->Piston(t); };
  signals.rig = [shared](double t) { return shared->Rig(t); };
  signals.initial = initial.Mean();
  signals.warmup = options.warmup;
  signals.profile = options.profile;
  return signals;
}

Result<InputSignals> SignalsFromLog(const riglog::RigLog& log, const std::string& path,
                                    const InputReplayOptions& options) {
  if (log.num_rows() < 2) return Status::Error(path + ": needs at least 2 samples");
  auto columns = InputColumnsFromLog(log, path);
  if (!columns.ok()) return columns.status();
  return SignalsFromColumns(std::move(columns).value(), path, options);
}

}  // namespace mpdrig
