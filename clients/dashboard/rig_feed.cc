#include "clients/dashboard/rig_feed.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "clients/dashboard/json_out.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/dds/topics.h"

namespace mpdrig::dashboard {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One RigSensors sample as held (the wire's lab units), with when it was written.
struct SensorsView {
  std::uint64_t counter = 0;
  double t = 0.0;
  double piston_m = kNaN, choke_deg = kNaN, P1 = kNaN, P2 = kNaN, C1 = kNaN, C2 = kNaN;
  double PT[10] = {kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};
  double FT1 = kNaN, FT2 = kNaN, FT3 = kNaN, FT4 = kNaN;
  dds_time_t written_ns = 0;
};

SensorsView FromWire(const mpdrig_RigSensors& s, const dds_sample_info_t& info) {
  SensorsView v;
  v.counter = s.sample_counter;
  v.t = s.sim_time_s;
  v.piston_m = s.piston_position_m;
  v.choke_deg = s.choke_position_deg;
  v.P1 = s.P1_barg;
  v.P2 = s.P2_barg;
  std::copy(std::begin(s.PT_barg), std::end(s.PT_barg), std::begin(v.PT));
  v.C1 = s.C1_barg;
  v.C2 = s.C2_barg;
  v.FT1 = s.FT1_lpm;
  v.FT2 = s.FT2_lpm;
  v.FT3 = s.FT3_lpm;
  v.FT4 = s.FT4_lpm;
  v.written_ns = info.source_timestamp;
  return v;
}

struct EstimateView {
  double t = 0.0, bhp = kNaN, piston_m = kNaN, velocity = kNaN, FT4 = kNaN, freq_hz = kNaN;
  std::string source;
};

struct ProfileView {
  std::uint64_t counter = 0;
  double t = 0.0;
  std::vector<double> x, p, p_est;
};

// PT1..PT10 of one sample, kept for a few seconds so that the profile chart can show the rig,
// the observer and the shadow at one instant: the shadow trails the rig by a few samples, and
// under heave a tenth of a second moves PT1 by several hundredths of a bar.
struct PtAt {
  std::uint64_t counter;
  std::array<double, 10> PT;
};
constexpr std::size_t kPtRing = 400;      // 4 s at 100 Hz
constexpr std::size_t kProfileRing = 64;  // 6 s at the default 10 Hz

template <typename T>
void PushRing(std::deque<T>* ring, T item, std::size_t size) {
  ring->push_back(std::move(item));
  while (ring->size() > size) ring->pop_front();
}

struct StatusView {
  std::string clock;
  double t = 0.0, rtf = 0.0, longest_stall_s = 0.0;
  std::uint64_t deadline_misses = 0, lost_periods = 0, rejected = 0;
  std::string last_rejection, noise;
  std::vector<std::string> warnings, effects, owners;
};

struct ShadowStatusView {
  double t = 0.0, window_s = 0.0, error = kNaN, last_change_t = -1.0, error_at_change = kNaN;
  std::vector<std::string> channels, effects, parameters, available;
  std::vector<double> nrmse;
  std::string last_change, last_rejection, fit_state;
  std::uint64_t rejected = 0, last_command_id = 0;
};

std::vector<std::string> Strings(const dds_sequence_string& seq) {
  std::vector<std::string> out;
  out.reserve(seq._length);
  for (std::uint32_t i = 0; i < seq._length; ++i) out.emplace_back(seq._buffer[i]);
  return out;
}

std::vector<double> Doubles(const dds_sequence_double& seq) {
  return std::vector<double>(seq._buffer, seq._buffer + seq._length);
}

const char* ClockName(mpdrig_ClockMode clock) {
  switch (clock) {
    case mpdrig_CLOCK_REALTIME:
      return "realtime";
    case mpdrig_CLOCK_FAST:
      return "fast";
    case mpdrig_CLOCK_LOCKSTEP:
      return "lockstep";
  }
  return "unknown";
}

const char* SourceName(mpdrig_FrequencySource source) {
  switch (source) {
    case mpdrig_FREQUENCY_PISTON_SINE:
      return "piston sine";
    case mpdrig_FREQUENCY_TRACKED:
      return "tracked";
    case mpdrig_FREQUENCY_UNLOCKED:
      return "unlocked";
  }
  return "unknown";
}

// A thinned time series for one chart: one point per frame at most, the newest `history_s` of
// rig time. A point is {sequence number, rig time, values...}; the sequence lets a browser ask
// only for what it has not got.
class Series {
 public:
  void Add(std::uint64_t seq, double t, std::vector<double> values, double history_s) {
    if (!points_.empty() && t <= points_.back().t) {
      if (t == points_.back().t) return;  // nothing new since the last frame
      points_.clear();                    // time went back: another run of the rig
    }
    points_.push_back({seq, t, std::move(values)});
    while (!points_.empty() && points_.front().t < t - history_s) points_.pop_front();
  }
  void Clear() { points_.clear(); }

  // [[seq, t, values...], ...] for the points newer than `since`.
  Json ToJson(std::uint64_t since) const {
    Json out = Json::array();
    for (const Point& p : points_) {
      if (p.seq <= since) continue;
      Json point = Json::array({p.seq, JsonNumber(p.t)});
      for (const double v : p.values) point.push_back(JsonNumber(v));
      out.push_back(std::move(point));
    }
    return out;
  }

 private:
  struct Point {
    std::uint64_t seq;
    double t;
    std::vector<double> values;
  };
  std::deque<Point> points_;
};

Json SensorsJson(const SensorsView& s, dds_time_t now) {
  return {{"counter", s.counter},
          {"t", JsonNumber(s.t)},
          {"piston_m", JsonNumber(s.piston_m)},
          {"choke_deg", JsonNumber(s.choke_deg)},
          {"P1", JsonNumber(s.P1)},
          {"P2", JsonNumber(s.P2)},
          {"C1", JsonNumber(s.C1)},
          {"C2", JsonNumber(s.C2)},
          {"FT1", JsonNumber(s.FT1)},
          {"FT2", JsonNumber(s.FT2)},
          {"FT3", JsonNumber(s.FT3)},
          {"FT4", JsonNumber(s.FT4)},
          {"age_ms", JsonNumber(static_cast<double>(now - s.written_ns) * 1e-6)},
          {"PT", JsonNumbers(std::vector<double>(std::begin(s.PT), std::end(s.PT)))}};
}

std::optional<std::string> ActionOf(const std::string& action, mpdrig_ShadowAction* wire) {
  if (action == "effect_on")
    *wire = mpdrig_SHADOW_EFFECT_ON;
  else if (action == "effect_off")
    *wire = mpdrig_SHADOW_EFFECT_OFF;
  else if (action == "set")
    *wire = mpdrig_SHADOW_SET;
  else if (action == "reset")
    *wire = mpdrig_SHADOW_RESET;
  else if (action == "fit_now")
    *wire = mpdrig_SHADOW_FIT_NOW;
  else
    return "unknown action '" + action + "' (effect_on, effect_off, set, reset, fit_now)";
  return std::nullopt;
}

EstimateView EstimateFromWire(const mpdrig_RigEstimate& w) {
  return EstimateView{w.sim_time_s,
                      w.BHP_est_barg,
                      w.piston_position_est_m,
                      w.piston_velocity_est_mps,
                      w.FT4_est_lpm,
                      w.disturbance_frequency_hz,
                      SourceName(w.frequency_source)};
}

StatusView StatusFromWire(const mpdrig_RigStatus& w) {
  StatusView st;
  st.clock = ClockName(w.clock);
  st.t = w.sim_time_s;
  st.rtf = w.real_time_factor;
  st.deadline_misses = w.deadline_misses;
  st.lost_periods = w.lost_periods;
  st.longest_stall_s = w.longest_stall_s;
  st.rejected = w.rejected_commands;
  st.last_rejection = w.last_rejection;
  st.noise = w.sensor_noise;
  st.warnings = Strings(w.warnings);
  st.effects = Strings(w.active_effects);
  st.owners = Strings(w.actuator_owners);
  return st;
}

ShadowStatusView ShadowStatusFromWire(const mpdrig_ShadowStatus& w) {
  ShadowStatusView st;
  st.t = w.sim_time_s;
  st.window_s = w.window_s;
  st.error = w.error;
  st.channels = Strings(w.channels);
  st.nrmse = Doubles(w.nrmse);
  st.effects = Strings(w.active_effects);
  st.parameters = Strings(w.parameters);
  st.available = Strings(w.available_effects);
  st.last_change = w.last_change;
  st.last_change_t = w.last_change_sim_time_s;
  st.error_at_change = w.error_at_last_change;
  st.rejected = w.rejected_commands;
  st.last_rejection = w.last_rejection;
  st.last_command_id = w.last_command_id;
  st.fit_state = w.fit_state;
  return st;
}

}  // namespace

struct RigFeed::DomainHolder {
  dds::Domain domain;
};

struct RigFeed::Session {
  dds::ClientScope scope;  // first: destroyed last (deleting it deletes its children)
  std::vector<dds::Entity> topics;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors, shadow_sensors;
  std::optional<dds::Reader<mpdrig_RigEstimate>> estimate;
  std::optional<dds::Reader<mpdrig_PressureProfile>> profile;
  std::optional<dds::Reader<mpdrig_RigStatus>> status;
  std::optional<dds::Reader<mpdrig_ShadowStatus>> shadow_status;
  std::optional<dds::Writer<mpdrig_ShadowCommand>> shadow_command;
};

struct RigFeed::RigView {
  std::optional<SensorsView> sensors, shadow;
  std::optional<EstimateView> estimate;
  std::optional<StatusView> status;
  std::optional<ShadowStatusView> shadow_status;
  std::deque<ProfileView> profiles;    // the newest few, for the aligned snapshot
  std::deque<PtAt> rig_pt, shadow_pt;  // the newest few seconds of PT1..PT10
  std::uint64_t samples = 0;           // sensor samples taken
  // Charts: rig {PT1, piston, choke, FT2}, estimate {BHP}, shadow {PT1}, error {error, nrmse...}.
  Series rig_series, estimate_series, shadow_series, error_series;
  std::vector<std::string> error_channels;
  bool fresh_sensors = false, fresh_estimate = false, fresh_shadow = false, fresh_error = false;
};

namespace {

// Creates topic `name` and a reader of it into `*reader`; the topic is kept in `topics`.
template <typename T>
Status OpenReader(std::optional<dds::Reader<T>>* reader, const dds::ClientScope& scope,
                  std::vector<dds::Entity>* topics, const dds::TopicSpec& spec) {
  const char* name = spec.name;
  auto topic = dds::CreateTopic(scope.participant.handle(), spec);
  if (!topic.ok()) return topic.status().Within(name);
  auto created = dds::Reader<T>::Create(scope.sub(), topic->handle(), dds::ReaderQos(spec));
  topics->push_back(std::move(topic).value());
  if (!created.ok()) return created.status().Within(name);
  reader->emplace(std::move(created).value());
  return Status::Ok();
}

// The DDS entities of a watched period: one participant (with FeedOptions::security_dir, its
// subscriber and publisher in the rig's partition), a reader per topic, the command writer.
Result<std::unique_ptr<RigFeed::Session>> OpenSession(const FeedOptions& options) {
  auto session = std::make_unique<RigFeed::Session>();
  auto scope =
      dds::CreateClientScope(options.domain, options.security_dir,
                             options.security_dir.empty() ? std::string() : options.rigs.front());
  if (!scope.ok()) return scope.status();
  session->scope = std::move(scope).value();
  const dds::ClientScope& p = session->scope;
  auto* topics = &session->topics;
  MPDRIG_RETURN_IF_ERROR(OpenReader(&session->sensors, p, topics, dds::topics::kSensors));
  MPDRIG_RETURN_IF_ERROR(OpenReader(&session->estimate, p, topics, dds::topics::kEstimate));
  MPDRIG_RETURN_IF_ERROR(OpenReader(&session->profile, p, topics, dds::topics::kPressureProfile));
  MPDRIG_RETURN_IF_ERROR(OpenReader(&session->status, p, topics, dds::topics::kStatus));
  MPDRIG_RETURN_IF_ERROR(
      OpenReader(&session->shadow_sensors, p, topics, dds::topics::kShadowSensors));
  MPDRIG_RETURN_IF_ERROR(
      OpenReader(&session->shadow_status, p, topics, dds::topics::kShadowStatus));
  auto command_topic = dds::CreateTopic(p.participant.handle(), dds::topics::kShadowCommand);
  if (!command_topic.ok()) return command_topic.status();
  auto writer = dds::Writer<mpdrig_ShadowCommand>::Create(p.pub(), command_topic->handle(),
                                                          dds::RequestQos());
  if (!writer.ok()) return writer.status();
  session->topics.push_back(std::move(command_topic).value());
  session->shadow_command.emplace(std::move(writer).value());
  return session;
}

}  // namespace

Result<std::unique_ptr<RigFeed>> RigFeed::Create(const FeedOptions& options) {
  if (!(options.frame_hz > 0.0 && options.frame_hz <= 100.0))
    return Status::Error("the frame rate must be in (0, 100] Hz");
  if (!(options.idle_s > 0.0)) return Status::Error("the idle time must be positive");
  if (!options.security_dir.empty()) {
    // Refused now, saying why, rather than when a browser first asks.
    if (options.rigs.size() != 1) {
      return Status::Error(
          "--security shows one rig, in its partition: give its id once with --rig");
    }
    MPDRIG_RETURN_IF_ERROR(dds::CheckSecureRigId(options.rigs.front()));
    auto files = dds::LoadSecurityDirectory(options.security_dir);
    if (!files.ok()) return files.status().Within("--security");
  }
  auto domain = dds::Domain::Create(
      options.domain, options.dds_config.empty() ? dds::LoopbackConfig() : options.dds_config);
  if (!domain.ok()) return domain.status().Within("DDS domain " + std::to_string(options.domain));
  std::unique_ptr<RigFeed> feed(new RigFeed(options));
  feed->domain_ = std::make_unique<DomainHolder>(DomainHolder{std::move(domain).value()});
  feed->thread_ = std::thread([f = feed.get()] { f->Run(); });
  return feed;
}

RigFeed::RigFeed(const FeedOptions& options) : options_(options) {}

RigFeed::~RigFeed() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  session_.reset();
}

void RigFeed::Touch() {
  std::lock_guard lock(mu_);
  last_touch_ = std::chrono::steady_clock::now();
  touched_ = true;
  if (!session_) wake_.notify_all();  // open now, not at the next frame
}

void RigFeed::Run() {
  using Clock = std::chrono::steady_clock;
  const auto frame = std::chrono::duration<double>(1.0 / options_.frame_hz);
  const auto idle = std::chrono::duration<double>(options_.idle_s);
  Clock::time_point last_attempt{};
  std::unique_lock lock(mu_);
  while (!stop_) {
    wake_.wait_for(lock, frame);
    if (stop_) break;
    const auto now = Clock::now();
    const bool watched = touched_ && now - last_touch_ < idle;
    if (!watched && session_) {
      session_.reset();  // nobody watches: the service's writers lose their reader
      views_.clear();
      health_.open = false;
    }
    if (watched && !session_ && now - last_attempt > std::chrono::seconds(1)) {
      last_attempt = now;
      auto session = OpenSession(options_);
      if (session.ok()) {
        session_ = std::move(session).value();
        health_.open = true;
        health_.error.clear();
        ++health_.sessions_opened;
      } else {
        health_.error = session.status().message();
      }
    }
    if (session_) Drain();
  }
}

bool RigFeed::Wanted(const char* rig_id) const {
  return options_.rigs.empty() ||
         std::find(options_.rigs.begin(), options_.rigs.end(), rig_id) != options_.rigs.end();
}

RigFeed::RigView& RigFeed::View(const std::string& rig_id) {
  auto& view = views_[rig_id];
  if (!view) view = std::make_unique<RigView>();
  return *view;
}

void RigFeed::Drain() {
  Session& s = *session_;
  std::uint64_t taken = 0;
  auto count = [&](const Result<int>& n) {
    if (n.ok()) {
      taken += static_cast<std::uint64_t>(*n);
    } else {
      health_.error = n.status().message();  // shown by the page (GET /api/rigs)
    }
  };
  count(s.sensors->TakeEach([&](const mpdrig_RigSensors& w, const dds_sample_info_t& info) {
    if (!Wanted(w.rig_id)) return;
    RigView& v = View(w.rig_id);
    v.sensors = FromWire(w, info);
    PushRing(&v.rig_pt, PtAt{w.sample_counter, std::to_array(w.PT_barg)}, kPtRing);
    v.fresh_sensors = true;
    ++v.samples;
  }));
  count(s.estimate->TakeEach([&](const mpdrig_RigEstimate& w, const dds_sample_info_t&) {
    if (!Wanted(w.rig_id)) return;
    RigView& v = View(w.rig_id);
    v.estimate = EstimateFromWire(w);
    v.fresh_estimate = true;
  }));
  count(s.profile->TakeEach([&](const mpdrig_PressureProfile& w, const dds_sample_info_t&) {
    if (!Wanted(w.rig_id)) return;
    PushRing(&View(w.rig_id).profiles,
             ProfileView{w.sample_counter, w.sim_time_s, Doubles(w.position_m),
                         Doubles(w.pressure_barg), Doubles(w.pressure_est_barg)},
             kProfileRing);
  }));
  count(s.status->TakeEach([&](const mpdrig_RigStatus& w, const dds_sample_info_t&) {
    if (!Wanted(w.rig_id)) return;
    View(w.rig_id).status = StatusFromWire(w);
  }));
  count(s.shadow_sensors->TakeEach([&](const mpdrig_RigSensors& w, const dds_sample_info_t& info) {
    if (!Wanted(w.rig_id)) return;
    RigView& v = View(w.rig_id);
    v.shadow = FromWire(w, info);
    PushRing(&v.shadow_pt, PtAt{w.sample_counter, std::to_array(w.PT_barg)}, kPtRing);
    v.fresh_shadow = true;
  }));
  count(s.shadow_status->TakeEach([&](const mpdrig_ShadowStatus& w, const dds_sample_info_t&) {
    if (!Wanted(w.rig_id) || options_.shadow_id != w.shadow_id) return;
    RigView& v = View(w.rig_id);
    v.shadow_status = ShadowStatusFromWire(w);
    v.fresh_error = true;
  }));
  health_.samples_taken += taken;
  ++health_.frames;

  AddHistoryPoints();
}

// One history point per series per frame: the newest sample (the thinning).
void RigFeed::AddHistoryPoints() {
  for (auto& [id, v] : views_) {
    if (v->fresh_sensors) {
      const SensorsView& x = *v->sensors;
      v->rig_series.Add(next_seq_++, x.t, {x.PT[0], x.piston_m, x.choke_deg, x.FT2},
                        options_.history_s);
    }
    if (v->fresh_estimate) {
      v->estimate_series.Add(next_seq_++, v->estimate->t, {v->estimate->bhp}, options_.history_s);
    }
    if (v->fresh_shadow) {
      v->shadow_series.Add(next_seq_++, v->shadow->t, {v->shadow->PT[0]}, options_.history_s);
    }
    if (v->fresh_error) {
      const ShadowStatusView& st = *v->shadow_status;
      if (st.channels != v->error_channels) {  // another shadow, or other channels: start over
        v->error_series.Clear();
        v->error_channels = st.channels;
      }
      std::vector<double> values{st.error};
      values.insert(values.end(), st.nrmse.begin(), st.nrmse.end());
      v->error_series.Add(next_seq_++, st.t, std::move(values), options_.history_s);
    }
    v->fresh_sensors = v->fresh_estimate = v->fresh_shadow = v->fresh_error = false;
  }
}

std::string RigFeed::RigsJson() const {
  std::lock_guard lock(mu_);
  std::vector<std::string> rigs = options_.rigs;
  for (const auto& [id, v] : views_) {
    if (std::find(rigs.begin(), rigs.end(), id) == rigs.end()) rigs.push_back(id);
  }
  std::sort(rigs.begin(), rigs.end());
  return JsonText({{"rigs", rigs},
                   {"dds", session_ ? "open" : (touched_ ? "opening" : "closed")},
                   {"error", health_.error}});
}

FeedHealth RigFeed::Health() const {
  std::lock_guard lock(mu_);
  return health_;
}

namespace {

Json StatusJson(const StatusView& st) {
  return {{"clock", st.clock},
          {"t", JsonNumber(st.t)},
          {"rtf", JsonNumber(st.rtf)},
          {"deadline_misses", st.deadline_misses},
          {"lost_periods", st.lost_periods},
          {"longest_stall_s", JsonNumber(st.longest_stall_s)},
          {"rejected", st.rejected},
          {"last_rejection", st.last_rejection},
          {"noise", st.noise},
          {"warnings", st.warnings},
          {"effects", st.effects},
          {"owners", st.owners}};
}

Json ShadowStatusJson(const ShadowStatusView& st) {
  return {{"t", JsonNumber(st.t)},
          {"window_s", JsonNumber(st.window_s)},
          {"error", JsonNumber(st.error)},
          {"last_change_t", JsonNumber(st.last_change_t)},
          {"error_at_change", JsonNumber(st.error_at_change)},
          {"rejected", st.rejected},
          // A command id is a 64-bit number: as a string, since JavaScript's numbers hold 53 bits.
          {"last_command_id", std::to_string(st.last_command_id)},
          {"channels", st.channels},
          {"effects", st.effects},
          {"parameters", st.parameters},
          {"available", st.available},
          {"nrmse", JsonNumbers(st.nrmse)},
          {"last_change", st.last_change},
          {"last_rejection", st.last_rejection},
          {"fit_state", st.fit_state}};
}

// The pressure along the pipe at one instant for the rig, the observer and the shadow: the newest
// profile sample the shadow has reached (the newest one without a shadow), with the rig's and the
// shadow's PT1..PT10 of that same sample; null before the first profile.
Json AlignedProfileJson(const RigFeed::RigView& v) {
  if (v.profiles.empty()) return nullptr;
  const ProfileView* chosen = &v.profiles.back();
  if (!v.shadow_pt.empty()) {
    const std::uint64_t reached = v.shadow_pt.back().counter;
    for (auto it = v.profiles.rbegin(); it != v.profiles.rend(); ++it) {
      chosen = &*it;
      if (it->counter <= reached) break;
    }
  }
  auto pt_at = [&](const std::deque<PtAt>& ring) -> std::vector<double> {
    for (auto it = ring.rbegin(); it != ring.rend(); ++it) {
      if (it->counter == chosen->counter) return {it->PT.begin(), it->PT.end()};
      if (it->counter < chosen->counter) break;
    }
    return {};
  };
  return {{"t", JsonNumber(chosen->t)},
          {"x", JsonNumbers(chosen->x)},
          {"p", JsonNumbers(chosen->p)},
          {"p_est", JsonNumbers(chosen->p_est)},
          {"rig_PT", JsonNumbers(pt_at(v.rig_pt))},
          {"shadow_PT", JsonNumbers(pt_at(v.shadow_pt))}};
}

}  // namespace

std::string RigFeed::StateJson(const std::string& rig_id, std::uint64_t since) const {
  std::lock_guard lock(mu_);
  Json out = {{"rig", rig_id}, {"dds", session_ ? "open" : "opening"}};
  const auto found = views_.find(rig_id);
  if (found == views_.end()) {
    out["known"] = false;
    return JsonText(out);
  }
  const RigView& v = *found->second;
  const dds_time_t now = dds_time();
  out["known"] = true;
  out["samples"] = v.samples;
  out["seq"] = next_seq_ - 1;
  if (v.sensors) out["sensors"] = SensorsJson(*v.sensors, now);
  if (v.shadow) out["shadow"] = SensorsJson(*v.shadow, now);
  if (v.estimate) {
    const EstimateView& e = *v.estimate;
    out["estimate"] = {{"t", JsonNumber(e.t)},
                       {"bhp", JsonNumber(e.bhp)},
                       {"piston_m", JsonNumber(e.piston_m)},
                       {"velocity", JsonNumber(e.velocity)},
                       {"FT4", JsonNumber(e.FT4)},
                       {"freq_hz", JsonNumber(e.freq_hz)},
                       {"source", e.source}};
  }
  if (Json profile = AlignedProfileJson(v); !profile.is_null()) out["profile"] = std::move(profile);
  if (v.status) out["status"] = StatusJson(*v.status);
  if (v.shadow_status) out["shadow_status"] = ShadowStatusJson(*v.shadow_status);
  out["hist"] = {{"rig", v.rig_series.ToJson(since)},
                 {"est", v.estimate_series.ToJson(since)},
                 {"shadow", v.shadow_series.ToJson(since)},
                 {"err", v.error_series.ToJson(since)},
                 {"err_channels", v.error_channels}};
  return JsonText(out);
}

Result<std::uint64_t> RigFeed::SendShadowCommand(const std::string& rig_id,
                                                 const std::string& action,
                                                 const std::string& argument) {
  mpdrig_ShadowAction wire_action{};
  if (auto bad = ActionOf(action, &wire_action)) return Status::Error(*bad);
  const bool needs_argument = wire_action == mpdrig_SHADOW_EFFECT_ON ||
                              wire_action == mpdrig_SHADOW_EFFECT_OFF ||
                              wire_action == mpdrig_SHADOW_SET;
  if (needs_argument && argument.empty())
    return Status::Error(action + " needs an argument (an effect name, or KEY=VALUE for set)");
  if (rig_id.empty()) return Status::Error("no rig chosen");
  Touch();
  // The writer exists while a browser watches; a shadow that started a moment ago may not have
  // matched it yet, so wait a little (without holding the feed) before saying there is none.
  for (int attempt = 0;; ++attempt) {
    {
      std::lock_guard lock(mu_);
      if (session_) {
        dds_publication_matched_status_t matched{};
        const dds_entity_t writer = session_->shadow_command->handle();
        const Status got = dds::Check(dds_get_publication_matched_status(writer, &matched),
                                      "dds_get_publication_matched_status");
        if (!got.ok()) return got;
        if (matched.current_count > 0) {
          mpdrig_ShadowCommand command{};
          std::string id_text = rig_id, shadow_text = options_.shadow_id, argument_text = argument;
          command.rig_id = id_text.data();
          command.shadow_id = shadow_text.data();
          command.command_id = static_cast<std::uint64_t>(
              std::chrono::system_clock::now().time_since_epoch().count());
          command.action = wire_action;
          command.argument = argument_text.data();
          MPDRIG_RETURN_IF_ERROR(session_->shadow_command->Write(command));
          return command.command_id;
        }
      }
    }
    if (attempt >= 40) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return Status::Error("no shadow model is listening (start `mpdrig shadow --rig " + rig_id +
                       " --shadow-id " + options_.shadow_id + "` on this domain)");
}

}  // namespace mpdrig::dashboard
