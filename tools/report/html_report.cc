#include "tools/report/html_report.h"

#include "model/common/units.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

#include "model/riglog/channels.h"
#include "tools/report/lab_units.h"
#include "tools/report/svg_plot.h"

namespace mpdrig::report {
namespace {

constexpr const char* kMeasuredColor = "#1f5fbf";
constexpr const char* kModelColor = "#e07b00";
constexpr const char* kResidualColor = "#a02040";
constexpr const char* kBandColor = "#888";

std::string Name(Channel channel) { return std::string(riglog::ChannelName(channel)); }

// Background colour of a fit cell: green at >= 90 %, yellow around 50 %, red at <= 0 %.
std::string FitColor(double fit_percent) {
  if (!std::isfinite(fit_percent)) return "#eee";
  if (fit_percent >= 90.0) return "#c8ecc8";
  if (fit_percent >= 70.0) return "#e4f4c0";
  if (fit_percent >= 40.0) return "#fbefb8";
  return "#f6c6c0";
}

// The band with the largest error amplitude (not the largest relative error: a harmonic with
// almost no signal would win that).
const BandMetrics* WorstBand(const ChannelMetrics& channel) {
  const BandMetrics* worst = nullptr;
  for (const BandMetrics& band : channel.bands) {
    if (std::isfinite(band.error_amplitude) &&
        (worst == nullptr || band.error_amplitude > worst->error_amplitude))
      worst = &band;
  }
  return worst;
}

std::string YesNo(bool value) {
  return value ? "<span class=ok>yes</span>" : "<span class=bad>no</span>";
}

std::string SummaryTable(const Comparison& comparison) {
  std::string html =
      "<table><tr><th>channel</th><th>fit %</th><th>NRMSE</th><th>RMS error</th><th>bias "
      "(model &minus; meas.)</th><th>lag [s]<br><small>+ model late</small></th><th>worst band "
      "[Hz]</th><th>error amplitude</th><th>band NRMSE</th><th>|model/meas.|</th><th>phase diff "
      "[deg]</th><th>residual "
      "white</th><th>indep. of inputs</th></tr>";
  for (const ChannelMetrics& channel : comparison.channels) {
    const std::string unit = DifferenceUnit(channel.unit);
    const BandMetrics* worst = WorstBand(channel);
    html += "<tr><td><a href=\"#ch-" + Name(channel.channel) + "\">" + Name(channel.channel) +
            "</a></td><td style=\"background:" + FitColor(channel.fit_percent) + "\">" +
            FormatValue(channel.fit_percent, 4) + "</td><td>" + FormatValue(channel.nrmse) +
            "</td><td>" + FormatValue(LabDifference(channel.unit, channel.rms_si)) + " " + unit +
            "</td><td>" + FormatValue(LabDifference(channel.unit, channel.bias_si)) + " " + unit +
            "</td><td>" + FormatValue(channel.lag_s) + "</td>";
    if (worst != nullptr) {
      html += "<td>" + FormatValue(worst->freq_hz) + "</td><td>" +
              FormatValue(LabDifference(channel.unit, worst->error_amplitude)) + " " + unit +
              "</td><td>" + FormatValue(worst->band_nrmse) + "</td><td>" +
              FormatValue(worst->magnitude_ratio) + "</td><td>" +
              FormatValue(worst->phase_diff_deg, 3) + "</td>";
    } else {
      html += "<td colspan=5>no piston peak</td>";
    }
    html += "<td>" + YesNo(channel.residual.white) + "</td><td>" +
            YesNo(channel.residual.independent_of_inputs) + "</td></tr>";
  }
  return html + "</table>";
}

std::string ProfileSection(const Comparison& comparison) {
  if (comparison.profile.empty()) return "<p>No PT1..PT10 in the log.</p>";
  std::vector<double> x, fit, bias, rms;
  std::string unit = "bar";
  for (const ProfilePoint& point : comparison.profile) {
    const ChannelMetrics* channel = comparison.Find(point.channel);
    unit = DifferenceUnit(channel->unit);
    x.push_back(point.x_m);
    fit.push_back(point.fit_percent);
    bias.push_back(LabDifference(channel->unit, point.bias_si));
    rms.push_back(LabDifference(channel->unit, point.rms_si));
  }
  SvgPlot fit_plot(560, 240, "x along the pipe [m] (0: heave generator, 900: choke)", "fit %");
  fit_plot.Line(x, fit, kMeasuredColor, 1.5);
  fit_plot.Markers(x, fit, kMeasuredColor, 3.5);
  fit_plot.HorizontalLine(100.0, "#2a2");
  SvgPlot error_plot(560, 240, "x along the pipe [m]", "error [" + unit + "]");
  error_plot.Line(x, rms, kResidualColor, 1.5);
  error_plot.Markers(x, rms, kResidualColor, 3.5);
  error_plot.Line(x, bias, kModelColor, 1.5, "5 3");
  error_plot.Markers(x, bias, kModelColor, 3.0);
  error_plot.HorizontalLine(0.0, "#555");
  error_plot.Legend("RMS error", kResidualColor);
  error_plot.Legend("bias (model - meas.)", kModelColor);
  return "<div class=row>" + fit_plot.Render() + error_plot.Render() + "</div>";
}

std::string TransferSection(const Comparison& comparison) {
  if (comparison.transfer_functions.empty()) return "<p>Neither PT1 nor C2 is in the log.</p>";
  std::string html;
  for (const TransferFunction& tf : comparison.transfer_functions) {
    const ChannelMetrics* channel = comparison.Find(tf.output);
    const std::string unit = DifferenceUnit(channel->unit) + "/m";
    std::vector<double> f, mag_measured, mag_model, phase_measured, phase_model;
    for (const TransferPoint& point : tf.points) {
      f.push_back(point.freq_hz);
      mag_measured.push_back(LabDifference(channel->unit, std::abs(point.measured)));
      mag_model.push_back(LabDifference(channel->unit, std::abs(point.model)));
      phase_measured.push_back(std::arg(point.measured) * 180.0 / std::numbers::pi);
      phase_model.push_back(std::arg(point.model) * 180.0 / std::numbers::pi);
    }
    // Phases continued along frequency (the measured curve), and the model's drawn on the branch
    // nearest the measured one, so that a curve through +-180 deg does not jump across the plot.
    for (std::size_t i = 1; i < phase_measured.size(); ++i) {
      phase_measured[i] =
          phase_measured[i - 1] + std::remainder(phase_measured[i] - phase_measured[i - 1], 360.0);
    }
    for (std::size_t i = 0; i < phase_model.size(); ++i) {
      phase_model[i] =
          phase_measured[i] + std::remainder(phase_model[i] - phase_measured[i], 360.0);
    }
    html += "<h3>piston_position &rarr; " + Name(tf.output) + "</h3>";
    if (tf.points.empty()) {
      html += "<p>The piston does not excite any frequency.</p>";
      continue;
    }
    const bool log_x = f.size() > 2 && f.back() > 20.0 * f.front();
    SvgPlot magnitude(560, 260, "frequency [Hz]", "|H| [" + unit + "]");
    magnitude.SetLogX(log_x);
    magnitude.SetLogY(true);
    SvgPlot phase(560, 260, "frequency [Hz]", "phase [deg]");
    phase.SetLogX(log_x);
    for (SvgPlot* plot : {&magnitude, &phase}) {
      const bool is_mag = plot == &magnitude;
      if (f.size() > 1) {
        plot->Line(f, is_mag ? mag_measured : phase_measured, kMeasuredColor, 1.2);
        plot->Line(f, is_mag ? mag_model : phase_model, kModelColor, 1.2, "5 3");
      }
      plot->Markers(f, is_mag ? mag_measured : phase_measured, kMeasuredColor, 3.0);
      plot->Markers(f, is_mag ? mag_model : phase_model, kModelColor, 2.2);
      plot->Legend("measured", kMeasuredColor);
      plot->Legend("model", kModelColor);
    }
    html += "<div class=row>" + magnitude.Render() + phase.Render() + "</div>";
  }
  return html;
}

// The inputs as measured and as the model was fed them (reconstructed under their noise, or as
// measured), over the log's first kInputCloseUpSamples samples, in lab units.
std::string InputsSection(const Comparison& comparison) {
  const InputCloseUp& inputs = comparison.input_close_up;
  if (inputs.time_s.size() < 2) return "";
  std::string html = "<h2>Inputs: as measured and as replayed</h2><p>";
  if (const auto& plan = comparison.input_reconstruction) {
    html +=
        "The model was fed the inputs reconstructed under their noise, estimated from the log: "
        "piston " +
        FormatValue(plan->piston_noise_m * 1e3, 3) + " mm (band up to " +
        FormatValue(plan->piston_band_hz, 3) + " Hz), choke " +
        FormatValue(units::ChokeFracToDeg(plan->choke_noise_frac), 3) + " deg, FT2 " +
        FormatValue(units::M3psToLpm(plan->pump_noise_m3ps), 3) + " L/min, C1 " +
        FormatValue(plan->outlet_noise_pa * 1e-5, 3) + " bar (standard deviations).";
    if (plan->levels.applied()) {
      html +=
          " The choke's and FT2's levels were corrected from the measured pressures, within "
          "what their noise allows: choke " +
          FormatValue(units::ChokeFracToDeg(plan->levels.choke_offset_frac), 3) + " deg (trend " +
          FormatValue(units::ChokeFracToDeg(plan->levels.choke_trend_frac), 3) + "), FT2 " +
          FormatValue(units::M3psToLpm(plan->levels.pump_offset_m3ps), 3) + " L/min (trend " +
          FormatValue(units::M3psToLpm(plan->levels.pump_trend_m3ps), 3) +
          ") (mean pressure residual " + FormatValue(plan->levels.residual_before_pa * 1e-5, 3) +
          " bar before" +
          (plan->levels.at_bound ? ", at the bound: the rest is the model's)." : ").");
    }
  } else {
    html += "The model was fed the inputs as measured (--raw-inputs).";
  }
  if (comparison.warmup) {
    html += " The log starts mid-heave: the replay started after a " +
            FormatValue(comparison.warmup->duration_s, 3) + " s warm-up on its periodic " +
            "excitation (period " + FormatValue(comparison.warmup->period_s, 4) + " s).";
  }
  if (comparison.measured_start) {
    html +=
        " The log starts in the middle of an excitation that is not periodic: the replay "
        "started from the pipe's state as measured (pressures and velocities along the pipe "
        "fitted to the first travel times).";
  }
  html += " First " + FormatValue(inputs.time_s.back() - inputs.time_s.front(), 3) +
          " s.</p><div class=row>";
  struct Input {
    const char* name;
    const char* unit;
    double (*lab)(double, double);
  };
  const Input kInputs[] = {
      {"piston_position", "mm", [](double v, double) { return v * 1e3; }},
      {"choke_position", "deg", [](double v, double) { return units::ChokeFracToDeg(v); }},
      {"FT2", "L/min", [](double v, double) { return units::M3psToLpm(v); }},
      {"C1", "barg", [](double v, double atm) { return (v - atm) * 1e-5; }},
  };
  for (std::size_t k = 0; k < 4; ++k) {
    auto lab = [&](const std::vector<double>& v) {
      std::vector<double> out(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) {
        out[i] = kInputs[k].lab(v[i], comparison.atmospheric_pressure_pa);
      }
      return out;
    };
    SvgPlot plot(570, 200, "time [s]", std::string(kInputs[k].name) + " [" + kInputs[k].unit + "]");
    plot.Line(inputs.time_s, lab(inputs.measured[k]), kMeasuredColor, 0.8);
    plot.Line(inputs.time_s, lab(inputs.replayed[k]), kModelColor, 1.6);
    plot.Legend("measured", kMeasuredColor);
    plot.Legend("replayed", kModelColor);
    html += plot.Render();
  }
  return html + "</div>";
}

// The channel's traces: measured and model as min/max bands per column, their difference, and a
// close-up of every sample around the largest error.
std::string ChannelTraces(const ChannelMetrics& channel, const ReportContext& context) {
  const std::string name = Name(channel.channel);
  const riglog::Unit unit = channel.unit;
  const std::string level_unit(riglog::UnitSuffix(unit));
  const std::string diff_unit = DifferenceUnit(unit);
  const TraceEnvelope& env = channel.envelope;
  const std::size_t columns = env.measured_min.size();
  std::vector<double> t(columns);
  for (std::size_t c = 0; c < columns; ++c) {
    t[c] = env.t0_s + (c + 0.5) / static_cast<double>(columns) * (env.t1_s - env.t0_s);
  }
  auto level = [&](const std::vector<double>& v) {
    std::vector<double> out(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      out[i] = LabValue(unit, v[i], context.atmospheric_pressure_pa);
    }
    return out;
  };
  auto difference = [&](const std::vector<double>& v) {
    std::vector<double> out(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) out[i] = LabDifference(unit, v[i]);
    return out;
  };
  SvgPlot traces(1160, 260, "time [s]", name + " [" + level_unit + "]");
  traces.Band(t, level(env.measured_min), level(env.measured_max), kMeasuredColor, 0.35);
  traces.Band(t, level(env.model_min), level(env.model_max), kModelColor, 0.35);
  traces.Legend("measured (min/max per column)", kMeasuredColor);
  traces.Legend("model", kModelColor);
  SvgPlot residual(1160, 170, "time [s]", "meas. - model [" + diff_unit + "]");
  residual.Band(t, difference(env.residual_min), difference(env.residual_max), kResidualColor, 0.5);
  residual.HorizontalLine(0.0, "#555");
  std::string html = traces.Render() + "<br>" + residual.Render();
  if (channel.zoom.time_s.size() > 1) {
    SvgPlot zoom(1160, 220, "time [s]", name + " [" + level_unit + "]");
    zoom.Line(channel.zoom.time_s, level(channel.zoom.measured), kMeasuredColor, 1.5);
    zoom.Line(channel.zoom.time_s, level(channel.zoom.model), kModelColor, 1.5, "6 3");
    zoom.Legend("measured", kMeasuredColor);
    zoom.Legend("model", kModelColor);
    html +=
        "<p><small>Close-up: every sample around the largest error.</small></p>" + zoom.Render();
  }
  return html;
}

// The error at the dominant frequencies and their harmonics, one row per band.
std::string BandTable(const ChannelMetrics& channel) {
  if (channel.bands.empty()) return "";
  const riglog::Unit unit = channel.unit;
  const std::string diff_unit = DifferenceUnit(unit);
  std::string html =
      "<table><tr><th>band [Hz]</th><th>harmonic</th><th>measured amplitude</th><th>model "
      "amplitude</th><th>|model/meas.|</th><th>phase diff [deg]<br><small>&minus; model "
      "lags</small></th><th>band NRMSE</th><th>error amplitude</th></tr>";
  for (const BandMetrics& band : channel.bands) {
    html += "<tr><td>" + FormatValue(band.freq_hz) + " (" + FormatValue(band.low_hz, 3) +
            "&ndash;" + FormatValue(band.high_hz, 3) + ")</td><td>" +
            (band.harmonic > 0 ? std::to_string(band.harmonic) + " f0" : "other peak") +
            "</td><td>" + FormatValue(LabDifference(unit, band.measured_amplitude)) + " " +
            diff_unit + "</td><td>" + FormatValue(LabDifference(unit, band.model_amplitude)) + " " +
            diff_unit + "</td><td>" + FormatValue(band.magnitude_ratio) + "</td><td>" +
            FormatValue(band.phase_diff_deg, 3) + "</td><td>" + FormatValue(band.band_nrmse) +
            "</td><td>" + FormatValue(LabDifference(unit, band.error_amplitude)) + " " + diff_unit +
            "</td></tr>";
  }
  return html + "</table>";
}

// One correlation plot against the 99 % band.
std::string CorrelationPlot(const std::vector<double>& lags, const std::vector<double>& r,
                            const std::string& x_label, const std::string& y_label, double band) {
  SvgPlot plot(380, 200, x_label, y_label);
  plot.Stems(lags, r, kResidualColor);
  plot.HorizontalLine(band, kBandColor);
  plot.HorizontalLine(-band, kBandColor);
  return plot.Render();
}

// Residual analysis, as MATLAB's resid: correlations against the 99% band.
std::string ResidualDetails(const ResidualAnalysis& analysis) {
  const double band = analysis.confidence;
  std::vector<double> k, r;
  for (std::size_t i = 1; i < analysis.autocorrelation.size(); ++i) {
    k.push_back(static_cast<double>(i));
    r.push_back(analysis.autocorrelation[i]);
  }
  std::string plots = CorrelationPlot(k, r, "lag [samples]", "residual autocorrelation", band);
  for (const Correlation& cross : analysis.cross) {
    if (cross.constant_input) continue;
    k.clear(), r.clear();
    for (std::size_t i = 0; i < cross.r.size(); ++i) {
      k.push_back(static_cast<double>(i) - analysis.lags);
      r.push_back(cross.r[i]);
    }
    plots +=
        CorrelationPlot(k, r, "lag [samples] (+: input leads)", "corr. with " + cross.input, band);
  }
  return "<details><summary>Residual analysis: white " + YesNo(analysis.white) +
         ", independent of the inputs " + YesNo(analysis.independent_of_inputs) +
         " (99% band &plusmn;" + FormatValue(band, 3) + ")</summary><div class=row>" + plots +
         "</div></details>";
}

std::string ChannelSection(const ChannelMetrics& channel, const ReportContext& context) {
  const std::string name = Name(channel.channel);
  const riglog::Unit unit = channel.unit;
  const std::string diff_unit = DifferenceUnit(unit);
  std::string html = "<section id=\"ch-" + name + "\"><h3>" + name + "</h3><p>fit " +
                     FormatValue(channel.fit_percent) + " %, NRMSE " + FormatValue(channel.nrmse) +
                     ", RMS error " + FormatValue(LabDifference(unit, channel.rms_si)) + " " +
                     diff_unit + ", bias " + FormatValue(LabDifference(unit, channel.bias_si)) +
                     " " + diff_unit + ", lag " + FormatValue(channel.lag_s) + " s (correlation " +
                     FormatValue(channel.lag_correlation, 3) + "), " +
                     std::to_string(channel.samples) + " measured samples.</p>";
  html += ChannelTraces(channel, context);
  html += BandTable(channel);
  html += ResidualDetails(channel.residual);
  return html + "</section>";
}

}  // namespace

std::string ComparisonHtml(const Comparison& comparison, const ReportContext& context) {
  std::string html =
      "<!DOCTYPE html>\n<html lang=en><head><meta charset=\"utf-8\"><title>mpdrig compare: " +
      EscapeHtml(context.log_path) +
      "</title><style>"
      "body{font-family:sans-serif;margin:16px;color:#222;max-width:1200px}"
      "table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px "
      "7px;text-align:right;font-size:13px}th{background:#f0f0f0}td:first-child{text-align:left}"
      ".row{display:flex;flex-wrap:wrap;gap:8px}.ok{color:#282}.bad{color:#b22;font-weight:bold}"
      "h2{border-bottom:2px solid #ddd;margin-top:28px}section{margin-bottom:24px}"
      "small{color:#666}.warn{background:#fde;padding:6px}"
      "</style></head><body>\n";
  html += "<h1>Model vs measurement</h1><p>Log <b>" + EscapeHtml(context.log_path) +
          "</b>: " + std::to_string(comparison.samples) + " samples over " +
          FormatValue(comparison.duration_s) + " s (mean interval " +
          FormatValue(comparison.sample_interval_s) + " s" +
          (comparison.uniform_sampling ? "" : ", <b>not uniform</b>: spectra approximate") +
          ").<br>Model: " + EscapeHtml(context.model_description) +
          (context.config.empty() ? "" : "; " + EscapeHtml(context.config)) +
          ".<br>Error (mean NRMSE over the channels): <b>" + FormatValue(comparison.error) +
          "</b>. Piston excitation bands at ";
  for (std::size_t i = 0; i < comparison.dominant_freqs_hz.size(); ++i) {
    html += (i ? ", " : "") + FormatValue(comparison.dominant_freqs_hz[i]);
  }
  html += comparison.dominant_freqs_hz.empty() ? "(none found)" : " Hz";
  html += comparison.spectrum_segments > 1
              ? ". Spectra: Welch average of " + std::to_string(comparison.spectrum_segments) +
                    " half-overlapping Hann segments of " +
                    FormatValue(comparison.spectrum_segment_s) + " s"
              : ". Spectra: one Hann-windowed periodogram of the whole log";
  html += ".</p>";
  if (comparison.first_range_event) {
    html +=
        "<p class=warn>Warning: " + EscapeHtml(comparison.first_range_event->Describe()) + "</p>";
  }
  html += "<h2>Summary</h2>" + SummaryTable(comparison) +
          "<p><small>fit = 100 (1 &minus; NRMSE), NRMSE = ||y &minus; &ycirc;|| / ||y &minus; "
          "mean(y)||. Lag from the cross-correlation peak (positive: the model is late). Bands: "
          "&plusmn;" +
          "3 bins around the piston's dominant frequencies and harmonics.</small></p>";
  html += InputsSection(comparison);
  html += "<h2>Error along the pipe</h2>" + ProfileSection(comparison);
  html +=
      "<h2>Frequency response: measured vs model</h2><p><small>Empirical transfer "
      "functions from the piston position, at the frequencies the piston "
      "excites.</small></p>" +
      TransferSection(comparison);
  html += "<h2>Channels</h2>";
  for (const ChannelMetrics& channel : comparison.channels) {
    html += ChannelSection(channel, context);
  }
  html += "<p><small>Generated by mpdrig compare.</small></p></body></html>\n";
  return html;
}

}  // namespace mpdrig::report
