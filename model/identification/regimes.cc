#include "model/identification/regimes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "model/boundary/choke.h"

namespace mpdrig {
namespace {

// The p-quantile (0..1) of the finite values, 0 if there is none.
double Quantile(const std::vector<double>& values, double p) {
  std::vector<double> v;
  v.reserve(values.size());
  for (double x : values) {
    if (std::isfinite(x)) v.push_back(x);
  }
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(p * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Runs of one state: [first, end) sample indices.
struct Run {
  std::size_t first = 0, end = 0;
  bool state = false;
};

// The runs of `state` with those shorter than kMinRegimeS given to the run before them (the first
// to the one after it), adjacent runs of one state joined.
std::vector<Run> Runs(const std::vector<bool>& state, const std::vector<double>& t) {
  std::vector<Run> raw;
  for (std::size_t n = 0; n < state.size(); ++n) {
    if (raw.empty() || raw.back().state != state[n]) {
      raw.push_back({n, n + 1, state[n]});
    } else {
      raw.back().end = n + 1;
    }
  }
  const auto duration = [&](const Run& run) {
    const double end = run.end < t.size() ? t[run.end] : t.back();
    return end - t[run.first];
  };
  std::vector<Run> kept;
  for (Run run : raw) {
    if (duration(run) < kMinRegimeS && !kept.empty()) {
      kept.back().end = run.end;  // a short run belongs to the state around it
      continue;
    }
    if (!kept.empty() && kept.back().state == run.state) {
      kept.back().end = run.end;
    } else if (kept.size() == 1 && duration(kept.front()) < kMinRegimeS) {
      run.first = 0;  // a short first run belongs to the one after it
      kept.back() = run;
    } else {
      kept.push_back(run);
    }
  }
  return kept;
}

// The two regimes of an input whose state changes (state true: `on_name`), none otherwise.
void AddRegimes(const std::vector<bool>& state, const std::vector<double>& t,
                const std::string& input, const std::string& on_name, const std::string& off_name,
                std::vector<Regime>* regimes) {
  const std::vector<Run> runs = Runs(state, t);
  if (runs.size() < 2) return;
  Regime on, off;
  on.name = on_name, on.input = input;
  off.name = off_name, off.input = input;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const bool last = i + 1 == runs.size();
    TimeInterval interval{
        t[runs[i].first],
        last ? std::nextafter(t.back(), std::numeric_limits<double>::infinity()) : t[runs[i].end]};
    Regime& regime = runs[i].state ? on : off;
    regime.intervals.push_back(interval);
    regime.duration_s += interval.end_s - interval.begin_s;
  }
  regimes->push_back(std::move(on));
  regimes->push_back(std::move(off));
}

// RMS of the piston velocity over kPistonWindowS about each sample (central differences of the
// reconstructed position; running sums over the window).
std::vector<double> PistonVelocityRms(const std::vector<double>& t, const std::vector<double>& x) {
  const std::size_t n = t.size();
  std::vector<double> v2(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = i > 0 ? i - 1 : i, b = i + 1 < n ? i + 1 : i;
    if (b > a && t[b] > t[a]) {
      const double v = (x[b] - x[a]) / (t[b] - t[a]);
      v2[i] = std::isfinite(v) ? v * v : 0.0;
    }
  }
  std::vector<double> sums(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) sums[i + 1] = sums[i] + v2[i];
  std::vector<double> rms(n, 0.0);
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (t[i] - t[lo] > 0.5 * kPistonWindowS) ++lo;
    while (hi < n && t[hi] - t[i] <= 0.5 * kPistonWindowS) ++hi;
    rms[i] = std::sqrt((sums[hi] - sums[lo]) / static_cast<double>(hi - lo));
  }
  return rms;
}

}  // namespace

bool Regime::Contains(double t_s) const {
  for (const TimeInterval& interval : intervals) {
    if (t_s >= interval.begin_s && t_s < interval.end_s) return true;
  }
  return false;
}

double Regime::TimeIn(double begin_s, double end_s) const {
  double time = 0.0;
  for (const TimeInterval& interval : intervals) {
    time += std::max(0.0, std::min(end_s, interval.end_s) - std::max(begin_s, interval.begin_s));
  }
  return time;
}

std::vector<Regime> DetectRegimes(const MeasuredLog& log, const RigParams& params) {
  std::vector<Regime> regimes;
  const LogInputColumns& inputs =
      log.reconstructed_inputs.time_s.empty() ? log.inputs : log.reconstructed_inputs;
  const std::vector<double>& t = inputs.time_s;
  const std::size_t n = t.size();
  if (n < 2) return regimes;
  // The pump: stopped below a tenth of its running level, where it has one above its noise.
  if (inputs.pump_flow_m3ps.size() == n) {
    const double running = Quantile(inputs.pump_flow_m3ps, 0.9);
    const double noise = log.reconstruction.pump_noise_m3ps;
    if (running > 5.0 * noise && running > 0.0) {
      std::vector<bool> stopped(n);
      for (std::size_t i = 0; i < n; ++i) {
        stopped[i] = inputs.pump_flow_m3ps[i] < kPumpOffFraction * running;
      }
      AddRegimes(stopped, t, "FT2", "pump stopped", "pump running", &regimes);
    }
  }
  // The choke: closed where it passes little more than its leak.
  if (inputs.choke_opening_frac.size() == n) {
    const ChokeCharacteristic choke(params);
    std::vector<bool> closed(n);
    for (std::size_t i = 0; i < n; ++i) {
      closed[i] = choke.FlowCoefficientM2(inputs.choke_opening_frac[i]) <=
                  kClosedLeakFactor * params.choke_leak_m2;
    }
    AddRegimes(closed, t, "choke_position", "choke closed", "choke open", &regimes);
  }
  // The heave: stopped where the piston's velocity is a small part of its moving level.
  if (inputs.piston_position_m.size() == n) {
    const std::vector<double> rms = PistonVelocityRms(t, inputs.piston_position_m);
    const double moving = Quantile(rms, 0.9);
    if (moving > 0.0) {
      std::vector<bool> still(n);
      for (std::size_t i = 0; i < n; ++i) still[i] = rms[i] < kPistonStillFraction * moving;
      AddRegimes(still, t, "piston_position", "heave stopped", "heave running", &regimes);
    }
  }
  return regimes;
}

bool OnSide(const Regime& regime, double side_s) {
  return side_s >= kMinRegimeSideS && side_s >= kMinRegimeShare * regime.duration_s;
}

RegimeSplit SplitByRegimes(std::vector<Regime> regimes, double t0_s, double t1_s,
                           double fit_fraction) {
  RegimeSplit split;
  split.requested_s = t0_s + fit_fraction * (t1_s - t0_s);
  split.split_s = split.requested_s;
  const double end_s = std::nextafter(t1_s, std::numeric_limits<double>::infinity());
  const auto two_sided = [&](double s) {
    int count = 0;
    for (const Regime& regime : regimes) {
      count += OnSide(regime, regime.TimeIn(t0_s, s)) && OnSide(regime, regime.TimeIn(s, end_s));
    }
    return count;
  };
  if (!regimes.empty()) {
    // The requested split first (it wins ties), then a grid of the allowed ones: the most regimes
    // on both sides, nearest the requested fraction.
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    const auto consider = [&](double fraction) {
      const double s = t0_s + fraction * (t1_s - t0_s);
      const int count = two_sided(s);
      const double distance = std::fabs(fraction - fit_fraction);
      if (count > best || (count == best && distance < best_distance)) {
        best = count, best_distance = distance, split.split_s = s;
      }
    };
    consider(fit_fraction);
    const double lo = std::min(kMinFitFraction, fit_fraction);
    const double hi = std::max(kMaxFitFraction, fit_fraction);
    constexpr int kSteps = 400;
    for (int k = 0; k <= kSteps; ++k) {
      consider(lo + (hi - lo) * k / kSteps);
    }
  }
  RegimeSplit chosen = SplitAt(std::move(regimes), t0_s, t1_s, split.split_s);
  chosen.requested_s = split.requested_s;
  return chosen;
}

RegimeSplit SplitAt(std::vector<Regime> regimes, double t0_s, double t1_s, double split_s) {
  RegimeSplit split;
  split.split_s = split.requested_s = split_s;
  const double end_s = std::nextafter(t1_s, std::numeric_limits<double>::infinity());
  for (Regime& regime : regimes) {
    regime.fit_s = regime.TimeIn(t0_s, split.split_s);
    regime.score_s = regime.TimeIn(split.split_s, end_s);
    const bool in_fit = OnSide(regime, regime.fit_s), in_score = OnSide(regime, regime.score_s);
    if (in_fit && in_score) continue;
    char text[200];
    std::snprintf(
        text, sizeof text,
        "%s: %s (%.1f s of %.1f s in the fitting data, %.1f s in "
        "the scoring data)",
        regime.name.c_str(),
        in_fit ? (regime.score_s > 0.0 ? "mostly in the fitting data" : "only in the fitting data")
        : in_score
            ? (regime.fit_s > 0.0 ? "mostly in the scoring data" : "only in the scoring data")
            : "too short for either part",
        regime.fit_s, regime.duration_s, regime.score_s);
    split.one_sided.push_back(text);
  }
  split.regimes = std::move(regimes);
  return split;
}

}  // namespace mpdrig
