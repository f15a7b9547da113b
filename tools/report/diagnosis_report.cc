#include "tools/report/diagnosis_report.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "model/common/units.h"
#include "model/riglog/channels.h"
#include "tools/report/json.h"
#include "tools/report/svg_plot.h"

namespace mpdrig::report {
namespace {

Json ParamsJson(const std::vector<NamedValue>& params) {
  Json out = Json::object();
  for (const NamedValue& p : params) {
    out[p.key] = {{"value", JsonNumber(p.value)},
                  {"std_error", JsonNumber(p.standard_error)},
                  {"held", p.held}};
  }
  return out;
}

Json ChannelsJson(const std::vector<std::pair<Channel, double>>& errors) {
  Json out = Json::object();
  for (const auto& [channel, error] : errors) {
    out[std::string(riglog::ChannelName(channel))] = JsonNumber(error);
  }
  return out;
}

Json OptionalNumber(const std::optional<double>& value) {
  return value ? JsonNumber(*value) : Json(nullptr);
}

double ErrorOf(const CandidateResult& result, Channel channel) {
  for (const auto& [c, e] : result.channel_errors) {
    if (c == channel) return e;
  }
  return std::nan("");
}

// One candidate's object; `reference` is the model it was measured against (the baseline, or
// the model with the effects selected before it).
Json CandidateJson(const CandidateResult& c, const CandidateResult& reference) {
  Json out = {{"effect", c.effect},
              {"round", c.round},
              {"params", ParamsJson(c.params)},
              {"error", JsonNumber(c.error)},
              {"penalised_error", JsonNumber(c.penalised_error)},
              {"fit_error", JsonNumber(c.fit_error)},
              {"improvement", JsonNumber(c.improvement)},
              {"improvement_std_error", JsonNumber(c.improvement_std_error)},
              {"extra_params", c.extra_params},
              {"significant", c.significant},
              {"explains", c.explains},
              {"description", DescribeCandidate(c, reference)},
              {"channels", ChannelsJson(c.channel_errors)}};
  if (c.floor_error) out["floor_error"] = JsonNumber(*c.floor_error);
  if (!c.failure.empty()) out["failure"] = c.failure;
  if (!c.strength_key.empty()) {
    out["strength_key"] = c.strength_key;
    out["detectable_from"] = OptionalNumber(c.detectable_from);
    out["strength_inverse"] = c.strength_inverse;
    out["strength_scan_limit"] = JsonNumber(c.strength_scan_limit);
  }
  return out;
}

// The log's regimes and the split (regimes.h).
void AddRegimes(const Diagnosis& d, Json& out) {
  out["split"] = {{"fit_end_s", JsonNumber(d.fit_end_s)},
                  {"requested_fit_end_s", JsonNumber(d.requested_fit_end_s)},
                  {"one_sided", d.one_sided_regimes}};
  Json regimes = Json::array();
  for (const Regime& r : d.regimes) {
    Json intervals = Json::array();
    for (const TimeInterval& interval : r.intervals) {
      intervals.push_back(Json::array({JsonNumber(interval.begin_s), JsonNumber(interval.end_s)}));
    }
    regimes.push_back({{"name", r.name},
                       {"input", r.input},
                       {"duration_s", JsonNumber(r.duration_s)},
                       {"fit_s", JsonNumber(r.fit_s)},
                       {"score_s", JsonNumber(r.score_s)},
                       {"intervals", intervals}});
  }
  out["regimes"] = std::move(regimes);
}

// What the best model leaves (residual_signature.h), lab units for the offsets.
Json ResidualJson(const ResidualSignature& r) {
  Json channels = Json::array();
  for (const ChannelResidual& c : r.channels) {
    channels.push_back({{"channel", std::string(riglog::ChannelName(c.channel))},
                        {"x_m", OptionalNumber(c.x_m)},
                        {"nrmse", JsonNumber(c.nrmse)},
                        {"sensor_floor", JsonNumber(c.sensor_floor)},
                        {"input_floor", JsonNumber(c.input_floor)},
                        {"floor", JsonNumber(c.floor)},
                        {"excess", JsonNumber(c.excess)},
                        {"bias", JsonNumber(c.bias_unit)},
                        {"steady_share", JsonNumber(c.steady_share)},
                        {"score_nrmse", JsonNumber(c.score_nrmse)},
                        {"score_floor", JsonNumber(c.score_floor)}});
  }
  Json bands = Json::array();
  for (const BandResidual& b : r.bands) {
    bands.push_back({{"name", b.name},
                     {"low_hz", JsonNumber(b.low_hz)},
                     {"high_hz", JsonNumber(b.high_hz)},
                     {"error", JsonNumber(b.error)},
                     {"floor", JsonNumber(b.floor)},
                     {"excess_share", JsonNumber(b.excess_share)}});
  }
  Json regimes = Json::array();
  for (const RegimeResidual& g : r.regimes) {
    regimes.push_back({{"regime", g.regime},
                       {"input", g.input},
                       {"duration_s", JsonNumber(g.duration_s)},
                       {"error", JsonNumber(g.error)},
                       {"floor", JsonNumber(g.floor)},
                       {"steady_share", JsonNumber(g.steady_share)},
                       {"channels", ChannelsJson(g.channel_errors)}});
  }
  return {{"model", r.model},
          {"misses", r.misses},
          {"above_noise", r.above_noise},
          {"error", JsonNumber(r.error)},
          {"noise_floor", JsonNumber(r.noise_floor)},
          {"sensor_floor", JsonNumber(r.sensor_floor)},
          {"input_floor", JsonNumber(r.input_floor)},
          {"misses_factor", JsonNumber(kMissesFactor)},
          {"noise_floor_method", kNoiseFloorMethod},
          {"whole_error", JsonNumber(r.whole_error)},
          {"whole_floor", JsonNumber(r.whole_floor)},
          {"steady_share", JsonNumber(r.steady_share)},
          {"quarter_wave_hz", JsonNumber(r.quarter_wave_hz)},
          {"summary", r.Summary()},
          {"reasons", r.reasons},
          {"findings", r.findings},
          {"channels", channels},
          {"bands", bands},
          {"regimes", regimes}};
}

}  // namespace

std::string DiagnosisJson(const Diagnosis& d, const std::string& log_path) {
  const CandidateResult& b = d.baseline;
  Json out = {{"log", log_path},
              {"fit_end_s", JsonNumber(d.fit_end_s)},
              {"noise_floor", JsonNumber(d.noise_floor)},
              {"replays", d.replays}};
  // Pressures held on a floor (cavity_evidence.h): where, at what level, how often.
  Json floors = Json::array();
  for (const ChannelFloor& floor : d.pressure_floors.floors) {
    floors.push_back({{"channel", std::string(ChannelName(floor.channel))},
                      {"level_pa", JsonNumber(floor.level_pa)},
                      {"holds", floor.holds.size()}});
  }
  out["pressure_floors"] = {{"present", d.pressure_floors.present()},
                            {"level_pa", JsonNumber(d.pressure_floors.level_pa)},
                            {"holds", d.pressure_floors.holds},
                            {"channels", floors}};
  // Where the model runs went, stage by stage.
  Json runs = Json::array();
  for (const StageRuns& r : d.runs) {
    runs.push_back({{"stage", r.stage},
                    {"scans", r.scans},
                    {"fits", r.fits},
                    {"detectability", r.detectability},
                    {"scoring", r.scoring}});
  }
  out["runs"] = std::move(runs);
  // The choke's and FT2's levels as estimated at the fitted base model, lab units.
  out["input_levels"] = {
      {"choke_offset_deg", JsonNumber(units::ChokeFracToDeg(d.input_levels.choke_offset_frac))},
      {"choke_trend_deg", JsonNumber(units::ChokeFracToDeg(d.input_levels.choke_trend_frac))},
      {"FT2_offset_lpm", JsonNumber(units::M3psToLpm(d.input_levels.pump_offset_m3ps))},
      {"FT2_trend_lpm", JsonNumber(units::M3psToLpm(d.input_levels.pump_trend_m3ps))},
      {"at_bound", d.input_levels.at_bound}};
  out["baseline"] = {{"error", JsonNumber(b.error)},
                     {"fit_error", JsonNumber(b.fit_error)},
                     {"params", ParamsJson(b.params)},
                     {"channels", ChannelsJson(b.channel_errors)}};
  Json candidates = Json::array();
  for (const CandidateResult& c : d.candidates) candidates.push_back(CandidateJson(c, b));
  out["candidates"] = std::move(candidates);
  out["verdict"] = d.verdict ? Json(*d.verdict) : Json(nullptr);
  out["equivalent"] = d.equivalent;
  // Forward selection: the effects added in order, each against the model before it.
  Json selected = Json::array();
  for (std::size_t i = 0; i < d.selected.size(); ++i) {
    selected.push_back(CandidateJson(d.selected[i], i ? d.selected[i - 1] : b));
  }
  out["selected"] = std::move(selected);
  out["next"] =
      d.next ? CandidateJson(*d.next, d.selected.empty() ? b : d.selected.back()) : Json(nullptr);
  // Each later round's ranking, against the model selected before it.
  Json rounds = Json::array();
  for (std::size_t r = 0; r < d.later_rounds.size(); ++r) {
    const CandidateResult& reference = r < d.selected.size() ? d.selected[r] : d.selected.back();
    Json ranked = Json::array();
    for (const CandidateResult& c : d.later_rounds[r])
      ranked.push_back(CandidateJson(c, reference));
    rounds.push_back({{"round", static_cast<int>(r) + 2},
                      {"reference", reference.effect},
                      {"reference_error", JsonNumber(reference.error)},
                      {"candidates", std::move(ranked)}});
  }
  out["later_rounds"] = std::move(rounds);
  out["selection_end"] = d.selection_end;
  Json failed = Json::array();
  for (const auto& f : d.failed) {
    failed.push_back({{"effect", f.effect}, {"round", f.round}, {"failure", f.failure}});
  }
  out["failed"] = std::move(failed);
  AddRegimes(d, out);
  if (d.residual) out["residual"] = ResidualJson(*d.residual);
  // Where the fitted base model fails: worst channels, worst bands, lags.
  const Comparison& cmp = d.baseline_comparison;
  std::vector<const ChannelMetrics*> channels;
  for (const ChannelMetrics& m : cmp.channels) channels.push_back(&m);
  std::sort(channels.begin(), channels.end(), [](auto* a, auto* b) {
    return (std::isfinite(a->nrmse) ? a->nrmse : -1.0) >
           (std::isfinite(b->nrmse) ? b->nrmse : -1.0);
  });
  Json worst = Json::array();
  for (std::size_t i = 0; i < channels.size() && i < 5; ++i) {
    const ChannelMetrics& m = *channels[i];
    Json bands = Json::array();
    for (const BandMetrics& band : m.bands) {
      bands.push_back({{"freq_hz", JsonNumber(band.freq_hz)},
                       {"magnitude_ratio", JsonNumber(band.magnitude_ratio)},
                       {"phase_diff_deg", JsonNumber(band.phase_diff_deg)},
                       {"band_nrmse", JsonNumber(band.band_nrmse)}});
    }
    worst.push_back({{"channel", std::string(riglog::ChannelName(m.channel))},
                     {"nrmse", JsonNumber(m.nrmse)},
                     {"lag_s", JsonNumber(m.lag_s)},
                     {"residual_white", m.residual.white},
                     {"residual_independent_of_inputs", m.residual.independent_of_inputs},
                     {"bands", bands}});
  }
  out["where_baseline_fails"] = {{"worst_channels", worst}};
  return JsonText(out);
}

namespace {

// The page's head, the log and the verdict: the missing effect, or none.
void WriteVerdict(const Diagnosis& d, const CandidateResult* winner, const std::string& log_path,
                  std::ostringstream& html) {
  const CandidateResult& b = d.baseline;
  html << "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>mpdrig diagnose: "
       << EscapeHtml(log_path)
       << "</title><style>body{font-family:sans-serif;max-width:1100px;margin:1em auto;color:#222}"
          "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:3px "
          "8px;text-align:right}th{background:#eee}td.l{text-align:left}.yes{color:#080;font-"
          "weight:bold}.no{color:#888}.verdict{font-size:1.3em;padding:0.5em;background:#eef6ee;"
          "border-left:5px solid "
          "#080}.none{background:#f6f6f6;border-left-color:#888}.misses{background:#fbeee6;border-"
          "left:5px "
          "solid #c60}</style>"
          "</head><body>\n<h1>Which effect is missing?</h1>\n<p>Log <code>"
       << EscapeHtml(log_path) << "</code>. Fitted on t &lt; " << FormatValue(d.fit_end_s)
       << " s, scored on the rest. Noise floor (a perfect model's error): "
       << FormatValue(100.0 * d.noise_floor) << " %. " << d.replays << " model runs.</p>\n";
  if (winner != nullptr) {
    html << "<p class=\"verdict\">Missing effect: <b>" << EscapeHtml(winner->effect) << "</b>. "
         << EscapeHtml(DescribeCandidate(*winner, b)) << ".</p>\n";
    for (std::size_t i = 1; i < d.selected.size(); ++i) {
      html << "<p class=\"verdict\">And with it, missing too: <b>"
           << EscapeHtml(d.selected[i].effect) << "</b>. "
           << EscapeHtml(DescribeCandidate(d.selected[i], d.selected[i - 1])) << ".</p>\n";
    }
    if (!d.equivalent.empty()) {
      std::string names;
      for (const std::string& name : d.equivalent) names += (names.empty() ? "" : ", ") + name;
      html << "<p>Explains the log as well (the verdict does not clearly beat it): <b>"
           << EscapeHtml(names)
           << "</b>. The log does not excite what tells them apart; see what each explains "
              "below.</p>\n";
    }
  } else {
    html << "<p class=\"verdict none\">No effect of the catalogue explains the remaining error "
            "beyond noise and extra freedom. Baseline error "
         << FormatValue(100.0 * b.error) << " %.</p>\n";
  }
  if (d.residual && d.residual->above_noise) {
    html << "<p class=\"verdict misses\">The " << EscapeHtml(d.residual->model)
         << (d.residual->misses ? " misses something the catalogue does not hold: error "
                                : " still leaves more than noise (its effects' fits stopping "
                                  "short, or something the catalogue does not hold): error ")
         << FormatValue(100.0 * d.residual->error) << " % on the scoring data against a noise "
         << "floor of " << FormatValue(100.0 * d.residual->noise_floor)
         << " %. See <a href=\"#left\">what is left</a>.</p>\n";
  }
}

// The regimes of the log and how the split left them (regimes.h).
void WriteRegimes(const Diagnosis& d, std::ostringstream& html) {
  html << "<h2>Regimes of the log and the split</h2>\n<p>Fitted on t &lt; "
       << FormatValue(d.fit_end_s) << " s";
  if (d.fit_end_s != d.requested_fit_end_s) {
    html << " (moved from " << FormatValue(d.requested_fit_end_s)
         << " s so that every regime is in both parts)";
  }
  html << ", scored on the rest.";
  if (d.regimes.empty()) {
    html << " No regimes: every input keeps one state (the pump running, the choke open, the "
            "heave running).</p>\n";
    return;
  }
  html << "</p>\n<table><tr><th class=\"l\">regime</th><th class=\"l\">told by</th><th>time "
          "[s]</th><th>fitted [s]</th><th>scored [s]</th><th class=\"l\">intervals [s]</th></tr>\n";
  for (const Regime& r : d.regimes) {
    std::string intervals;
    for (const TimeInterval& i : r.intervals) {
      intervals += FormatValue(i.begin_s, 4) + "&ndash;" + FormatValue(i.end_s, 4) + " ";
    }
    html << "<tr><td class=\"l\">" << EscapeHtml(r.name) << "</td><td class=\"l\">"
         << EscapeHtml(r.input) << "</td><td>" << FormatValue(r.duration_s, 3) << "</td><td>"
         << FormatValue(r.fit_s, 3) << "</td><td>" << FormatValue(r.score_s, 3)
         << "</td><td class=\"l\">" << intervals << "</td></tr>\n";
  }
  html << "</table>\n";
  for (const std::string& note : d.one_sided_regimes) {
    html << "<p class=\"misses\">On one side of the split only: " << EscapeHtml(note) << ".</p>\n";
  }
}

// What the best model leaves, against the noise floor: per channel, per band, per regime.
void WriteWhatIsLeft(const Diagnosis& d, std::ostringstream& html) {
  if (!d.residual) return;
  const ResidualSignature& r = *d.residual;
  html << "<h2 id=\"left\">What is left</h2>\n<p>" << EscapeHtml(r.Summary()) << "</p>\n"
       << "<p><small>Noise floor: " << EscapeHtml(kNoiseFloorMethod)
       << ". Over the whole log unless said.</small></p>\n";
  std::vector<double> x, error, floor;
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    x.push_back(static_cast<double>(i));
    error.push_back(100.0 * r.channels[i].nrmse);
    floor.push_back(100.0 * r.channels[i].floor);
  }
  SvgPlot plot(1000, 240, "channel (table below)", "NRMSE, whole log [%]");
  plot.Stems(x, error, "#c33");
  plot.Legend(r.model, "#c33");
  plot.Markers(x, floor, "#888");
  plot.Legend("noise floor", "#888");
  html << plot.Render()
       << "\n<table><tr><th class=\"l\">channel</th><th>x [m]</th><th>error "
          "[%]</th><th>floor [%]</th><th>sensor [%]</th><th>inputs [%]</th><th>beyond the noise "
          "[%]</th><th>mean offset (model - log)</th><th>steady share</th><th>scoring: error / "
          "floor [%]</th></tr>\n";
  for (const ChannelResidual& c : r.channels) {
    html << "<tr><td class=\"l\">" << riglog::ChannelName(c.channel) << "</td><td>"
         << (c.x_m ? FormatValue(*c.x_m, 3) : std::string()) << "</td><td>"
         << FormatValue(100.0 * c.nrmse, 3) << "</td><td>" << FormatValue(100.0 * c.floor, 3)
         << "</td><td>" << FormatValue(100.0 * c.sensor_floor, 3) << "</td><td>"
         << FormatValue(100.0 * c.input_floor, 3) << "</td><td>" << FormatValue(100.0 * c.excess, 3)
         << "</td><td>" << FormatValue(c.bias_unit, 3) << "</td><td>"
         << FormatValue(100.0 * c.steady_share, 2) << " %</td><td>"
         << FormatValue(100.0 * c.score_nrmse, 3) << " / " << FormatValue(100.0 * c.score_floor, 3)
         << "</td></tr>\n";
  }
  html << "</table>\n<table><tr><th class=\"l\">band</th><th>from [Hz]</th><th>to [Hz]</th>"
          "<th>error [%]</th><th>floor [%]</th><th>share of what is not noise</th></tr>\n";
  for (const BandResidual& b : r.bands) {
    html << "<tr><td class=\"l\">" << EscapeHtml(b.name) << "</td><td>" << FormatValue(b.low_hz, 3)
         << "</td><td>" << FormatValue(b.high_hz, 3) << "</td><td>"
         << FormatValue(100.0 * b.error, 3) << "</td><td>" << FormatValue(100.0 * b.floor, 3)
         << "</td><td>" << FormatValue(100.0 * b.excess_share, 3) << " %</td></tr>\n";
  }
  html << "</table>\n";
  if (!r.regimes.empty()) {
    html << "<table><tr><th class=\"l\">regime</th><th>time [s]</th><th>error [%]</th>"
            "<th>floor [%]</th><th>steady share</th></tr>\n";
    for (const RegimeResidual& g : r.regimes) {
      html << "<tr><td class=\"l\">" << EscapeHtml(g.regime) << "</td><td>"
           << FormatValue(g.duration_s, 3) << "</td><td>" << FormatValue(100.0 * g.error, 3)
           << "</td><td>" << FormatValue(100.0 * g.floor, 3) << "</td><td>"
           << FormatValue(100.0 * g.steady_share, 2) << " %</td></tr>\n";
    }
    html << "</table>\n";
  }
  html << "<ul>";
  for (const std::string& finding : r.findings) html << "<li>" << EscapeHtml(finding) << "</li>";
  html << "</ul>\n";
}

// Per channel: the error before and after adding the verdict, side by side.
void WriteChannelErrors(const Diagnosis& d, const CandidateResult* winner,
                        std::ostringstream& html) {
  const CandidateResult& b = d.baseline;
  html << "<h2>Error per channel, before and after"
       << (winner ? " adding " + EscapeHtml(winner->effect) : std::string()) << "</h2>\n";
  std::vector<double> x, before, after;
  std::string names;
  for (std::size_t i = 0; i < b.channel_errors.size(); ++i) {
    x.push_back(static_cast<double>(i));
    before.push_back(100.0 * b.channel_errors[i].second);
    after.push_back(winner ? 100.0 * ErrorOf(*winner, b.channel_errors[i].first) : std::nan(""));
  }
  SvgPlot plot(1000, 260, "channel (table below)", "NRMSE on scoring data [%]");
  plot.Stems(x, before, "#c33");
  plot.Legend("fitted base model", "#c33");
  if (winner) {
    std::vector<double> shifted;
    for (double v : x) shifted.push_back(v + 0.25);
    plot.Stems(shifted, after, "#080");
    plot.Legend("with " + winner->effect, "#080");
  }
  plot.HorizontalLine(100.0 * d.noise_floor, "#888");
  html << plot.Render() << "\n<table><tr><th class=\"l\">channel</th><th>base model [%]</th>"
       << (winner ? "<th>with " + EscapeHtml(winner->effect) + " [%]</th><th>change</th>" : "")
       << "</tr>\n";
  for (const auto& [channel, error] : b.channel_errors) {
    html << "<tr><td class=\"l\">" << riglog::ChannelName(channel) << "</td><td>"
         << FormatValue(100.0 * error) << "</td>";
    if (winner) {
      const double e = ErrorOf(*winner, channel);
      html << "<td>" << FormatValue(100.0 * e) << "</td><td>"
           << FormatValue(100.0 * (e - error) / error, 3) << " %</td>";
    }
    html << "</tr>\n";
  }
  html << "</table>\n";
}

// Forward selection: the error falling step by step as the selected effects are added, overall
// and per channel, and what stopped it (the next candidate, with what the log could show of it).
void WriteSelection(const Diagnosis& d, std::ostringstream& html) {
  const CandidateResult& b = d.baseline;
  html << "<h2>Effects added one after the other</h2>\n";
  if (!d.selected.empty()) {
    html << "<p>Each effect is added to the model with the ones before it (their strengths "
            "refitted with it and the base parameters) while it beats that model significantly "
            "(at most "
         << kMaxSelectedEffects << "). Error on the scoring data: base model "
         << FormatValue(100.0 * b.error) << " %";
    for (const CandidateResult& step : d.selected) {
      html << " &rarr; <b>+ " << EscapeHtml(step.effect) << "</b> "
           << FormatValue(100.0 * step.error) << " %";
    }
    html << ".</p>\n";
    static const char* kColors[] = {"#080", "#06c", "#a0a", "#c80"};
    std::vector<double> x;
    for (std::size_t i = 0; i < b.channel_errors.size(); ++i) x.push_back(static_cast<double>(i));
    SvgPlot plot(1000, 260, "channel (table below)", "NRMSE on scoring data [%]");
    std::vector<double> before;
    for (const auto& [channel, error] : b.channel_errors) before.push_back(100.0 * error);
    plot.Stems(x, before, "#c33");
    plot.Legend("fitted base model", "#c33");
    for (std::size_t s = 0; s < d.selected.size(); ++s) {
      std::vector<double> shifted, after;
      for (std::size_t i = 0; i < b.channel_errors.size(); ++i) {
        shifted.push_back(x[i] + 0.2 * static_cast<double>(s + 1));
        after.push_back(100.0 * ErrorOf(d.selected[s], b.channel_errors[i].first));
      }
      const char* color = kColors[s % 4];
      plot.Stems(shifted, after, color);
      plot.Legend("+ " + d.selected[s].effect, color);
    }
    plot.HorizontalLine(100.0 * d.noise_floor, "#888");
    html << plot.Render() << "\n<table><tr><th class=\"l\">channel</th><th>base model [%]</th>";
    for (const CandidateResult& step : d.selected) {
      html << "<th>+ " << EscapeHtml(step.effect) << " [%]</th>";
    }
    html << "</tr>\n<tr><td class=\"l\"><b>mean</b></td><td><b>" << FormatValue(100.0 * b.error)
         << "</b></td>";
    for (const CandidateResult& step : d.selected) {
      html << "<td><b>" << FormatValue(100.0 * step.error) << "</b> ("
           << FormatValue(-100.0 * step.improvement, 3) << " %)</td>";
    }
    html << "</tr>\n";
    for (const auto& [channel, error] : b.channel_errors) {
      html << "<tr><td class=\"l\">" << riglog::ChannelName(channel) << "</td><td>"
           << FormatValue(100.0 * error) << "</td>";
      for (const CandidateResult& step : d.selected) {
        html << "<td>" << FormatValue(100.0 * ErrorOf(step, channel)) << "</td>";
      }
      html << "</tr>\n";
    }
    html << "</table>\n";
  }
  html << "<p>Selection ended: " << EscapeHtml(d.selection_end) << ".";
  if (d.next) {
    html << " Next best: "
         << EscapeHtml(DescribeCandidate(*d.next, d.selected.empty() ? b : d.selected.back()))
         << ".";
  }
  html << "</p>\n";
}

// Every candidate, best first, with what it explains.
void WriteCandidates(const Diagnosis& d, std::ostringstream& html) {
  const CandidateResult& b = d.baseline;
  html << "<h2>Candidates, best first</h2>\n<table><tr><th>#</th><th class=\"l\">effect</th>"
          "<th>error [%]</th><th>penalised [%]</th><th>improvement</th><th>significant</th>"
          "<th class=\"l\">fitted effect parameters</th><th class=\"l\">what it "
          "explains</th></tr>\n";
  html << "<tr><td></td><td class=\"l\">(base model)</td><td>" << FormatValue(100.0 * b.error)
       << "</td><td></td><td></td><td></td><td class=\"l\"></td><td class=\"l\"></td></tr>\n";
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    const CandidateResult& c = d.candidates[i];
    std::string params;
    for (const NamedValue& p : c.params) {
      if (p.key.find('.') == std::string::npos) continue;
      params += p.key + " = " + FormatValue(p.value) + " &plusmn; " +
                FormatValue(p.standard_error, 2) + " ";
    }
    html << "<tr><td>" << i + 1 << "</td><td class=\"l\">" << EscapeHtml(c.effect) << "</td><td>"
         << FormatValue(100.0 * c.error) << "</td><td>" << FormatValue(100.0 * c.penalised_error)
         << "</td><td>" << FormatValue(100.0 * c.improvement, 3) << " %</td><td class=\""
         << (c.significant ? "yes\">yes" : "no\">no") << "</td><td class=\"l\">" << params
         << "</td><td class=\"l\">"
         << EscapeHtml(c.failure.empty() ? c.explains : "not fitted: " + c.failure)
         << (c.significant || c.strength_key.empty()
                 ? std::string()
                 : "<br><small>" + EscapeHtml(DescribeDetectability(c)) + "</small>")
         << "</td></tr>\n";
  }
  html << "</table>\n";
  if (!d.failed.empty()) {
    html << "<p>Could not be fitted (not ranked):";
    for (const CandidateResult& c : d.failed) {
      html << " <b>" << EscapeHtml(c.effect) << "</b>"
           << (c.round > 1 ? " (round " + std::to_string(c.round) + ")" : std::string()) << ": "
           << EscapeHtml(c.failure) << ";";
    }
    html << "</p>\n";
  }
}

// Where the fitted base model fails: along the pipe and per channel.
void WriteBaseModelFailures(const Diagnosis& d, std::ostringstream& html) {
  const Comparison& cmp = d.baseline_comparison;
  html << "<h2>Where the fitted base model fails</h2>\n";
  if (!cmp.profile.empty()) {
    std::vector<double> x, y;
    for (const ProfilePoint& p : cmp.profile) x.push_back(p.x_m), y.push_back(100.0 * p.nrmse);
    SvgPlot plot(1000, 220, "position along the pipe [m]", "NRMSE [%]");
    plot.Line(x, y, "#c33", 1.5);
    plot.Markers(x, y, "#c33");
    html << plot.Render() << "\n";
  }
  html << "<table><tr><th class=\"l\">channel</th><th>NRMSE [%]</th><th>lag [s]</th>"
          "<th class=\"l\">bands (f: model/measured, phase)</th><th>residual white</th>"
          "<th>independent of inputs</th></tr>\n";
  for (const ChannelMetrics& m : cmp.channels) {
    std::string bands;
    for (const BandMetrics& band : m.bands) {
      bands += FormatValue(band.freq_hz, 3) + " Hz: " + FormatValue(band.magnitude_ratio, 3) +
               ", " + FormatValue(band.phase_diff_deg, 3) + "&deg;; ";
    }
    html << "<tr><td class=\"l\">" << riglog::ChannelName(m.channel) << "</td><td>"
         << FormatValue(100.0 * m.nrmse) << "</td><td>" << FormatValue(m.lag_s, 3)
         << "</td><td class=\"l\">" << bands << "</td><td>" << (m.residual.white ? "yes" : "no")
         << "</td><td>" << (m.residual.independent_of_inputs ? "yes" : "no") << "</td></tr>\n";
  }
  html << "</table>\n";
}

}  // namespace

std::string DiagnosisHtml(const Diagnosis& d, const std::string& log_path) {
  std::ostringstream html;
  const CandidateResult* winner = nullptr;
  if (d.verdict) {
    for (const CandidateResult& c : d.candidates) {
      if (c.effect == *d.verdict) winner = &c;
    }
  }
  WriteVerdict(d, winner, log_path, html);
  WriteSelection(d, html);
  WriteWhatIsLeft(d, html);
  WriteRegimes(d, html);
  WriteChannelErrors(d, winner, html);
  WriteCandidates(d, html);
  WriteBaseModelFailures(d, html);
  html << "<p>Made by <code>mpdrig diagnose</code>. Ranking: compare's error on the "
          "scoring data times (1 + "
       << FormatValue(100.0 * kParameterPrice) << " % per extra parameter); significant: "
       << "better than the model it extends by more than "
       << FormatValue(100.0 * kMinRelativeImprovement) << " % and more than "
       << FormatValue(kSignificanceZ) << " standard errors over " << kScoreBlocks
       << " blocks of the scoring data.</p>\n</body></html>\n";
  return html.str();
}

}  // namespace mpdrig::report
