// Simulator speed, after thesis Table 7.4.1: 20 s of rig time with N = 10, 100 and 1000 pipe
// elements, quasi-linear and linear pipe models (the thesis: MATLAB ode45, C-MEX right-hand side).
//
// Scenario (the same for every row): piston sine x_d(t) = 0.1 m sin(2 pi 0.2 Hz t), choke held at
// 31 deg (u_c = 0.3444), pump q_b = 5 L/min, outlet p_0 = 101325 Pa abs, thesis parameters
// (Tables 8.1.x, 9.4.1), output every 10 ms (the fixed step the thesis recommends, 0.01 s). The
// pipe solver's own step is dx / c, 1.06 ms at N = 1000.
//
//   BM_Simulate20s/<model>/<scheme>/N:<cells>  one Simulate() call over [0, 20] s, wall time.
//     counters: steps (pipe solver steps), cells, rtf (real-time factor = 20 s / wall time).
//   BM_Step/<model>/<scheme>/N:<cells>          RigSimulator::Step alone, no sampling.
//     counters: cells, ns_per_cell_step (wall time / (steps * cells)) and, for the
//     characteristics scheme, limit_ns_per_cell_step: the arithmetic limit of its cell loops on
//     this CPU (ArithmeticLimitNsPerCellStep). N = 10000 too, where the per-step work at the ends
//     (the choke's Newton iteration, the inputs) is spread over more cells.
//
//   BM_BergantSimpsonSevere/N:<cells>  the reservoir - pipe - valve rig of
//     docs/examples/bergant-simpson-1999.pbtxt (V0 = 1.4 m/s, column separation by the discrete
//     gas cavity model, gas_void_fraction = 1e-7 at the reservoir's 316 950 Pa abs), 0.8 s of rig
//     time written at 10 kHz, the linear law: what `mpdrig simulate` runs for that config.
//   BM_BergantSimpsonSevereVapour/N:200  the same with the discrete vapour cavity model
//     (gas_void_fraction = 0).
//   BM_BergantSimpsonSevereWeighted/N:200  the example with convolution unsteady friction
//     (weighted_friction: Vardy & Brown's weighting function, 32 exponentials per node).
//
// Frequency-response accuracy is reported by bench/accuracy_report.cc (bench/README.md).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "model/common/units.h"
#include "model/config/rig_config.h"
#include "model/effects/effect.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {
namespace {

constexpr double kSimulatedTimeS = 20.0;
constexpr double kOutputIntervalS = 0.01;
constexpr double kPistonAmplitudeM = 0.1;
constexpr double kPistonFrequencyHz = 0.2;
constexpr double kChokeOpeningDeg = 31.0;
constexpr double kPumpFlowLpm = 5.0;
constexpr double kOutletPressurePa = units::kStandardAtmospherePa;

constexpr double kPistonOmega = 2.0 * std::numbers::pi * kPistonFrequencyHz;

double PistonPositionM(double t) { return kPistonAmplitudeM * std::sin(kPistonOmega * t); }
double PistonVelocityMps(double t) {
  return kPistonAmplitudeM * kPistonOmega * std::cos(kPistonOmega * t);
}

RigInputs HeldInputs() {
  RigInputs in;
  in.choke_opening_frac = units::ChokeDegToFrac(kChokeOpeningDeg);
  in.pump_flow_m3ps = units::LpmToM3ps(kPumpFlowLpm);
  in.outlet_pressure_pa = kOutletPressurePa;
  return in;
}

std::vector<double> OutputTimes() {
  const int count = static_cast<int>(std::lround(kSimulatedTimeS / kOutputIntervalS));
  std::vector<double> times;
  times.reserve(count + 1);
  for (int i = 0; i <= count; ++i) times.push_back(i * kOutputIntervalS);
  return times;
}

// Wall time of a whole benchmark loop (the counters below are per wall second, like the thesis's
// table, and are printed as plain numbers rather than as the library's rate counters).
double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Case {
  PipeModel model;
  PipeScheme scheme;
  int cells;
};

SimulationOptions OptionsFor(const Case& c) {
  SimulationOptions options;
  options.model = c.model;
  options.scheme = c.scheme;
  options.cells = c.cells;
  return options;
}

std::string CaseName(const Case& c) {
  return std::string(c.model == PipeModel::kQuasiLinear ? "quasilinear" : "linear") + "/" +
         (c.scheme == PipeScheme::kCharacteristics ? "characteristics" : "mol") +
         "/N:" + std::to_string(c.cells);
}

void BM_Simulate20s(benchmark::State& state, Case c) {
  const RigParams params;
  const SimulationOptions options = OptionsFor(c);
  InputSignals inputs;
  inputs.piston_position_m = PistonPositionM;
  const RigInputs held = HeldInputs();
  inputs.rig = [held](double) { return held; };
  const std::vector<double> times = OutputTimes();

  long steps = 0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    auto run = Simulate(params, options, inputs, times);
    if (!run.ok()) {
      state.SkipWithError(run.status().message().c_str());
      return;
    }
    steps = run->steps;
    benchmark::DoNotOptimize(run->samples.back().values.data());
  }
  const double wall_s = SecondsSince(start);
  state.counters["steps"] = static_cast<double>(steps);
  state.counters["cells"] = c.cells;
  state.counters["rtf"] = kSimulatedTimeS * static_cast<double>(state.iterations()) / wall_s;
}

// The characteristics scheme's interior (model/pipe/characteristics_solver.cc, StepInterior) per
// node and step: 23 vector operations in the first loop (u, |u|, lambda, the friction and
// gravity term (2), theta, four differences, the upwind compare, two selects, two shifts, the two
// leaving values (4), K (3, one of them a division)) and 6 in the second (A + B, K (A + B), the
// two new invariants, their difference and the running minimum of the range check): 29. The
// limit: 29 / (lanes x 2 vector instructions a cycle) cycles per cell-step, lanes the width the
// solver runs at on this CPU (8 doubles with AVX-512, 4 with AVX2, 2 without), 2 the FMA/multiply
// pipes of current x86 cores, at the clock /proc/cpuinfo states ("cpu MHz"; under a hypervisor
// the TSC's, which a boost may exceed). 0 if the clock is unknown.
constexpr double kOperationsPerCellStep = 29.0;

double ArithmeticLimitNsPerCellStep() {
  double lanes = 2.0;
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  if (__builtin_cpu_supports("x86-64-v4")) {
    lanes = 8.0;
  } else if (__builtin_cpu_supports("x86-64-v3")) {
    lanes = 4.0;
  }
#endif
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  double mhz = 0.0;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("cpu MHz", 0) == 0) {
      mhz = std::atof(line.substr(line.find(':') + 1).c_str());
      break;
    }
  }
  if (!(mhz > 0.0)) return 0.0;
  const double cycles = kOperationsPerCellStep / (lanes * 2.0);
  return cycles / (mhz * 1e-3);
}

void BM_Step(benchmark::State& state, Case c) {
  const RigParams params;
  auto created = RigSimulator::Create(params, OptionsFor(c), HeldInputs());
  if (!created.ok()) {
    state.SkipWithError(created.status().message().c_str());
    return;
  }
  RigSimulator& sim = *created;
  StepInputs step;
  step.rig = HeldInputs();
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    // Inputs at the end of the step, as Simulate() gives them (the sine keeps the state bounded
    // however many iterations the library runs).
    const double t = sim.time_s() + sim.time_step_s();
    step.piston_velocity_mps = PistonVelocityMps(t);
    step.piston_position_m = PistonPositionM(t);
    const Status status = sim.Step(step);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      return;
    }
  }
  const double wall_s = SecondsSince(start);
  benchmark::DoNotOptimize(sim.pipe().alpha().data());
  state.counters["cells"] = c.cells;
  state.counters["ns_per_cell_step"] =
      1e9 * wall_s / (static_cast<double>(state.iterations()) * c.cells);
  if (c.scheme == PipeScheme::kCharacteristics) {
    state.counters["limit_ns_per_cell_step"] = ArithmeticLimitNsPerCellStep();
  }
}

// `effect`: an --effect spec added to the config's, or empty.
void BM_BergantSimpsonSevere(benchmark::State& state, int cells, std::string effect) {
  auto params =
      LoadRigConfig(std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/bergant-simpson-1999.pbtxt");
  if (!params.ok()) {
    state.SkipWithError(params.status().message().c_str());
    return;
  }
  if (!effect.empty()) {
    const Status status = ApplyEffectSpec(&*params, effect);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      return;
    }
  }
  SimulationOptions options;
  options.model = PipeModel::kLinear;
  options.cells = cells;
  InputSignals inputs;
  inputs.piston_position_m = [](double) { return 0.0; };
  inputs.rig = [](double) { return RigInputs{}; };
  std::vector<double> times;
  for (int k = 0; k <= 8000; ++k) times.push_back(k * 1e-4);
  long steps = 0;
  for (auto _ : state) {
    auto run = SimulateEach(*params, options, inputs, times, [](const RigSample&) {});
    if (!run.ok()) {
      state.SkipWithError(run.status().message().c_str());
      return;
    }
    steps = run->steps;
  }
  state.counters["steps"] = static_cast<double>(steps);
  state.counters["rtf"] = benchmark::Counter(0.8 * state.iterations(), benchmark::Counter::kIsRate);
}

void RegisterAll() {
  for (int cells : {16, 200}) {
    benchmark::RegisterBenchmark(("BM_BergantSimpsonSevere/N:" + std::to_string(cells)).c_str(),
                                 BM_BergantSimpsonSevere, cells, std::string())
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MinTime(0.5);
  }
  benchmark::RegisterBenchmark("BM_BergantSimpsonSevereVapour/N:200", BM_BergantSimpsonSevere, 200,
                               std::string("column_separation:gas_void_fraction=0"))
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->MinTime(0.5);
  benchmark::RegisterBenchmark("BM_BergantSimpsonSevereWeighted/N:200", BM_BergantSimpsonSevere,
                               200, std::string("weighted_friction"))
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->MinTime(0.5);
  const PipeModel models[] = {PipeModel::kQuasiLinear, PipeModel::kLinear};
  const PipeScheme schemes[] = {PipeScheme::kCharacteristics, PipeScheme::kMethodOfLines};
  const int cell_counts[] = {10, 100, 1000};
  for (PipeModel model : models) {
    for (PipeScheme scheme : schemes) {
      for (int cells : cell_counts) {
        const Case c{model, scheme, cells};
        auto* simulate = benchmark::RegisterBenchmark(("BM_Simulate20s/" + CaseName(c)).c_str(),
                                                      BM_Simulate20s, c);
        simulate->Unit(benchmark::kMillisecond)->UseRealTime();
        // The method of lines at N = 1000 takes seconds per run: one run is enough. The rest get
        // at least 0.5 s of runs each.
        if (scheme == PipeScheme::kMethodOfLines && cells >= 1000) {
          simulate->Iterations(1);
        } else {
          simulate->MinTime(0.5);
        }
        auto* step = benchmark::RegisterBenchmark(("BM_Step/" + CaseName(c)).c_str(), BM_Step, c);
        step->Unit(benchmark::kMicrosecond)->UseRealTime()->MinTime(0.2);
      }
    }
    const Case wide{model, PipeScheme::kCharacteristics, 10000};
    benchmark::RegisterBenchmark(("BM_Step/" + CaseName(wide)).c_str(), BM_Step, wide)
        ->Unit(benchmark::kMicrosecond)
        ->UseRealTime()
        ->MinTime(0.2);
  }
}

}  // namespace
}  // namespace mpdrig

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  mpdrig::RegisterAll();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
