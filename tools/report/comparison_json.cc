#include "tools/report/comparison_json.h"

#include "model/common/units.h"

#include <cmath>
#include <complex>
#include <numbers>

#include "model/riglog/channels.h"
#include "tools/report/json.h"
#include "tools/report/lab_units.h"

namespace mpdrig::report {
namespace {

double PhaseDeg(std::complex<double> value) { return std::arg(value) * 180.0 / std::numbers::pi; }

// How the inputs reached the model (log_inputs.h): reconstructed under their noise, in lab
// units, or as measured; and whether the replay started after a warm-up.
Json InputsJson(const Comparison& comparison) {
  Json inputs = Json::object();
  inputs["reconstructed"] = comparison.input_reconstruction.has_value();
  if (const auto& plan = comparison.input_reconstruction) {
    inputs["noise"] = {
        {"piston_position_mm", JsonNumber(plan->piston_noise_m * 1e3)},
        {"choke_position_deg", JsonNumber(units::ChokeFracToDeg(plan->choke_noise_frac))},
        {"FT2_lpm", JsonNumber(units::M3psToLpm(plan->pump_noise_m3ps))},
        {"C1_bar", JsonNumber(plan->outlet_noise_pa * 1e-5)}};
    inputs["piston_band_hz"] = JsonNumber(plan->piston_band_hz);
    inputs["piston_window_s"] = JsonNumber(2.0 * plan->piston_half_width_s);
    inputs["level_max_window_s"] = JsonNumber(
        2.0 * static_cast<double>(plan->level_max_half_width_samples) * plan->sample_interval_s);
    // The choke's and FT2's levels as corrected from the measured pressures (EstimateInputLevels).
    const InputLevelCorrection& levels = plan->levels;
    const auto deg = [](double frac) { return JsonNumber(units::ChokeFracToDeg(frac)); };
    const auto lpm = [](double m3ps) { return JsonNumber(units::M3psToLpm(m3ps)); };
    const auto bar = [](double pa) { return JsonNumber(pa * 1e-5); };
    inputs["levels"] = {
        // offset + trend * tau, tau from -1 at start_s to 1 at end_s (held beyond).
        {"start_s", JsonNumber(levels.center_s - levels.half_span_s)},
        {"end_s", JsonNumber(levels.center_s + levels.half_span_s)},
        {"choke_offset_deg", deg(levels.choke_offset_frac)},
        {"choke_trend_deg", deg(levels.choke_trend_frac)},
        {"FT2_offset_lpm", lpm(levels.pump_offset_m3ps)},
        {"FT2_trend_lpm", lpm(levels.pump_trend_m3ps)},
        {"choke_offset_bound_deg", deg(kMaxLevelOffsetSigmas * levels.choke_sigma_frac)},
        {"choke_trend_bound_deg", deg(kMaxLevelOffsetSigmas * levels.choke_trend_sigma_frac)},
        {"FT2_offset_bound_lpm", lpm(kMaxLevelOffsetSigmas * levels.pump_sigma_m3ps)},
        {"FT2_trend_bound_lpm", lpm(kMaxLevelOffsetSigmas * levels.pump_trend_sigma_m3ps)},
        {"pressure_residual_before_bar", bar(levels.residual_before_pa)},
        {"pressure_residual_after_bar", bar(levels.residual_after_pa)},
        {"pressure_residual_trend_before_bar", bar(levels.residual_trend_before_pa)},
        {"pressure_residual_trend_after_bar", bar(levels.residual_trend_after_pa)},
        {"at_bound", levels.at_bound}};
  }
  inputs["warmup"] = comparison.warmup.has_value();
  if (comparison.warmup) {
    inputs["warmup_period_s"] = JsonNumber(comparison.warmup->period_s);
    inputs["warmup_s"] = JsonNumber(comparison.warmup->duration_s);
  }
  inputs["measured_start"] = comparison.measured_start.has_value();
  return inputs;
}

// The error at the bands of the dominant frequencies and their harmonics.
Json BandsJson(const ChannelMetrics& channel) {
  const riglog::Unit unit = channel.unit;
  Json bands = Json::array();
  for (const BandMetrics& band : channel.bands) {
    bands.push_back(
        {{"freq_hz", JsonNumber(band.freq_hz)},
         {"low_hz", JsonNumber(band.low_hz)},
         {"high_hz", JsonNumber(band.high_hz)},
         {"harmonic", band.harmonic},
         {"measured_amplitude", JsonNumber(LabDifference(unit, band.measured_amplitude))},
         {"model_amplitude", JsonNumber(LabDifference(unit, band.model_amplitude))},
         {"magnitude_ratio", JsonNumber(band.magnitude_ratio)},
         {"phase_diff_deg", JsonNumber(band.phase_diff_deg)},
         {"band_nrmse", JsonNumber(band.band_nrmse)},
         {"error_amplitude", JsonNumber(LabDifference(unit, band.error_amplitude))}});
  }
  return bands;
}

// Is the residual white, and independent of the inputs?
Json ResidualJson(const ResidualAnalysis& residual) {
  Json cross = Json::object();
  for (const Correlation& c : residual.cross) {
    cross[c.input] = {{"constant_input", c.constant_input},
                      {"max_abs", JsonNumber(c.max_abs)},
                      {"independent", c.independent},
                      {"r", JsonNumbers(c.r)}};
  }
  return {{"lags", residual.lags},
          {"confidence", JsonNumber(residual.confidence)},
          {"autocorrelation", JsonNumbers(residual.autocorrelation)},
          {"max_abs_autocorrelation", JsonNumber(residual.max_abs_autocorrelation)},
          {"white", residual.white},
          {"independent_of_inputs", residual.independent_of_inputs},
          {"cross", cross}};
}

Json ChannelJson(const ChannelMetrics& channel, const ReportContext& context) {
  const riglog::Unit unit = channel.unit;
  return {{"unit", riglog::UnitSuffix(unit)},
          {"difference_unit", DifferenceUnit(unit)},
          {"samples", channel.samples},
          {"fit_percent", JsonNumber(channel.fit_percent)},
          {"nrmse", JsonNumber(channel.nrmse)},
          {"rms", JsonNumber(LabDifference(unit, channel.rms_si))},
          {"bias", JsonNumber(LabDifference(unit, channel.bias_si))},
          {"lag_s", JsonNumber(channel.lag_s)},
          {"lag_correlation", JsonNumber(channel.lag_correlation)},
          {"measured_mean",
           JsonNumber(LabValue(unit, channel.measured_mean_si, context.atmospheric_pressure_pa))},
          {"measured_std", JsonNumber(LabDifference(unit, channel.measured_std_si))},
          {"bands", BandsJson(channel)},
          {"residual", ResidualJson(channel.residual)}};
}

// The error along the pipe, one point per pressure transmitter.
Json ProfileJson(const Comparison& comparison) {
  Json profile = Json::array();
  for (const ProfilePoint& point : comparison.profile) {
    const ChannelMetrics* channel = comparison.Find(point.channel);
    const riglog::Unit unit = channel != nullptr ? channel->unit : riglog::Unit::kBarg;
    profile.push_back({{"channel", riglog::ChannelName(point.channel)},
                       {"x_m", JsonNumber(point.x_m)},
                       {"fit_percent", JsonNumber(point.fit_percent)},
                       {"nrmse", JsonNumber(point.nrmse)},
                       {"rms", JsonNumber(LabDifference(unit, point.rms_si))},
                       {"bias", JsonNumber(LabDifference(unit, point.bias_si))},
                       {"lag_s", JsonNumber(point.lag_s)}});
  }
  return profile;
}

// Piston position -> each output, measured and modelled, at the log's dominant frequencies.
Json TransferFunctionsJson(const Comparison& comparison) {
  Json functions = Json::object();
  for (const TransferFunction& tf : comparison.transfer_functions) {
    const ChannelMetrics* channel = comparison.Find(tf.output);
    const riglog::Unit unit = channel != nullptr ? channel->unit : riglog::Unit::kBarg;
    Json points = Json::array();
    for (const TransferPoint& point : tf.points) {
      points.push_back(
          {{"freq_hz", JsonNumber(point.freq_hz)},
           {"measured_magnitude", JsonNumber(LabDifference(unit, std::abs(point.measured)))},
           {"measured_phase_deg", JsonNumber(PhaseDeg(point.measured))},
           {"model_magnitude", JsonNumber(LabDifference(unit, std::abs(point.model)))},
           {"model_phase_deg", JsonNumber(PhaseDeg(point.model))}});
    }
    functions[std::string(riglog::ChannelName(tf.output))] = {
        {"input", "piston_position"}, {"unit", DifferenceUnit(unit) + "/m"}, {"points", points}};
  }
  return functions;
}

}  // namespace

std::string ComparisonJson(const Comparison& comparison, const ReportContext& context) {
  Json json = {{"format", "mpdrig-compare"},
               {"version", 1},
               {"log", context.log_path},
               {"model", context.model_description},
               {"config", context.config},
               {"samples", comparison.samples},
               {"duration_s", JsonNumber(comparison.duration_s)},
               {"sample_interval_s", JsonNumber(comparison.sample_interval_s)},
               {"uniform_sampling", comparison.uniform_sampling},
               {"error", JsonNumber(comparison.error)},
               {"dominant_freqs_hz", JsonNumbers(comparison.dominant_freqs_hz)},
               {"max_lag_s", JsonNumber(comparison.max_lag_s)},
               {"spectrum_segments", comparison.spectrum_segments},
               {"spectrum_segment_s", JsonNumber(comparison.spectrum_segment_s)},
               {"inputs", InputsJson(comparison)}};
  if (comparison.first_range_event) {
    json["warning"] = comparison.first_range_event->Describe();
  }
  Json channels = Json::object();
  for (const ChannelMetrics& channel : comparison.channels) {
    channels[std::string(riglog::ChannelName(channel.channel))] = ChannelJson(channel, context);
  }
  json["channels"] = std::move(channels);
  json["profile"] = ProfileJson(comparison);
  json["transfer_functions"] = TransferFunctionsJson(comparison);
  return JsonText(json);
}

}  // namespace mpdrig::report
