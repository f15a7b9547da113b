#include "model/analysis/shadow_model.h"

#include <cmath>
#include <limits>

#include "model/analysis/compare.h"
#include "model/effects/effect.h"

namespace mpdrig {

Status ShadowOptions::Validate() const {
  if (!(window_s > 0.0 && std::isfinite(window_s))) {
    return Status::Error("shadow window must be a positive number of seconds");
  }
  if (!(warmup_s >= 0.0 && std::isfinite(warmup_s))) {
    return Status::Error("shadow warm-up must be a non-negative number of seconds");
  }
  if (!(smoothing_s >= 0.0 && std::isfinite(smoothing_s))) {
    return Status::Error("piston smoothing must be a non-negative number of seconds");
  }
  if (smoothing_block_rows < 1) return Status::Error("smoothing block must hold a row");
  return simulation.Validate();
}

ShadowModel::ShadowModel(RigParams params, ShadowOptions options)
    : params_(std::move(params)), options_(std::move(options)), channels_(ComparedChannels()) {
  // A live model reports leaving its range (the error shows it) instead of stopping.
  options_.simulation.stop_on_range_violation = false;
}

Result<std::unique_ptr<ShadowModel>> ShadowModel::Create(RigParams params, ShadowOptions options) {
  MPDRIG_RETURN_IF_ERROR(options.Validate());
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  std::unique_ptr<ShadowModel> shadow(new ShadowModel(std::move(params), std::move(options)));
  return shadow;
}

void ShadowModel::Take(const PipelineSample& sample) {
  const RigSample& model = *sample.model;
  if (!replaying_) output_.push_back({sample.row->time_s, model});
  const double t = sample.row->time_s;
  if (t < start_time_s_ + options_.warmup_s) return;
  WindowEntry entry;
  entry.time_s = t;
  for (std::size_t k = 0; k < channels_.size(); ++k) {
    entry.measured[k] = sample.row->measured_si[k];
    entry.model[k] = model[channels_[k]];
  }
  window_.push_back(entry);
  while (!window_.empty() && window_.front().time_s <= t - options_.window_s) window_.pop_front();
}

Status ShadowModel::Rebuild() {
  window_.clear();
  ReplaySetup setup;
  setup.params = params_;
  setup.options = options_.simulation;
  // A live rig has no last sample: the piston velocity is never one-sided at an end.
  setup.end_time_s = std::numeric_limits<double>::infinity();
  pipeline_ = std::make_unique<RowPipeline>(
      options_.smoothing_s, std::move(setup), [this](const PipelineSample& s) { Take(s); },
      options_.smoothing_block_rows);
  if (history_.empty()) return Status::Ok();
  start_time_s_ = history_.front().time_s;
  replaying_ = true;
  Status status = Status::Ok();
  for (const LogRow& row : history_) {
    status = pipeline_->Push(row);
    if (!status.ok()) break;
  }
  replaying_ = false;
  return status;
}

Status ShadowModel::Push(const RigSample& measured) {
  const double t = measured.time_s;
  const double piston = measured[Channel::kPistonPosition];
  const double choke = measured[Channel::kChokePosition];
  if (!std::isfinite(t) || !std::isfinite(piston) || !std::isfinite(choke)) {
    ++skipped_;
    return Status::Ok();
  }
  if (t <= last_time_s_) Reset();
  LogRow row;
  row.time_s = t;
  row.piston_position_m = piston;
  row.choke_opening_frac = choke;
  const double pump = measured[Channel::kFT2];
  const double outlet = measured[Channel::kC1];
  row.pump_flow_m3ps = std::isfinite(pump) ? pump : 0.0;
  row.outlet_pressure_pa = std::isfinite(outlet) ? outlet : params_.atmospheric_pressure_pa;
  for (std::size_t k = 0; k < channels_.size(); ++k) row.measured_si[k] = measured[channels_[k]];
  row.measured_inputs = {row.piston_position_m, row.choke_opening_frac, row.pump_flow_m3ps,
                         row.outlet_pressure_pa};
  last_time_s_ = t;
  history_.push_back(row);
  // What a rebuild replays: the warm-up, then a whole window.
  const double keep_s = options_.warmup_s + options_.window_s;
  while (history_.size() > 2 && history_[1].time_s <= t - keep_s) history_.pop_front();
  if (!pipeline_) {
    MPDRIG_RETURN_IF_ERROR(Rebuild());  // pushes this first row
    return Status::Ok();
  }
  return pipeline_->Push(row);
}

std::vector<ShadowPoint> ShadowModel::TakeOutput() {
  std::vector<ShadowPoint> out;
  out.swap(output_);
  return out;
}

std::vector<std::pair<Channel, double>> ShadowModel::ChannelNrmse() const {
  std::vector<std::pair<Channel, double>> out;
  for (std::size_t k = 0; k < channels_.size(); ++k) {
    double sum = 0.0, sum_sq = 0.0, err_sq = 0.0;
    long n = 0;
    for (const WindowEntry& e : window_) {
      if (!std::isfinite(e.measured[k]) || !std::isfinite(e.model[k])) continue;
      sum += e.measured[k];
      ++n;
    }
    double nrmse = std::numeric_limits<double>::quiet_NaN();
    if (n >= 2) {
      const double mean = sum / static_cast<double>(n);
      for (const WindowEntry& e : window_) {
        if (!std::isfinite(e.measured[k]) || !std::isfinite(e.model[k])) continue;
        sum_sq += (e.measured[k] - mean) * (e.measured[k] - mean);
        err_sq += (e.measured[k] - e.model[k]) * (e.measured[k] - e.model[k]);
      }
      if (sum_sq > 0.0) nrmse = std::sqrt(err_sq / sum_sq);
    }
    out.push_back({channels_[k], nrmse});
  }
  return out;
}

double ShadowModel::error() const {
  double sum = 0.0;
  int count = 0;
  for (const auto& [channel, nrmse] : ChannelNrmse()) {
    if (std::isnan(nrmse)) continue;
    sum += nrmse;
    ++count;
  }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}

Status ShadowModel::SetParams(RigParams params) {
  MPDRIG_RETURN_IF_ERROR(params.Validate());
  MPDRIG_RETURN_IF_ERROR(ValidateEffects(params));
  params_ = std::move(params);
  if (history_.empty()) {
    pipeline_.reset();
    return Status::Ok();
  }
  return Rebuild();
}

void ShadowModel::Reset() {
  history_.clear();
  window_.clear();
  pipeline_.reset();
  last_time_s_ = -1.0e300;
}

}  // namespace mpdrig
