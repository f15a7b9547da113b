#include "tools/report/diagnosis_report.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "model/common/units.h"
#include "model/riglog/channels.h"
#include "tools/report/svg_plot.h"

namespace mpdrig::report {
namespace {

std::string Num(double value) {
  if (!std::isfinite(value)) return "null";
  std::string text;
  riglog::AppendNumber(value, &text);
  return text;
}

std::string Quote(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\', out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string ParamsJson(const std::vector<NamedValue>& params) {
  std::string out = "{";
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (i) out += ",";
    out += Quote(params[i].key) + ":{\"value\":" + Num(params[i].value) +
           ",\"std_error\":" + Num(params[i].standard_error) +
           ",\"held\":" + (params[i].held ? "true" : "false") + "}";
  }
  return out + "}";
}

std::string ChannelsJson(const std::vector<std::pair<Channel, double>>& errors) {
  std::string out = "{";
  for (std::size_t i = 0; i < errors.size(); ++i) {
    if (i) out += ",";
    out += Quote(std::string(riglog::ChannelName(errors[i].first))) + ":" + Num(errors[i].second);
  }
  return out + "}";
}

double ErrorOf(const CandidateResult& result, Channel channel) {
  for (const auto& [c, e] : result.channel_errors) {
    if (c == channel) return e;
  }
  return std::nan("");
}

// One candidate's object; `reference` is the model it was measured against (the baseline, or
// the model with the effects selected before it).
std::string CandidateJson(const CandidateResult& c, const CandidateResult& reference) {
  std::ostringstream out;
  out << "{\"effect\":" << Quote(c.effect) << ",\"round\":" << c.round
      << ",\"params\":" << ParamsJson(c.params) << ",\"error\":" << Num(c.error)
      << ",\"penalised_error\":" << Num(c.penalised_error) << ",\"fit_error\":" << Num(c.fit_error)
      << ",\"improvement\":" << Num(c.improvement)
      << ",\"improvement_std_error\":" << Num(c.improvement_std_error)
      << ",\"extra_params\":" << c.extra_params
      << ",\"significant\":" << (c.significant ? "true" : "false")
      << ",\"explains\":" << Quote(c.explains)
      << ",\"description\":" << Quote(DescribeCandidate(c, reference))
      << ",\"channels\":" << ChannelsJson(c.channel_errors);
  if (c.floor_error) out << ",\"floor_error\":" << Num(*c.floor_error);
  if (!c.failure.empty()) out << ",\"failure\":" << Quote(c.failure);
  if (!c.strength_key.empty()) {
    out << ",\"strength_key\":" << Quote(c.strength_key) << ",\"detectable_from\":"
        << (c.detectable_from ? Num(*c.detectable_from) : std::string("null"))
        << ",\"strength_inverse\":" << (c.strength_inverse ? "true" : "false")
        << ",\"strength_scan_limit\":" << Num(c.strength_scan_limit);
  }
  out << "}";
  return out.str();
}

// The log's regimes and the split (regimes.h).
std::string RegimesJson(const Diagnosis& d) {
  std::ostringstream out;
  out << ",\"split\":{\"fit_end_s\":" << Num(d.fit_end_s)
      << ",\"requested_fit_end_s\":" << Num(d.requested_fit_end_s) << ",\"one_sided\":[";
  for (std::size_t i = 0; i < d.one_sided_regimes.size(); ++i) {
    out << (i ? "," : "") << Quote(d.one_sided_regimes[i]);
  }
  out << "]},\"regimes\":[";
  for (std::size_t i = 0; i < d.regimes.size(); ++i) {
    const Regime& r = d.regimes[i];
    out << (i ? "," : "") << "{\"name\":" << Quote(r.name) << ",\"input\":" << Quote(r.input)
        << ",\"duration_s\":" << Num(r.duration_s) << ",\"fit_s\":" << Num(r.fit_s)
        << ",\"score_s\":" << Num(r.score_s) << ",\"intervals\":[";
    for (std::size_t k = 0; k < r.intervals.size(); ++k) {
      out << (k ? "," : "") << "[" << Num(r.intervals[k].begin_s) << ","
          << Num(r.intervals[k].end_s) << "]";
    }
    out << "]}";
  }
  out << "]";
  return out.str();
}

// What the best model leaves (residual_signature.h), lab units for the offsets.
std::string ResidualJson(const ResidualSignature& r) {
  std::ostringstream out;
  out << ",\"residual\":{\"model\":" << Quote(r.model)
      << ",\"misses\":" << (r.misses ? "true" : "false")
      << ",\"above_noise\":" << (r.above_noise ? "true" : "false") << ",\"error\":" << Num(r.error)
      << ",\"noise_floor\":" << Num(r.noise_floor) << ",\"sensor_floor\":" << Num(r.sensor_floor)
      << ",\"input_floor\":" << Num(r.input_floor) << ",\"misses_factor\":" << Num(kMissesFactor)
      << ",\"noise_floor_method\":" << Quote(kNoiseFloorMethod)
      << ",\"whole_error\":" << Num(r.whole_error) << ",\"whole_floor\":" << Num(r.whole_floor)
      << ",\"steady_share\":" << Num(r.steady_share)
      << ",\"quarter_wave_hz\":" << Num(r.quarter_wave_hz) << ",\"summary\":" << Quote(r.Summary())
      << ",\"reasons\":[";
  for (std::size_t i = 0; i < r.reasons.size(); ++i) out << (i ? "," : "") << Quote(r.reasons[i]);
  out << "],\"findings\":[";
  for (std::size_t i = 0; i < r.findings.size(); ++i) out << (i ? "," : "") << Quote(r.findings[i]);
  out << "],\"channels\":[";
  for (std::size_t i = 0; i < r.channels.size(); ++i) {
    const ChannelResidual& c = r.channels[i];
    out << (i ? "," : "") << "{\"channel\":" << Quote(std::string(riglog::ChannelName(c.channel)))
        << ",\"x_m\":" << (c.x_m ? Num(*c.x_m) : std::string("null"))
        << ",\"nrmse\":" << Num(c.nrmse) << ",\"sensor_floor\":" << Num(c.sensor_floor)
        << ",\"input_floor\":" << Num(c.input_floor) << ",\"floor\":" << Num(c.floor)
        << ",\"excess\":" << Num(c.excess) << ",\"bias\":" << Num(c.bias_unit)
        << ",\"steady_share\":" << Num(c.steady_share) << ",\"score_nrmse\":" << Num(c.score_nrmse)
        << ",\"score_floor\":" << Num(c.score_floor) << "}";
  }
  out << "],\"bands\":[";
  for (std::size_t i = 0; i < r.bands.size(); ++i) {
    const BandResidual& b = r.bands[i];
    out << (i ? "," : "") << "{\"name\":" << Quote(b.name) << ",\"low_hz\":" << Num(b.low_hz)
        << ",\"high_hz\":" << Num(b.high_hz) << ",\"error\":" << Num(b.error)
        << ",\"floor\":" << Num(b.floor) << ",\"excess_share\":" << Num(b.excess_share) << "}";
  }
  out << "],\"regimes\":[";
  for (std::size_t i = 0; i < r.regimes.size(); ++i) {
    const RegimeResidual& g = r.regimes[i];
    out << (i ? "," : "") << "{\"regime\":" << Quote(g.regime) << ",\"input\":" << Quote(g.input)
        << ",\"duration_s\":" << Num(g.duration_s) << ",\"error\":" << Num(g.error)
        << ",\"floor\":" << Num(g.floor) << ",\"steady_share\":" << Num(g.steady_share)
        << ",\"channels\":" << ChannelsJson(g.channel_errors) << "}";
  }
  out << "]}";
  return out.str();
}

}  // namespace

std::string DiagnosisJson(const Diagnosis& d, const std::string& log_path) {
  std::ostringstream out;
  const CandidateResult& b = d.baseline;
  out << "{\"log\":" << Quote(log_path) << ",\"fit_end_s\":" << Num(d.fit_end_s)
      << ",\"noise_floor\":" << Num(d.noise_floor) << ",\"replays\":" << d.replays;
  // Pressures held on a floor (cavity_evidence.h): where, at what level, how often.
  out << ",\"pressure_floors\":{\"present\":" << (d.pressure_floors.present() ? "true" : "false")
      << ",\"level_pa\":" << Num(d.pressure_floors.level_pa)
      << ",\"holds\":" << d.pressure_floors.holds << ",\"channels\":[";
  for (std::size_t i = 0; i < d.pressure_floors.floors.size(); ++i) {
    const ChannelFloor& floor = d.pressure_floors.floors[i];
    out << (i ? "," : "") << "{\"channel\":" << Quote(std::string(ChannelName(floor.channel)))
        << ",\"level_pa\":" << Num(floor.level_pa) << ",\"holds\":" << floor.holds.size() << "}";
  }
  out << "]},\"runs\":[";
  // Where the model runs went, stage by stage.
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const StageRuns& r = d.runs[i];
    out << (i ? "," : "") << "{\"stage\":" << Quote(r.stage) << ",\"scans\":" << r.scans
        << ",\"fits\":" << r.fits << ",\"detectability\":" << r.detectability
        << ",\"scoring\":" << r.scoring << "}";
  }
  out << "]"
      // The choke's and FT2's levels as estimated at the fitted base model, lab units.
      << ",\"input_levels\":{\"choke_offset_deg\":"
      << Num(units::ChokeFracToDeg(d.input_levels.choke_offset_frac))
      << ",\"choke_trend_deg\":" << Num(units::ChokeFracToDeg(d.input_levels.choke_trend_frac))
      << ",\"FT2_offset_lpm\":" << Num(units::M3psToLpm(d.input_levels.pump_offset_m3ps))
      << ",\"FT2_trend_lpm\":" << Num(units::M3psToLpm(d.input_levels.pump_trend_m3ps))
      << ",\"at_bound\":" << (d.input_levels.at_bound ? "true" : "false") << "}"
      << ",\"baseline\":{\"error\":" << Num(b.error) << ",\"fit_error\":" << Num(b.fit_error)
      << ",\"params\":" << ParamsJson(b.params)
      << ",\"channels\":" << ChannelsJson(b.channel_errors) << "},\"candidates\":[";
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    out << (i ? "," : "") << CandidateJson(d.candidates[i], b);
  }
  out << "],\"verdict\":" << (d.verdict ? Quote(*d.verdict) : std::string("null"));
  out << ",\"equivalent\":[";
  for (std::size_t i = 0; i < d.equivalent.size(); ++i)
    out << (i ? "," : "") << Quote(d.equivalent[i]);
  out << "]";
  // Forward selection: the effects added in order, each against the model before it.
  out << ",\"selected\":[";
  for (std::size_t i = 0; i < d.selected.size(); ++i) {
    out << (i ? "," : "") << CandidateJson(d.selected[i], i ? d.selected[i - 1] : b);
  }
  out << "],\"next\":"
      << (d.next ? CandidateJson(*d.next, d.selected.empty() ? b : d.selected.back())
                 : std::string("null"))
      << ",\"selection_end\":" << Quote(d.selection_end) << ",\"failed\":[";
  for (std::size_t i = 0; i < d.failed.size(); ++i) {
    out << (i ? "," : "") << "{\"effect\":" << Quote(d.failed[i].effect)
        << ",\"round\":" << d.failed[i].round << ",\"failure\":" << Quote(d.failed[i].failure)
        << "}";
  }
  out << "]";
  out << RegimesJson(d);
  if (d.residual) out << ResidualJson(*d.residual);
  // Where the fitted base model fails: worst channels, worst bands, lags.
  const Comparison& cmp = d.baseline_comparison;
  std::vector<const ChannelMetrics*> channels;
  for (const ChannelMetrics& m : cmp.channels) channels.push_back(&m);
  std::sort(channels.begin(), channels.end(), [](auto* a, auto* b) {
    return (std::isfinite(a->nrmse) ? a->nrmse : -1.0) >
           (std::isfinite(b->nrmse) ? b->nrmse : -1.0);
  });
  out << ",\"where_baseline_fails\":{\"worst_channels\":[";
  for (std::size_t i = 0; i < channels.size() && i < 5; ++i) {
    const ChannelMetrics& m = *channels[i];
    if (i) out << ",";
    out << "{\"channel\":" << Quote(std::string(riglog::ChannelName(m.channel)))
        << ",\"nrmse\":" << Num(m.nrmse) << ",\"lag_s\":" << Num(m.lag_s)
        << ",\"residual_white\":" << (m.residual.white ? "true" : "false")
        << ",\"residual_independent_of_inputs\":"
        << (m.residual.independent_of_inputs ? "true" : "false") << ",\"bands\":[";
    for (std::size_t k = 0; k < m.bands.size(); ++k) {
      const BandMetrics& band = m.bands[k];
      if (k) out << ",";
      out << "{\"freq_hz\":" << Num(band.freq_hz)
          << ",\"magnitude_ratio\":" << Num(band.magnitude_ratio)
          << ",\"phase_diff_deg\":" << Num(band.phase_diff_deg)
          << ",\"band_nrmse\":" << Num(band.band_nrmse) << "}";
    }
    out << "]}";
  }
  out << "]}}\n";
  return out.str();
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
