// mpdrig demo: a minute of the virtual rig under a heave, summarised for a first-time user.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "model/common/units.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"
#include "tools/cli/rig_log_output.h"

namespace mpdrig::cli {
namespace {

struct DemoArgs {
  ModelOptions model;
  std::string out_path = "mpdrig-demo.csv";
};

// The thesis's Fig. 9.5.2 situation: 0.2 Hz heave, choke at 31 deg; a 5 L/min back-pressure
// flow holds about 3.4 bar on the choke (5.3.2 with Table 8.4.1).
constexpr double kHeaveAmplitudeM = 0.1;
constexpr double kHeaveFrequencyHz = 0.2;
constexpr double kChokeDeg = 31.0;
constexpr double kPumpLpm = 5.0;
constexpr double kDurationS = 60.0;
constexpr double kRateHz = 100.0;

int RunDemo(const DemoArgs& args) {
  auto params = args.model.LoadNtnuRigParams("demo");
  if (!params.ok()) return Fail("demo", params.status());
  auto options = args.model.LoadSimulationOptions();
  if (!options.ok()) return Fail("demo", options.status());
  const double atmosphere = params->atmospheric_pressure_pa;

  InputSignals signals;
  signals.piston_position_m = [](double t) {
    return kHeaveAmplitudeM * std::sin(2.0 * M_PI * kHeaveFrequencyHz * t);
  };
  RigInputs held;
  held.choke_opening_frac = units::ChokeDegToFrac(kChokeDeg);
  held.pump_flow_m3ps = units::LpmToM3ps(kPumpLpm);
  held.outlet_pressure_pa = atmosphere;
  signals.rig = [held](double) { return held; };
  std::vector<double> times;
  for (int i = 0; i <= static_cast<int>(kDurationS * kRateHz); ++i) times.push_back(i / kRateHz);

  auto run = Simulate(*params, *options, signals, times);
  if (!run.ok()) return Fail("demo", run.status());
  Status written =
      WriteSamples(args.out_path,
                   {{"source", "mpdrig demo"},
                    {"drive", "piston sine 0.1 m at 0.2 Hz, choke 31 deg, pump 5 L/min"},
                    {"model", args.model.Describe(*params)}},
                   atmosphere, run->samples);
  if (!written.ok()) return Fail("demo", written);

  // Summary over the last 5 periods (after the start-up transient).
  auto range = [&](Channel channel) {
    double lo = 1e300, hi = -1e300;
    for (const RigSample& s : run->samples) {
      if (s.time_s < kDurationS - 5.0 / kHeaveFrequencyHz) continue;
      lo = std::min(lo, s[channel]);
      hi = std::max(hi, s[channel]);
    }
    return std::pair{lo, hi};
  };
  const auto [bhp_lo, bhp_hi] = range(Channel::kPT1);
  const auto [c2_lo, c2_hi] = range(Channel::kC2);
  const auto [ft3_lo, ft3_hi] = range(Channel::kFT3);
  std::printf(
      "mpdrig demo: the virtual MPD heave rig (900 m copper pipe, %s)\n"
      "  drive: piston (BHA) sine, amplitude %.2f m at %.2f Hz; choke fixed at %.0f deg;\n"
      "         back-pressure pump %.0f L/min; choke outlet at atmosphere; %.0f s simulated\n"
      "  bottom-hole pressure PT1: %.3f .. %.3f barg (heave swing %.3f bar)\n"
      "  choke pressure C2:        %.3f .. %.3f barg\n"
      "  choke flow FT3:           %.2f .. %.2f L/min\n"
      "  wrote %zu samples of every lab channel (P1, P2, PT1..PT10, C1, C2, FT1..FT4) to %s\n"
      "next: compare it with the model: mpdrig compare %s --json c.json --report c.html\n"
      "      run the rig as a DDS service: mpdrig serve --help;  everything: mpdrig --help\n",
      args.model.Describe(*params).c_str(), kHeaveAmplitudeM, kHeaveFrequencyHz, kChokeDeg,
      kPumpLpm, kDurationS, units::PaAbsToBarg(bhp_lo, atmosphere),
      units::PaAbsToBarg(bhp_hi, atmosphere), (bhp_hi - bhp_lo) / units::kPaPerBar,
      units::PaAbsToBarg(c2_lo, atmosphere), units::PaAbsToBarg(c2_hi, atmosphere),
      units::M3psToLpm(ft3_lo), units::M3psToLpm(ft3_hi), run->samples.size(),
      args.out_path.c_str(), args.out_path.c_str());
  return 0;
}

}  // namespace

void AddDemoCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* command = app->add_subcommand(
      "demo", "Simulate a minute of the rig under a 0.2 Hz heave and summarise what happened.");
  args->model.AddAll(command);
  command->add_option("--out", args->out_path, "where to write the rig log")->capture_default_str();
  command->callback([args, exit_code]() { *exit_code = RunDemo(*args); });
}

}  // namespace mpdrig::cli
