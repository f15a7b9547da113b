// Frequency-response accuracy that goes with the speed numbers of simulator_benchmark.cc: how far
// the simulated response p(0) / x_d (SimulatedFrequencyResponse, thesis 9.3) lies from the
// analytic one (9.2.13 times s, AnalyticFrequencyResponse) at the cell counts of Table 7.4.1.
//
// Cases: characteristics scheme, quasi-linear and linear models, N = 100 and 1000, closed choke
// (q_b = 0: a closed choke with pump flow has no steady state) and open choke (q_b = 5 L/min),
// f over an even grid on [0.02, 0.6] Hz (both closed resonances c/2L and the first open one
// c/4L inside). Quadratic friction is switched off (f2 = 0) because (9.2.13) has only the linear
// friction f1. Per case it prints the largest relative magnitude error
//   max_f | |H_sim(f)| - |H_an(f)| | / |H_an(f)|
// and the largest phase error max_f |arg H_sim(f) - arg H_an(f)| (wrapped to +-180 deg), with
// the frequencies where they occur, and whether the magnitude is within 1 %.
//
// Usage: mpdrig_accuracy_report [--points=30] [--threads=2] [--cells=100,1000]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "model/analysis/frequency_response.h"
#include "model/common/units.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {
namespace {

constexpr double kMinFrequencyHz = 0.02;
constexpr double kMaxFrequencyHz = 0.6;
constexpr double kOpenPumpFlowLpm = 5.0;
constexpr double kMagnitudeTolerancePct = 1.0;  // the target: within 1 % of analytic

struct ReportOptions {
  int points = 30;
  int threads = 2;
  std::vector<int> cells = {100, 1000};
};

struct Case {
  PipeModel model;
  int cells;
  ChokeSetting choke;
  double pump_flow_m3ps;
};

struct CaseResult {
  bool ok = false;
  std::string error;
  double max_magnitude_error_pct = 0.0;
  double magnitude_error_freq_hz = 0.0;
  double max_phase_error_deg = 0.0;
  double phase_error_freq_hz = 0.0;
  double wall_s = 0.0;
};

double WrapDeg(double deg) {
  double wrapped = std::fmod(deg + 180.0, 360.0);
  if (wrapped < 0.0) wrapped += 360.0;
  return wrapped - 180.0;
}

CaseResult RunCase(const Case& c, const std::vector<double>& freqs) {
  RigParams params;
  params.friction_f2_per_m = 0.0;  // (9.2.13) has only linear friction
  SimulationOptions options;
  options.model = c.model;
  options.scheme = PipeScheme::kCharacteristics;
  options.cells = c.cells;

  CaseResult result;
  const auto start = std::chrono::steady_clock::now();
  auto simulated = SimulatedFrequencyResponse(params, options, c.choke, c.pump_flow_m3ps, freqs);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!simulated.ok()) {
    result.error = simulated.status().message();
    return result;
  }
  const std::vector<FrequencyPoint> analytic =
      AnalyticFrequencyResponse(params, c.choke, c.pump_flow_m3ps, freqs);
  for (std::size_t i = 0; i < freqs.size(); ++i) {
    const FrequencyPoint& sim = (*simulated)[i];
    const FrequencyPoint& an = analytic[i];
    const double magnitude_error_pct =
        100.0 * std::fabs(sim.magnitude_pa_per_m - an.magnitude_pa_per_m) / an.magnitude_pa_per_m;
    const double phase_error_deg = std::fabs(WrapDeg(sim.phase_deg - an.phase_deg));
    if (magnitude_error_pct >= result.max_magnitude_error_pct) {
      result.max_magnitude_error_pct = magnitude_error_pct;
      result.magnitude_error_freq_hz = freqs[i];
    }
    if (phase_error_deg >= result.max_phase_error_deg) {
      result.max_phase_error_deg = phase_error_deg;
      result.phase_error_freq_hz = freqs[i];
    }
  }
  result.ok = true;
  return result;
}

// Returns the number of cases that failed to run or missed the tolerance.
int RunReport(const ReportOptions& options) {
  const std::vector<double> freqs =
      FrequencyGrid(kMinFrequencyHz, kMaxFrequencyHz, options.points, /*logarithmic=*/false);
  std::vector<Case> cases;
  for (int cells : options.cells) {
    for (PipeModel model : {PipeModel::kQuasiLinear, PipeModel::kLinear}) {
      cases.push_back({model, cells, ChokeSetting::Closed(), 0.0});
      cases.push_back({model, cells, ChokeSetting::Open(), units::LpmToM3ps(kOpenPumpFlowLpm)});
    }
  }

  // The cases are independent runs: spread them over the cores, largest first.
  std::vector<std::size_t> order(cases.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return cases[a].cells > cases[b].cells; });
  std::vector<CaseResult> results(cases.size());
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t k = next++; k < order.size(); k = next++) {
      results[order[k]] = RunCase(cases[order[k]], freqs);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < std::max(1, options.threads); ++t) pool.emplace_back(worker);
  for (std::thread& thread : pool) thread.join();

  std::printf(
      "Frequency response p(0)/x_d, simulated vs analytic (9.2.13): characteristics "
      "scheme, f2 = 0, %d points on [%.2f, %.2f] Hz\n",
      options.points, kMinFrequencyHz, kMaxFrequencyHz);
  std::printf("%-12s %6s %-7s %13s %9s %14s %9s %8s %s\n", "model", "N", "choke", "mag_err_pct",
              "at_hz", "phase_err_deg", "at_hz", "wall_s", "within_1pct");
  int failures = 0;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const CaseResult& r = results[i];
    const char* model = c.model == PipeModel::kQuasiLinear ? "quasilinear" : "linear";
    if (!r.ok) {
      std::printf("%-12s %6d %-7s error: %s\n", model, c.cells, c.choke.Describe().c_str(),
                  r.error.c_str());
      ++failures;
      continue;
    }
    const bool within = r.max_magnitude_error_pct <= kMagnitudeTolerancePct;
    if (!within) ++failures;
    std::printf("%-12s %6d %-7s %13.3f %9.3f %14.3f %9.3f %8.2f %s\n", model, c.cells,
                c.choke.Describe().c_str(), r.max_magnitude_error_pct, r.magnitude_error_freq_hz,
                r.max_phase_error_deg, r.phase_error_freq_hz, r.wall_s, within ? "yes" : "NO");
  }
  return failures;
}

bool ParseInt(std::string_view text, int* value) {
  const std::string s(text);
  char* end = nullptr;
  const long parsed = std::strtol(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || parsed < 1 || parsed > 100000) return false;
  *value = static_cast<int>(parsed);
  return true;
}

bool ParseFlags(int argc, char** argv, ReportOptions* options) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg.starts_with("--points=")) {
      if (!ParseInt(arg.substr(9), &options->points) || options->points < 2) return false;
    } else if (arg.starts_with("--threads=")) {
      if (!ParseInt(arg.substr(10), &options->threads)) return false;
    } else if (arg.starts_with("--cells=")) {
      options->cells.clear();
      std::stringstream list{std::string(arg.substr(8))};
      std::string item;
      while (std::getline(list, item, ',')) {
        int cells = 0;
        if (!ParseInt(item, &cells) || cells < 2) return false;
        options->cells.push_back(cells);
      }
      if (options->cells.empty()) return false;
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace
}  // namespace mpdrig

int main(int argc, char** argv) {
  mpdrig::ReportOptions options;
  if (!mpdrig::ParseFlags(argc, argv, &options)) {
    std::fprintf(stderr,
                 "usage: %s [--points=N>=2] [--threads=N] [--cells=N1,N2,...]\n"
                 "  bad or unknown argument\n",
                 argv[0]);
    return 2;
  }
  return mpdrig::RunReport(options) == 0 ? 0 : 1;
}
