// mpdrig traveltime: the speed of pressure fronts along the pipe from a log's transmitters
// PT1..PT10 (model/analysis/travel_time.h; thesis 8.3.2): per-pair delays from cross-correlation,
// the wave speed fitted over all pairs with its uncertainty; a table on stdout, JSON on request,
// progress on stderr.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "model/analysis/measured_log.h"
#include "model/analysis/travel_time.h"
#include "model/riglog/rig_log_reader.h"
#include "tools/cli/commands.h"
#include "tools/cli/model_options.h"
#include "tools/report/json.h"

namespace mpdrig::cli {
namespace {

using report::Json;
using report::JsonNumber;
using report::JsonText;

struct TravelTimeArgs {
  std::string log_path;
  std::string json_path;
  std::string window;
  riglog::ReadOptions read;
  TravelTimeOptions options;
  bool quiet = false;
  bool per_move = false;
  double min_move_deg = 2.0;
};

Status ParseWindow(const std::string& spec, TravelTimeOptions* options) {
  const std::size_t colon = spec.find(':');
  if (colon == std::string::npos) {
    return Status::Error("--window-s expects T0:T1 in seconds (either may be empty), got '" + spec +
                         "'");
  }
  const auto parse = [&](const std::string& text, double* out) -> Status {
    if (text.empty()) return Status::Ok();
    std::size_t used = 0;
    try {
      *out = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || !std::isfinite(*out)) {
      return Status::Error("--window-s: '" + text + "' is not a finite number");
    }
    return Status::Ok();
  };
  MPDRIG_RETURN_IF_ERROR(parse(spec.substr(0, colon), &options->window_begin_s));
  MPDRIG_RETURN_IF_ERROR(parse(spec.substr(colon + 1), &options->window_end_s));
  if (!(options->window_begin_s < options->window_end_s)) {
    return Status::Error("--window-s " + spec + ": T0 must be before T1");
  }
  return Status::Ok();
}

// Time and the pipe transmitters of the log, read one sample at a time (the other columns are
// not kept).
Status ReadTransmitters(const TravelTimeArgs& args, std::vector<double>* time_s,
                        std::vector<PressureTrace>* traces, std::vector<double>* choke_frac) {
  auto reader = riglog::RigLogReader::Open(args.log_path, args.read);
  if (!reader.ok()) return reader.status();
  std::vector<std::size_t> columns;
  for (int k = 0; k < kPipeTransmitterCount; ++k) {
    const Channel channel = static_cast<Channel>(static_cast<int>(Channel::kPT1) + k);
    const auto column = reader->FindColumn(riglog::ChannelName(channel));
    if (!column) continue;
    columns.push_back(*column);
    traces->push_back({std::string(riglog::ChannelName(channel)), *PipePositionM(channel), {}});
  }
  if (traces->size() < 3) {
    return Status::Error(args.log_path + ": needs at least three of PT1..PT10 (has " +
                         std::to_string(traces->size()) + ")");
  }
  const auto choke_column = reader->FindColumn(riglog::ChannelName(Channel::kChokePosition));
  if (args.per_move && !choke_column) {
    return Status::Error(args.log_path + ": --per-move needs the choke_position column");
  }
  std::vector<double> values;
  while (true) {
    auto more = reader->Next(&values);
    if (!more.ok()) return more.status();
    if (!*more) break;
    time_s->push_back(values[reader->time_index()]);
    for (std::size_t c = 0; c < columns.size(); ++c) {
      (*traces)[c].pressure_pa.push_back(values[columns[c]]);
    }
    if (choke_column) choke_frac->push_back(values[*choke_column]);
    if (!args.quiet && reader->samples_read() % 100000 == 0) {
      std::fprintf(stderr, "mpdrig traveltime: read %lld samples\r",
                   static_cast<long long>(reader->samples_read()));
    }
  }
  return Status::Ok();
}

// The end-to-end pair's delay (the thesis's measurement), NaN if it was not resolved.
double EndToEndDelay(const TravelTimeResult& r) {
  for (const PairDelay& p : r.pairs) {
    if (p.first == r.transmitters.front() && p.second == r.transmitters.back()) return p.delay_s;
  }
  return NAN;
}

Json MovesJson(const std::vector<MoveTravelTime>& moves) {
  Json out = Json::array();
  for (const MoveTravelTime& m : moves) {
    Json move = {{"time_s", JsonNumber(m.time_s)}};
    if (m.status.ok()) {
      move["wave_speed_mps"] = JsonNumber(m.result.wave_speed_mps);
      move["wave_speed_uncertainty_mps"] = JsonNumber(m.result.wave_speed_uncertainty_mps);
      move["pairs_used"] = m.result.pairs_used;
      move["end_to_end_delay_s"] = JsonNumber(EndToEndDelay(m.result));
    } else {
      move["error"] = m.status.message();
    }
    out.push_back(std::move(move));
  }
  return out;
}

std::string TravelTimeJson(const TravelTimeResult& r, const TravelTimeArgs& args,
                           const std::vector<MoveTravelTime>& moves) {
  Json pairs = Json::array();
  for (const PairDelay& p : r.pairs) {
    Json pair = {{"from", p.first},
                 {"to", p.second},
                 {"distance_m", JsonNumber(p.distance_m)},
                 {"delay_s", JsonNumber(p.delay_s)},
                 {"delay_up_s", JsonNumber(p.delay_up_s)},
                 {"delay_down_s", JsonNumber(p.delay_down_s)},
                 {"peak_correlation", JsonNumber(p.peak_correlation)},
                 {"peak_sigmas", JsonNumber(p.peak_sigmas)},
                 {"used", p.used}};
    if (!p.note.empty()) pair["note"] = p.note;
    pairs.push_back(std::move(pair));
  }
  Json json = {{"log", args.log_path},
               {"wave_speed_mps", JsonNumber(r.wave_speed_mps)},
               {"wave_speed_uncertainty_mps", JsonNumber(r.wave_speed_uncertainty_mps)},
               {"stack_wave_speed_mps", JsonNumber(r.stack_wave_speed_mps)},
               {"residual_rms_s", JsonNumber(r.residual_rms_s)},
               {"front_width_s", JsonNumber(r.front_width_s)},
               {"pairs_used", r.pairs_used},
               {"sample_rate_hz", JsonNumber(r.sample_rate_hz)},
               {"duration_s", JsonNumber(r.duration_s)},
               {"band_hz", Json::array({JsonNumber(r.band_low_hz), JsonNumber(r.band_high_hz)})},
               {"transmitters", r.transmitters},
               {"pairs", pairs}};
  if (args.per_move) json["moves"] = MovesJson(moves);
  return JsonText(json, 2);
}

// One line per move, then the mean and spread of their speeds, as the thesis's Table 8.3.1.
void PrintMoves(const std::vector<MoveTravelTime>& moves) {
  std::printf("%8s %9s %7s %6s %10s\n", "move s", "c m/s", "+- m/s", "pairs", "end-end s");
  std::vector<double> speeds;
  for (const MoveTravelTime& m : moves) {
    if (!m.status.ok()) {
      const std::string& why = m.status.message();
      std::printf("%8.2f  not timed: %s\n", m.time_s, why.substr(0, why.find(':')).c_str());
      continue;
    }
    std::printf("%8.2f %9.1f %7.1f %6d %10.4f\n", m.time_s, m.result.wave_speed_mps,
                m.result.wave_speed_uncertainty_mps, m.result.pairs_used, EndToEndDelay(m.result));
    speeds.push_back(m.result.wave_speed_mps);
  }
  if (speeds.empty()) {
    std::printf("no move with a clear front (%zu moves found)\n", moves.size());
    return;
  }
  double mean = 0.0, square = 0.0;
  for (double c : speeds) mean += c / static_cast<double>(speeds.size());
  for (double c : speeds) square += (c - mean) * (c - mean);
  const double sd =
      speeds.size() > 1 ? std::sqrt(square / static_cast<double>(speeds.size() - 1)) : NAN;
  std::printf(
      "%zu of %zu moves timed: mean %.1f m/s, standard deviation %.1f (the thesis, 12 moves "
      "read by hand: 1173, 74.5)\n",
      speeds.size(), moves.size(), mean, sd);
}

void PrintSummary(const TravelTimeResult& r) {
  std::printf("%-5s %-5s %8s %9s %9s %9s %6s  %s\n", "from", "to", "dist m", "delay s", "up s",
              "down s", "c m/s", "");
  for (const PairDelay& p : r.pairs) {
    const double c = std::isfinite(p.delay_s) ? p.distance_m / p.delay_s : NAN;
    std::printf("%-5s %-5s %8.0f %9.4f %9.4f %9.4f %6.0f  %s\n", p.first.c_str(), p.second.c_str(),
                p.distance_m, p.delay_s, p.delay_up_s, p.delay_down_s, c,
                p.used ? "" : p.note.c_str());
  }
  std::printf(
      "wave speed %.1f +- %.1f m/s (distance = c delay over %d pairs of %zu; delay rms %.2g s; "
      "%.0f Hz, %.1f s, band %.2g-%.3g Hz)\n",
      r.wave_speed_mps, r.wave_speed_uncertainty_mps, r.pairs_used, r.pairs.size(),
      r.residual_rms_s, r.sample_rate_hz, r.duration_s, r.band_low_hz, r.band_high_hz);
}

int RunTravelTime(const TravelTimeArgs& args) {
  const std::string name = "traveltime";
  TravelTimeOptions options = args.options;
  if (!args.window.empty()) {
    const Status window = ParseWindow(args.window, &options);
    if (!window.ok()) return Fail(name, window);
  }
  const Status valid = options.Validate();
  if (!valid.ok()) return Fail(name, valid);
  std::vector<double> time_s;
  std::vector<PressureTrace> traces;
  std::vector<double> choke_frac;
  const Status read = ReadTransmitters(args, &time_s, &traces, &choke_frac);
  if (!read.ok()) return Fail(name, read);
  if (!args.quiet) {
    std::fprintf(stderr,
                 "mpdrig traveltime: %zu samples of %zu transmitters; correlating %zu pairs\n",
                 time_s.size(), traces.size(), traces.size() * (traces.size() - 1) / 2);
  }
  auto result = EstimateTravelTime(time_s, traces, options);
  if (!result.ok()) return Fail(name, result.status().Within(args.log_path));
  std::vector<MoveTravelTime> moves;
  if (args.per_move) {
    const std::vector<double> times =
        FindChokeMoves(time_s, choke_frac, args.min_move_deg / 90.0, /*min_gap_s=*/3.0);
    if (!args.quiet) {
      std::fprintf(stderr, "mpdrig traveltime: %zu choke moves of %g deg or more; timing each\n",
                   times.size(), args.min_move_deg);
    }
    TravelTimeOptions per_move = options;
    per_move.window_begin_s = -1e300;
    per_move.window_end_s = 1e300;
    moves = TravelTimePerMove(time_s, traces, times, per_move);
  }
  if (!args.json_path.empty()) {
    const Status written = WriteText(args.json_path, TravelTimeJson(*result, args, moves));
    if (!written.ok()) return Fail(name, written);
  }
  if (args.json_path != "-") {
    PrintSummary(*result);
    if (args.per_move) PrintMoves(moves);
  }
  return 0;
}

}  // namespace

void AddTravelTimeCommand(CLI::App* app, int* exit_code) {
  auto args = std::make_shared<TravelTimeArgs>();
  CLI::App* command = app->add_subcommand(
      "traveltime", "Speed of pressure fronts between the pipe's transmitters PT1..PT10");
  command->footer(
      "How fast does a pressure front travel along the copper pipe? The thesis (8.3.2) read\n"
      "the delay of the front after a fast choke move between the pipe's two ends by hand,\n"
      "0.70-0.91 s over 900 m in 12 runs, and found c = 1173 +- 74.5 m/s. This does the same\n"
      "for every pair of the transmitters PT1..PT10 (0, 100, ..., 900 m along the pipe):\n"
      "  1. each pressure's time derivative (takes away the static levels, weights the fronts),\n"
      "  2. the cross-correlation of every pair, weighted to a band (--band-low-hz 3 to\n"
      "     --band-high-hz 10: below it the heave's sines and sweeps, standing waves that\n"
      "     correlate at every lag; above it the transmitters' noise),\n"
      "  3. a front coming up from the piston shows as a peak at +d/c, one coming down from the\n"
      "     choke at -d/c; the peak is located between samples (a parabola through three),\n"
      "     and the pair's delay is the mean of the two,\n"
      "  4. distance = c delay fitted over all pairs; its standard error, widened because the\n"
      "     pairs share transmitters, is the uncertainty.\n"
      "Any fast move of the choke or the piston, or any broadband excitation, will do; a log of\n"
      "slow sines alone has no front to time. Pairs closer than the fronts are wide (a slow choke\n"
      "move) are left out and say so. --window-s picks one move, as the thesis read them;\n"
      "--per-move finds the choke's moves and times each on its own, then their mean and spread.\n"
      "Examples:\n"
      "  mpdrig synth --seed 1 --out lab.csv && mpdrig traveltime lab.csv\n"
      "  mpdrig traveltime lab.csv --window-s 30:40 --json tt.json\n"
      "  mpdrig traveltime lab.csv --per-move\n"
      "JSON: wave_speed_mps, wave_speed_uncertainty_mps, stack_wave_speed_mps, residual_rms_s,\n"
      "front_width_s, pairs_used, sample_rate_hz, duration_s, band_hz, transmitters,\n"
      "pairs[{from, to, distance_m, delay_s, delay_up_s, delay_down_s, peak_correlation,\n"
      "peak_sigmas, used, note}], and with --per-move moves[{time_s, wave_speed_mps,\n"
      "wave_speed_uncertainty_mps, pairs_used, end_to_end_delay_s} or {time_s, error}]\n"
      "(docs/rig-measurements.md).\n"
      "Progress goes to stderr. The wave speed is what `--set wave_speed_mps=...` takes.");
  command->add_option("log", args->log_path, "measured rig log (rig-log-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_option("--json", args->json_path, "result as JSON ('-' for stdout)");
  command
      ->add_option("--window-s", args->window,
                   "use only the samples in [T0, T1] s, e.g. one choke move: 30:40")
      ->type_name("T0:T1");
  command
      ->add_option("--band-low-hz", args->options.band_low_hz,
                   "lower edge of the correlation band (f^4/(f^4 + f_lo^4))")
      ->capture_default_str();
  command
      ->add_option("--band-high-hz", args->options.band_high_hz,
                   "upper edge (exp(-(f/f_hi)^2)), at most 0.4 times the Nyquist frequency")
      ->capture_default_str();
  command
      ->add_option("--min-speed-mps", args->options.min_wave_speed_mps,
                   "slowest wave speed searched")
      ->capture_default_str();
  command
      ->add_option("--max-speed-mps", args->options.max_wave_speed_mps,
                   "fastest wave speed searched")
      ->capture_default_str();
  AddLogReadOptions(command, &args->read);
  command->add_flag("--per-move", args->per_move,
                    "also time each choke move on its own, in [t - 1, t + 4] s (as the thesis's "
                    "Table 8.3.1): needs the choke_position column");
  command
      ->add_option("--min-move-deg", args->min_move_deg,
                   "smallest choke move --per-move counts (mean opening 0.5 s after against 0.5 "
                   "s before)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_flag("--quiet", args->quiet, "no progress on stderr");
  command->callback([args, exit_code] { *exit_code = RunTravelTime(*args); });
}

}  // namespace mpdrig::cli
