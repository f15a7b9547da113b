// The shadow beside a mystery rig over loopback DDS: a rig with a hidden effect (lockstep, so the
// test sets the pace) read through the lab's sensor noise (thesis Table 4.1.1), the shadow
// subscribed to its sensors; the shadow's error, read from its status topic, falls by half when
// the model command switches the right effect on, not with a wrong one, and a bad command is
// refused and counted; fit now, asked with the effect at a wrong strength, brings the strength
// back and the error down while the shadow runs on, and a second one meanwhile is refused. A
// second shadow of the same rig (another id) takes only its own commands; a fit can be cancelled.
#include "service/shadow/shadow_service.h"
#include "service/dds/topics.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/effect.h"
#include "mpdrig.h"
#include "service/rig/rig_service.h"
#include "service/rig/wire.h"
#include "tests/support/test_domain.h"

namespace mpdrig::service {
namespace {

constexpr int kCells = 50;  // rig and shadow on the same grid; a finer one only costs time

struct StatusSeen {
  double sim_time_s = -1.0;
  double error = std::nan("");
  std::string last_change;
  std::uint64_t rejected = 0;
  std::string last_rejection;
  std::vector<std::string> effects;
  std::string fit_state;
};

// The number after `key=` in `text` (NaN if absent).
double ValueIn(const std::string& text, const std::string& key) {
  const std::size_t at = text.find(key + "=");
  if (at == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + at + key.size() + 1, nullptr);
}

class ShadowServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = static_cast<dds_domainid_t>(testing::ClaimTestDomain());
    ASSERT_GT(domain_, 0);
    SimulationOptions grid;
    grid.cells = kCells;
    ShadowOptions model;
    model.simulation = grid;
    model.window_s = 10.0;
    model.warmup_s = 20.0;
    ShadowServeOptions shadow_options;
    shadow_options.rig_id = "mystery";
    shadow_options.domain = domain_;
    shadow_options.status_period_s = 0.5;
    log_path_ = ::testing::TempDir() + "mpdrig-shadow-error.csv";
    shadow_options.log_path = log_path_;

    // The choke's inertance, at a heave that shows it above the lab's noise: choke 40 deg,
    // 15 L/min, 0.08 m at 0.4 Hz (the model test measures the effects at this and a slower one).
    RigParams truth;
    ASSERT_TRUE(ApplyEffectSpec(&truth, "choke_inertia").ok());
    SensorOptions sensors;
    sensors.noise = SensorNoise::Lab();
    sensors.seed = 3;
    auto rig = RigHost::Create("mystery", truth, grid, 100.0, {40.0, 15.0, 0.0}, {}, sensors);
    ASSERT_TRUE(rig.ok()) << rig.status().message();
    PistonCommandIn heave;
    heave.mode = PistonCommandIn::Mode::kSine;
    heave.amplitude_m = 0.08;
    heave.frequency_hz = 0.4;
    ASSERT_TRUE(rig->SetPiston(heave).ok());
    std::vector<RigHost> rigs;
    rigs.push_back(std::move(rig).value());
    ServeOptions options;
    options.clock = ClockMode::kLockstep;
    options.domain = domain_;
    options.hide_effects = true;
    options.observer = false;  // not what this test is about; it costs time
    auto service = RigService::Create(std::move(rigs), options);
    ASSERT_TRUE(service.ok()) << service.status().message();
    service_ = std::move(service).value();
    // The rig service configures the domain (loopback only); the shadow joins it.
    shadow_options.dds_config.clear();
    auto shadow = ShadowService::Create(RigParams(), model, shadow_options);
    ASSERT_TRUE(shadow.ok()) << shadow.status().message();
    shadow_ = std::move(shadow).value();
    ShadowServeOptions other_options = shadow_options;
    other_options.shadow_id = kOtherShadow;
    other_options.log_path.clear();
    auto other = ShadowService::Create(RigParams(), model, other_options);
    ASSERT_TRUE(other.ok()) << other.status().message();
    other_ = std::move(other).value();
    rig_thread_ = std::thread([this] { rig_status_ = service_->Run(stop_); });
    shadow_thread_ = std::thread([this] { shadow_status_ = shadow_->Run(stop_); });
    other_thread_ = std::thread([this] { other_status_ = other_->Run(stop_); });

    auto participant = dds::CreateParticipant(domain_);
    ASSERT_TRUE(participant.ok());
    participant_ = std::move(participant).value();
    const dds_entity_t p = participant_.handle();
    rig_status_topic_ = *dds::CreateTopic(p, dds::topics::kStatus.type, dds::topics::kStatus.name);
    step_topic_ =
        *dds::CreateTopic(p, dds::topics::kStepRequest.type, dds::topics::kStepRequest.name);
    shadow_status_topic_ =
        *dds::CreateTopic(p, dds::topics::kShadowStatus.type, dds::topics::kShadowStatus.name);
    command_topic_ =
        *dds::CreateTopic(p, dds::topics::kShadowCommand.type, dds::topics::kShadowCommand.name);
    rig_status_reader_.emplace(
        *dds::Reader<mpdrig_RigStatus>::Create(p, rig_status_topic_.handle(), dds::StatusQos()));
    shadow_reader_.emplace(*dds::Reader<mpdrig_ShadowStatus>::Create(
        p, shadow_status_topic_.handle(), dds::StatusQos()));
    const dds::Qos requests = dds::RequestQos();  // as the service reads them
    step_.emplace(*dds::Writer<mpdrig_StepRequest>::Create(p, step_topic_.handle(), requests));
    command_.emplace(
        *dds::Writer<mpdrig_ShadowCommand>::Create(p, command_topic_.handle(), requests));
    // Discovery: the rig takes step requests, the shadow commands and (through the rig's
    // writer) samples only once matched.
    for (int i = 0; i < 100; ++i) {
      dds_publication_matched_status_t steps{}, commands{};
      dds_get_publication_matched_status(step_->handle(), &steps);
      dds_get_publication_matched_status(command_->handle(), &commands);
      if (steps.current_count > 0 && commands.current_count > 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // rig sensors -> shadow
  }
  void TearDown() override {
    stop_ = true;
    if (rig_thread_.joinable()) rig_thread_.join();
    if (shadow_thread_.joinable()) shadow_thread_.join();
    if (other_thread_.joinable()) other_thread_.join();
    EXPECT_TRUE(rig_status_.ok()) << rig_status_.message();
    EXPECT_TRUE(shadow_status_.ok()) << shadow_status_.message();
    EXPECT_TRUE(other_status_.ok()) << other_status_.message();
  }

  // Runs the rig `seconds` further and waits until it has stepped.
  void RunRig(double seconds) {
    const auto steps = static_cast<std::uint32_t>(std::lround(seconds * 100.0));
    const std::uint64_t id = ++request_;
    char rig_id[] = "mystery";
    ASSERT_TRUE(step_->Write(mpdrig_StepRequest{rig_id, id, steps}).ok());
    bool done = false;
    for (int i = 0; i < 1200 && !done; ++i) {
      auto ready = rig_status_reader_->Wait(DDS_MSECS(100));
      if (!ready.ok() || !*ready) continue;
      (void)rig_status_reader_->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
        if (s.last_completed_step_request == id) done = true;
      });
    }
    ASSERT_TRUE(done) << "the rig did not complete " << steps << " steps";
    rig_time_s_ += seconds;
  }

  // The shadow's status once it has caught up with the rig (and, if given, made `change`).
  StatusSeen WaitShadow(const std::string& change = "", std::uint64_t rejected = 0,
                        const std::string& shadow_id = kDefaultShadowId) {
    StatusSeen& seen = seen_[shadow_id];
    for (int i = 0; i < 600; ++i) {
      (void)shadow_reader_->Wait(DDS_MSECS(100));
      (void)shadow_reader_->TakeEach([&](const mpdrig_ShadowStatus& s, const dds_sample_info_t&) {
        StatusSeen& of = seen_[s.shadow_id];
        of.sim_time_s = s.sim_time_s;
        of.error = s.error;
        of.last_change = s.last_change;
        of.rejected = s.rejected_commands;
        of.last_rejection = s.last_rejection;
        of.fit_state = s.fit_state;
        of.effects.clear();
        for (std::uint32_t k = 0; k < s.active_effects._length; ++k)
          of.effects.push_back(s.active_effects._buffer[k]);
      });
      // The rig's last sample is 0.01 s before its clock; the status period is 0.5 s.
      if (seen.sim_time_s >= rig_time_s_ - 0.6 && (change.empty() || seen.last_change == change) &&
          seen.rejected >= rejected)
        return seen;
    }
    ADD_FAILURE() << "the shadow did not catch up: status at " << seen.sim_time_s << " s, rig at "
                  << rig_time_s_ << " s, last change '" << seen.last_change << "'";
    return seen;
  }

  // The shadow's status once its fit has ended (fit_state "done: ..." or "failed: ..."), the rig
  // still, the shadow running on.
  StatusSeen WaitFit(bool or_cancelled = false) {
    StatusSeen seen;
    for (int i = 0; i < 1200; ++i) {
      seen = WaitShadow();
      if (seen.fit_state.rfind("done:", 0) == 0 || seen.fit_state.rfind("failed:", 0) == 0 ||
          (or_cancelled && seen.fit_state == "cancelled"))
        return seen;
    }
    ADD_FAILURE() << "the fit did not end: '" << seen.fit_state << "'";
    return seen;
  }

  void Command(mpdrig_ShadowAction action, const std::string& argument,
               std::string shadow_id = kDefaultShadowId) {
    char rig_id[] = "mystery";
    std::string text = argument;
    mpdrig_ShadowCommand command{rig_id, shadow_id.data(), ++command_id_, action, text.data()};
    ASSERT_TRUE(command_->Write(command).ok());
  }

  dds_domainid_t domain_ = 0;
  std::string log_path_;
  static constexpr const char* kOtherShadow = "other";
  std::map<std::string, StatusSeen> seen_;  // the newest status of each shadow
  std::unique_ptr<ShadowService> shadow_, other_;
  std::unique_ptr<RigService> service_;
  std::thread rig_thread_, shadow_thread_, other_thread_;
  std::atomic<bool> stop_{false};
  Status rig_status_ = Status::Ok(), shadow_status_ = Status::Ok(), other_status_ = Status::Ok();
  dds::Entity participant_, rig_status_topic_, step_topic_, shadow_status_topic_, command_topic_;
  std::optional<dds::Reader<mpdrig_RigStatus>> rig_status_reader_;
  std::optional<dds::Reader<mpdrig_ShadowStatus>> shadow_reader_;
  std::optional<dds::Writer<mpdrig_StepRequest>> step_;
  std::optional<dds::Writer<mpdrig_ShadowCommand>> command_;
  std::uint64_t request_ = 0, command_id_ = 0;
  double rig_time_s_ = 0.0;
};

TEST_F(ShadowServiceTest, ErrorHalvesWithTheHiddenEffectAndNotWithAWrongOne) {
  for (int i = 0; i < 8; ++i) RunRig(5.0);  // the warm-up and a window
  const StatusSeen without = WaitShadow();
  ASSERT_TRUE(std::isfinite(without.error));

  // A bad command changes nothing and is counted.
  Command(mpdrig_SHADOW_EFFECT_ON, "no_such_effect");
  const StatusSeen refused = WaitShadow("", 1);
  EXPECT_EQ(refused.rejected, 1u);
  EXPECT_NE(refused.last_rejection.find("no_such_effect"), std::string::npos);

  Command(mpdrig_SHADOW_EFFECT_ON, "choke_inertia");
  const StatusSeen right = WaitShadow("effect on: choke_inertia", 1);
  EXPECT_LE(right.error, 0.5 * without.error) << "without " << without.error;
  ASSERT_EQ(right.effects.size(), 1u);
  RunRig(10.0);  // a window later, still halved (the live model, not only the replay)
  const StatusSeen later = WaitShadow();
  EXPECT_LE(later.error, 0.5 * without.error) << "without " << without.error;

  Command(mpdrig_SHADOW_RESET, "");
  const StatusSeen reset = WaitShadow("reset", 1);
  EXPECT_TRUE(reset.effects.empty());
  EXPECT_NEAR(reset.error, without.error, 0.2 * without.error);  // back to the model it had

  // A wrong effect (the helical coil's extra friction) does not explain the rig's.
  Command(mpdrig_SHADOW_EFFECT_ON, "helical_friction");
  const StatusSeen wrong = WaitShadow("effect on: helical_friction", 1);
  EXPECT_GT(wrong.error, 0.5 * without.error);
  std::printf("  shadow error: without %.4f, right effect %.4f (a window later %.4f), wrong %.4f\n",
              without.error, right.error, later.error, wrong.error);

  // The right effect at a third of its strength, then fit now; a second fit while the first
  // runs is refused, saying why.
  Command(mpdrig_SHADOW_EFFECT_OFF, "helical_friction");
  (void)WaitShadow("effect off: helical_friction", 1);
  Command(mpdrig_SHADOW_EFFECT_ON, "choke_inertia:b1_per_m=1.5e5");
  const StatusSeen weak = WaitShadow("effect on: choke_inertia:b1_per_m=1.5e5", 1);
  Command(mpdrig_SHADOW_FIT_NOW, "");
  Command(mpdrig_SHADOW_FIT_NOW, "");
  const StatusSeen twice = WaitShadow("", 2);
  EXPECT_NE(twice.last_rejection.find("a fit is running"), std::string::npos)
      << twice.last_rejection;
  const StatusSeen fitted = WaitFit();
  ASSERT_EQ(fitted.fit_state.rfind("done:", 0), 0u) << fitted.fit_state;
  const double b1 = ValueIn(fitted.fit_state, "choke_inertia.b1_per_m");
  const double c = ValueIn(fitted.fit_state, "c");
  EXPECT_NEAR(b1, 5.0e5, 0.3 * 5.0e5) << fitted.fit_state;  // the effect's default: the truth
  EXPECT_NEAR(c, RigParams().wave_speed_mps, 0.03 * RigParams().wave_speed_mps) << fitted.fit_state;
  EXPECT_LT(fitted.error, 0.8 * weak.error) << fitted.fit_state;
  std::printf("  fit now from b1 = 1.5e5: error %.4f -> %.4f; %s\n", weak.error, fitted.error,
              fitted.fit_state.c_str());

  // The CSV: the header, then a row per status with the time and the overall error.
  std::ifstream log(log_path_);
  std::string header, row;
  std::getline(log, header);
  EXPECT_EQ(header.rfind("time_s,error,P1_nrmse,", 0), 0u) << header;
  int rows = 0;
  while (std::getline(log, row)) ++rows;
  EXPECT_GE(rows, 80);  // 50 s of rig time at one row per 0.5 s, less the first
}

TEST_F(ShadowServiceTest, EachShadowTakesOnlyItsOwnCommandsAndAFitCanBeCancelled) {
  for (int i = 0; i < 6; ++i) RunRig(5.0);
  (void)WaitShadow();
  (void)WaitShadow("", 0, kOtherShadow);

  // A command for the other shadow changes it, not this one, and this one counts nothing.
  Command(mpdrig_SHADOW_EFFECT_ON, "choke_inertia", kOtherShadow);
  const StatusSeen other = WaitShadow("effect on: choke_inertia", 0, kOtherShadow);
  ASSERT_EQ(other.effects.size(), 1u);
  RunRig(1.0);
  const StatusSeen mine = WaitShadow();
  EXPECT_TRUE(mine.effects.empty());
  EXPECT_EQ(mine.rejected, 0u);
  EXPECT_TRUE(mine.last_change.empty()) << mine.last_change;

  // Cancel with no fit running: refused, saying why.
  Command(mpdrig_SHADOW_FIT_CANCEL, "");
  const StatusSeen nothing = WaitShadow("", 1);
  EXPECT_NE(nothing.last_rejection.find("no fit is running"), std::string::npos)
      << nothing.last_rejection;

  // Fit now, cancelled at once: the fit ends "cancelled" and the model is left as it was.
  Command(mpdrig_SHADOW_FIT_NOW, "");
  Command(mpdrig_SHADOW_FIT_CANCEL, "");
  const StatusSeen cancelled = WaitFit(/*or_cancelled=*/true);
  EXPECT_EQ(cancelled.fit_state, "cancelled");
  EXPECT_TRUE(cancelled.last_change.empty()) << cancelled.last_change;
  EXPECT_EQ(cancelled.rejected, 1u) << cancelled.last_rejection;
  // And the next fit runs as usual.
  Command(mpdrig_SHADOW_FIT_NOW, "");
  RunRig(0.5);
  const StatusSeen again = WaitFit();
  EXPECT_EQ(again.fit_state.rfind("done:", 0), 0u) << again.fit_state;
}

}  // namespace
}  // namespace mpdrig::service
