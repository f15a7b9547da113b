#include "model/analysis/frequency_response.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "model/boundary/choke.h"

namespace mpdrig {
namespace {

using Complex = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// An ideal open choke: G = 1 m^2 gives 1e-3 Pa across it at 1 L/s, i.e. p(L) = p_0.
constexpr double kOpenChokeFlowCoefficientM2 = 1.0;

// The rig as the response sees it: the choke setting turned into a characteristic.
RigParams WithChoke(const RigParams& params, const ChokeSetting& choke) {
  RigParams adjusted = params;
  if (choke.kind == ChokeSetting::Kind::kClosed) {
    adjusted.choke_leak_m2 = 0.0;  // tight: u(L) = -q_b/A, i.e. k -> infinity
    adjusted.choke_characteristic = {{0.0, 0.0}, {1.0, 0.0}};
  } else if (choke.kind == ChokeSetting::Kind::kOpen) {
    adjusted.choke_characteristic = {{0.0, kOpenChokeFlowCoefficientM2},
                                     {1.0, kOpenChokeFlowCoefficientM2}};
  }
  return adjusted;
}

Complex FourierCoefficient(const std::vector<double>& values, const std::vector<double>& times,
                           std::size_t first, double omega) {
  Complex sum = 0.0;
  for (std::size_t i = first; i < values.size(); ++i) {
    sum += values[i] * std::exp(Complex(0.0, -omega * times[i]));
  }
  return sum;
}

}  // namespace

std::string ChokeSetting::Describe() const {
  switch (kind) {
    case Kind::kClosed:
      return "closed";
    case Kind::kOpen:
      return "open";
    case Kind::kOpening:
      return std::to_string(opening_frac * 90.0) + " deg";
  }
  return "?";
}

double LinearizedOutletImpedance(const RigParams& params, const ChokeSetting& choke,
                                 double pump_flow_m3ps) {
  switch (choke.kind) {
    case ChokeSetting::Kind::kClosed:
      return std::numeric_limits<double>::infinity();
    case ChokeSetting::Kind::kOpen:
      return 0.0;
    case ChokeSetting::Kind::kOpening:
      break;
  }
  const double g = ChokeCharacteristic(params).FlowCoefficientM2(choke.opening_frac);
  if (g <= 0.0) return std::numeric_limits<double>::infinity();
  // d(p_c - p_0)/du of rho_L (q_b + A u)^2 / G^2 at u = 0.
  return 2.0 * params.choke_density_kgpm3 * params.PipeAreaM2() * std::fabs(pump_flow_m3ps) /
         (g * g);
}

Complex AnalyticBhpPerPistonPosition(const RigParams& params, double k, double freq_hz) {
  const double c = params.wave_speed_mps;
  const double rho = params.density_kgpm3;
  const double length = params.pipe_length_m;
  const double a2 = params.PistonDisplacementAreaM2() / params.PipeAreaM2();
  const Complex s(0.0, kTwoPi * freq_hz);
  const Complex kappa = std::sqrt(s * (s + params.friction_f1_per_s)) / c;  // (9.2.11)
  const Complex z = rho * c * c * kappa / s;  // characteristic impedance, P = Z U for a wave
  const Complex sh = std::sinh(kappa * length);
  const Complex ch = std::cosh(kappa * length);
  Complex ratio;  // P(0) / U(0)
  if (std::isinf(k)) {
    ratio = z * ch / sh;  // closed: U(L) = 0
  } else {
    ratio = z * (z * sh + k * ch) / (z * ch + k * sh);
  }
  // U(0) = -A_2 V_d (9.2.5), V_d = s X.
  return -a2 * ratio * s;
}

std::vector<FrequencyPoint> AnalyticFrequencyResponse(const RigParams& params,
                                                      const ChokeSetting& choke,
                                                      double pump_flow_m3ps,
                                                      const std::vector<double>& freqs_hz) {
  const double k = LinearizedOutletImpedance(params, choke, pump_flow_m3ps);
  std::vector<FrequencyPoint> points;
  for (double f : freqs_hz) {
    const Complex h = AnalyticBhpPerPistonPosition(params, k, f);
    points.push_back({f, std::abs(h), std::arg(h) * 180.0 / std::numbers::pi});
  }
  UnwrapPhase(&points);
  return points;
}

Result<std::vector<FrequencyPoint>> SimulatedFrequencyResponse(
    const RigParams& params, const SimulationOptions& sim_options, const ChokeSetting& choke,
    double pump_flow_m3ps, const std::vector<double>& freqs_hz,
    const SimulatedResponseOptions& options, const std::function<void(int, int)>& progress) {
  if (choke.kind == ChokeSetting::Kind::kClosed && pump_flow_m3ps != 0.0) {
    return Status::Error(
        "a closed choke with pump flow has no steady state: set the pump flow to 0");
  }
  const RigParams rig = WithChoke(params, choke);
  const double decay_rate = 0.5 * rig.friction_f1_per_s;
  std::vector<FrequencyPoint> points;
  int done = 0;
  for (double f : freqs_hz) {
    if (!(f > 0.0)) return Status::Error("frequencies must be > 0");
    const double period = 1.0 / f;
    double settle = options.min_settle_periods * period;
    if (decay_rate > 0.0) settle = std::max(settle, options.settle_decay / decay_rate);
    const int settle_periods = static_cast<int>(std::ceil(settle / period));
    const int total_periods = settle_periods + options.measure_periods;
    const int samples_per_period = options.samples_per_period;

    std::vector<double> times;
    times.reserve(total_periods * samples_per_period + 1);
    for (int i = 0; i <= total_periods * samples_per_period; ++i) {
      times.push_back(i * period / samples_per_period);
    }
    const double omega = kTwoPi * f;
    const double amplitude = options.amplitude_m;
    InputSignals inputs;
    inputs.piston_position_m = [=](double t) { return amplitude * std::sin(omega * t); };
    RigInputs held;
    held.choke_opening_frac = choke.opening_frac;
    held.pump_flow_m3ps = pump_flow_m3ps;
    held.outlet_pressure_pa = options.outlet_pressure_pa;
    inputs.rig = [held](double) { return held; };

    SimulationOptions run_options = sim_options;
    run_options.choke_input = ChokeInput::kMeasured;
    auto run = Simulate(rig, run_options, inputs, times);
    if (!run.ok()) return run.status().Within("simulated response at " + std::to_string(f) + " Hz");

    // Fundamental over the last measure_periods whole periods (the final sample is the first of
    // the next period, so it is left out).
    std::vector<double> bhp, position;
    for (const RigSample& sample : run->samples) {
      bhp.push_back(sample[Channel::kPT1]);
      position.push_back(sample[Channel::kPistonPosition]);
    }
    bhp.pop_back();
    position.pop_back();
    times.pop_back();
    const std::size_t first = static_cast<std::size_t>(settle_periods) * samples_per_period;
    const Complex h = FourierCoefficient(bhp, times, first, omega) /
                      FourierCoefficient(position, times, first, omega);
    points.push_back({f, std::abs(h), std::arg(h) * 180.0 / std::numbers::pi});
    if (progress) progress(++done, static_cast<int>(freqs_hz.size()));
  }
  UnwrapPhase(&points);
  return points;
}

std::vector<double> FrequencyGrid(double fmin_hz, double fmax_hz, int count, bool logarithmic) {
  std::vector<double> freqs;
  if (count <= 1) return {fmin_hz};
  for (int i = 0; i < count; ++i) {
    const double w = static_cast<double>(i) / (count - 1);
    freqs.push_back(logarithmic ? fmin_hz * std::pow(fmax_hz / fmin_hz, w)
                                : fmin_hz + w * (fmax_hz - fmin_hz));
  }
  return freqs;
}

void UnwrapPhase(std::vector<FrequencyPoint>* points) {
  for (std::size_t i = 1; i < points->size(); ++i) {
    double& phase = (*points)[i].phase_deg;
    const double previous = (*points)[i - 1].phase_deg;
    while (phase - previous > 180.0) phase -= 360.0;
    while (phase - previous < -180.0) phase += 360.0;
  }
}

}  // namespace mpdrig
