#include "model/identification/residual_signature.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "model/analysis/window_error.h"
#include "model/signal/spectrum.h"

namespace mpdrig {
namespace {

std::string Percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g %%", 100.0 * fraction);
  return text;
}

std::string Number(double value, int digits = 3) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

// A difference of `value_si` in the log's unit of the channel (gauge and absolute pressures
// differ by an offset only).
double DifferenceInUnit(riglog::Unit unit, double value_si) {
  return riglog::FromSi(unit, value_si, 0.0) - riglog::FromSi(unit, 0.0, 0.0);
}

std::string Signed(double value, riglog::Unit unit) {
  char text[48];
  std::snprintf(text, sizeof text, "%+.3g %s", value,
                std::string(riglog::UnitSuffix(unit)).c_str());
  return text;
}

std::string Where(const ChannelResidual& channel) {
  std::string name(riglog::ChannelName(channel.channel));
  if (channel.x_m) name += " (" + Number(*channel.x_m) + " m)";
  return name;
}

// Sums of one channel over a set of samples.
struct Sums {
  long n = 0;
  double y = 0.0, yy = 0.0;  // measurement
  double e = 0.0, ee = 0.0;  // residual yhat - y
  double dd = 0.0;           // replayed input noise (yhat' - yhat)^2
  void Add(double y_n, double e_n, double d_n) {
    ++n, y += y_n, yy += y_n * y_n, e += e_n, ee += e_n * e_n, dd += d_n * d_n;
  }
  double ss_tot() const { return n > 0 ? std::max(0.0, yy - y * y / n) : 0.0; }
  double mean_y() const { return n > 0 ? y / n : 0.0; }
  double bias() const { return n > 0 ? e / n : 0.0; }
};

// Band energies of a series (mean removed; NaN as 0) by Parseval over the zero-padded DFT:
// sum_n x^2 = (1 / M) sum_k w_k |X_k|^2, w_k = 2 but at 0 and M / 2.
std::vector<double> BandEnergies(std::vector<double> x, double rate_hz,
                                 const std::vector<double>& edges_hz) {
  double mean = 0.0;
  long count = 0;
  for (double v : x) {
    if (std::isfinite(v)) mean += v, ++count;
  }
  mean = count > 0 ? mean / count : 0.0;
  for (double& v : x) v = std::isfinite(v) ? v - mean : 0.0;
  const std::size_t size = FastFftSize(x.size());
  const std::vector<std::complex<double>> spectrum = RealDft(x, size);
  std::vector<double> energies(edges_hz.size() - 1, 0.0);
  for (std::size_t k = 0; k < spectrum.size(); ++k) {
    const double f = rate_hz * static_cast<double>(k) / static_cast<double>(size);
    const double weight = k == 0 || 2 * k == size ? 1.0 : 2.0;
    std::size_t b = 0;
    while (b + 2 < edges_hz.size() && f >= edges_hz[b + 1]) ++b;
    energies[b] += weight * std::norm(spectrum[k]) / static_cast<double>(size);
  }
  return energies;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Portable normal draws (Box-Muller on the engine's bits: the same numbers with any library).
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : engine_(seed) {}
  double operator()() {
    const double u1 = std::max(Uniform(), 1e-300), u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  std::mt19937_64 engine_;
};

// The findings along the pipe: one transmitter that stands out (a sensor), or where along it.
std::string AlongThePipe(const std::vector<ChannelResidual>& channels) {
  std::vector<const ChannelResidual*> pipe;
  for (const ChannelResidual& c : channels) {
    if (c.x_m) pipe.push_back(&c);
  }
  if (pipe.size() < 3) return "along the pipe: fewer than 3 transmitters PT1..PT10 in the log";
  const auto worst = std::max_element(pipe.begin(), pipe.end(),
                                      [](auto* a, auto* b) { return a->excess < b->excess; });
  std::vector<double> others;
  for (const ChannelResidual* c : pipe) {
    if (c != *worst) others.push_back(c->excess);
  }
  const double second = *std::max_element(others.begin(), others.end());
  if ((*worst)->excess > 0.0 && (*worst)->excess >= kSingleTransmitterFactor * second) {
    return "along the pipe: one transmitter, " + Where(**worst) + ", " + Percent((*worst)->excess) +
           " beyond its noise against at most " + Percent(second) +
           " at the others: a sensor of its own (gain, offset, position) rather than the pipe";
  }
  double inlet = 0.0, outlet = 0.0;
  int n_inlet = 0, n_outlet = 0;
  for (const ChannelResidual* c : pipe) {
    if (*c->x_m < 450.0) {  // PT1..PT5 of the 900 m pipe
      inlet += c->excess, ++n_inlet;
    } else {
      outlet += c->excess, ++n_outlet;
    }
  }
  inlet = n_inlet > 0 ? inlet / n_inlet : 0.0;
  outlet = n_outlet > 0 ? outlet / n_outlet : 0.0;
  const std::string numbers = " (beyond the noise: " + Percent(inlet) + " on the inlet half, " +
                              Percent(outlet) + " on the outlet half; largest at " +
                              Where(**worst) + ")";
  if (outlet >= 1.5 * inlet && outlet > 0.0)
    return "along the pipe: grows toward the outlet" + numbers;
  if (inlet >= 1.5 * outlet && inlet > 0.0)
    return "along the pipe: grows toward the inlet" + numbers;
  return "along the pipe: the whole pipe alike" + numbers;
}

}  // namespace

double MeasurementNoiseSigma(const std::vector<double>& y) {
  std::vector<double> d2;
  for (std::size_t n = 2; n < y.size(); ++n) {
    if (std::isfinite(y[n]) && std::isfinite(y[n - 1]) && std::isfinite(y[n - 2])) {
      d2.push_back(y[n] - 2.0 * y[n - 1] + y[n - 2]);
    }
  }
  if (d2.size() < 3) return 0.0;
  const double centre = Median(d2);
  for (double& v : d2) v = std::fabs(v - centre);
  return 1.4826 * Median(d2) / std::sqrt(6.0);
}

MeasuredLog WithFreshInputNoise(const MeasuredLog& log, std::uint64_t seed) {
  MeasuredLog noisy = log;
  Normal normal(seed);
  const InputReconstruction& plan = log.reconstruction;
  const auto add = [&](std::vector<double>& values, double sigma) {
    for (double& v : values) v += sigma * normal();
  };
  add(noisy.inputs.piston_position_m, plan.piston_noise_m);
  add(noisy.inputs.choke_opening_frac, plan.choke_noise_frac);
  add(noisy.inputs.pump_flow_m3ps, plan.pump_noise_m3ps);
  add(noisy.inputs.outlet_pressure_pa, plan.outlet_noise_pa);
  noisy.reconstructed_inputs = ReconstructInputColumns(noisy.inputs, plan);
  return noisy;
}

ResidualSignature DescribeResidual(const ResidualInputs& in) {
  ResidualSignature signature;
  signature.model = in.model_name;
  signature.quarter_wave_hz = in.quarter_wave_hz;
  const MeasuredLog& log = *in.log;
  const std::vector<double>& t = log.time_s();
  const std::size_t samples = t.size();
  if (samples < 4) return signature;
  const double rate_hz = static_cast<double>(samples - 1) / (t.back() - t.front());
  const std::vector<Regime> no_regimes;
  const std::vector<Regime>& regimes = in.regimes != nullptr ? *in.regimes : no_regimes;
  // Each sample's regimes (a bit each) and, per regime, which samples: the partition of the log
  // by its inputs' states, over which a steady residual is an offset per part.
  std::vector<unsigned> part(samples, 0u);
  for (std::size_t n = 0; n < samples; ++n) {
    for (std::size_t r = 0; r < regimes.size() && r < 32; ++r) {
      if (regimes[r].Contains(t[n])) part[n] |= 1u << r;
    }
  }
  const double f_q = in.quarter_wave_hz > 0.0 ? in.quarter_wave_hz : 0.25;
  const double nyquist = 0.5 * rate_hz;
  std::vector<double> edges = {0.0, f_q / 3.0, 2.0 * f_q, 10.0 * f_q, nyquist};
  for (std::size_t b = 1; b + 1 < edges.size(); ++b) edges[b] = std::min(edges[b], nyquist);
  const char* band_names[] = {"slow", "heave and first modes", "higher modes", "fast"};
  std::vector<double> band_error(4, 0.0), band_floor(4, 0.0), band_excess(4, 0.0);
  std::vector<RegimeResidual> regime_results(regimes.size());
  std::vector<double> regime_floor_sum(regimes.size(), 0.0), regime_steady(regimes.size(), 0.0),
      regime_energy(regimes.size(), 0.0);
  std::vector<int> regime_channels(regimes.size(), 0);
  double score_sum = 0.0, score_sensor = 0.0, score_input = 0.0, score_floor = 0.0;
  double whole_sum = 0.0, whole_floor = 0.0, steady = 0.0, energy = 0.0;
  int score_used = 0, whole_used = 0;
  for (std::size_t c = 0; c < log.channels.size(); ++c) {
    const MeasuredChannel& channel = log.channels[c];
    const std::vector<double>& y = channel.values_si;
    const std::vector<double>& yhat = in.model->values_si[c];
    const std::vector<double>* other =
        in.input_noise != nullptr ? &in.input_noise->values_si[c] : nullptr;
    Sums whole, score;
    std::vector<Sums> in_regime(regimes.size());
    std::map<unsigned, Sums> in_part;
    std::vector<double> e(samples, std::nan("")), d(samples, 0.0);
    for (std::size_t n = 0; n < samples; ++n) {
      if (!std::isfinite(y[n]) || !std::isfinite(yhat[n])) continue;
      e[n] = yhat[n] - y[n];
      const double d_n =
          other != nullptr && std::isfinite((*other)[n]) ? (*other)[n] - yhat[n] : 0.0;
      d[n] = d_n;
      whole.Add(y[n], e[n], d_n);
      if (t[n] >= in.score_begin_s && t[n] <= in.score_end_s) score.Add(y[n], e[n], d_n);
      for (std::size_t r = 0; r < regimes.size() && r < 32; ++r) {
        if (part[n] & (1u << r)) in_regime[r].Add(y[n], e[n], d_n);
      }
      in_part[part[n]].Add(y[n], e[n], d_n);
    }
    const double ss_tot = whole.ss_tot();
    if (whole.n < 4 || !(ss_tot > 0.0) ||
        IsConstantSpread(channel.channel, whole.mean_y(), std::sqrt(ss_tot / whole.n))) {
      continue;
    }
    const double sigma = MeasurementNoiseSigma(y);
    const double variance = ss_tot / whole.n;
    ChannelResidual result;
    result.channel = channel.channel;
    result.x_m = PipePositionM(channel.channel);
    result.nrmse = std::sqrt(whole.ee / ss_tot);
    result.sensor_floor = sigma / std::sqrt(variance);
    result.input_floor = std::sqrt(whole.dd / ss_tot);
    result.floor = std::hypot(result.sensor_floor, result.input_floor);
    result.excess =
        std::sqrt(std::max(0.0, result.nrmse * result.nrmse - result.floor * result.floor));
    result.bias_si = whole.bias();
    result.bias_unit = DifferenceInUnit(channel.unit, result.bias_si);
    // Steady: the mean residual of each part of the log (its inputs' states).
    double part_steady = 0.0;
    for (const auto& [key, sums] : in_part) part_steady += sums.n * sums.bias() * sums.bias();
    // Its share of what is not noise (the noise's means over parts of seconds are ~0).
    const double beyond = result.excess * result.excess * ss_tot;
    result.steady_share = beyond > 0.0 ? std::min(1.0, part_steady / beyond) : 0.0;
    steady += part_steady / ss_tot;
    energy += beyond / ss_tot;
    whole_sum += result.nrmse;
    whole_floor += result.floor;
    ++whole_used;
    // The scoring data: the model's error and the floor there, each over the window's variation.
    const double score_tot = score.ss_tot();
    if (score.n >= 4 && score_tot > 0.0 &&
        !IsConstantSpread(channel.channel, score.mean_y(), std::sqrt(score_tot / score.n))) {
      const double sensor = sigma / std::sqrt(score_tot / score.n);
      const double input = std::sqrt(score.dd / score_tot);
      result.score_nrmse = std::sqrt(score.ee / score_tot);
      result.score_floor = std::hypot(sensor, input);
      score_sum += std::sqrt(score.ee / score_tot);
      score_sensor += sensor;
      score_input += input;
      score_floor += std::hypot(sensor, input);
      ++score_used;
    }
    // Bands: the residual's energy in each against white sensor noise's share and the replayed
    // input noise's own spectrum.
    const std::vector<double> residual_bands = BandEnergies(e, rate_hz, edges);
    const std::vector<double> input_bands =
        other != nullptr ? BandEnergies(d, rate_hz, edges) : std::vector<double>(4, 0.0);
    for (std::size_t b = 0; b < 4; ++b) {
      const double white = whole.n * sigma * sigma * (edges[b + 1] - edges[b]) / nyquist;
      const double noise = white + input_bands[b];
      band_error[b] += std::sqrt(residual_bands[b] / ss_tot);
      band_floor[b] += std::sqrt(noise / ss_tot);
      // Summed over channels before the clip: clipped per channel, the noise's own fluctuations
      // about its expected energy would add up as excess in the noisiest band.
      band_excess[b] += (residual_bands[b] - noise) / ss_tot;
    }
    // Regimes: over the whole log's variation per sample, so that they compare.
    for (std::size_t r = 0; r < regimes.size() && r < 32; ++r) {
      const Sums& sums = in_regime[r];
      if (sums.n < 2) continue;
      const double error = std::sqrt(sums.ee / (sums.n * variance));
      regime_results[r].channel_errors.emplace_back(channel.channel, error);
      // Pressures only: an offset of a flow is not comparable with one of a pressure.
      if (riglog::QuantityOf(channel.channel) == riglog::Quantity::kPressure) {
        regime_results[r].channel_bias.emplace_back(channel.channel,
                                                    DifferenceInUnit(channel.unit, sums.bias()));
      }
      regime_results[r].error += error;
      const double floor =
          std::hypot(result.sensor_floor, std::sqrt(sums.dd / (sums.n * variance)));
      regime_floor_sum[r] += floor;
      regime_steady[r] += sums.n * sums.bias() * sums.bias() / ss_tot;
      regime_energy[r] += std::max(0.0, sums.ee - sums.n * variance * floor * floor) / ss_tot;
      ++regime_channels[r];
    }
    signature.channels.push_back(result);
  }
  if (score_used > 0) {
    signature.error = score_sum / score_used;
    signature.sensor_floor = score_sensor / score_used;
    signature.input_floor = score_input / score_used;
    signature.noise_floor = score_floor / score_used;
    if (signature.error > kMissesFactor * signature.noise_floor) {
      signature.reasons.push_back("its error on the scoring data over " + Number(kMissesFactor) +
                                  " times the noise floor");
    }
  }
  if (whole_used == 0) return signature;
  signature.whole_error = whole_sum / whole_used;
  signature.whole_floor = whole_floor / whole_used;
  signature.steady_share = energy > 0.0 ? std::min(1.0, steady / energy) : 0.0;
  double excess_total = 0.0;
  for (double& x : band_excess) x = std::max(0.0, x), excess_total += x;
  for (std::size_t b = 0; b < 4; ++b) {
    signature.bands.push_back({band_names[b], edges[b], edges[b + 1], band_error[b] / whole_used,
                               band_floor[b] / whole_used,
                               excess_total > 0.0 ? band_excess[b] / excess_total : 0.0});
  }
  for (std::size_t r = 0; r < regimes.size() && r < 32; ++r) {
    RegimeResidual& result = regime_results[r];
    result.regime = regimes[r].name;
    result.input = regimes[r].input;
    result.duration_s = regimes[r].duration_s;
    if (regime_channels[r] > 0) {
      result.error /= regime_channels[r];
      result.floor = regime_floor_sum[r] / regime_channels[r];
      result.steady_share =
          regime_energy[r] > 0.0 ? std::min(1.0, regime_steady[r] / regime_energy[r]) : 0.0;
    }
    signature.regimes.push_back(std::move(result));
  }

  {
    std::vector<const ChannelResidual*> over;
    for (const ChannelResidual& c : signature.channels) {
      if (c.score_nrmse > kMissesFactor * c.score_floor) over.push_back(&c);
    }
    std::stable_sort(over.begin(), over.end(), [](auto* a, auto* b) {
      return a->score_nrmse / a->score_floor > b->score_nrmse / b->score_floor;
    });
    if (!over.empty()) {
      std::string text = std::to_string(over.size()) +
                         (over.size() == 1 ? " channel's error" : " channels' errors") +
                         " on the scoring data over " + Number(kMissesFactor) + " times " +
                         (over.size() == 1 ? "its floor" : "their floors") + " (";
      for (std::size_t i = 0; i < over.size() && i < 3; ++i) {
        text += std::string(i ? ", " : "") + std::string(riglog::ChannelName(over[i]->channel)) +
                " " + Percent(over[i]->score_nrmse) + " against " + Percent(over[i]->score_floor);
      }
      signature.reasons.push_back(text + (over.size() > 3 ? ", ...)" : ")"));
    }
  }
  for (const RegimeResidual& r : signature.regimes) {
    if (r.error > kMissesFactor * r.floor) {
      signature.reasons.push_back("while " + r.regime + " " + Percent(r.error) +
                                  " against a floor of " + Percent(r.floor) + " there");
    }
  }
  signature.above_noise = !signature.reasons.empty();
  signature.misses = signature.above_noise && in.selected_effects == 0;

  // The findings.
  // Channels by how far above their floors they are (a noisy flow meter's large error is not
  // a large miss).
  std::vector<const ChannelResidual*> ranked;
  for (const ChannelResidual& c : signature.channels) ranked.push_back(&c);
  const auto ratio = [](const ChannelResidual* c) {
    return c->floor > 0.0 ? c->nrmse / c->floor : std::numeric_limits<double>::infinity();
  };
  std::stable_sort(ranked.begin(), ranked.end(),
                   [&](auto* a, auto* b) { return ratio(a) > ratio(b); });
  {
    std::string text = "channels:";
    int listed = 0;
    for (const ChannelResidual* c : ranked) {
      if (listed == 6 || !(ratio(c) > kMissesFactor)) break;
      text += std::string(listed ? "," : "") + " " + Where(*c) + " " + Percent(c->nrmse) +
              " against a floor of " + Percent(c->floor);
      ++listed;
    }
    if (listed == 0) {
      text += " none over " + Number(kMissesFactor) +
              " times its floor (the most: " + Where(*ranked.front()) + ", " +
              Number(ratio(ranked.front()), 2) + " times)";
    }
    signature.findings.push_back(text);
  }
  {
    std::string text = "bands (f_q = c/4L = " + Number(f_q) + " Hz):";
    int listed = 0;
    for (const BandResidual& band : signature.bands) {
      if (band.excess_share < kBandShare) continue;
      text += std::string(listed ? "," : "") + " " + band.name + " (" + Number(band.low_hz, 2) +
              "-" + Number(band.high_hz, 2) + " Hz) " + Percent(band.excess_share) +
              " of what is not noise, error " + Percent(band.error) + " against " +
              Percent(band.floor);
      ++listed;
    }
    if (listed == 0) text += " none beyond the noise";
    signature.findings.push_back(text);
  }
  signature.findings.push_back(AlongThePipe(signature.channels));
  {
    std::string text = signature.steady_share >= kSteadyShare ? "steady: " : "dynamic: ";
    text += Percent(signature.steady_share) + " of what is not noise is a steady offset" +
            std::string(regimes.empty() ? "" : " (within each regime)");
    if (signature.steady_share >= kSteadyShare) {
      const ChannelResidual& worst = *ranked.front();
      for (const MeasuredChannel& m : log.channels) {
        if (m.channel != worst.channel) continue;
        text += "; over the whole log " + Where(worst) + " reads " +
                Signed(-worst.bias_unit, m.unit) + " against the model";
      }
    }
    signature.findings.push_back(text);
  }
  {
    std::string text = "regimes:";
    if (regimes.empty()) text += " none in this log (every input keeps one state)";
    int listed = 0;
    for (std::size_t r = 0; r < signature.regimes.size(); ++r) {
      const RegimeResidual& here = signature.regimes[r];
      // The other state of the same input.
      const RegimeResidual* there = nullptr;
      for (const RegimeResidual& o : signature.regimes) {
        if (&o != &here && o.input == here.input) there = &o;
      }
      const auto excess = [](const RegimeResidual& r) {
        return std::sqrt(std::max(0.0, r.error * r.error - r.floor * r.floor));
      };
      if (there == nullptr || !(excess(here) >= kRegimeContrast * excess(*there)) ||
          !(here.error > kMissesFactor * here.floor)) {
        continue;
      }
      text += std::string(listed ? ";" : "") + " concentrated while " + here.regime + " (" +
              Number(here.duration_s) + " s): " + Percent(excess(here)) +
              " beyond the noise there (error " + Percent(here.error) + ", floor " +
              Percent(here.floor) + ") against " + Percent(excess(*there)) + " while " +
              there->regime + ", " +
              (here.steady_share >= kSteadyShare ? "steady there (" : "dynamic there (") +
              Percent(here.steady_share) + " an offset";
      if (!here.channel_bias.empty()) {
        const auto largest = std::max_element(
            here.channel_bias.begin(), here.channel_bias.end(),
            [](const auto& a, const auto& b) { return std::fabs(a.second) < std::fabs(b.second); });
        for (const MeasuredChannel& m : log.channels) {
          if (m.channel != largest->first) continue;
          text += "; " + std::string(riglog::ChannelName(m.channel)) + " reads " +
                  Signed(-largest->second, m.unit) + " against the model there";
        }
      }
      text += ")";
      ++listed;
    }
    if (!regimes.empty() && listed == 0) {
      text += " alike in every regime (";
      for (std::size_t r = 0; r < signature.regimes.size(); ++r) {
        text += std::string(r ? ", " : "") + signature.regimes[r].regime + " " +
                Percent(signature.regimes[r].error);
      }
      text += ")";
    }
    signature.findings.push_back(text);
  }
  return signature;
}

std::string ResidualSignature::Summary() const {
  std::string text;
  const std::string numbers = Percent(error) + " on the scoring data against a noise floor of " +
                              Percent(noise_floor) + " (sensor noise " + Percent(sensor_floor) +
                              ", the inputs' noise replayed " + Percent(input_floor) + ")";
  if (!above_noise) return "what the " + model + " leaves is noise: error " + numbers + ".";
  text = misses ? "the " + model + " misses something the catalogue does not hold: error "
                : "the " + model +
                      " still leaves more than noise (the selected effects' fits stopping short "
                      "of their strengths, or something the catalogue does not hold): error ";
  text += numbers + "; ";
  for (std::size_t i = 0; i < reasons.size(); ++i) text += (i ? ", " : "") + reasons[i];
  text += ". What is left:";
  for (std::size_t i = 0; i < findings.size(); ++i) text += (i ? "; " : " ") + findings[i];
  return text + ".";
}

}  // namespace mpdrig
