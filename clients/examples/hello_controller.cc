// hello_controller: the smallest controller of a rig's bottom-hole pressure (BHP) against heave,
// with the choke, on the observer's estimate BHP_est (no downhole sensor, as on a real well). The
// client library's loop runs it (real time or lockstep, the lost-rig rule, Ctrl-C); this file
// writes only the update: a PI on BHP_est plus the library's heave canceller. Why not a PI alone:
// the choke acts on the bottom through 1.06 s of pipe (l/c), 40-90 degrees of phase at a 0.1-0.2 Hz
// heave. Measured at 0.1 Hz, lab noise (docs/service.md): PT1's periodic swing 0.259 bar with the
// choke fixed, 0.263 bar under a PI. The canceller adapts a feed-forward on the observer's heave
// phasor until the swing is gone (clients/client/heave_control.h): with it, 19-22x less swing
// than the fixed choke at the lab's noise (ctest -R HelloController).
//   mpdrig serve --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5 --choke-deg 31 &
//   hello_controller --rig rig-1 --duration 80     # watches 20 s, then holds the mean BHP
#include <algorithm>
#include <cstdio>

#include <CLI/CLI.hpp>

#include "clients/client/control_loop.h"
#include "clients/client/heave_control.h"

using namespace mpdrig::client;

int main(int argc, char** argv) {
  CLI::App app("hello_controller - hold a rig's BHP against heave: a PI + the heave canceller");
  RigOptions rig_options;
  LoopOptions loop;
  loop.estimates = LoopOptions::Estimates::kPaired;  // each tick with its sample's BHP_est
  app.add_option("--rig", rig_options.rig_id, "rig id")->capture_default_str();
  app.add_option("--domain", rig_options.domain, "DDS domain id")->capture_default_str();
  app.add_option("--duration", loop.duration_s, "stop at this rig time [s] (0: at Ctrl-C)");
  CLI11_PARSE(app, argc, argv);
  auto rig = Rig::Connect(rig_options);
  if (!rig.ok()) {
    std::fprintf(stderr, "hello_controller: %s\n", rig.status().message().c_str());
    return 1;
  }
  const double kp = 0.1, ki = 0.05;  // [deg/bar], [deg/(bar s)]
  SetpointLearner setpoint;          // the mean BHP over whole heave periods, choke left alone
  HeaveCanceller canceller;
  double integral_deg = 0.0;
  const LoopResult result = RunController(**rig, loop, [&](const Tick& tick) -> Commands {
    const Estimate& estimate = *tick.estimate;
    const double bhp = estimate.BHP_est_barg;
    if (!setpoint.learnt()) {
      if (!setpoint.Add(tick.sensors.time_s, bhp, tick.sensors.choke_position_deg,
                        estimate.disturbance_frequency_hz)) {
        return {};  // command nothing yet
      }
      integral_deg = setpoint.choke_deg();
    }
    const double e = bhp - setpoint.setpoint_barg();  // too high: open the choke
    const double wanted = integral_deg + kp * e + canceller.Update(e, estimate, tick.dt_s);
    const double choke = std::clamp(wanted, 2.0, 88.0);
    if (choke == wanted) integral_deg += ki * e * tick.dt_s;  // no wind-up at a limit
    return Commands::Choke(choke);
  });
  std::fprintf(stderr, "hello_controller: %s at rig time %.2f s, set point %.4f barg %s\n",
               LoopEndName(result.end), result.last_time_s, setpoint.setpoint_barg(),
               result.message.c_str());
  return result.ExitCode();
}
