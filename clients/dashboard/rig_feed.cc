#include "clients/dashboard/rig_feed.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <utility>

#include "clients/client/participant.h"
#include "clients/client/rig_streams.h"
#include "clients/client/shadow_client.h"
#include "clients/dashboard/json_out.h"

namespace mpdrig::dashboard {

namespace {

// Now on the writers' clock (s since 1970), for a sample's age.
double WallClockS() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

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

Json SensorsJson(const client::Sensors& s, double now_s) {
  return {{"counter", s.sample_counter},
          {"t", JsonNumber(s.time_s)},
          {"piston_m", JsonNumber(s.piston_position_m)},
          {"choke_deg", JsonNumber(s.choke_position_deg)},
          {"P1", JsonNumber(s.P1_barg)},
          {"P2", JsonNumber(s.P2_barg)},
          {"C1", JsonNumber(s.C1_barg)},
          {"C2", JsonNumber(s.C2_barg)},
          {"FT1", JsonNumber(s.FT1_lpm)},
          {"FT2", JsonNumber(s.FT2_lpm)},
          {"FT3", JsonNumber(s.FT3_lpm)},
          {"FT4", JsonNumber(s.FT4_lpm)},
          {"age_ms", JsonNumber((now_s - s.published_s) * 1e3)},
          {"PT", JsonNumbers(std::vector<double>(s.PT_barg.begin(), s.PT_barg.end()))}};
}

// The actions the page offers (a fit is cancelled from shadow_ctl).
Result<client::ShadowAction> ActionOf(const std::string& action) {
  for (const char* offered : {"effect_on", "effect_off", "set", "reset", "fit_now"}) {
    if (action == offered) return client::ShadowActionNamed(action);
  }
  return Status::Error("unknown action '" + action +
                       "' (effect_on, effect_off, set, reset, fit_now)");
}

}  // namespace

struct RigFeed::DomainHolder {
  std::shared_ptr<client::ClientDomain> domain;  // configured while the feed lives
};

// The DDS side of a watched period, on the client library: one participant (with
// FeedOptions::security_dir, each rig's endpoints in its partition), the rigs' streams, and a
// shadow command handle per rig (made when the rig is first seen, so it has matched the shadow
// by the time a browser sends a command).
struct RigFeed::Session {
  std::shared_ptr<client::Participant> participant;  // first: the others go before it
  std::unique_ptr<client::RigStreams> streams;
  std::map<std::string, std::unique_ptr<client::Shadow>> shadows;

  // The rig's shadow handle, made on the first call; nullptr (and `error` set) if it cannot be.
  client::Shadow* ShadowOf(const std::string& rig_id, const std::string& shadow_id,
                           std::string* error) {
    auto& shadow = shadows[rig_id];
    if (!shadow) {
      auto opened = client::Shadow::Open(participant, rig_id, shadow_id, /*read_status=*/false);
      if (!opened.ok()) {
        *error = opened.status().message();
        shadows.erase(rig_id);
        return nullptr;
      }
      shadow = std::move(opened).value();
      auto writer = shadow->AwaitCommandReader(0.0);  // the writer now, to match meanwhile
      if (!writer.ok()) *error = writer.status().message();
    }
    return shadow.get();
  }
};

struct RigFeed::RigView {
  std::optional<client::Sensors> sensors, shadow;
  std::optional<client::Estimate> estimate;
  std::optional<client::RigStatus> status;
  std::optional<client::ShadowStatus> shadow_status;
  std::deque<client::Profile> profiles;  // the newest few, for the aligned snapshot
  std::deque<PtAt> rig_pt, shadow_pt;    // the newest few seconds of PT1..PT10
  std::uint64_t samples = 0;             // sensor samples taken
  // Charts: rig {PT1, piston, choke, FT2}, estimate {BHP}, shadow {PT1}, error {error, nrmse...}.
  Series rig_series, estimate_series, shadow_series, error_series;
  std::vector<std::string> error_channels;
  bool fresh_sensors = false, fresh_estimate = false, fresh_shadow = false, fresh_error = false;
};

namespace {

// Joins the domain, opens the rigs' streams and the named rigs' shadow command handles.
Result<std::unique_ptr<RigFeed::Session>> OpenSession(const FeedOptions& options) {
  auto session = std::make_unique<RigFeed::Session>();
  auto participant = client::Participant::Join({.domain = options.domain,
                                                .dds_config = options.dds_config,
                                                .security_dir = options.security_dir});
  if (!participant.ok()) return participant.status();
  session->participant = std::move(participant).value();
  auto streams = client::RigStreams::Open(session->participant,
                                          {.rigs = options.rigs, .shadow_id = options.shadow_id});
  if (!streams.ok()) return streams.status();
  session->streams = std::move(streams).value();
  for (const std::string& rig_id : options.rigs) {
    std::string error;
    if (session->ShadowOf(rig_id, options.shadow_id, &error) == nullptr) {
      return Status::Error(error);
    }
  }
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
    MPDRIG_RETURN_IF_ERROR(client::Participant::Check({.domain = options.domain,
                                                       .dds_config = options.dds_config,
                                                       .security_dir = options.security_dir},
                                                      options.rigs));
  }
  // Configured now (nothing on the wire until a browser watches), and kept while the feed lives.
  auto domain = client::ClientDomain::Configure(options.domain, options.dds_config);
  if (!domain.ok()) return domain.status();
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

RigFeed::RigView& RigFeed::View(const std::string& rig_id) {
  auto& view = views_[rig_id];
  if (!view) view = std::make_unique<RigView>();
  return *view;
}

void RigFeed::Drain() {
  Session& s = *session_;
  client::RigStreams::Visitor visit;
  visit.sensors = [&](const std::string& rig_id, const client::Sensors& x) {
    RigView& v = View(rig_id);
    v.sensors = x;
    PushRing(&v.rig_pt, PtAt{x.sample_counter, x.PT_barg}, kPtRing);
    v.fresh_sensors = true;
    ++v.samples;
  };
  visit.estimate = [&](const std::string& rig_id, const client::Estimate& e) {
    RigView& v = View(rig_id);
    v.estimate = e;
    v.fresh_estimate = true;
  };
  visit.profile = [&](const std::string& rig_id, const client::Profile& p) {
    PushRing(&View(rig_id).profiles, p, kProfileRing);
  };
  visit.status = [&](const std::string& rig_id, const client::RigStatus& st) {
    View(rig_id).status = st;
  };
  visit.shadow_sensors = [&](const std::string& rig_id, const client::Sensors& x) {
    RigView& v = View(rig_id);
    v.shadow = x;
    PushRing(&v.shadow_pt, PtAt{x.sample_counter, x.PT_barg}, kPtRing);
    v.fresh_shadow = true;
  };
  visit.shadow_status = [&](const client::ShadowStatus& st) {
    RigView& v = View(st.rig_id);
    v.shadow_status = st;
    v.fresh_error = true;
  };
  const client::RigStreams::Taken taken = s.streams->Take(visit);
  if (!taken.error.empty()) health_.error = taken.error;  // shown by the page (GET /api/rigs)
  // A rig seen for the first time gets its shadow command handle now (see Session).
  for (const auto& [id, view] : views_) {
    std::string error;
    if (s.ShadowOf(id, options_.shadow_id, &error) == nullptr || !error.empty()) {
      health_.error = error;
    }
  }
  health_.samples_taken += taken.samples;
  ++health_.frames;

  AddHistoryPoints();
}

// One history point per series per frame: the newest sample (the thinning).
void RigFeed::AddHistoryPoints() {
  for (auto& [id, v] : views_) {
    if (v->fresh_sensors) {
      const client::Sensors& x = *v->sensors;
      v->rig_series.Add(next_seq_++, x.time_s,
                        {x.PT_barg[0], x.piston_position_m, x.choke_position_deg, x.FT2_lpm},
                        options_.history_s);
    }
    if (v->fresh_estimate) {
      v->estimate_series.Add(next_seq_++, v->estimate->time_s, {v->estimate->BHP_est_barg},
                             options_.history_s);
    }
    if (v->fresh_shadow) {
      v->shadow_series.Add(next_seq_++, v->shadow->time_s, {v->shadow->PT_barg[0]},
                           options_.history_s);
    }
    if (v->fresh_error) {
      const client::ShadowStatus& st = *v->shadow_status;
      if (st.channels != v->error_channels) {  // another shadow, or other channels: start over
        v->error_series.Clear();
        v->error_channels = st.channels;
      }
      std::vector<double> values{st.error};
      values.insert(values.end(), st.nrmse.begin(), st.nrmse.end());
      v->error_series.Add(next_seq_++, st.sim_time_s, std::move(values), options_.history_s);
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

Json StatusJson(const client::RigStatus& st) {
  return {{"clock", st.clock},
          {"t", JsonNumber(st.sim_time_s)},
          {"rtf", JsonNumber(st.real_time_factor)},
          {"deadline_misses", st.deadline_misses},
          {"lost_periods", st.lost_periods},
          {"longest_stall_s", JsonNumber(st.longest_stall_s)},
          {"rejected", st.rejected_commands},
          {"last_rejection", st.last_rejection},
          {"noise", st.sensor_noise},
          {"warnings", st.warnings},
          {"effects", st.active_effects},
          {"owners", st.actuator_owners}};
}

Json ShadowStatusJson(const client::ShadowStatus& st) {
  return {{"t", JsonNumber(st.sim_time_s)},
          {"window_s", JsonNumber(st.window_s)},
          {"error", JsonNumber(st.error)},
          {"last_change_t", JsonNumber(st.last_change_sim_time_s)},
          {"error_at_change", JsonNumber(st.error_at_last_change)},
          {"rejected", st.rejected_commands},
          // A command id is a 64-bit number: as a string, since JavaScript's numbers hold 53 bits.
          {"last_command_id", std::to_string(st.last_command_id)},
          {"channels", st.channels},
          {"effects", st.active_effects},
          {"parameters", st.parameters},
          {"available", st.available_effects},
          {"nrmse", JsonNumbers(st.nrmse)},
          {"last_change", st.last_change},
          {"last_rejection", st.last_rejection},
          {"fit_state", st.fit_state}};
}

// The observer's estimate; its frequency source as the page names it ("piston sine").
Json EstimateJson(const client::Estimate& e) {
  std::string source = e.frequency_source;
  std::replace(source.begin(), source.end(), '_', ' ');
  return {{"t", JsonNumber(e.time_s)},
          {"bhp", JsonNumber(e.BHP_est_barg)},
          {"piston_m", JsonNumber(e.piston_position_est_m)},
          {"velocity", JsonNumber(e.piston_velocity_est_mps)},
          {"FT4", JsonNumber(e.FT4_est_lpm)},
          {"freq_hz", JsonNumber(e.disturbance_frequency_hz)},
          {"source", source}};
}

// The pressure along the pipe at one instant for the rig, the observer and the shadow: the newest
// profile sample the shadow has reached (the newest one without a shadow), with the rig's and the
// shadow's PT1..PT10 of that same sample; null before the first profile.
Json AlignedProfileJson(const RigFeed::RigView& v) {
  if (v.profiles.empty()) return nullptr;
  const client::Profile* chosen = &v.profiles.back();
  if (!v.shadow_pt.empty()) {
    const std::uint64_t reached = v.shadow_pt.back().counter;
    for (auto it = v.profiles.rbegin(); it != v.profiles.rend(); ++it) {
      chosen = &*it;
      if (it->sample_counter <= reached) break;
    }
  }
  auto pt_at = [&](const std::deque<PtAt>& ring) -> std::vector<double> {
    for (auto it = ring.rbegin(); it != ring.rend(); ++it) {
      if (it->counter == chosen->sample_counter) return {it->PT.begin(), it->PT.end()};
      if (it->counter < chosen->sample_counter) break;
    }
    return {};
  };
  return {
      {"t", JsonNumber(chosen->time_s)},         {"x", JsonNumbers(chosen->position_m)},
      {"p", JsonNumbers(chosen->pressure_barg)}, {"p_est", JsonNumbers(chosen->pressure_est_barg)},
      {"rig_PT", JsonNumbers(pt_at(v.rig_pt))},  {"shadow_PT", JsonNumbers(pt_at(v.shadow_pt))}};
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
  const double now = WallClockS();
  out["known"] = true;
  out["samples"] = v.samples;
  out["seq"] = next_seq_ - 1;
  if (v.sensors) out["sensors"] = SensorsJson(*v.sensors, now);
  if (v.shadow) out["shadow"] = SensorsJson(*v.shadow, now);
  if (v.estimate) out["estimate"] = EstimateJson(*v.estimate);
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
  auto wire_action = ActionOf(action);
  if (!wire_action.ok()) return wire_action.status();
  if (client::ShadowActionNeedsArgument(*wire_action) && argument.empty())
    return Status::Error(action + " needs an argument (an effect name, or KEY=VALUE for set)");
  if (rig_id.empty()) return Status::Error("no rig chosen");
  Touch();
  // The writer exists while a browser watches; a shadow that started a moment ago may not have
  // matched it yet, so wait a little (without holding the feed) before saying there is none.
  for (int attempt = 0;; ++attempt) {
    {
      std::lock_guard lock(mu_);
      if (session_) {
        std::string error;
        client::Shadow* shadow = session_->ShadowOf(rig_id, options_.shadow_id, &error);
        if (shadow == nullptr) return Status::Error(error);
        auto matched = shadow->AwaitCommandReader(0.0);
        if (!matched.ok()) return matched.status();
        if (*matched) return shadow->Send(*wire_action, argument);
      }
    }
    if (attempt >= 40) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return Status::Error("no shadow model is listening (start `mpdrig shadow --rig " + rig_id +
                       " --shadow-id " + options_.shadow_id + "` on this domain)");
}

}  // namespace mpdrig::dashboard
