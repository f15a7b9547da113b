// mpdrig freqresp: piston position -> bottom-hole pressure p(0), analytic (9.2.13) or simulated,
// for a choke setting or one of the rig's terminations (model/analysis/termination.h); or, with
// --from-log, the empirical response of a measured log (freqresp_log.h).
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>

#include "model/analysis/frequency_response.h"
#include "model/analysis/resonance.h"
#include "model/analysis/termination.h"
#include "model/common/units.h"
#include "tools/cli/commands.h"
#include "tools/cli/freqresp_log.h"
#include "tools/cli/model_options.h"

namespace mpdrig::cli {
namespace {

struct FreqrespArgs {
  ModelOptions model;
  bool analytic = false;
  bool simulated = false;
  std::string choke = "closed";
  std::string termination;  // empty: --choke decides
  double pump_lpm = 0.0;
  double fmin_hz = 0.02;
  double fmax_hz = 0.6;
  int points = 59;
  bool logarithmic = false;
  double amplitude_m = 0.001;
  double outlet_barg = 4.0;
  std::string out_path;
};

Result<ChokeSetting> ParseChoke(const std::string& text) {
  if (text == "closed") return ChokeSetting::Closed();
  if (text == "open") return ChokeSetting::Open();
  double deg = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), deg);
  if (error != std::errc() || end != text.data() + text.size() || !(deg >= 0.0 && deg <= 90.0)) {
    return Status::Error("--choke takes closed, open, or an opening in degrees 0..90; got '" +
                         text + "'");
  }
  return ChokeSetting::Opening(units::ChokeDegToFrac(deg));
}

int RunFreqresp(const FreqrespArgs& args) {
  const std::string name = "freqresp";
  auto params = args.model.LoadNtnuRigParams("freqresp");
  if (!params.ok()) return Fail(name, params.status());
  Result<ChokeSetting> choke = ChokeSetting::Closed();
  std::string setting;  // what the summary calls it
  if (!args.termination.empty()) {
    auto termination = ParseTermination(args.termination);
    if (!termination.ok()) return Fail(name, termination.status().Within("--termination"));
    if (args.pump_lpm != 0.0) {
      return Fail(name, Status::Error("--termination: the pump is off in every termination; "
                                      "leave --pump-lpm at 0"));
    }
    TerminatedRig rig = ApplyTermination(*params, *termination);
    *params = rig.params;
    choke = rig.choke;
    setting = "termination " + args.termination;
  } else {
    choke = ParseChoke(args.choke);
    if (!choke.ok()) return Fail(name, choke.status());
    setting = "choke " + choke->Describe();
  }
  const double outlet_pa = units::BargToPaAbs(args.outlet_barg, params->atmospheric_pressure_pa);
  if (!(args.fmin_hz > 0.0) || !(args.fmax_hz >= args.fmin_hz) || args.points < 1) {
    return Fail(name, Status::Error("need 0 < --fmin <= --fmax and --points >= 1"));
  }
  const double pump = units::LpmToM3ps(args.pump_lpm);
  const std::vector<double> freqs =
      FrequencyGrid(args.fmin_hz, args.fmax_hz, args.points, args.logarithmic);

  std::vector<FrequencyPoint> points;
  if (args.analytic) {
    if (choke->kind == ChokeSetting::Kind::kOpening && pump == 0.0) {
      std::fprintf(stderr,
                   "mpdrig freqresp: note: without pump flow the linearised orifice (5.3.2) has "
                   "zero slope, so a partly open choke acts as an open one in (9.2.13)\n");
    }
    const std::string outside = EffectsOutsideAnalytic(*params);
    if (!outside.empty()) {
      std::fprintf(stderr,
                   "mpdrig freqresp: note: the analytic response leaves out %s (it holds "
                   "topside_compliance, hose_compliance and gas_entrainment); --simulated has "
                   "them\n",
                   outside.c_str());
    }
    RigParams held = *params;
    std::erase_if(held.effects, [](const EffectSetting& e) { return !AnalyticRepresents(e.name); });
    points = AnalyticFrequencyResponseWithEffects(held, *choke, pump,
                                                  MeanLinePressurePa(held, outlet_pa), freqs);
  } else {
    auto options = args.model.LoadSimulationOptions();
    if (!options.ok()) return Fail(name, options.status());
    SimulatedResponseOptions response;
    response.amplitude_m = args.amplitude_m;
    response.outlet_pressure_pa = outlet_pa;
    auto simulated = SimulatedFrequencyResponse(
        *params, *options, *choke, pump, freqs, response, [](int done, int total) {
          std::fprintf(stderr, "\rmpdrig freqresp: %d/%d frequencies", done, total);
          if (done == total) std::fprintf(stderr, "\n");
        });
    if (!simulated.ok()) return Fail(name, simulated.status());
    points = *simulated;
  }

  std::ofstream file;
  std::ostream* out = &std::cout;
  if (args.out_path != "-") {
    file.open(args.out_path);
    if (!file) return Fail(name, Status::Error(args.out_path + ": cannot write"));
    out = &file;
  }
  out->precision(10);
  *out << "freq_hz,magnitude_pa_per_m,phase_deg\n";
  const FrequencyPoint* peak = &points.front();
  for (const FrequencyPoint& p : points) {
    *out << p.freq_hz << "," << p.magnitude_pa_per_m << "," << p.phase_deg << "\n";
    if (p.magnitude_pa_per_m > peak->magnitude_pa_per_m) peak = &p;
  }
  if (!*out) return Fail(name, Status::Error(args.out_path + ": write failed"));
  if (args.out_path != "-") {
    std::printf(
        "%s response, %s, pump %g L/min: %zu frequencies %g..%g Hz written to %s; "
        "largest |p(0)/x| = %.4g bar/m at %.4g Hz",
        args.analytic ? "analytic (9.2.13)" : "simulated", setting.c_str(), args.pump_lpm,
        points.size(), args.fmin_hz, args.fmax_hz, args.out_path.c_str(),
        peak->magnitude_pa_per_m / 1e5, peak->freq_hz);
    // The peak between the grid's points: the analytic response's refined by golden section,
    // the simulated one's by a parabola through log |H|.
    if (args.analytic) {
      ResonanceOptions options;
      options.fmin_hz = args.fmin_hz;
      options.fmax_hz = args.fmax_hz;
      RigParams held = *params;
      std::erase_if(held.effects,
                    [](const EffectSetting& e) { return !AnalyticRepresents(e.name); });
      auto first =
          FirstAnalyticResonance(held, *choke, pump, MeanLinePressurePa(held, outlet_pa), options);
      if (first.ok()) std::printf("; first resonance %.4f Hz", first->freq_hz);
    } else {
      std::printf("; peak %.4f Hz (parabola)", PeakOfSampledResponse(points));
    }
    std::printf("\n");
  }
  return 0;
}

}  // namespace

void AddFreqrespCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<FreqrespArgs>();
  CLI::App* command = app->add_subcommand(
      "freqresp", "Frequency response piston position -> bottom-hole pressure (thesis 9.2)");
  command->footer(
      "Frequency response from piston position to bottom-hole pressure p(0) (thesis 9.2):\n"
      "columns freq_hz, magnitude_pa_per_m, phase_deg.\n"
      "  --analytic   the closed form (9.2.13): linear model, linear friction f1, choke "
      "linearised\n"
      "  --simulated  the simulator driven by a small piston sine at each frequency\n"
      "Resonances without friction: open choke (2n+1) c/(4L), closed choke n c/(2L).\n"
      "  mpdrig freqresp --analytic --choke closed --fmin 0.02 --fmax 0.6 --out fr.csv\n"
      "The rig's terminations (pump off; --termination instead of --choke):\n"
      "  choke-closed        choke shut: pipe, topside tubes, closed choke (thesis: 0.44 Hz)\n"
      "  choke-open          choke fully open (thesis: 0.25 Hz)\n"
      "  closed-at-pipe-end  a valve right after the copper pipe: tubes and choke cut off "
      "(0.49 Hz)\n"
      "  mpdrig freqresp --analytic --termination closed-at-pipe-end --set wave_speed_mps=1173 "
      "--out -\n"
      "The analytic response holds topside_compliance, hose_compliance and gas_entrainment (at\n"
      "the mean pressure); other effects need --simulated.\n"
      "From a measured sweep or multi-tone log: piston position -> every pressure channel, with\n"
      "coherence, and the resonance peaks with an uncertainty (docs/rig-measurements.md):\n"
      "  mpdrig freqresp --from-log sweep.csv --json fr.json --csv fr.csv");
  args->model.AddAll(command);
  auto* analytic = command->add_flag("--analytic", args->analytic, "closed form (9.2.13)");
  auto* simulated = command->add_flag("--simulated", args->simulated, "simulate each frequency");
  analytic->excludes(simulated);
  auto* choke =
      command->add_option("--choke", args->choke, "closed, open, or an opening in degrees")
          ->capture_default_str();
  command
      ->add_option("--termination", args->termination,
                   "the rig's line end, pump off: " + TerminationNames())
      ->excludes(choke);
  command
      ->add_option("--pump-lpm", args->pump_lpm,
                   "back-pressure pump flow [L/min]; sets the linearised choke k = 2 rho A q_b/G^2")
      ->capture_default_str();
  command->add_option("--fmin", args->fmin_hz, "lowest frequency [Hz]")->capture_default_str();
  auto* fmax =
      command->add_option("--fmax", args->fmax_hz, "highest frequency [Hz] (--from-log: 2)")
          ->capture_default_str();
  command->add_option("--points", args->points, "number of frequencies")->capture_default_str();
  command->add_flag("--log", args->logarithmic, "space the frequencies geometrically");
  command->add_option("--amplitude-m", args->amplitude_m, "piston amplitude for --simulated [m]")
      ->capture_default_str();
  command
      ->add_option("--outlet-barg", args->outlet_barg,
                   "choke outlet pressure for --simulated [bar gauge]")
      ->capture_default_str();
  command->add_option("--out", args->out_path, "output CSV ('-' for stdout)");
  auto log_args = std::make_shared<FreqrespLogArgs>();
  command->add_option("--from-log", log_args->log_path,
                      "empirical response of a measured log (piston position -> pressures)");
  command->add_option("--json", log_args->json_path, "--from-log: result as JSON ('-' stdout)");
  command->add_option("--csv", log_args->csv_path,
                      "--from-log: channel,freq_hz,magnitude_pa_per_m,phase_deg,coherence");
  command
      ->add_option("--segment-s", log_args->response.segment_s,
                   "--from-log: Welch segment [s]; the frequency step is 1/segment")
      ->capture_default_str();
  command
      ->add_option("--min-coherence", log_args->response.min_coherence,
                   "--from-log: gamma^2 a resonance peak must have")
      ->capture_default_str();
  command->add_option("--resonance-list", log_args->resonance_list_path,
                      "--from-log: append the first resonance of --resonance-channel to this "
                      "resonance list (CSV configuration,frequency_hz,uncertainty_hz) under "
                      "--termination, for fit/diagnose --resonances");
  command
      ->add_option("--resonance-channel", log_args->resonance_channel,
                   "--from-log: the channel whose first peak --resonance-list takes")
      ->capture_default_str();
  AddLogReadOptions(command, &log_args->read);
  command->callback([args, log_args, fmax, exit_code]() {
    if (!log_args->log_path.empty()) {
      log_args->termination = args->termination;
      if (args->analytic || args->simulated || !args->out_path.empty()) {
        *exit_code = Fail("freqresp", Status::Error("--from-log takes --json and --csv, not "
                                                    "--analytic, --simulated or --out"));
        return;
      }
      log_args->response.fmin_hz = args->fmin_hz;
      log_args->response.fmax_hz = fmax->count() > 0 ? args->fmax_hz : 2.0;
      *exit_code = RunFreqrespFromLog(*log_args);
      return;
    }
    if (args->out_path.empty()) {
      *exit_code = Fail("freqresp", Status::Error("give --out (or --from-log)"));
      return;
    }
    if (!args->analytic && !args->simulated) {
      *exit_code = Fail("freqresp", Status::Error("give --analytic or --simulated"));
      return;
    }
    *exit_code = RunFreqresp(*args);
  });
}

}  // namespace mpdrig::cli
