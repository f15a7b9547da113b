#include "model/analysis/shadow_model.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "model/analysis/measured_log.h"
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
  if (!(history_s >= 0.0 && history_s <= 3600.0)) {
    return Status::Error("shadow history must be between 0 and 3600 s of rows");
  }
  if (reconstruct_inputs) {
    if (!(lookahead_s >= 0.0 && lookahead_s <= 60.0)) {
      return Status::Error("shadow look-ahead must be between 0 and 60 s");
    }
    if (!(plan_s > 0.0 && plan_s <= 600.0)) {
      return Status::Error("shadow reconstruction plan needs between 0 and 600 s of rows");
    }
    if (!(block_s > 0.0 && block_s <= 10.0)) {
      return Status::Error("shadow reconstruction block must be between 0 and 10 s");
    }
    if (!(reach_back_s > 0.0 && reach_back_s <= kMaxLevelHalfWidthS)) {
      return Status::Error("shadow reconstruction reach back must be between 0 and " +
                           std::to_string(kMaxLevelHalfWidthS) + " s");
    }
  }
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
  // Reconstructed inputs come smoothed (the piston by its band-limited fit), as in compare.
  const double smoothing_s = Reconstructing() ? 0.0 : options_.smoothing_s;
  pipeline_ = std::make_unique<RowPipeline>(
      smoothing_s, std::move(setup), [this](const PipelineSample& s) { Take(s); },
      options_.smoothing_block_rows);
  fed_until_s_ = -1.0e300;
  if (history_.empty()) return Status::Ok();
  const double last_s = history_.back().time_s;
  double frontier_s = last_s;
  double from_s = history_.front().time_s;
  if (Reconstructing()) {
    if (!plan_) {
      if (last_s - history_.front().time_s < options_.plan_s) return Status::Ok();  // not yet
      plan_ = PlanInputReconstruction(HeldColumns(0));
      // The level windows reach no further back than the rows held for them.
      if (plan_->sample_interval_s > 0.0) {
        long cap = 2;
        while (2.0 * static_cast<double>(cap) * plan_->sample_interval_s <= options_.reach_back_s)
          cap *= 2;
        plan_->level_max_half_width_samples = std::min(plan_->level_max_half_width_samples, cap);
      }
    }
    frontier_s = last_s - options_.lookahead_s;
  }
  // Replayed: the warm-up and a window before the frontier; older rows only reach back (the
  // reconstruction's windows) or wait for a fit.
  from_s = std::max(from_s, frontier_s - options_.warmup_s - options_.window_s);
  auto first = std::lower_bound(history_.begin(), history_.end(), from_s,
                                [](const LogRow& row, double t) { return row.time_s < t; });
  if (first == history_.end() || first->time_s > frontier_s) return Status::Ok();
  start_time_s_ = first->time_s;
  fed_until_s_ = first != history_.begin() ? std::prev(first)->time_s : -1.0e300;
  replaying_ = true;
  Status status = Status::Ok();
  // In blocks, as the live rows are fed: every row sees the look-ahead it would have seen live,
  // so the error after a change compares with the error before it.
  if (Reconstructing()) {
    for (double until_s = start_time_s_ + options_.block_s; status.ok() && until_s < frontier_s;
         until_s += options_.block_s) {
      status = FeedUntil(until_s);
    }
  }
  if (status.ok()) status = FeedUntil(frontier_s);
  replaying_ = false;
  return status;
}

LogInputColumns ShadowModel::HeldColumns(std::size_t first, std::size_t end) const {
  LogInputColumns columns;
  for (std::size_t i = first; i < std::min(end, history_.size()); ++i) {
    const LogRow& row = history_[i];
    columns.time_s.push_back(row.time_s);
    columns.piston_position_m.push_back(row.measured_inputs[0]);
    columns.choke_opening_frac.push_back(row.measured_inputs[1]);
    columns.pump_flow_m3ps.push_back(row.measured_inputs[2]);
    columns.outlet_pressure_pa.push_back(row.measured_inputs[3]);
  }
  return columns;
}

Status ShadowModel::FeedUntil(double until_s) {
  auto by_time = [](const LogRow& row, double t) { return row.time_s <= t; };
  // history_ is in time order: the first row not fed, and the end of those to feed now.
  const auto begin =
      std::lower_bound(history_.begin(), history_.end(), fed_until_s_, by_time) - history_.begin();
  const auto end =
      std::lower_bound(history_.begin(), history_.end(), until_s, by_time) - history_.begin();
  if (begin >= end) return Status::Ok();
  const auto b = static_cast<std::size_t>(begin), e = static_cast<std::size_t>(end);
  if (!Reconstructing() || !plan_) {
    for (std::size_t i = b; i < e; ++i) MPDRIG_RETURN_IF_ERROR(pipeline_->Push(history_[i]));
    fed_until_s_ = history_[e - 1].time_s;
    return Status::Ok();
  }
  // A row is reconstructed once, when first fed (the inputs do not depend on the model): a
  // replay after a change feeds the very inputs the live model had.
  const auto r =
      std::max(b, static_cast<std::size_t>(std::lower_bound(history_.begin(), history_.end(),
                                                            reconstructed_until_s_, by_time) -
                                           history_.begin()));
  if (r < e) {
    // Two-sided where the rows allow: from the level windows' reach back (or the piston's, if
    // longer) to the look-ahead of the last row fed, as live.
    const double dt = plan_->sample_interval_s;
    const double back_s = std::max(plan_->piston_half_width_s,
                                   static_cast<double>(plan_->level_reach_samples()) * dt);
    const double from_s = history_[r].time_s - back_s;
    auto a = static_cast<std::size_t>(
        std::lower_bound(history_.begin(), history_.end(), from_s,
                         [](const LogRow& row, double t) { return row.time_s < t; }) -
        history_.begin());
    a = std::min(a, r);
    const auto ahead = static_cast<std::size_t>(
        std::upper_bound(history_.begin(), history_.end(), until_s + options_.lookahead_s,
                         [](double t, const LogRow& row) { return t < row.time_s; }) -
        history_.begin());
    const LogInputColumns done =
        ReconstructInputColumns(HeldColumns(a, std::max(ahead, e)), *plan_);
    for (std::size_t i = r; i < e; ++i) {
      LogRow& row = history_[i];
      const std::size_t k = i - a;
      row.piston_position_m = done.piston_position_m[k];
      row.choke_opening_frac = done.choke_opening_frac[k];
      row.pump_flow_m3ps = done.pump_flow_m3ps[k];
      row.outlet_pressure_pa = done.outlet_pressure_pa[k];
    }
    reconstructed_until_s_ = history_[e - 1].time_s;
  }
  for (std::size_t i = b; i < e; ++i) MPDRIG_RETURN_IF_ERROR(pipeline_->Push(history_[i]));
  fed_until_s_ = history_[e - 1].time_s;
  return Status::Ok();
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
  // What a rebuild replays: the warm-up, then a whole window; reconstructing, also the look-ahead
  // and the rows the level windows reach back to.
  double keep_s = options_.warmup_s + options_.window_s;
  if (Reconstructing()) keep_s += options_.lookahead_s + options_.reach_back_s;
  keep_s = std::max(keep_s, options_.history_s);
  while (history_.size() > 2 && history_[1].time_s <= t - keep_s) history_.pop_front();
  if (Reconstructing() && !plan_) {
    // The plan wants plan_s of rows (each input's noise, the piston's band); then the replay.
    return t - history_.front().time_s < options_.plan_s ? Status::Ok() : Rebuild();
  }
  if (!pipeline_) return Rebuild();
  if (!Reconstructing()) return FeedUntil(t);
  const double frontier_s = t - options_.lookahead_s;
  if (frontier_s - fed_until_s_ < options_.block_s) return Status::Ok();
  return FeedUntil(frontier_s);
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

Result<MeasuredLog> ShadowModel::HeldLog(double span_s) const {
  MeasuredLog log;
  log.path = "the shadow's rows";
  log.atmospheric_pressure_pa = params_.atmospheric_pressure_pa;
  std::size_t first = 0;
  if (!history_.empty()) {
    const double from_s = history_.back().time_s - span_s;
    while (first < history_.size() && history_[first].time_s < from_s) ++first;
  }
  if (history_.size() - first < 4) {
    return Status::Error("the shadow holds " + std::to_string(history_.size() - first) +
                         " rows; a fit needs at least 4");
  }
  log.inputs = HeldColumns(first);
  for (std::size_t k = 0; k < channels_.size(); ++k) {
    MeasuredChannel channel{channels_[k], riglog::LabUnitFor(riglog::QuantityOf(channels_[k])), {}};
    bool measured = false;
    for (std::size_t i = first; i < history_.size(); ++i) {
      channel.values_si.push_back(history_[i].measured_si[k]);
      measured = measured || std::isfinite(history_[i].measured_si[k]);
    }
    if (measured) log.channels.push_back(std::move(channel));
  }
  if (log.channels.empty())
    return Status::Error("no compared channel is measured in the rows held");
  ReconstructInputs(&log);
  return log;
}

void ShadowModel::Reset() {
  history_.clear();
  window_.clear();
  pipeline_.reset();
  plan_.reset();
  fed_until_s_ = -1.0e300;
  reconstructed_until_s_ = -1.0e300;
  last_time_s_ = -1.0e300;
}

}  // namespace mpdrig
