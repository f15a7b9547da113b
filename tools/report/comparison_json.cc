#include "tools/report/comparison_json.h"

#include "model/common/units.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <string_view>

#include "model/riglog/channels.h"
#include "tools/report/lab_units.h"

namespace mpdrig::report {
namespace {

// A small JSON writer: objects and arrays with commas handled, numbers as the shortest text that
// reads back the same double (riglog::AppendNumber), NaN and infinities as null.
class JsonWriter {
 public:
  void BeginObject() { Value(), out_ += '{', first_ = true; }
  void EndObject() { out_ += '}', first_ = false; }
  void BeginArray() { Value(), out_ += '[', first_ = true; }
  void EndArray() { out_ += ']', first_ = false; }
  JsonWriter& Key(std::string_view key) {
    Value();
    String(key);
    out_ += ':';
    first_ = true;  // the value that follows takes no comma
    return *this;
  }
  void Number(double value) {
    Value();
    if (std::isfinite(value)) {
      riglog::AppendNumber(value, &out_);
    } else {
      out_ += "null";
    }
  }
  void Integer(long value) { Value(), out_ += std::to_string(value); }
  void Bool(bool value) { Value(), out_ += value ? "true" : "false"; }
  void Text(std::string_view text) { Value(), String(text); }
  void Numbers(const std::vector<double>& values) {
    BeginArray();
    for (double v : values) Number(v);
    EndArray();
  }
  const std::string& str() const { return out_; }

 private:
  void Value() {
    if (!first_) out_ += ',';
    first_ = false;
  }
  void String(std::string_view text) {
    out_ += '"';
    for (char c : text) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '"' || c == '\\') {
        out_ += '\\', out_ += c;
      } else if (u < 0x20) {
        static const char* kHex = "0123456789abcdef";
        out_ += "\\u00";
        out_ += kHex[u >> 4];
        out_ += kHex[u & 15];
      } else {
        out_ += c;
      }
    }
    out_ += '"';
  }
  std::string out_;
  bool first_ = true;
};

double PhaseDeg(std::complex<double> value) { return std::arg(value) * 180.0 / std::numbers::pi; }

// How the inputs reached the model (log_inputs.h): reconstructed under their noise, in lab
// units, or as measured; and whether the replay started after a warm-up.
void WriteInputs(const Comparison& comparison, JsonWriter& json) {
  json.Key("inputs").BeginObject();
  json.Key("reconstructed").Bool(comparison.input_reconstruction.has_value());
  if (const auto& plan = comparison.input_reconstruction) {
    json.Key("noise").BeginObject();
    json.Key("piston_position_mm").Number(plan->piston_noise_m * 1e3);
    json.Key("choke_position_deg").Number(units::ChokeFracToDeg(plan->choke_noise_frac));
    json.Key("FT2_lpm").Number(units::M3psToLpm(plan->pump_noise_m3ps));
    json.Key("C1_bar").Number(plan->outlet_noise_pa * 1e-5);
    json.EndObject();
    json.Key("piston_band_hz").Number(plan->piston_band_hz);
    json.Key("piston_window_s").Number(2.0 * plan->piston_half_width_s);
    json.Key("level_max_window_s")
        .Number(2.0 * static_cast<double>(plan->level_max_half_width_samples) *
                plan->sample_interval_s);
    // The choke's and FT2's levels as corrected from the measured pressures (EstimateInputLevels).
    const InputLevelCorrection& levels = plan->levels;
    json.Key("levels").BeginObject();
    // offset + trend * tau, tau from -1 at start_s to 1 at end_s (held beyond).
    json.Key("start_s").Number(levels.center_s - levels.half_span_s);
    json.Key("end_s").Number(levels.center_s + levels.half_span_s);
    json.Key("choke_offset_deg").Number(units::ChokeFracToDeg(levels.choke_offset_frac));
    json.Key("choke_trend_deg").Number(units::ChokeFracToDeg(levels.choke_trend_frac));
    json.Key("FT2_offset_lpm").Number(units::M3psToLpm(levels.pump_offset_m3ps));
    json.Key("FT2_trend_lpm").Number(units::M3psToLpm(levels.pump_trend_m3ps));
    json.Key("choke_offset_bound_deg")
        .Number(units::ChokeFracToDeg(kMaxLevelOffsetSigmas * levels.choke_sigma_frac));
    json.Key("choke_trend_bound_deg")
        .Number(units::ChokeFracToDeg(kMaxLevelOffsetSigmas * levels.choke_trend_sigma_frac));
    json.Key("FT2_offset_bound_lpm")
        .Number(units::M3psToLpm(kMaxLevelOffsetSigmas * levels.pump_sigma_m3ps));
    json.Key("FT2_trend_bound_lpm")
        .Number(units::M3psToLpm(kMaxLevelOffsetSigmas * levels.pump_trend_sigma_m3ps));
    json.Key("pressure_residual_before_bar").Number(levels.residual_before_pa * 1e-5);
    json.Key("pressure_residual_after_bar").Number(levels.residual_after_pa * 1e-5);
    json.Key("pressure_residual_trend_before_bar").Number(levels.residual_trend_before_pa * 1e-5);
    json.Key("pressure_residual_trend_after_bar").Number(levels.residual_trend_after_pa * 1e-5);
    json.Key("at_bound").Bool(levels.at_bound);
    json.EndObject();
  }
  json.Key("warmup").Bool(comparison.warmup.has_value());
  if (comparison.warmup) {
    json.Key("warmup_period_s").Number(comparison.warmup->period_s);
    json.Key("warmup_s").Number(comparison.warmup->duration_s);
  }
  json.Key("measured_start").Bool(comparison.measured_start.has_value());
  json.EndObject();
}

// The error at the bands of the dominant frequencies and their harmonics.
void WriteBands(const ChannelMetrics& channel, JsonWriter& json) {
  const riglog::Unit unit = channel.unit;
  json.Key("bands").BeginArray();
  for (const BandMetrics& band : channel.bands) {
    json.BeginObject();
    json.Key("freq_hz").Number(band.freq_hz);
    json.Key("low_hz").Number(band.low_hz);
    json.Key("high_hz").Number(band.high_hz);
    json.Key("harmonic").Integer(band.harmonic);
    json.Key("measured_amplitude").Number(LabDifference(unit, band.measured_amplitude));
    json.Key("model_amplitude").Number(LabDifference(unit, band.model_amplitude));
    json.Key("magnitude_ratio").Number(band.magnitude_ratio);
    json.Key("phase_diff_deg").Number(band.phase_diff_deg);
    json.Key("band_nrmse").Number(band.band_nrmse);
    json.Key("error_amplitude").Number(LabDifference(unit, band.error_amplitude));
    json.EndObject();
  }
  json.EndArray();
}

// Is the residual white, and independent of the inputs?
void WriteResidual(const ResidualAnalysis& residual, JsonWriter& json) {
  json.Key("residual").BeginObject();
  json.Key("lags").Integer(residual.lags);
  json.Key("confidence").Number(residual.confidence);
  json.Key("autocorrelation").Numbers(residual.autocorrelation);
  json.Key("max_abs_autocorrelation").Number(residual.max_abs_autocorrelation);
  json.Key("white").Bool(residual.white);
  json.Key("independent_of_inputs").Bool(residual.independent_of_inputs);
  json.Key("cross").BeginObject();
  for (const Correlation& cross : residual.cross) {
    json.Key(cross.input).BeginObject();
    json.Key("constant_input").Bool(cross.constant_input);
    json.Key("max_abs").Number(cross.max_abs);
    json.Key("independent").Bool(cross.independent);
    json.Key("r").Numbers(cross.r);
    json.EndObject();
  }
  json.EndObject();
  json.EndObject();
}

void WriteChannel(const ChannelMetrics& channel, const ReportContext& context, JsonWriter& json) {
  const riglog::Unit unit = channel.unit;
  json.Key(riglog::ChannelName(channel.channel)).BeginObject();
  json.Key("unit").Text(riglog::UnitSuffix(unit));
  json.Key("difference_unit").Text(DifferenceUnit(unit));
  json.Key("samples").Integer(channel.samples);
  json.Key("fit_percent").Number(channel.fit_percent);
  json.Key("nrmse").Number(channel.nrmse);
  json.Key("rms").Number(LabDifference(unit, channel.rms_si));
  json.Key("bias").Number(LabDifference(unit, channel.bias_si));
  json.Key("lag_s").Number(channel.lag_s);
  json.Key("lag_correlation").Number(channel.lag_correlation);
  json.Key("measured_mean")
      .Number(LabValue(unit, channel.measured_mean_si, context.atmospheric_pressure_pa));
  json.Key("measured_std").Number(LabDifference(unit, channel.measured_std_si));
  WriteBands(channel, json);
  WriteResidual(channel.residual, json);
  json.EndObject();
}

// The error along the pipe, one point per pressure transmitter.
void WriteProfile(const Comparison& comparison, JsonWriter& json) {
  json.Key("profile").BeginArray();
  for (const ProfilePoint& point : comparison.profile) {
    const ChannelMetrics* channel = comparison.Find(point.channel);
    const riglog::Unit unit = channel != nullptr ? channel->unit : riglog::Unit::kBarg;
    json.BeginObject();
    json.Key("channel").Text(riglog::ChannelName(point.channel));
    json.Key("x_m").Number(point.x_m);
    json.Key("fit_percent").Number(point.fit_percent);
    json.Key("nrmse").Number(point.nrmse);
    json.Key("rms").Number(LabDifference(unit, point.rms_si));
    json.Key("bias").Number(LabDifference(unit, point.bias_si));
    json.Key("lag_s").Number(point.lag_s);
    json.EndObject();
  }
  json.EndArray();
}

// Piston position -> each output, measured and modelled, at the log's dominant frequencies.
void WriteTransferFunctions(const Comparison& comparison, JsonWriter& json) {
  json.Key("transfer_functions").BeginObject();
  for (const TransferFunction& tf : comparison.transfer_functions) {
    const ChannelMetrics* channel = comparison.Find(tf.output);
    const riglog::Unit unit = channel != nullptr ? channel->unit : riglog::Unit::kBarg;
    json.Key(riglog::ChannelName(tf.output)).BeginObject();
    json.Key("input").Text("piston_position");
    json.Key("unit").Text(DifferenceUnit(unit) + "/m");
    json.Key("points").BeginArray();
    for (const TransferPoint& point : tf.points) {
      json.BeginObject();
      json.Key("freq_hz").Number(point.freq_hz);
      json.Key("measured_magnitude").Number(LabDifference(unit, std::abs(point.measured)));
      json.Key("measured_phase_deg").Number(PhaseDeg(point.measured));
      json.Key("model_magnitude").Number(LabDifference(unit, std::abs(point.model)));
      json.Key("model_phase_deg").Number(PhaseDeg(point.model));
      json.EndObject();
    }
    json.EndArray();
    json.EndObject();
  }
  json.EndObject();
}

}  // namespace

std::string ComparisonJson(const Comparison& comparison, const ReportContext& context) {
  JsonWriter json;
  json.BeginObject();
  json.Key("format").Text("mpdrig-compare");
  json.Key("version").Integer(1);
  json.Key("log").Text(context.log_path);
  json.Key("model").Text(context.model_description);
  json.Key("config").Text(context.config);
  json.Key("samples").Integer(comparison.samples);
  json.Key("duration_s").Number(comparison.duration_s);
  json.Key("sample_interval_s").Number(comparison.sample_interval_s);
  json.Key("uniform_sampling").Bool(comparison.uniform_sampling);
  json.Key("error").Number(comparison.error);
  json.Key("dominant_freqs_hz").Numbers(comparison.dominant_freqs_hz);
  json.Key("max_lag_s").Number(comparison.max_lag_s);
  json.Key("spectrum_segments").Integer(comparison.spectrum_segments);
  json.Key("spectrum_segment_s").Number(comparison.spectrum_segment_s);
  WriteInputs(comparison, json);
  if (comparison.first_range_event) {
    json.Key("warning").Text(comparison.first_range_event->Describe());
  }

  json.Key("channels").BeginObject();
  for (const ChannelMetrics& channel : comparison.channels) WriteChannel(channel, context, json);
  json.EndObject();

  WriteProfile(comparison, json);
  WriteTransferFunctions(comparison, json);
  json.EndObject();
  return json.str() + "\n";
}

}  // namespace mpdrig::report
