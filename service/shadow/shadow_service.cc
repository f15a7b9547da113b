#include "service/shadow/shadow_service.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

#include "model/effects/effect.h"
#include "model/effects/param_by_key.h"
#include "model/identification/shadow_fit.h"
#include "mpdrig.h"
#include "service/dds/security.h"
#include "service/rig/wire.h"

namespace mpdrig::service {
namespace {

std::string DescribeEffect(const EffectSetting& effect) {
  std::string text = effect.name;
  for (const auto& [key, value] : effect.values) {
    std::ostringstream v;
    v << value;
    text += " " + key + "=" + v.str();
  }
  return text;
}

// A string sequence of the wire that points into `texts` (which must outlive it).
dds_sequence_string StringSequence(std::vector<std::string>* texts, std::vector<char*>* ptrs) {
  ptrs->clear();
  for (std::string& text : *texts) ptrs->push_back(text.data());
  dds_sequence_string seq{};
  seq._length = seq._maximum = static_cast<std::uint32_t>(ptrs->size());
  seq._buffer = ptrs->empty() ? nullptr : ptrs->data();
  seq._release = false;
  return seq;
}

// A fit on its worker thread: what it computes, shared with it (it owns nothing of the service).
// `cancel` ends it after the solver iteration in progress (a cancel command, or the service
// stopping).
struct FitSlot {
  std::atomic<bool> cancel{false};
  std::mutex mutex;
  bool finished = false;
  Status status = Status::Ok();
  ShadowFitOutcome outcome;
};

}  // namespace

struct ShadowService::Impl {
  ShadowServeOptions options;
  RigParams initial_params;
  std::unique_ptr<ShadowModel> model;
  std::vector<std::string> parameters;  // "key=value", as set
  std::optional<dds::Domain> domain;
  dds::Entity participant, publisher, subscriber, sensors_topic, shadow_sensors_topic, status_topic,
      command_topic;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors;
  std::optional<dds::Writer<mpdrig_RigSensors>> shadow_sensors;
  std::optional<dds::Writer<mpdrig_ShadowStatus>> status;
  std::optional<dds::Reader<mpdrig_ShadowCommand>> commands;
  std::ofstream log;
  std::uint64_t samples = 0, published = 0;
  std::uint64_t rejected = 0;
  std::uint64_t last_command_id = 0;
  std::string last_rejection;
  std::string fit_state;         // ShadowStatus.fit_state
  std::shared_ptr<FitSlot> fit;  // the fit running, if any
  std::thread fit_thread;
  double fit_error_at_start = std::numeric_limits<double>::quiet_NaN();

  ~Impl() {
    // A fit stops after its solver iteration in progress (a fraction of a second of replays).
    if (fit) fit->cancel = true;
    if (fit_thread.joinable()) fit_thread.join();
  }

  // Asks the running fit to stop; FinishFit then drops its result.
  Status CancelFit() {
    if (!fit) return Status::Error("no fit is running");
    fit->cancel = true;
    fit_state = "cancelling: " + fit_state;
    return Status::Ok();
  }

  Status StartFit() {
    if (fit) return Status::Error("a fit is running (" + fit_state + "); wait for it");
    auto log = model->HeldLog(options.fit_window_s);
    if (!log.ok()) return log.status();
    auto parameters = ShadowFitParameters(model->params());
    if (!parameters.ok()) return parameters.status();
    std::string keys;
    for (const FitParameter& p : *parameters) keys += (keys.empty() ? "" : ", ") + p.key;
    char text[160];
    std::snprintf(text, sizeof text, "running: %s on the last %.0f s of rows (t = %.1f s)",
                  keys.c_str(), log->time_s().back() - log->time_s().front(), model->last_time_s());
    fit_state = text;
    fit = std::make_shared<FitSlot>();
    fit_error_at_start = model->error();
    if (fit_thread.joinable()) fit_thread.join();
    fit_thread = std::thread([slot = fit, log = std::move(log).value(), start = model->params(),
                              simulation = model->options().simulation,
                              iterations = options.fit_max_iterations]() mutable {
      auto outcome = FitShadowParameters(std::move(log), start, simulation, iterations,
                                         [&slot] { return slot->cancel.load(); });
      std::lock_guard<std::mutex> lock(slot->mutex);
      if (outcome.ok()) {
        slot->outcome = std::move(outcome).value();
      } else {
        slot->status = outcome.status();
      }
      slot->finished = true;
    });
    return Status::Ok();
  }

  // A finished fit: its estimates written into the model as it is now (an effect switched off
  // meanwhile keeps off; its estimate is dropped) and replayed, as a SetParams.
  void FinishFit() {
    if (!fit) return;
    {
      std::lock_guard<std::mutex> lock(fit->mutex);
      if (!fit->finished) return;
    }
    fit_thread.join();
    std::shared_ptr<FitSlot> done = std::move(fit);
    fit.reset();
    if (done->cancel) {
      fit_state = "cancelled";  // whatever it found is dropped, even a fit that just finished
      next_status_s = -std::numeric_limits<double>::infinity();
      return;
    }
    if (!done->status.ok()) {
      fit_state = "failed: " + done->status.message();
      next_status_s = -std::numeric_limits<double>::infinity();
      return;
    }
    RigParams params = model->params();
    const FitResult& result = done->outcome.fit;
    for (std::size_t j = 0; j < result.keys.size(); ++j) {
      (void)SetParamValue(&params, result.keys[j], result.estimates[j]);
    }
    const double before = model->error();
    const Status applied = model->SetParams(params);
    if (!applied.ok()) {
      fit_state = "failed: the fitted parameters were refused: " + applied.message();
    } else {
      fit_state = "done: " + done->outcome.summary;
      last_change = "fit now: " + done->outcome.summary;
      last_change_s = model->last_time_s();
      error_at_change = before;
    }
    next_status_s = -std::numeric_limits<double>::infinity();
  }
  std::string last_change;
  double last_change_s = -1.0;
  double error_at_change = std::numeric_limits<double>::quiet_NaN();
  double first_time_s = std::numeric_limits<double>::quiet_NaN();
  double next_status_s = -std::numeric_limits<double>::infinity();

  void Refuse(const std::string& reason) {
    ++rejected;
    last_rejection = reason;
    next_status_s = -std::numeric_limits<double>::infinity();  // say so at once
  }

  void Apply(const mpdrig_ShadowCommand& command) {
    const std::string argument = command.argument != nullptr ? command.argument : "";
    if (options.rig_id != command.rig_id || command.shadow_id == nullptr ||
        options.shadow_id != command.shadow_id) {
      // Another shadow's command: on a shared domain several shadows may listen, several of
      // one rig too, each with its own id.
      return;
    }
    last_command_id = command.command_id;
    const double before = model->error();
    RigParams params = model->params();
    std::string change;
    Status status = Status::Ok();
    switch (command.action) {
      case mpdrig_SHADOW_EFFECT_ON:
        status = ApplyEffectSpec(&params, argument);
        change = "effect on: " + argument;
        break;
      case mpdrig_SHADOW_EFFECT_OFF: {
        const auto before_size = params.effects.size();
        std::erase_if(params.effects, [&](const EffectSetting& e) { return e.name == argument; });
        if (params.effects.size() == before_size) {
          status = Status::Error("effect '" + argument + "' is not on (on: " +
                                 std::to_string(params.effects.size()) + " effects)");
        }
        change = "effect off: " + argument;
        break;
      }
      case mpdrig_SHADOW_SET:
        status = ApplyOverride(&params, argument);
        change = "set " + argument;
        break;
      case mpdrig_SHADOW_RESET:
        params = initial_params;
        change = "reset";
        break;
      case mpdrig_SHADOW_FIT_NOW: {
        // Nothing changes now: the fit's answer comes later (fit_state, then a change).
        const Status started = StartFit();
        if (!started.ok()) {
          Refuse(std::string(dds::topics::kShadowCommand.name) +
                 " refused: fit now: " + started.message());
        } else {
          next_status_s = -std::numeric_limits<double>::infinity();
        }
        return;
      }
      case mpdrig_SHADOW_FIT_CANCEL: {
        const Status cancelled = CancelFit();
        if (!cancelled.ok()) {
          Refuse(std::string(dds::topics::kShadowCommand.name) +
                 " refused: cancel fit: " + cancelled.message());
        } else {
          next_status_s = -std::numeric_limits<double>::infinity();
        }
        return;
      }
      default:
        status =
            Status::Error("unknown action " + std::to_string(static_cast<int>(command.action)));
    }
    if (status.ok()) status = model->SetParams(params);
    if (!status.ok()) {
      Refuse(std::string(dds::topics::kShadowCommand.name) + " refused: " + status.message());
      return;
    }
    if (command.action == mpdrig_SHADOW_RESET) {
      parameters.clear();
    } else if (command.action == mpdrig_SHADOW_SET) {
      parameters.push_back(argument);
    }
    last_change = change;
    last_change_s = model->last_time_s();
    error_at_change = before;
    next_status_s = -std::numeric_limits<double>::infinity();  // say so at once
  }

  Status PublishStatus(double time_s) {
    mpdrig_ShadowStatus wire{};
    wire.rig_id = const_cast<char*>(options.rig_id.c_str());
    wire.shadow_id = const_cast<char*>(options.shadow_id.c_str());
    wire.sim_time_s = time_s;
    wire.window_s = model->options().window_s;
    wire.error = model->error();
    const auto nrmse = model->ChannelNrmse();
    std::vector<std::string> names;
    std::vector<double> values;
    for (const auto& [channel, value] : nrmse) {
      names.emplace_back(riglog::ChannelName(channel));
      values.push_back(value);
    }
    std::vector<char*> name_ptrs, effect_ptrs, param_ptrs;
    wire.channels = StringSequence(&names, &name_ptrs);
    wire.nrmse._length = wire.nrmse._maximum = static_cast<std::uint32_t>(values.size());
    wire.nrmse._buffer = values.data();
    wire.nrmse._release = false;
    std::vector<std::string> effects;
    for (const EffectSetting& e : model->params().effects) effects.push_back(DescribeEffect(e));
    wire.active_effects = StringSequence(&effects, &effect_ptrs);
    std::vector<std::string> params = parameters;
    wire.parameters = StringSequence(&params, &param_ptrs);
    wire.last_change = const_cast<char*>(last_change.c_str());
    wire.last_change_sim_time_s = last_change_s;
    wire.error_at_last_change = error_at_change;
    wire.rejected_commands = rejected;
    wire.last_rejection = const_cast<char*>(last_rejection.c_str());
    wire.last_command_id = last_command_id;
    std::vector<std::string> available;
    for (const EffectInfo* info : EffectCatalogue()) available.emplace_back(info->name);
    std::vector<char*> available_ptrs;
    wire.available_effects = StringSequence(&available, &available_ptrs);
    wire.fit_state = const_cast<char*>(fit_state.c_str());
    MPDRIG_RETURN_IF_ERROR(status->Write(wire));
    if (log.is_open()) {
      char number[64];
      auto field = [&](double v) {
        if (std::isnan(v)) return std::string();  // not defined: empty, as a rig log's gap
        std::snprintf(number, sizeof number, "%.6g", v);
        return std::string(number);
      };
      log << field(time_s) << "," << field(wire.error);
      for (double v : values) log << "," << field(v);
      log << "\n";
      log.flush();
      if (!log) return Status::Error(options.log_path + ": cannot write");
    }
    return Status::Ok();
  }

  Status TakeSamples(bool* done) {
    const double atm = model->params().atmospheric_pressure_pa;
    Status failed = Status::Ok();
    auto taken = sensors->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
      if (!failed.ok() || *done || options.rig_id != s.rig_id) return;
      const RigSample sample = FromWire(s, atm);
      if (std::isnan(first_time_s)) first_time_s = sample.time_s;
      ++samples;
      failed = model->Push(sample);
      // A batch of samples (a rig stepped ahead, a burst after a stall) still gives a status
      // every period of rig time: the error over time is what the log is for.
      if (failed.ok()) failed = StatusIfDue();
      if (options.duration_s > 0.0 && sample.time_s - first_time_s >= options.duration_s)
        *done = true;
    });
    if (!taken.ok()) return taken.status();
    MPDRIG_RETURN_IF_ERROR(failed);
    return StatusIfDue();  // a command's answer while the rig is still
  }

  Status StatusIfDue() {
    for (const ShadowPoint& point : model->TakeOutput()) {
      MPDRIG_RETURN_IF_ERROR(shadow_sensors->Write(ToWire(
          options.rig_id, published++, point.model, model->params().atmospheric_pressure_pa)));
    }
    if (samples > 0 && model->last_time_s() >= next_status_s) {
      MPDRIG_RETURN_IF_ERROR(PublishStatus(model->last_time_s()));
      next_status_s = std::max(next_status_s, model->last_time_s()) + options.status_period_s;
    }
    return Status::Ok();
  }
};

ShadowService::ShadowService(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ShadowService::~ShadowService() = default;
const ShadowModel& ShadowService::model() const { return *impl_->model; }
std::uint64_t ShadowService::samples() const { return impl_->samples; }

Status CheckShadowId(const std::string& shadow_id) {
  const bool valid = !shadow_id.empty() && shadow_id.size() <= 64 &&
                     std::all_of(shadow_id.begin(), shadow_id.end(), [](unsigned char c) {
                       return std::isalnum(c) || c == '_' || c == '.' || c == '-';
                     });
  if (valid) return Status::Ok();
  return Status::Error("shadow id '" + shadow_id.substr(0, 64) +
                       "': 1 to 64 characters of letters, digits, '_', '.' and '-'");
}

Result<std::unique_ptr<ShadowService>> ShadowService::Create(RigParams params,
                                                             ShadowOptions model_options,
                                                             const ShadowServeOptions& options) {
  if (options.rig_id.empty()) return Status::Error("shadow: rig id must not be empty");
  MPDRIG_RETURN_IF_ERROR(CheckShadowId(options.shadow_id));
  if (!(options.duration_s >= 0.0) || !(options.status_period_s > 0.0)) {
    return Status::Error("shadow: duration must be >= 0 and the status period > 0");
  }
  if (!(options.fit_window_s > 0.0 && options.fit_window_s <= 3600.0) ||
      options.fit_max_iterations < 1) {
    return Status::Error("shadow: the fit window must be in (0, 3600] s and allow an iteration");
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  // The rows a fit needs are held (a change replays only the warm-up and the window of them).
  model_options.history_s = std::max(model_options.history_s, options.fit_window_s);
  impl->initial_params = params;
  auto model = ShadowModel::Create(std::move(params), std::move(model_options));
  if (!model.ok()) return model.status();
  impl->model = std::move(model).value();
  if (!options.log_path.empty()) {
    impl->log.open(options.log_path);
    if (!impl->log) return Status::Error(options.log_path + ": cannot write");
    impl->log << "time_s,error";
    for (Channel channel : ComparedChannels()) {
      impl->log << "," << riglog::ChannelName(channel) << "_nrmse";
    }
    impl->log << "\n";
  }
  if (!options.dds_config.empty()) {
    auto domain = dds::Domain::Create(options.domain, options.dds_config);
    if (!domain.ok()) {
      return domain.status().Within("DDS domain " + std::to_string(options.domain));
    }
    impl->domain.emplace(std::move(domain).value());
  }
  // With security the rig's topics, and so the shadow's, are in the rig's partition.
  auto scope = dds::CreateClientScope(options.domain, options.security_dir, options.rig_id);
  if (!scope.ok()) return scope.status();
  impl->participant = std::move(scope->participant);
  impl->publisher = std::move(scope->publisher);
  impl->subscriber = std::move(scope->subscriber);
  const dds_entity_t p = impl->participant.handle();
  const dds_entity_t pub = impl->publisher.handle() > 0 ? impl->publisher.handle() : p;
  const dds_entity_t sub = impl->subscriber.handle() > 0 ? impl->subscriber.handle() : p;
  auto topic = [p](const dds::TopicSpec& spec, dds::Entity* out) {
    auto created = dds::CreateTopic(p, spec);
    if (!created.ok()) return created.status();
    *out = std::move(created).value();
    return Status::Ok();
  };
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kSensors, &impl->sensors_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kShadowSensors, &impl->shadow_sensors_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kShadowStatus, &impl->status_topic));
  MPDRIG_RETURN_IF_ERROR(topic(dds::topics::kShadowCommand, &impl->command_topic));
  // Keep all: the model needs every sample in order (a gap is a hold of the inputs).
  auto sensors = dds::Reader<mpdrig_RigSensors>::Create(sub, impl->sensors_topic.handle(),
                                                        dds::SensorQos(true));
  if (!sensors.ok()) return sensors.status();
  impl->sensors.emplace(std::move(sensors).value());
  auto shadow_sensors = dds::Writer<mpdrig_RigSensors>::Create(
      pub, impl->shadow_sensors_topic.handle(), dds::SensorQos(false));
  if (!shadow_sensors.ok()) return shadow_sensors.status();
  impl->shadow_sensors.emplace(std::move(shadow_sensors).value());
  auto status =
      dds::Writer<mpdrig_ShadowStatus>::Create(pub, impl->status_topic.handle(), dds::StatusQos());
  if (!status.ok()) return status.status();
  impl->status.emplace(std::move(status).value());
  auto commands = dds::Reader<mpdrig_ShadowCommand>::Create(sub, impl->command_topic.handle(),
                                                            dds::RequestQos());
  if (!commands.ok()) return commands.status();
  impl->commands.emplace(std::move(commands).value());
  return std::unique_ptr<ShadowService>(new ShadowService(std::move(impl)));
}

Status ShadowService::Run(const std::atomic<bool>& stop) {
  Impl& s = *impl_;
  bool done = false;
  while (!stop.load() && !done) {
    auto ready = s.sensors->Wait(DDS_MSECS(50));
    if (!ready.ok()) return ready.status();
    auto taken = s.commands->TakeEach(
        [&](const mpdrig_ShadowCommand& c, const dds_sample_info_t&) { s.Apply(c); });
    if (!taken.ok()) return taken.status();
    MPDRIG_RETURN_IF_ERROR(s.TakeSamples(&done));
    s.FinishFit();
  }
  if (s.samples > 0) MPDRIG_RETURN_IF_ERROR(s.PublishStatus(s.model->last_time_s()));
  return Status::Ok();
}

}  // namespace mpdrig::service
