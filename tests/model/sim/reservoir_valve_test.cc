// The reservoir - pipe - valve rig (model/params/rig_layout.h) on the column-separation apparatus
// of Bergant & Simpson (J. Hydraul. Eng. 125(8), 1999; docs/examples/bergant-simpson-1999.pbtxt),
// checked against closed forms of the water-hammer equations:
//   - Joukowsky: closing the valve raises p(L) by rho c V0, for 2L/c when the column does not
//     separate, and the pressure at the valve then swings with the period 4L/c;
//   - the first cavity at the valve, frictionless and level, instantaneous closure: the wave
//     solution. The cavity opens at 2L/c; while it lives each round trip 2L/c of the pipe changes
//     the column's velocity at the valve by 2 du, du = (p_R - p_v)/(rho c), from -(V0 - du), and
//     the cavity's volume integrates that velocity until it is 0 again. Its long-cavity limit is
//     the rigid-column estimate (Newton's law on the whole column, p_R pushing, p_v pulling):
//     T = 2 rho L V0 / (p_R - p_v - rho g dz), with quadratic friction f2 V|V| in closed form;
//   - mass: what the reservoir delivers less what the valve passes is the pipe's stored volume
//     change plus the cavities.
// The discrete gas cavity model (DGCM, column_separation's gas_void_fraction > 0), against the
// same closed forms as alpha_0 -> 0, against Wood's wave speed of a bubbly liquid,
//   1 / (rho c_m^2) = 1 / (rho c^2) + alpha / (p - p_v),   alpha = alpha_0 (p_0 - p_v) / (p - p_v),
// (the gas's own compressibility 1/p_g, isothermal, at its partial pressure p_g = p - p_v; the
// (1 - alpha) factors of the full formula change it by alpha, 1e-4 here), against mass balance,
// and on the grid: its later cavities and rebounds do not depend on it as the DVCM's do.
// The tests use the linear law (thesis 7.0), the literature's water-hammer equations, which is
// what `mpdrig simulate` runs this rig with.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "model/config/rig_config.h"
#include "model/effects/effect.h"
#include "model/sim/rig_simulator.h"
#include "tests/support/bergant_simpson.h"

namespace mpdrig {
namespace {

const std::string& kSevere = testing::kBergantSimpsonSevere;
const std::string& kModerate = testing::kBergantSimpsonModerate;
const auto Load = testing::LoadExampleRig;
// The closed forms of the discrete vapour cavity model, and what involves no cavity: the examples'
// discrete gas cavity model taken out.
const auto LoadVapour = testing::LoadExampleRigWithVapourCavities;

double VapourPressure(const RigParams& params) {
  const EffectSetting* cavities = params.FindEffect("column_separation");
  EXPECT_NE(cavities, nullptr);
  return cavities != nullptr && cavities->Find("vapour_pressure_pa") != nullptr
             ? *cavities->Find("vapour_pressure_pa")
             : 0.0;
}

double ReservoirPressure(const RigParams& params) {
  return params.atmospheric_pressure_pa +
         params.density_kgpm3 * params.gravity_mps2 * params.layout.reservoir_head_m;
}

// One run, every grid step.
struct Trace {
  double dt = 0.0;
  std::vector<double> time_s, valve_pa, inlet_m3ps, outlet_m3ps, cavity_m3, stored_m3, lowest_pa;
};

Trace RunRig(const RigParams& params, double duration_s, int cells = 200,
             PipeModel model = PipeModel::kLinear) {
  SimulationOptions options;
  options.model = model;
  options.cells = cells;
  Trace trace;
  const double length = params.pipe_length_m;
  trace.dt = testing::StepValveRig(params, options, duration_s, [&](const RigSimulator& sim) {
    const PipeSolver& pipe = sim.pipe();
    const RigSample sample = sim.Sample();
    trace.time_s.push_back(sim.time_s());
    trace.valve_pa.push_back(pipe.PressureAt(length));
    trace.inlet_m3ps.push_back(sample[Channel::kFT4]);
    trace.outlet_m3ps.push_back(sample[Channel::kFT1]);
    trace.cavity_m3.push_back(pipe.CavityVolumeM3());
    trace.stored_m3.push_back(pipe.StoredVolumeM3());
    double lowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= cells; ++i) lowest = std::min(lowest, pipe.PressureAt(i * length / cells));
    trace.lowest_pa.push_back(lowest);
  });
  return trace;
}

// The first interval [open, close) during which p(L) is held at p_v (within 1 Pa).
// The largest gap, up to `until_s`, between the liquid delivered (the trapezoidal sum of q_in -
// q_out) and the change of the stored volume less the vapour: mass balance.
double WorstMassImbalance(const Trace& trace, double until_s) {
  double delivered = 0.0, worst = 0.0;
  for (std::size_t k = 1; k < trace.time_s.size(); ++k) {
    delivered += 0.5 * trace.dt *
                 (trace.inlet_m3ps[k] + trace.inlet_m3ps[k - 1] - trace.outlet_m3ps[k] -
                  trace.outlet_m3ps[k - 1]);
    const double held = trace.stored_m3[k] - trace.stored_m3[0] - trace.cavity_m3[k];
    if (trace.time_s[k] <= until_s) worst = std::max(worst, std::abs(delivered - held));
  }
  return worst;
}

struct Hold {
  double open_s = -1.0;
  double close_s = -1.0;
};
Hold FirstHold(const Trace& trace, double p_v) {
  Hold hold;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    const bool held = trace.valve_pa[k] < p_v + 1.0;
    if (held && hold.open_s < 0.0) hold.open_s = trace.time_s[k];
    if (!held && hold.open_s >= 0.0) {
      hold.close_s = trace.time_s[k];
      break;
    }
  }
  return hold;
}

// The valve's cavity by the wave solution (header): opens at t_open, velocities at the valve
// -(V0 - (2k + 1) du) for the k-th round trip; returns its life.
double WaveSolutionCavityLife(double v0, double du, double round_trip_s) {
  double volume_per_area = 0.0;
  for (int k = 0; k < 1000; ++k) {
    const double away = v0 - (2 * k + 1) * du;  // > 0: the column leaves the valve
    const double after = volume_per_area + away * round_trip_s;
    if (after <= 0.0) return k * round_trip_s + volume_per_area / -away;
    volume_per_area = after;
  }
  return std::numeric_limits<double>::infinity();
}

// Rigid column with quadratic friction: leaving the valve, dv/dt = -a - k v^2 until it stops
// after atan(v0 sqrt(k/a)) / sqrt(a k) at x1 = ln(1 + k v0^2 / a) / (2k); returning, dv/dt =
// a - k v^2, x = ln(cosh(sqrt(a k) t)) / k. a: the net pressure force per unit mass of the column.
double RigidColumnCavityLife(double v0, double a, double k) {
  if (k == 0.0) return 2.0 * v0 / a;
  const double rate = std::sqrt(a * k);
  const double leaving = std::atan(v0 * std::sqrt(k / a)) / rate;
  const double distance = std::log(1.0 + k * v0 * v0 / a) / (2.0 * k);
  return leaving + std::acosh(std::exp(k * distance)) / rate;
}

RigParams FrictionlessLevelInstantaneous(const std::string& path, double v0) {
  RigParams params = LoadVapour(path);
  params.friction_f2_per_m = 0.0;
  params.pipe_elevation_gain_m = 0.0;
  params.layout.valve.closure_time_s = 1e-4;
  params.layout.steady_velocity_mps = v0;
  return params;
}

// Without column separation (V0 = 0.1 m/s: rho c V0 = 1.3 bar, less than p(L) - p_v = 1.9 bar)
// the valve's pressure rises by rho c V0, holds it for 2L/c, and swings with the period 4L/c.
TEST(ReservoirValve, JoukowskyRiseLastsTwoTravelTimesAndSwingsWithFour) {
  RigParams params = LoadVapour(kModerate);
  params.layout.steady_velocity_mps = 0.1;
  const Trace trace = RunRig(params, 0.6);
  const double c = params.wave_speed_mps;
  const double travel_s = params.pipe_length_m / c;
  const double p0 = trace.valve_pa.front();
  const double joukowsky = params.density_kgpm3 * c * 0.1;
  // The plateau between the end of the 9 ms closure and 2L/c.
  double plateau = 0.0;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    if (std::abs(trace.time_s[k] - 0.5 * (0.009 + 2 * travel_s)) < 0.5 * trace.dt) {
      plateau = trace.valve_pa[k] - p0;
    }
  }
  EXPECT_NEAR(plateau, joukowsky, 0.03 * joukowsky);
  EXPECT_GT(*std::min_element(trace.lowest_pa.begin(), trace.lowest_pa.end()),
            VapourPressure(params) + 1e4)
      << "no column separation in this case";
  // The valve's pressure is p0 + J r(t) while it closes (J = rho c V0, r the closure's ramp 0 ->
  // 1), then falls as p0 + J - 2J r(t - 2L/c) when the reflection returns, and swings between
  // p0 - J and p0 + J: the rise's midpoint (p0 + J/2) and the fall's (p0) are 2L/c apart, and the
  // crossings of p0 one way are 4L/c apart.
  const auto crossings = [&](double level, bool upwards, double after_s) {
    std::vector<double> times;
    for (std::size_t k = 1; k < trace.time_s.size(); ++k) {
      const double a = trace.valve_pa[k - 1] - level;
      const double b = trace.valve_pa[k] - level;
      const double t = trace.time_s[k - 1] + trace.dt * a / (a - b);
      if (t > after_s && (upwards ? (a < 0.0 && b >= 0.0) : (a >= 0.0 && b < 0.0))) {
        times.push_back(t);
      }
    }
    return times;
  };
  const std::vector<double> rise = crossings(p0 + 0.5 * joukowsky, true, 0.0);
  const std::vector<double> down = crossings(p0, false, 0.0);
  const std::vector<double> up = crossings(p0, true, travel_s);
  ASSERT_FALSE(rise.empty());
  ASSERT_GE(down.size(), 1u);
  ASSERT_GE(up.size(), 3u);
  // One grid step: the crossings are interpolated between steps of dt = L/(N c).
  EXPECT_NEAR(down[0] - rise[0], 2 * travel_s, trace.dt);
  // Friction (f2 V0 = 0.08 1/s) damps the swing and shifts its period by far less than 1 %.
  const double period = (up[2] - up[0]) / 2.0;
  EXPECT_NEAR(period, 4 * travel_s, 0.01 * 4 * travel_s);
}

// The severe case's plateau (rho c V0 = 18.4 bar at 1.4 m/s) before the column separates at 2L/c.
// Friction packs the line as the wave runs up the pipe (the plateau climbs 2 % in 2L/c): within
// 3 % (the tolerance) throughout.
TEST(ReservoirValve, SevereJoukowskyPlateau) {
  const RigParams params = Load(kSevere);
  const Trace trace = RunRig(params, 0.06);
  const double c = params.wave_speed_mps;
  const double joukowsky = params.density_kgpm3 * c * params.layout.steady_velocity_mps;
  const double p0 = trace.valve_pa.front();
  int checked = 0;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    const double t = trace.time_s[k];
    if (t < 0.010 || t > 2 * params.pipe_length_m / c) continue;
    EXPECT_NEAR(trace.valve_pa[k] - p0, joukowsky, 0.03 * joukowsky) << "t = " << t;
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

// Frictionless, level, instantaneous closure: the first cavity at the valve opens at 2L/c and
// lives as long as the wave solution says; in the severe case that is the rigid-column estimate.
TEST(ReservoirValve, FirstCavityLivesAsTheWaveSolutionAndTheRigidColumnSay) {
  for (const auto& [path, v0] : {std::pair{kSevere, 1.4}, std::pair{kModerate, 0.3}}) {
    SCOPED_TRACE("V0 = " + std::to_string(v0));
    const RigParams params = FrictionlessLevelInstantaneous(path, v0);
    const double c = params.wave_speed_mps;
    const double rho = params.density_kgpm3;
    const double p_v = VapourPressure(params);
    const double round_trip = 2 * params.pipe_length_m / c;
    const Trace trace = RunRig(params, 0.5);
    const Hold hold = FirstHold(trace, p_v);
    ASSERT_GT(hold.close_s, 0.0);
    EXPECT_NEAR(hold.open_s, round_trip, 2 * trace.dt);
    const double du = (ReservoirPressure(params) - p_v) / (rho * c);
    const double life = WaveSolutionCavityLife(v0, du, round_trip);
    EXPECT_NEAR(hold.close_s - hold.open_s, life, 0.01 * life + 2 * trace.dt);
    // Only the valve's cavity: the liquid balances to round-off while it lives, and its collapse
    // leaves at most A dt |du| <= A dt 2 V0 (characteristics_solver.h).
    EXPECT_LT(WorstMassImbalance(trace, hold.close_s + trace.dt),
              params.PipeAreaM2() * trace.dt * 2.0 * v0);
    if (v0 > 1.0) {
      const double rigid = RigidColumnCavityLife(
          v0, (ReservoirPressure(params) - p_v) / (rho * params.pipe_length_m), 0.0);
      EXPECT_NEAR(hold.close_s - hold.open_s, rigid, 0.02 * rigid);
    }
  }
}

// The same with the quasi-linear law, the NTNU rig's default. Its characteristics move at u +- c,
// so the foot of the one arriving next to the valve can lie beyond the valve's node; it was read
// there from the valve's side (velocity 0) and the cavity collapsed after 2L/c (57 ms instead of
// 0.33 s). The law's odd-even pattern in the vapour zone (docs/bergant-simpson.md) shortens the
// cavity by 6 %: within 10 %.
TEST(ReservoirValve, FirstCavityWithTheQuasiLinearLawOutlivesItsRoundTrip) {
  const RigParams params = FrictionlessLevelInstantaneous(kSevere, 1.4);
  const double c = params.wave_speed_mps;
  const double p_v = VapourPressure(params);
  const double round_trip = 2 * params.pipe_length_m / c;
  const Trace trace = RunRig(params, 0.5, 200, PipeModel::kQuasiLinear);
  const Hold hold = FirstHold(trace, p_v);
  ASSERT_GT(hold.close_s, 0.0);
  const double du = (ReservoirPressure(params) - p_v) / (params.density_kgpm3 * c);
  const double life = WaveSolutionCavityLife(1.4, du, round_trip);
  EXPECT_NEAR(hold.close_s - hold.open_s, life, 0.1 * life);
}

// The severe case as the example config has it (friction f2 = 0.557 1/m, the pipe rising 2.03 m
// to the valve), closed in 0.1 ms: the rigid column with quadratic friction and its weight. The
// rigid column stops at once; the pipe's column stops in steps of 2L/c, and the reservoir's
// pressure reaches it with its friction already at the reversed flow's: within 5 %.
TEST(ReservoirValve, FirstCavityWithFrictionAndSlopeAsTheRigidColumn) {
  RigParams params = LoadVapour(kSevere);
  params.layout.valve.closure_time_s = 1e-4;
  const double rho = params.density_kgpm3;
  const double p_v = VapourPressure(params);
  const Trace trace = RunRig(params, 0.5);
  const Hold hold = FirstHold(trace, p_v);
  ASSERT_GT(hold.close_s, 0.0);
  const double net =
      ReservoirPressure(params) - p_v - rho * params.gravity_mps2 * params.pipe_elevation_gain_m;
  const double rigid =
      RigidColumnCavityLife(1.4, net / (rho * params.pipe_length_m), params.friction_f2_per_m);
  EXPECT_NEAR(hold.close_s - hold.open_s, rigid, 0.05 * rigid);
}

// The severe and the moderate case as the example configs have them (9 ms closure): the first
// cavity's life does not depend on the grid (16 to 200 cells: the DVCM's later collapses do, see
// docs/bergant-simpson.md), pressures never fall below p_v, and the liquid is conserved: what the
// reservoir delivered less what the valve passed is the stored volume's change plus the cavities.
TEST(ReservoirValve, ExampleCasesFirstCavityIsGridIndependentAndMassBalances) {
  for (const std::string& path : {kSevere, kModerate}) {
    SCOPED_TRACE(path);
    const RigParams params = LoadVapour(path);
    const double p_v = VapourPressure(params);
    std::vector<double> lives;
    for (int cells : {16, 50, 200}) {
      const Trace trace = RunRig(params, 0.5, cells);
      const Hold hold = FirstHold(trace, p_v);
      ASSERT_GT(hold.close_s, 0.0) << cells << " cells";
      lives.push_back(hold.close_s - hold.open_s);
      EXPECT_GT(*std::min_element(trace.lowest_pa.begin(), trace.lowest_pa.end()), p_v - 1.0);
      // Mass: the trapezoidal sum of q_in - q_out against the stored volume's change less the
      // vapour (the liquid fills the pipe but for its cavities). Each collapse leaves at most
      // A dt |du| (characteristics_solver.h); the 9 ms closure opens many small cavities near
      // the valve (docs/bergant-simpson.md) and their collapses add up. Measured, as a share of
      // the volume the steady flow moves in 0.5 s: severe 0.8, 1.6, 2.8 %, moderate 2.4, 2.3,
      // 2.4 % at 16, 50, 200 cells; the bound 4 % guards against a worse leak.
      const double v0 = params.layout.steady_velocity_mps;
      EXPECT_LT(WorstMassImbalance(trace, trace.time_s.back()),
                0.04 * params.PipeAreaM2() * v0 * trace.time_s.back())
          << cells << " cells";
    }
    for (double life : lives) EXPECT_NEAR(life, lives.back(), 0.05 * lives.back());
  }
}

// The config: the three blocks go together, one closure law, and a V0 the reservoir can drive;
// each error names the file, line and column.
TEST(ReservoirValve, ConfigErrorsNameTheirPlace) {
  const auto error = [](const std::string& text) {
    auto parsed = ParseRigConfig(text, "rig.pbtxt");
    EXPECT_FALSE(parsed.ok()) << text;
    return parsed.ok() ? std::string() : parsed.status().message();
  };
  EXPECT_EQ(error("pipe_length_m: 37.23\nvalve { closure_time_s: 0.009 }\n")
                .rfind("rig.pbtxt:2:1: `reservoir`, `valve` and `steady_flow` go together", 0),
            0u);
  EXPECT_EQ(error("reservoir { head_m: 22 }\nvalve { closure_time_s: 0.009 point { time_s: 0 "
                  "opening: 1 } }\nsteady_flow { velocity_mps: 1 }\n")
                .rfind("rig.pbtxt:2:1: give the valve either", 0),
            0u);
  EXPECT_EQ(
      error("reservoir { head_m: 22 }\nvalve {\n  point { time_s: 0 opening: 1 }\n  point "
            "{ time_s: 0 opening: 0 }\n}\nsteady_flow { velocity_mps: 1 }\n")
          .rfind("rig.pbtxt:4:3: valve opening point 1: times must be strictly increasing", 0),
      0u);
  EXPECT_EQ(error("reservoir { head_m: 22 }\nvalve { closure_time_s: 0 }\nsteady_flow { "
                  "velocity_mps: 1 }\n")
                .rfind("rig.pbtxt:2:1: valve closure_time_s must be", 0),
            0u);
  // A V0 the head cannot drive through the pipe's friction: refused when the rig is built.
  RigParams params = Load(kSevere);
  params.layout.steady_velocity_mps = 20.0;
  auto sim = RigSimulator::Create(params, SimulationOptions{}, RigInputs{});
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.status().message().find("no steady flow of 20 m/s"), std::string::npos)
      << sim.status().message();
  // The configs write back as they were read.
  auto again = ParseRigConfig(FormatRigConfig(params), "round_trip.pbtxt");
  ASSERT_TRUE(again.ok()) << again.status().message();
  EXPECT_EQ(again->layout.Describe(), params.layout.Describe());
}

// The valve's closure law: tau = (1 - (t - t_s)/t_c)^m, or linear between points.
TEST(ReservoirValve, ClosureLaw) {
  ValveClosure valve;
  valve.start_s = 0.1;
  valve.closure_time_s = 0.01;
  valve.exponent = 2.0;
  EXPECT_EQ(valve.RelativeOpening(0.0), 1.0);
  EXPECT_NEAR(valve.RelativeOpening(0.105), 0.25, 1e-12);
  EXPECT_EQ(valve.RelativeOpening(0.2), 0.0);
  EXPECT_DOUBLE_EQ(valve.ClosedAtS(), 0.11);
  valve.points = {{0.0, 1.0}, {0.004, 0.2}, {0.009, 0.0}};
  EXPECT_NEAR(valve.RelativeOpening(0.002), 0.6, 1e-12);
  EXPECT_NEAR(valve.RelativeOpening(0.0065), 0.1, 1e-12);
  EXPECT_EQ(valve.RelativeOpening(1.0), 0.0);
  EXPECT_DOUBLE_EQ(valve.ClosedAtS(), 0.009);
}

// --- The discrete gas cavity model -------------------------------------------------------------

// The config's column separation with free gas alpha_0 at p_0 (the literature's usual alpha_0 =
// 1e-7 at the reservoir's pressure: Bergant & Simpson 1999).
RigParams WithGas(RigParams params, double alpha_0, double p_0) {
  EffectSetting* cavities = params.FindEffect("column_separation");
  EXPECT_NE(cavities, nullptr);
  if (cavities == nullptr) return params;
  cavities->Set("gas_void_fraction", alpha_0);
  cavities->Set("gas_reference_pressure_pa", p_0);
  return params;
}

RigParams WithGas(const RigParams& params, double alpha_0) {
  return WithGas(params, alpha_0, ReservoirPressure(params));
}

// The pressure at the valve at or within 1 kPa of p_v: a cavity there (the DVCM holds p_v exactly;
// the DGCM's gas holds p_v + G/V, 1 kPa once the cavity is 1e-7 of the node's volume at 1e-7).
constexpr double kCavityMarginPa = 1e3;

// The cavities at the valve longer than 20 ms (the 9 ms closure opens short ones) and the largest
// pressure in the round trip 2L/c after each collapse (its rebound).
struct ValveEvents {
  std::vector<double> lives_s, rebounds_pa;
  double largest_pa = 0.0;
};
ValveEvents EventsAtTheValve(const Trace& trace, double p_v, double round_trip_s) {
  ValveEvents events;
  const std::size_t n = trace.time_s.size();
  for (std::size_t k = 0; k < n; ++k) {
    events.largest_pa = std::max(events.largest_pa, trace.valve_pa[k]);
    if (trace.valve_pa[k] >= p_v + kCavityMarginPa) continue;
    const std::size_t open = k;
    while (k < n && trace.valve_pa[k] < p_v + kCavityMarginPa) ++k;
    if (k == n) break;
    const double close_s = trace.time_s[k];
    if (close_s - trace.time_s[open] <= 0.02) continue;
    double rebound = 0.0;
    for (std::size_t j = k; j < n && trace.time_s[j] <= close_s + round_trip_s; ++j) {
      rebound = std::max(rebound, trace.valve_pa[j]);
    }
    events.lives_s.push_back(close_s - trace.time_s[open]);
    events.rebounds_pa.push_back(rebound);
  }
  return events;
}

// The tables' cells of the first two cavities (life, rebound) and the largest pressure, in barg.
void PrintEvents(const ValveEvents& events, double atmospheric_pa) {
  for (std::size_t j = 0; j < 2; ++j) {
    if (j < events.lives_s.size()) {
      std::printf(" | %.3f s | %.1f barg", events.lives_s[j],
                  (events.rebounds_pa[j] - atmospheric_pa) / 1e5);
    } else {
      std::printf(" | - | -");
    }
  }
  std::printf(" | %.1f barg", (events.largest_pa - atmospheric_pa) / 1e5);
}

// As alpha_0 -> 0 the DGCM's cavity is the DVCM's: frictionless, level, instantaneous closure,
// the first cavity at the valve lives as the wave solution says (the DVCM's test above, the same
// tolerance), and with the example's friction and rise as the DVCM's; the example's severe
// plateau is Joukowsky's (3 %).
TEST(ReservoirValveGas, TendsToTheVapourCavitiesAsTheGasVanishes) {
  for (const auto& [path, v0] : {std::pair{kSevere, 1.4}, std::pair{kModerate, 0.3}}) {
    SCOPED_TRACE("V0 = " + std::to_string(v0));
    const RigParams params = WithGas(FrictionlessLevelInstantaneous(path, v0), 1e-9);
    const double c = params.wave_speed_mps;
    const double p_v = VapourPressure(params);
    const double round_trip = 2 * params.pipe_length_m / c;
    const Trace trace = RunRig(params, 0.5);
    const ValveEvents events = EventsAtTheValve(trace, p_v, round_trip);
    ASSERT_FALSE(events.lives_s.empty());
    const double du = (ReservoirPressure(params) - p_v) / (params.density_kgpm3 * c);
    const double life = WaveSolutionCavityLife(v0, du, round_trip);
    EXPECT_NEAR(events.lives_s[0], life, 0.01 * life + 2 * trace.dt);
    std::printf("V0 %.1f: first cavity %.4f s, wave solution %.4f s\n", v0, events.lives_s[0],
                life);
  }
  // With the example's friction and rise, closed in 0.1 ms: the DVCM's cavity (0.333 s, the
  // rigid column's 0.342 s within 5 %, FirstCavityWithFrictionAndSlopeAsTheRigidColumn) within
  // 1 % + 2 dt.
  RigParams fast = LoadVapour(kSevere);
  fast.layout.valve.closure_time_s = 1e-4;
  const double round_trip = 2 * fast.pipe_length_m / fast.wave_speed_mps;
  const Trace vapour = RunRig(fast, 0.5);
  const Trace gas = RunRig(WithGas(fast, 1e-9), 0.5);
  const ValveEvents vapour_events = EventsAtTheValve(vapour, VapourPressure(fast), round_trip);
  const ValveEvents gas_events = EventsAtTheValve(gas, VapourPressure(fast), round_trip);
  ASSERT_FALSE(vapour_events.lives_s.empty());
  ASSERT_FALSE(gas_events.lives_s.empty());
  EXPECT_NEAR(gas_events.lives_s[0], vapour_events.lives_s[0],
              0.01 * vapour_events.lives_s[0] + 2 * gas.dt);
  std::printf("0.1 ms closure with friction and rise: first cavity %.4f s (DVCM %.4f s)\n",
              gas_events.lives_s[0], vapour_events.lives_s[0]);
  const RigParams params = WithGas(Load(kSevere), 1e-7);
  const Trace trace = RunRig(params, 0.06);
  const double c = params.wave_speed_mps;
  const double joukowsky = params.density_kgpm3 * c * params.layout.steady_velocity_mps;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    if (trace.time_s[k] < 0.010 || trace.time_s[k] > 2 * params.pipe_length_m / c) continue;
    EXPECT_NEAR(trace.valve_pa[k] - trace.valve_pa.front(), joukowsky, 0.03 * joukowsky);
  }
}

// With more gas the liquid is a bubbly mixture: level, frictionless, V0 = 3 mm/s (no cavity; the
// swing rho c_m V0 = 0.03 bar moves p_g by 1 %, the gas's share of the compliance by 0.5 %, c_m by
// 0.3 % at its extremes, which average out over a period), alpha_0 = 1e-4 at the reservoir's
// pressure: the valve's pressure swings with the period 4L/c_m of Wood's wave speed, and
// closing the valve raises it by rho c_m V0. The period is measured between crossings two
// periods apart, each interpolated to a fraction of dt: within 0.5 %; the rise within 3 %.
TEST(ReservoirValveGas, WoodsWaveSpeedInTheBubblyLiquid) {
  RigParams params = WithGas(Load(kModerate), 1e-4);
  params.friction_f2_per_m = 0.0;
  params.pipe_elevation_gain_m = 0.0;
  const double v0 = 0.003;
  params.layout.steady_velocity_mps = v0;
  const double rho = params.density_kgpm3;
  const double c = params.wave_speed_mps;
  const double p_g = ReservoirPressure(params) - VapourPressure(params);
  const double c_m = 1.0 / std::sqrt(rho * (1.0 / (rho * c * c) + 1e-4 / p_g));
  const Trace trace = RunRig(params, 0.8);
  const double p0 = trace.valve_pa.front();
  std::vector<double> up;
  for (std::size_t k = 1; k < trace.time_s.size(); ++k) {
    const double a = trace.valve_pa[k - 1] - p0;
    const double b = trace.valve_pa[k] - p0;
    if (trace.time_s[k] > params.pipe_length_m / c_m && a < 0.0 && b >= 0.0) {
      up.push_back(trace.time_s[k - 1] + trace.dt * a / (a - b));
    }
  }
  ASSERT_GE(up.size(), 3u);
  const double period = (up[2] - up[0]) / 2.0;
  EXPECT_NEAR(period, 4 * params.pipe_length_m / c_m, 0.005 * 4 * params.pipe_length_m / c_m);
  EXPECT_GT(c_m, 0.8 * c) << "the check needs the gas to matter";
  std::printf("period %.5f s, 4L/c_m %.5f s (c_m %.1f m/s)\n", period,
              4 * params.pipe_length_m / c_m, c_m);
  double plateau = 0.0;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    if (std::abs(trace.time_s[k] - 0.5 * (0.009 + 2 * params.pipe_length_m / c_m)) <
        0.5 * trace.dt) {
      plateau = trace.valve_pa[k] - p0;
    }
  }
  EXPECT_NEAR(plateau, rho * c_m * v0, 0.03 * rho * c_m * v0);
  std::printf("rise %.1f Pa, rho c_m V0 %.1f Pa\n", plateau, rho * c_m * v0);
}

// Mass: what the reservoir delivered less what the valve passed is the stored liquid's change
// less the change of the gas and cavity volume. The DGCM has no collapse that drops volume (the
// DVCM's leaves up to A dt |du| each, 1-3 % of the flow's volume on these cases). Frictionless
// and level the balance is the scheme's round-off (measured < 1e-12 of the volume the steady
// flow moves in the run; bound 1e-9). With friction each side of a node takes its own share
// h lambda / 2 of the new point's friction, so a node's liquid balance is off by that share of
// its jump: first order in dt, measured 7e-6 of the moved volume at 32 cells, 1.2e-6 at 200;
// bound 1e-4, a hundredth of the DVCM's leak.
TEST(ReservoirValveGas, MassBalances) {
  for (const std::string& path : {kSevere, kModerate}) {
    SCOPED_TRACE(path);
    for (int cells : {32, 200}) {
      for (const bool friction : {false, true}) {
        RigParams params = WithGas(Load(path), 1e-7);
        if (!friction) {
          params.friction_f2_per_m = 0.0;
          params.pipe_elevation_gain_m = 0.0;
        }
        const Trace trace = RunRig(params, 0.5, cells);
        double delivered = 0.0, worst = 0.0;
        for (std::size_t k = 1; k < trace.time_s.size(); ++k) {
          delivered += 0.5 * trace.dt *
                       (trace.inlet_m3ps[k] + trace.inlet_m3ps[k - 1] - trace.outlet_m3ps[k] -
                        trace.outlet_m3ps[k - 1]);
          const double held =
              trace.stored_m3[k] - trace.stored_m3[0] - (trace.cavity_m3[k] - trace.cavity_m3[0]);
          worst = std::max(worst, std::abs(delivered - held));
        }
        const double moved = params.PipeAreaM2() * params.layout.steady_velocity_mps * 0.5;
        std::printf("%d cells, friction %d: imbalance %.2e of the moved volume\n", cells, friction,
                    worst / moved);
        EXPECT_LT(worst, (friction ? 1e-4 : 1e-9) * moved)
            << cells << " cells, friction " << friction;
        EXPECT_GT(*std::min_element(trace.lowest_pa.begin(), trace.lowest_pa.end()),
                  VapourPressure(params));
      }
    }
  }
}

// The grid: the DGCM's (alpha_0 = 1e-7 at the reservoir's pressure) first two cavities at the
// valve and their rebounds at 32 and 256 cells. The DVCM's second cavity and rebounds change by
// a factor 2-3 between these grids (docs/bergant-simpson.md); the DGCM's must agree within what
// the grid's own resolution of a 9 ms closure and a collapse allows: cavity lives within 5 %,
// rebounds within 10 %, the largest pressure within 10 %.
// MPDRIG_BERGANT_TABLES=1 prints the docs' tables (32-256 cells, DVCM and DGCM, both cases).
TEST(ReservoirValveGas, LaterCavitiesDoNotDependOnTheGrid) {
  const auto row = [](const std::string& path, const RigParams& params, int cells) {
    const Trace trace = RunRig(params, 0.8, cells);
    const ValveEvents events = EventsAtTheValve(trace, VapourPressure(params),
                                                2 * params.pipe_length_m / params.wave_speed_mps);
    std::printf("%-9s %4d", path == kSevere ? "severe" : "moderate", cells);
    PrintEvents(events, params.atmospheric_pressure_pa);
    std::printf("\n");
    return events;
  };
  if (std::getenv("MPDRIG_BERGANT_TABLES") != nullptr) {
    for (const std::string& path : {kSevere, kModerate}) {
      for (double alpha_0 : {0.0, 1e-7}) {
        std::printf("%s\n", alpha_0 > 0.0 ? "DGCM alpha_0 = 1e-7" : "DVCM");
        for (int cells : {32, 64, 128, 256}) {
          row(path, WithGas(Load(path), alpha_0), cells);
        }
      }
    }
  }
  const RigParams params = WithGas(Load(kSevere), 1e-7);
  const ValveEvents coarse = row(kSevere, params, 32);
  const ValveEvents fine = row(kSevere, params, 256);
  ASSERT_GE(coarse.lives_s.size(), 2u);
  ASSERT_GE(fine.lives_s.size(), 2u);
  const double atm = params.atmospheric_pressure_pa;
  for (std::size_t j = 0; j < 2; ++j) {
    EXPECT_NEAR(coarse.lives_s[j], fine.lives_s[j], 0.05 * fine.lives_s[j]) << "cavity " << j;
    EXPECT_NEAR(coarse.rebounds_pa[j] - atm, fine.rebounds_pa[j] - atm,
                0.1 * (fine.rebounds_pa[j] - atm))
        << "rebound " << j;
  }
  EXPECT_NEAR(coarse.largest_pa - atm, fine.largest_pa - atm, 0.1 * (fine.largest_pa - atm));
}

// --scheme mol has no cavities: the DGCM is refused with a message that names it (on the NTNU
// rig: mol refuses this rig's reservoir first).
TEST(ReservoirValveGas, MethodOfLinesRefusesIt) {
  RigParams params;
  ASSERT_TRUE(ApplyEffectSpec(&params, "column_separation:gas_void_fraction=1e-7").ok());
  SimulationOptions options;
  options.scheme = PipeScheme::kMethodOfLines;
  auto sim = RigSimulator::Create(params, options, RigInputs{});
  ASSERT_FALSE(sim.ok());
  EXPECT_NE(sim.status().message().find("gas_void_fraction"), std::string::npos)
      << sim.status().message();
}

// --- Unsteady friction on this rig ----------------------------------------------------------

// The theoretical Brunone coefficient k* = sqrt(C*) / 2 from Vardy & Brown's shear decay
// coefficient: C* = 0.00476 laminar (Re < 2000), 7.41 / Re^(log10(14.3 / Re^0.05)) turbulent.
double VardyBrownK(double reynolds) {
  const double c_star =
      reynolds < 2000.0 ? 0.00476
                        : 7.41 / std::pow(reynolds, std::log10(14.3 / std::pow(reynolds, 0.05)));
  return std::sqrt(c_star) / 2.0;
}

// Water at 15 degC (docs/bergant-simpson.md).
constexpr double kKinematicViscosity = 1.139e-6;

double ReynoldsNumber(const RigParams& params) {
  return params.layout.steady_velocity_mps * 2.0 * params.pipe_inner_radius_m / kKinematicViscosity;
}

RigParams WithUnsteadyFriction(RigParams params, double k, bool variant) {
  EXPECT_TRUE(ApplyEffectSpec(&params, "unsteady_friction:k=" + std::to_string(k) +
                                           ",convective_form=" + (variant ? "1" : "0"))
                  .ok());
  return params;
}

// The swing without cavities (V0 = 0.1 m/s, Re = 1940, laminar: k* = sqrt(0.00476)/2 = 0.0345).
// Quasi-steady friction alone keeps 98 % of the swing over four periods. The default form,
// c sgn(u) |u_x| (= c sgn(u u_x) u_x), damps it at k* (measured 75 %: below 93 %). The variant
// c sgn(u u_x) |u_x| (= c sgn(u) u_x) does not damp it beyond the quasi-steady friction (98 %,
// within 2 %): every front of this swing travels on a characteristic that the variant's
// bracket either follows (no term) or crosses with alternating sign. A guard on both behaviours.
TEST(ReservoirValveUnsteadyFriction, DampsTheJoukowskySwingAtVardyBrownsK) {
  RigParams base = LoadVapour(kModerate);
  base.layout.steady_velocity_mps = 0.1;
  const double k = VardyBrownK(ReynoldsNumber(base));
  EXPECT_NEAR(k, 0.0345, 0.0005);
  // The rig's own flows: severe Re = 27 160, moderate 5 820.
  EXPECT_NEAR(VardyBrownK(ReynoldsNumber(Load(kSevere))), 0.0116, 0.0002);
  EXPECT_NEAR(VardyBrownK(ReynoldsNumber(Load(kModerate))), 0.0206, 0.0002);
  const double period = 4 * base.pipe_length_m / base.wave_speed_mps;
  // The swing's amplitude in the first and the fifth period: half the range of p(L) there.
  const auto amplitudes = [&](const RigParams& params) {
    const Trace trace = RunRig(params, 5.5 * period);
    std::vector<double> lo(6, std::numeric_limits<double>::infinity()), hi(6, -lo[0]);
    for (std::size_t j = 0; j < trace.time_s.size(); ++j) {
      const int m = static_cast<int>((trace.time_s[j] - 0.02) / period);
      if (trace.time_s[j] < 0.02 || m > 5) continue;
      lo[m] = std::min(lo[m], trace.valve_pa[j]);
      hi[m] = std::max(hi[m], trace.valve_pa[j]);
    }
    return std::pair{0.5 * (hi[0] - lo[0]), 0.5 * (hi[4] - lo[4])};
  };
  const auto [qs0, qs4] = amplitudes(base);
  std::printf("k* = %.4f; swing after 4 periods: quasi-steady %.3f", k, qs4 / qs0);
  for (const bool variant : {false, true}) {
    const auto [a0, a4] = amplitudes(WithUnsteadyFriction(base, k, variant));
    std::printf(", %s %.3f", variant ? "sgn(u u_x)" : "sgn(u)", a4 / a0);
    if (variant) {
      EXPECT_NEAR(a4 / a0, qs4 / qs0, 0.02);
    } else {
      EXPECT_LT(a4 / a0, qs4 / qs0 - 0.05);
    }
  }
  std::printf("\n");
}

// MPDRIG_BERGANT_TABLES=1: the docs' table of both cases with unsteady friction at k* (both
// forms), DVCM and DGCM, 32 and 200 cells.
TEST(ReservoirValveUnsteadyFriction, TablesAtVardyBrownsK) {
  if (std::getenv("MPDRIG_BERGANT_TABLES") == nullptr) {
    GTEST_SKIP() << "prints docs/bergant-simpson.md's tables only, asserts nothing: "
                    "MPDRIG_BERGANT_TABLES=1 runs it";
  }
  for (const std::string& path : {kSevere, kModerate}) {
    const RigParams base = Load(path);
    const double k = VardyBrownK(ReynoldsNumber(base));
    for (int form = -1; form <= 1; ++form) {
      for (double alpha_0 : {0.0, 1e-7}) {
        for (int cells : {32, 200}) {
          RigParams params = WithGas(base, alpha_0);  // 0: the DVCM
          if (form >= 0) params = WithUnsteadyFriction(params, k, form == 1);
          const Trace trace = RunRig(params, 0.8, cells);
          const ValveEvents events = EventsAtTheValve(
              trace, VapourPressure(params), 2 * params.pipe_length_m / params.wave_speed_mps);
          std::printf("%s | %s | %s | %d", path == kSevere ? "severe" : "moderate",
                      form < 0 ? "none" : (form == 1 ? "sgn(u u_x)" : "sgn(u)"),
                      alpha_0 > 0.0 ? "DGCM" : "DVCM", cells);
          PrintEvents(events, params.atmospheric_pressure_pa);
          std::printf("   (k %.4f)\n", k);
        }
      }
    }
  }
}

// --- Convolution unsteady friction (weighted_friction) on this rig ---------------------------

// MPDRIG_BERGANT_TABLES=1: docs/bergant-simpson.md's table of both cases with quasi-steady
// friction, Brunone's model at k* (the default form) and the convolution (weighted_friction at its
// defaults: Vardy & Brown's weighting function at the initial flow's Re, 32 exponentials), DVCM
// and DGCM, 32 and 200 cells: the first two cavities and their rebounds, every rebound in 0.8 s,
// the largest pressure in 0.6-0.8 s and in all 0.8 s.
TEST(ReservoirValveWeightedFriction, Tables) {
  if (std::getenv("MPDRIG_BERGANT_TABLES") == nullptr) {
    GTEST_SKIP() << "prints docs/bergant-simpson.md's table only, asserts nothing: "
                    "MPDRIG_BERGANT_TABLES=1 runs it";
  }
  const char* const frictions[] = {"quasi-steady", "Brunone k*", "convolution"};
  for (const std::string& path : {kSevere, kModerate}) {
    const RigParams base = Load(path);
    const double k = VardyBrownK(ReynoldsNumber(base));
    for (int friction = 0; friction < 3; ++friction) {
      for (double alpha_0 : {0.0, 1e-7}) {
        for (int cells : {32, 200}) {
          RigParams params = WithGas(base, alpha_0);  // 0: the DVCM
          if (friction == 1) params = WithUnsteadyFriction(params, k, false);
          if (friction == 2) {
            EXPECT_TRUE(ApplyEffectSpec(&params, "weighted_friction").ok());
          }
          const Trace trace = RunRig(params, 0.8, cells);
          const ValveEvents events = EventsAtTheValve(
              trace, VapourPressure(params), 2 * params.pipe_length_m / params.wave_speed_mps);
          const double atm = params.atmospheric_pressure_pa;
          double late = 0.0;
          for (std::size_t j = 0; j < trace.time_s.size(); ++j) {
            if (trace.time_s[j] >= 0.6) late = std::max(late, trace.valve_pa[j]);
          }
          std::printf("%s | %s | %s | %d", path == kSevere ? "severe" : "moderate",
                      frictions[friction], alpha_0 > 0.0 ? "DGCM" : "DVCM", cells);
          PrintEvents(events, atm);
          std::printf(" | ");
          for (std::size_t j = 0; j < events.rebounds_pa.size(); ++j) {
            std::printf("%s%.1f", j == 0 ? "" : ", ", (events.rebounds_pa[j] - atm) / 1e5);
          }
          std::printf(" | %.1f barg\n", (late - atm) / 1e5);
        }
      }
    }
  }
}

// --- Against the measured record ---------------------------------------------------------------

// The severe case's measured pressure at the valve: Bergant & Simpson's record as He, Li & Guo
// reproduce it (Processes 13(11), 3510, 2025, open access, Fig. 4: the experiment, V0 = 1.4 m/s),
// read from the digitisation of that figure published with the RTHYM-MOC project (GitHub
// jlillywh/RTHYM-MOC, validation/datasets/bergant_adelaide/severe_valve_trace_reference.csv:
// WebPlotDigitizer, 600 points). Its pressure axis is offset: the cavities read -16 and -22 kPa,
// where they hold the vapour pressure, 2 kPa absolute. So every level here is taken above the
// cavity's level, p - p_v, which needs neither the axis's offset nor whether it is gauge or
// absolute. docs/bergant-simpson.md lists the points each number is read from.
struct SevereRecord {
  double plateau_over_pv_pa;           // the mean 10-55 ms: 2083.5 kPa, the cavity's level -15.6
  double first_open_s, first_close_s;  // the cavity's level reached; the rise begins
  double first_rebound_over_pv_pa;     // 2035.4 kPa at 0.433 s, the first cavity's level -15.6
  double second_open_s, second_close_s;
  double second_rebound_over_pv_pa;  // 1870.9 kPa at 0.778 s, the second cavity's level -21
};
constexpr SevereRecord kSevereRecord{2.099e6, 0.0625, 0.3805, 2.051e6, 0.4436, 0.7165, 1.892e6};

// What a model of the severe case says of the record's features (lives and rebounds of the
// first two cavities longer than 20 ms, levels above p_v), as shares of the record's.
struct RecordDeviations {
  double plateau = 0.0, first_life = 0.0, first_rebound = 0.0, second_life = 0.0,
         second_rebound = 0.0;
  bool two_cavities = false;
};
RecordDeviations AgainstTheRecord(const RigParams& params, int cells) {
  const double p_v = VapourPressure(params);
  const Trace trace = RunRig(params, 0.8, cells);
  const ValveEvents events =
      EventsAtTheValve(trace, p_v, 2 * params.pipe_length_m / params.wave_speed_mps);
  RecordDeviations deviations;
  double plateau = 0.0;
  int samples = 0;
  for (std::size_t k = 0; k < trace.time_s.size(); ++k) {
    if (trace.time_s[k] < 0.010 || trace.time_s[k] > 0.055) continue;
    plateau += trace.valve_pa[k] - p_v;
    ++samples;
  }
  const SevereRecord& r = kSevereRecord;
  deviations.plateau = plateau / std::max(samples, 1) / r.plateau_over_pv_pa - 1.0;
  deviations.two_cavities = events.lives_s.size() >= 2;
  if (!deviations.two_cavities) return deviations;
  deviations.first_life = events.lives_s[0] / (r.first_close_s - r.first_open_s) - 1.0;
  deviations.first_rebound = (events.rebounds_pa[0] - p_v) / r.first_rebound_over_pv_pa - 1.0;
  deviations.second_life = events.lives_s[1] / (r.second_close_s - r.second_open_s) - 1.0;
  deviations.second_rebound = (events.rebounds_pa[1] - p_v) / r.second_rebound_over_pv_pa - 1.0;
  return deviations;
}

// The severe example as it is configured (the DGCM at 1e-7, quasi-steady friction, 200 cells)
// against the record. The tolerances are what the record's own statement of its inputs allows,
// not what this model reaches:
//   - a cavity's life is the time the column takes to stop and come back, proportional to V0
//     over the net pressure that drives it back (the rigid column, above); "1.4 m/s" and "22 m"
//     are given to two digits, +-0.05 m/s (3.6 % of V0) and +-0.5 m (1.7 % of the 30 m of
//     pressure head, p_R - p_v less the rise, that drives the column), and the digitised record
//     places each transition within about 3 ms (0.9 %): together (root of the sum of squares)
//     4.0 % of the first life. The second cavity inherits the first's uncertainty through the
//     velocity the first collapse leaves and adds the first cycle's friction, which the
//     literature's models disagree on most (unsteady friction shortens the later cavities): twice
//     the first's;
//   - a rebound is the reservoir's pressure plus the Joukowsky rise of the returning column,
//     rho c times a velocity proportional to V0: 3.6 %, and the digitised pen's +-20 kPa, 1 %:
//     5 % for the first. The valve's closure law is stated only as "about 9 ms": the record's
//     rise is front-loaded (half of it by about 3 ms), the example's closure is linear in the
//     effective area (half by 7 ms). Over tau = (1 - t/9 ms)^m, m = 1 to 4 (which spans the
//     record's rise), this model's lives move by at most 1 %, its first rebound by 2 %, its
//     second rebound by up to 12.6 %: 15 % for the second;
//   - the plateau: the 3 %.
// Measured: plateau +0.9 %, first life -0.9 %, rebound +0.5 %, second life +5.1 %, its rebound
// -0.3 %. The DVCM (the examples' model before the record was read) misses the second cavity
// by 41 % and the first rebound by 38 % on this grid; MPDRIG_BERGANT_TABLES=1 prints every
// cavity model, friction and grid against the record (docs/bergant-simpson.md).
TEST(ReservoirValveRecord, SevereExampleAsTheMeasuredRecord) {
  const RigParams example = Load(kSevere);
  const double p_v = VapourPressure(example);
  const double drive_head_m =
      (ReservoirPressure(example) - p_v) / (example.density_kgpm3 * example.gravity_mps2) -
      example.pipe_elevation_gain_m;
  const double first_life = kSevereRecord.first_close_s - kSevereRecord.first_open_s;
  const double life_tolerance = std::hypot(0.05 / 1.4, 0.5 / drive_head_m, 0.003 / first_life);
  const double first_rebound_tolerance = 0.05, second_rebound_tolerance = 0.15;
  const auto print = [](const char* name, int cells, const RecordDeviations& d) {
    std::printf(
        "%-28s %4d cells: plateau %+5.1f %%, first cavity %+5.1f %%, rebound %+5.1f %%, "
        "second cavity %+5.1f %%, rebound %+5.1f %%\n",
        name, cells, 100 * d.plateau, 100 * d.first_life, 100 * d.first_rebound,
        100 * d.second_life, 100 * d.second_rebound);
  };
  const RecordDeviations example_run = AgainstTheRecord(example, 200);
  print("the example", 200, example_run);
  ASSERT_TRUE(example_run.two_cavities);
  EXPECT_LT(std::abs(example_run.plateau), 0.03);
  EXPECT_LT(std::abs(example_run.first_life), life_tolerance) << life_tolerance;
  EXPECT_LT(std::abs(example_run.second_life), 2 * life_tolerance) << life_tolerance;
  EXPECT_LT(std::abs(example_run.first_rebound), first_rebound_tolerance);
  EXPECT_LT(std::abs(example_run.second_rebound), second_rebound_tolerance);
  // The discrete vapour cavity model on the same grid, as a guard that the comparison can tell
  // models apart: its second cavity is far outside (a test that every model passed would say
  // nothing of the record).
  const RecordDeviations vapour = AgainstTheRecord(LoadVapour(kSevere), 200);
  print("DVCM", 200, vapour);
  EXPECT_TRUE(!vapour.two_cavities || std::abs(vapour.second_life) > 2 * life_tolerance);
  if (std::getenv("MPDRIG_BERGANT_TABLES") == nullptr) return;
  const double k = VardyBrownK(ReynoldsNumber(example));
  const char* const frictions[] = {"quasi-steady", "Brunone k*", "convolution"};
  for (int friction = 0; friction < 3; ++friction) {
    for (double alpha_0 : {0.0, 1e-7}) {
      for (int cells : {32, 64, 200}) {
        RigParams params = WithGas(example, alpha_0);  // 0: the DVCM
        if (friction == 1) params = WithUnsteadyFriction(params, k, false);
        if (friction == 2) {
          EXPECT_TRUE(ApplyEffectSpec(&params, "weighted_friction").ok());
        }
        const std::string name =
            std::string(frictions[friction]) + (alpha_0 > 0.0 ? ", DGCM" : ", DVCM");
        print(name.c_str(), cells, AgainstTheRecord(params, cells));
      }
    }
  }
}

}  // namespace
}  // namespace mpdrig
