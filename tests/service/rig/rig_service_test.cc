// The rig service end to end over loopback DDS with the lockstep clock: a client commands the
// rig, asks for steps, and reads sensors and status like a controller would. Each test runs the
// service in its own DDS domain.
#include "service/rig/rig_service.h"
#include "service/dds/topics.h"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <thread>

#include <gtest/gtest.h>

#include "model/effects/effect.h"

#include "model/common/units.h"
#include "mpdrig.h"
#include "service/rig/wire.h"
#include "tests/support/process.h"
#include "tests/support/sanitizer.h"
#include "tests/support/test_domain.h"

namespace mpdrig::service {
namespace {

// A domain no other test process uses (tests/support/test_domain.h).
dds_domainid_t TestDomain() {
  const int id = testing::ClaimTestDomain();
  EXPECT_GT(id, 0) << "no free DDS domain id for the test";
  return static_cast<dds_domainid_t>(id);
}

// The service on a thread, and a client participant in the same domain.
class ServiceTest : public ::testing::Test {
 protected:
  // rig-1's sensors read with `rig1_sensors` (default: no noise); rig-2's never have noise.
  void Start(double safe_choke_deg = std::nan(""), SensorOptions rig1_sensors = {}) {
    std::vector<RigHost> rigs;
    for (const char* id : {"rig-1", "rig-2"}) {
      // rig-2 runs with a physical effect, which its status reports.
      RigParams params;
      if (std::string(id) == "rig-2") {
        ASSERT_TRUE(ApplyEffectSpec(&params, "sensor_lag:time_constant_s=0.2").ok());
      }
      auto rig = RigHost::Create(id, params, SimulationOptions(), 100.0, {31.0, 5.0, 0.0}, {},
                                 std::string(id) == "rig-1" ? rig1_sensors : SensorOptions{});
      ASSERT_TRUE(rig.ok()) << rig.status().message();
      rigs.push_back(std::move(rig).value());
    }
    ServeOptions options;
    options.clock = ClockMode::kLockstep;
    options.domain = TestDomain();
    options.safe_choke_deg = safe_choke_deg;
    auto service = RigService::Create(std::move(rigs), options);
    ASSERT_TRUE(service.ok()) << service.status().message();
    service_ = std::move(service).value();
    thread_ = std::thread([this] {
      run_status_ = service_->Run(stop_);
      finished_ = true;
    });

    auto participant = dds::CreateParticipant(options.domain);
    ASSERT_TRUE(participant.ok());
    participant_ = std::move(participant).value();
    const dds_entity_t p = participant_.handle();
    auto make_topic = [p](const dds_topic_descriptor_t* d, const char* name) {
      auto t = dds::CreateTopic(p, d, name);
      EXPECT_TRUE(t.ok()) << t.status().message();
      return std::move(t).value();
    };
    sensors_topic_ = make_topic(dds::topics::kSensors.type, dds::topics::kSensors.name);
    status_topic_ = make_topic(dds::topics::kStatus.type, dds::topics::kStatus.name);
    choke_topic_ = make_topic(dds::topics::kChokeCommand.type, dds::topics::kChokeCommand.name);
    piston_topic_ = make_topic(dds::topics::kPistonCommand.type, dds::topics::kPistonCommand.name);
    step_topic_ = make_topic(dds::topics::kStepRequest.type, dds::topics::kStepRequest.name);
    estimate_topic_ = make_topic(dds::topics::kEstimate.type, dds::topics::kEstimate.name);
    profile_topic_ =
        make_topic(dds::topics::kPressureProfile.type, dds::topics::kPressureProfile.name);
    estimates_.emplace(*dds::Reader<mpdrig_RigEstimate>::Create(p, estimate_topic_.handle(),
                                                                dds::SensorQos(true)));
    profiles_.emplace(*dds::Reader<mpdrig_PressureProfile>::Create(p, profile_topic_.handle(),
                                                                   dds::SensorQos(true)));
    sensors_.emplace(
        *dds::Reader<mpdrig_RigSensors>::Create(p, sensors_topic_.handle(), dds::SensorQos(true)));
    status_.emplace(
        *dds::Reader<mpdrig_RigStatus>::Create(p, status_topic_.handle(), dds::StatusQos()));
    choke_.emplace(
        *dds::Writer<mpdrig_ChokeCommand>::Create(p, choke_topic_.handle(), dds::CommandQos()));
    piston_.emplace(
        *dds::Writer<mpdrig_PistonCommand>::Create(p, piston_topic_.handle(), dds::CommandQos()));
    const dds::Qos step_qos = dds::RequestQos();  // as the service reads requests
    step_.emplace(*dds::Writer<mpdrig_StepRequest>::Create(p, step_topic_.handle(), step_qos));
  }

  void TearDown() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    EXPECT_TRUE(run_status_.ok()) << run_status_.message();
  }

  // Waits for commands to reach the service's reader cache, so the next step applies them.
  void Acked(dds_entity_t writer) {
    ASSERT_EQ(dds_wait_for_acks(writer, DDS_SECS(5)), DDS_RETCODE_OK);
  }

  // Sends a step request and waits for the status that completes it; returns that status's
  // rejected-command count and last rejection.
  std::pair<std::uint64_t, std::string> Step(const char* rig_id, std::uint32_t steps) {
    const std::uint64_t id = ++request_id_;
    mpdrig_StepRequest request{const_cast<char*>(rig_id), id, steps};
    EXPECT_TRUE(step_->Write(request).ok());
    std::pair<std::uint64_t, std::string> result{0, ""};
    bool done = false;
    for (int attempt = 0; attempt < 100 && !done; ++attempt) {
      auto ready = status_->Wait(DDS_MSECS(100));
      if (!ready.ok() || !*ready) continue;
      (void)status_->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
        if (std::string(s.rig_id) == rig_id && s.last_completed_step_request == id) {
          done = true;
          result = {s.rejected_commands, s.last_rejection};
          last_warnings_.clear();
          for (std::uint32_t i = 0; i < s.warnings._length; ++i) {
            last_warnings_ += std::string(s.warnings._buffer[i]) + "\n";
          }
          last_owners_.clear();
          for (std::uint32_t i = 0; i < s.actuator_owners._length; ++i) {
            last_owners_ += std::string(s.actuator_owners._buffer[i]) + "\n";
          }
          last_effects_.clear();
          for (std::uint32_t i = 0; i < s.active_effects._length; ++i) {
            last_effects_ += std::string(s.active_effects._buffer[i]) + "\n";
          }
          last_sensor_noise_ = s.sensor_noise;
        }
      });
    }
    EXPECT_TRUE(done) << "step request " << id << " for " << rig_id << " never completed";
    return result;
  }

  // All sensor samples received so far, per rig.
  std::map<std::string, std::vector<RigSample>> TakeSensors(
      std::map<std::string, std::vector<std::uint64_t>>* counters = nullptr) {
    std::map<std::string, std::vector<RigSample>> out;
    (void)sensors_->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
      out[s.rig_id].push_back(FromWire(s, 101325.0));
      if (counters) (*counters)[s.rig_id].push_back(s.sample_counter);
    });
    return out;
  }

  std::unique_ptr<RigService> service_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};  // Run has returned
  Status run_status_ = Status::Ok();
  std::uint64_t request_id_ = 0;
  std::string last_warnings_;
  std::string last_effects_;
  std::string last_sensor_noise_;  // sensor_noise of the last completed step's status
  std::string
      last_owners_;  // actuator_owners of the last completed step's status  // active_effects of
                     // the last completed step's status  // of the last completed step's status
  dds::Entity participant_;
  dds::Entity sensors_topic_, status_topic_, choke_topic_, piston_topic_, step_topic_,
      estimate_topic_, profile_topic_;
  std::optional<dds::Reader<mpdrig_RigEstimate>> estimates_;
  std::optional<dds::Reader<mpdrig_PressureProfile>> profiles_;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors_;
  std::optional<dds::Reader<mpdrig_RigStatus>> status_;
  std::optional<dds::Writer<mpdrig_ChokeCommand>> choke_;
  std::optional<dds::Writer<mpdrig_PistonCommand>> piston_;
  std::optional<dds::Writer<mpdrig_StepRequest>> step_;
};

// Commands and status are transient-local: a subscriber that joins late (a monitor, a second
// controller) receives the command in force and the current status at once.
TEST_F(ServiceTest, LateJoinerReceivesTheCurrentCommandAndStatus) {
  Start();
  char rig_id[] = "rig-1";
  mpdrig_ChokeCommand command{rig_id, 37.5};
  ASSERT_TRUE(choke_->Write(command).ok());
  Acked(choke_->handle());
  Step("rig-1", 1);

  const dds_entity_t p = participant_.handle();
  auto late_commands =
      dds::Reader<mpdrig_ChokeCommand>::Create(p, choke_topic_.handle(), dds::CommandQos(0));
  auto late_status =
      dds::Reader<mpdrig_RigStatus>::Create(p, status_topic_.handle(), dds::StatusQos());
  ASSERT_TRUE(late_commands.ok() && late_status.ok());
  double seen_deg = -1.0;
  for (int attempt = 0; attempt < 50 && seen_deg < 0.0; ++attempt) {
    (void)late_commands->Wait(DDS_MSECS(100));
    (void)late_commands->TakeEach([&](const mpdrig_ChokeCommand& c, const dds_sample_info_t&) {
      if (std::string(c.rig_id) == "rig-1") seen_deg = c.opening_deg;
    });
  }
  EXPECT_EQ(seen_deg, 37.5) << "the late joiner got the command in force";
  bool status_seen = false;
  for (int attempt = 0; attempt < 50 && !status_seen; ++attempt) {
    (void)late_status->Wait(DDS_MSECS(100));
    (void)late_status->TakeEach([&](const mpdrig_RigStatus& st, const dds_sample_info_t&) {
      status_seen |= std::string(st.rig_id) == "rig-1" && st.last_completed_step_request > 0;
    });
  }
  EXPECT_TRUE(status_seen) << "the late joiner got the current status";
}

TEST_F(ServiceTest, StatusReportsTheActiveEffectsPerRig) {
  Start();
  Step("rig-1", 1);
  EXPECT_EQ(last_effects_, "");
  Step("rig-2", 1);
  EXPECT_EQ(last_effects_, "sensor_lag time_constant_s=0.200000\n");
}

// The status names each rig's sensor noise, and the sensors carry it: at rest (the rig starts in
// its steady state) the pressure transmitters scatter by the lab's 0.024 bar on rig-1 and not at
// all on rig-2. Pooled over 14 transmitters x 300 samples, the sample standard deviation spreads
// by 1 / sqrt(2 n) = 1.1 %; 4 of those is the tolerance.
TEST_F(ServiceTest, StatusNamesTheSensorNoiseAndTheSensorsCarryIt) {
  Start(std::nan(""), SensorOptions{SensorNoise::Lab(), 3});
  Step("rig-1", 300);
  EXPECT_EQ(last_sensor_noise_, "lab, seed 3");
  Step("rig-2", 300);
  EXPECT_EQ(last_sensor_noise_, "none");
  auto sensors = TakeSensors();
  ASSERT_EQ(sensors["rig-1"].size(), 300u);
  ASSERT_EQ(sensors["rig-2"].size(), 300u);
  auto pooled_stddev = [](const std::vector<RigSample>& samples) {
    double sum = 0.0;
    std::size_t n = 0;
    for (Channel channel :
         {Channel::kP1, Channel::kP2, Channel::kPT1, Channel::kPT2, Channel::kPT3, Channel::kPT4,
          Channel::kPT5, Channel::kPT6, Channel::kPT7, Channel::kPT8, Channel::kPT9, Channel::kPT10,
          Channel::kC1, Channel::kC2}) {
      double mean = 0.0;
      for (const RigSample& s : samples) mean += s[channel];
      mean /= static_cast<double>(samples.size());
      for (const RigSample& s : samples) sum += (s[channel] - mean) * (s[channel] - mean);
      n += samples.size() - 1;
    }
    return std::sqrt(sum / static_cast<double>(n));
  };
  const double tolerance = 4.0 / std::sqrt(2.0 * 14.0 * 299.0);
  EXPECT_NEAR(pooled_stddev(sensors["rig-1"]), 2400.0, tolerance * 2400.0);
  EXPECT_LT(pooled_stddev(sensors["rig-2"]), 10.0) << "a rig at rest without sensor noise";
  // The choke feedback scatters about the 31 deg the choke holds (its mean to 4 sigma / sqrt(n)).
  double choke_sum = 0.0;
  for (const RigSample& s : sensors["rig-1"]) choke_sum += s[Channel::kChokePosition];
  EXPECT_NEAR(units::ChokeFracToDeg(choke_sum / 300.0), 31.0, 4.0 * 0.1 / std::sqrt(300.0));
}

TEST_F(ServiceTest, LockstepPublishesEveryStepAndClosingTheChokeRaisesC2) {
  Start();
  Step("rig-1", 100);
  std::map<std::string, std::vector<std::uint64_t>> counters;
  auto before = TakeSensors(&counters);
  ASSERT_EQ(before["rig-1"].size(), 100u) << "one sensor sample per step, none lost";
  for (std::size_t i = 0; i < counters["rig-1"].size(); ++i) EXPECT_EQ(counters["rig-1"][i], i);
  EXPECT_EQ(before.count("rig-2"), 0u) << "rig-2 was not stepped";
  const double c2_before = before["rig-1"].back()[Channel::kC2];

  mpdrig_ChokeCommand close{const_cast<char*>("rig-1"), 28.0};
  ASSERT_TRUE(choke_->Write(close).ok());
  Acked(choke_->handle());
  Step("rig-1", 3000);  // 30 s of rig time: several of the 7 s filling time constants
  auto after = TakeSensors();
  ASSERT_EQ(after["rig-1"].size(), 3000u);
  const double c2_after = after["rig-1"].back()[Channel::kC2];
  EXPECT_GT(c2_after - c2_before, 5e5)
      << "closing the choke from 31 to 28 deg must raise C2 by bars";
  EXPECT_NEAR(after["rig-1"].back()[Channel::kChokePosition], 28.0 / 90.0, 1e-6);
}

// A step request cannot be cancelled and a rig's later requests wait behind it: 2^32 - 1 steps
// (49 days of rig time at 100 Hz) ran about 15 h while the rig's own controller failed. Now a
// request for more than an hour of rig time is refused on the status with the reason; one at the
// limit (360 000 steps) starves no other rig, its rig's status moves while it runs, and a stop
// ends the service at once.
TEST_F(ServiceTest, AStepRequestIsBoundedAndALongOneStarvesNoOtherRig) {
  Start();
  mpdrig_StepRequest huge{const_cast<char*>("rig-1"), 1000,
                          std::numeric_limits<std::uint32_t>::max()};
  ASSERT_TRUE(step_->Write(huge).ok());
  Acked(step_->handle());
  const auto [refused, reason] = Step("rig-1", 10);  // served at once: nothing ahead of it
  EXPECT_EQ(refused, 1u);
  EXPECT_NE(reason.find("more than 3600 s of rig time"), std::string::npos) << reason;

  mpdrig_StepRequest longest{const_cast<char*>("rig-1"), 1001, 360000};
  ASSERT_TRUE(step_->Write(longest).ok());
  Acked(step_->handle());
  Step("rig-2", 10);
  Step("rig-2", 10);
  auto samples = TakeSensors();
  EXPECT_EQ(samples["rig-2"].size(), 20u) << "rig-2 served while rig-1's request runs";
  EXPECT_GT(samples["rig-1"].size(), 0u) << "rig-1's request runs too";
  // rig-1's status moves while its request runs (every 0.5 s of wall time).
  double first_s = -1.0, last_s = -1.0;
  for (int attempt = 0; attempt < 30 && !(last_s > first_s && first_s >= 0.0); ++attempt) {
    auto ready = status_->Wait(DDS_MSECS(100));
    if (!ready.ok() || !*ready) continue;
    (void)status_->TakeEach([&](const mpdrig_RigStatus& st, const dds_sample_info_t&) {
      if (std::string(st.rig_id) != "rig-1" || st.last_completed_step_request == 1001) return;
      if (first_s < 0.0) first_s = st.sim_time_s;
      last_s = st.sim_time_s;
    });
  }
  EXPECT_GT(last_s, first_s) << "no status of rig-1 while its long request ran";

  stop_ = true;
  const auto asked = std::chrono::steady_clock::now();
  while (!finished_ && std::chrono::steady_clock::now() - asked < std::chrono::seconds(5)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!finished_) {
    // The service thread cannot be joined: report and end the test process.
    ADD_FAILURE() << "the service did not stop within 5 s of the stop request";
    std::fflush(stdout);
    std::_Exit(1);
  }
}

TEST_F(ServiceTest, PistonSineMakesBottomHolePressureOscillateAtItsFrequency) {
  Start();
  mpdrig_PistonCommand sine{};
  sine.rig_id = const_cast<char*>("rig-1");
  sine.mode = mpdrig_PISTON_SINE;
  sine.amplitude_m = 0.1;
  sine.frequency_hz = 0.2;
  ASSERT_TRUE(piston_->Write(sine).ok());
  Acked(piston_->handle());
  Step("rig-1", 4000);
  auto samples = TakeSensors()["rig-1"];
  ASSERT_EQ(samples.size(), 4000u);
  // Fourier amplitude of PT1 about its mean, after the start-up transient.
  double mean = 0.0;
  for (std::size_t i = 1500; i < samples.size(); ++i) mean += samples[i][Channel::kPT1];
  mean /= static_cast<double>(samples.size() - 1500);
  auto amplitude_at = [&](double f) {
    std::complex<double> sum = 0.0;
    for (std::size_t i = 1500; i < samples.size(); ++i) {
      sum += (samples[i][Channel::kPT1] - mean) *
             std::exp(std::complex<double>(0, -2 * M_PI * f * samples[i].time_s));
    }
    return std::abs(sum);
  };
  const double drive = amplitude_at(0.2);
  for (double f : {0.1, 0.15, 0.25, 0.3, 0.4})
    EXPECT_GT(drive, 5.0 * amplitude_at(f)) << f << " Hz";
}

TEST_F(ServiceTest, BadCommandsAreRefusedCountedReportedAndTheRigRunsOn) {
  Start();
  mpdrig_ChokeCommand nan_choke{const_cast<char*>("rig-1"), std::nan("")};
  ASSERT_TRUE(choke_->Write(nan_choke).ok());
  Acked(choke_->handle());
  auto [rejected, reason] = Step("rig-1", 10);
  EXPECT_EQ(rejected, 1u);
  EXPECT_NE(reason.find("choke opening"), std::string::npos) << reason;

  mpdrig_ChokeCommand unknown{const_cast<char*>("rig-9"), 40.0};
  ASSERT_TRUE(choke_->Write(unknown).ok());
  Acked(choke_->handle());
  std::tie(rejected, reason) = Step("rig-1", 10);
  EXPECT_EQ(rejected, 2u);
  EXPECT_NE(reason.find("unknown rig 'rig-9'"), std::string::npos) << reason;
  auto samples = TakeSensors()["rig-1"];
  ASSERT_EQ(samples.size(), 20u) << "the rig kept running";
  EXPECT_NEAR(samples.back()[Channel::kChokePosition], 31.0 / 90.0, 1e-9)
      << "last valid command in force";
}

// Found by a bad-input probe: a stranger's 10 MB rig id was copied into every rig's last_rejection,
// so each status carried 10 MB. The status now repeats at most 64 bytes of it, and its length.
// (Samples over dds::kServiceMaxSampleSize no longer reach the service at all: the largest id it
// still receives is just under it.)
TEST_F(ServiceTest, AHugeUnknownRigIdIsNotCopiedIntoTheStatus) {
  Start();
  std::string huge(200000, 'x');
  mpdrig_ChokeCommand command{huge.data(), 40.0};
  ASSERT_TRUE(choke_->Write(command).ok());
  Acked(choke_->handle());
  auto [rejected, reason] = Step("rig-1", 1);
  EXPECT_EQ(rejected, 1u);
  EXPECT_LT(reason.size(), 300u);
  EXPECT_NE(reason.find("unknown rig '" + std::string(64, 'x') + "...' (200000 bytes) refused"),
            std::string::npos)
      << reason.substr(0, 300);
}

// A dispose carries only the key, and the topic filters that drop an unknown rig's samples see
// only samples with data: a step request's dispose for a rig the service does not run is refused
// and reported like the command topics' (DisposesOfManyUnknownRigIdsAreRefusedAndReported).
TEST_F(ServiceTest, ADisposedStepRequestOfAnUnknownRigIsRefusedAndReported) {
  Start();
  mpdrig_StepRequest stranger{const_cast<char*>("rig-9"), 1, 10};
  ASSERT_EQ(dds_dispose(step_->handle(), &stranger), DDS_RETCODE_OK);
  auto [rejected, reason] = Step("rig-1", 5);  // the same writer: the dispose arrives first
  EXPECT_EQ(rejected, 1u);
  EXPECT_NE(
      reason.find(std::string(dds::topics::kStepRequest.name) + " for unknown rig 'rig-9' refused"),
      std::string::npos)
      << reason;
  EXPECT_EQ(TakeSensors()["rig-1"].size(), 5u) << "rig-1 stepped as asked, and only rig-1";
}

TEST_F(ServiceTest, StrongestControllerWinsTheNextTakesOverAndNoneLeftMeansSafeState) {
  Start(/*safe_choke_deg=*/90.0);
  const dds_entity_t p = participant_.handle();
  auto weak =
      dds::Writer<mpdrig_ChokeCommand>::Create(p, choke_topic_.handle(), dds::CommandQos(10));
  auto strong =
      dds::Writer<mpdrig_ChokeCommand>::Create(p, choke_topic_.handle(), dds::CommandQos(20));
  ASSERT_TRUE(weak.ok() && strong.ok());
  choke_.reset();  // the fixture's strength-0 writer leaves: only the two controllers remain
  char rig_id[] = "rig-1";
  auto opening_after_steps = [&]() {
    Step("rig-1", 300);  // 3 s: the actuator (rate 90 deg/s, lag 0.1 s) settles
    auto samples = TakeSensors()["rig-1"];
    EXPECT_FALSE(samples.empty());
    return samples.empty() ? -1.0 : 90.0 * samples.back()[Channel::kChokePosition];
  };

  mpdrig_ChokeCommand from_weak{rig_id, 40.0};
  mpdrig_ChokeCommand from_strong{rig_id, 50.0};
  ASSERT_TRUE(weak->Write(from_weak).ok());
  ASSERT_TRUE(strong->Write(from_strong).ok());
  Acked(weak->handle());
  Acked(strong->handle());
  EXPECT_NEAR(opening_after_steps(), 50.0, 0.01) << "the stronger controller wins";
  EXPECT_NE(last_owners_.find("choke: strength 20, writer "), std::string::npos) << last_owners_;

  // The strong controller goes; the weak one's next command is in force.
  dds::Writer<mpdrig_ChokeCommand> gone = std::move(strong).value();
  { auto leaving = std::move(gone); }
  from_weak.opening_deg = 45.0;
  ASSERT_TRUE(weak->Write(from_weak).ok());
  Acked(weak->handle());
  EXPECT_NEAR(opening_after_steps(), 45.0, 0.01) << "the next controller takes over";
  EXPECT_NE(last_owners_.find("choke: strength 10, writer "), std::string::npos) << last_owners_;

  // The last controller goes: the safe state (choke fully open), and the status says so.
  { auto leaving = std::move(weak).value(); }
  dds_sleepfor(DDS_MSECS(200));  // the writer's disappearance reaches the service's reader
  EXPECT_NEAR(opening_after_steps(), 90.0, 0.01) << "safe state: choke open";
  EXPECT_NE(last_warnings_.find("no choke controller left"), std::string::npos) << last_warnings_;
  EXPECT_NE(last_owners_.find("choke: none"), std::string::npos) << last_owners_;
}

// What the estimate topic carried for one rig, copied out of DDS's loan.
struct EstimateRow {
  std::uint64_t counter;
  double sim_time_s, observer_time_s, bhp_barg, velocity_mps, frequency_hz;
  mpdrig_FrequencySource source;
};

std::vector<EstimateRow> TakeEstimates(const dds::Reader<mpdrig_RigEstimate>& reader,
                                       const char* rig_id) {
  std::vector<EstimateRow> out;
  (void)reader.TakeEach([&](const mpdrig_RigEstimate& e, const dds_sample_info_t&) {
    if (std::string(e.rig_id) != rig_id) return;
    out.push_back({e.sample_counter, e.sim_time_s, e.observer_time_s, e.BHP_est_barg,
                   e.piston_velocity_est_mps, e.disturbance_frequency_hz, e.frequency_source});
  });
  return out;
}

TEST_F(ServiceTest, ObserverEstimatesBottomHolePressureAndHeaveFromTopsideChannels) {
  Start();
  // The lab's heave, 0.1 m at 0.2 Hz (thesis 10.3), commanded as a sine: the observer uses
  // its frequency.
  mpdrig_PistonCommand sine{};
  sine.rig_id = const_cast<char*>("rig-1");
  sine.mode = mpdrig_PISTON_SINE;
  sine.amplitude_m = 0.1;
  sine.frequency_hz = 0.2;
  ASSERT_TRUE(piston_->Write(sine).ok());
  Acked(piston_->handle());
  Step("rig-1", 3000);  // 30 s, six periods
  std::map<std::string, std::vector<std::uint64_t>> counters;
  const std::vector<RigSample> sensors = TakeSensors(&counters)["rig-1"];
  const std::vector<EstimateRow> estimates = TakeEstimates(*estimates_, "rig-1");
  ASSERT_EQ(sensors.size(), 3000u);
  ASSERT_EQ(estimates.size(), 3000u) << "one estimate per sensor sample (default rate)";

  double bhp_lo = 1e300, bhp_hi = -1e300, max_bhp_error = 0.0, max_velocity_error = 0.0;
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const EstimateRow& e = estimates[i];
    ASSERT_EQ(e.counter, counters["rig-1"][i]);
    ASSERT_DOUBLE_EQ(e.sim_time_s, sensors[i].time_s);
    // The observer steps on its own 5.3 ms grid and never runs ahead of the sample.
    EXPECT_LE(e.observer_time_s, e.sim_time_s + 1e-9);
    EXPECT_GT(e.observer_time_s, e.sim_time_s - 0.0054);
    EXPECT_EQ(e.source, mpdrig_FREQUENCY_PISTON_SINE);
    EXPECT_DOUBLE_EQ(e.frequency_hz, 0.2);
    if (sensors[i].time_s < 15.0) continue;  // three periods: the observer's transient
    const double pt1_barg = units::PaAbsToBarg(sensors[i][Channel::kPT1], 101325.0);
    bhp_lo = std::min(bhp_lo, pt1_barg);
    bhp_hi = std::max(bhp_hi, pt1_barg);
    max_bhp_error = std::max(max_bhp_error, std::fabs(e.bhp_barg - pt1_barg));
    // The commanded heave's velocity at the observer's time.
    const double v = 0.1 * 2 * M_PI * 0.2 * std::cos(2 * M_PI * 0.2 * e.observer_time_s);
    max_velocity_error = std::max(max_velocity_error, std::fabs(e.velocity_mps - v));
  }
  const double swing = bhp_hi - bhp_lo;
  std::printf(
      "estimate vs PT1 after 15 s: max |error| %.4f bar = %.2f %% of the %.3f bar swing; "
      "max heave velocity error %.2f %% of its amplitude\n",
      max_bhp_error, 100 * max_bhp_error / swing, swing,
      100 * max_velocity_error / (0.1 * 2 * M_PI * 0.2));
  ASSERT_GT(swing, 0.5) << "the heave must move the bottom-hole pressure by about a bar";
  // Thesis 10.3's target, 2 % of the BHP swing. The estimate lags the sample by up to one
  // observer step (5.3 ms, about 0.7 % of the swing at 0.2 Hz); the observer itself is within
  // 0.1 % (docs/service.md, "Observer beside each rig").
  EXPECT_LT(max_bhp_error, 0.02 * swing) << "swing " << swing << " bar";
  // Heave velocity amplitude 0.126 m/s; 5 % of it.
  EXPECT_LT(max_velocity_error, 0.05 * 0.1 * 2 * M_PI * 0.2);
}

TEST_F(ServiceTest, ObserverTracksTheHeaveFrequencyWhenItIsNotACommandedSine) {
  Start();
  // A "sweep" from 0.15 to 0.15 Hz: a sine the rig does not announce as one.
  mpdrig_PistonCommand sweep{};
  sweep.rig_id = const_cast<char*>("rig-1");
  sweep.mode = mpdrig_PISTON_SWEEP;
  sweep.amplitude_m = 0.1;
  sweep.frequency_hz = 0.15;
  sweep.sweep_end_hz = 0.15;
  sweep.sweep_duration_s = 1.0;
  ASSERT_TRUE(piston_->Write(sweep).ok());
  Acked(piston_->handle());
  Step("rig-1", 6000);  // 60 s, nine periods
  const std::vector<EstimateRow> estimates = TakeEstimates(*estimates_, "rig-1");
  ASSERT_EQ(estimates.size(), 6000u);
  EXPECT_EQ(estimates.front().source, mpdrig_FREQUENCY_UNLOCKED);
  EXPECT_DOUBLE_EQ(estimates.front().frequency_hz, 0.2) << "the starting guess";
  EXPECT_EQ(estimates.back().source, mpdrig_FREQUENCY_TRACKED);
  // The tracker averages three zero-crossing periods; the retune threshold is 0.5 %.
  EXPECT_NEAR(estimates.back().frequency_hz, 0.15, 0.01 * 0.15);
}

TEST_F(ServiceTest, PressureProfileAlongThePipeAtTenHertzMatchesTheTransmitters) {
  Start();
  Step("rig-1", 100);  // 1 s at 100 Hz: profiles at samples 0, 10, ..., 90
  std::map<std::string, std::vector<std::uint64_t>> counters;
  const std::vector<RigSample> sensors = TakeSensors(&counters)["rig-1"];
  ASSERT_EQ(sensors.size(), 100u);
  std::vector<std::uint64_t> profile_counters;
  (void)profiles_->TakeEach([&](const mpdrig_PressureProfile& p, const dds_sample_info_t&) {
    ASSERT_EQ(p.position_m._length, 19u);
    ASSERT_EQ(p.pressure_barg._length, 19u);
    ASSERT_EQ(p.pressure_est_barg._length, 19u);
    EXPECT_DOUBLE_EQ(p.position_m._buffer[0], 0.0);
    EXPECT_DOUBLE_EQ(p.position_m._buffer[18], 900.0);
    const RigSample& s = sensors.at(p.sample_counter);
    EXPECT_DOUBLE_EQ(p.sim_time_s, s.time_s);
    // Both ends are transmitters: PT1 = p(0) and PT10 = p(900 m), the same interpolation.
    EXPECT_NEAR(p.pressure_barg._buffer[0], units::PaAbsToBarg(s[Channel::kPT1], 101325.0), 1e-9);
    EXPECT_NEAR(p.pressure_barg._buffer[18], units::PaAbsToBarg(s[Channel::kPT10], 101325.0), 1e-9);
    // Hydrostatics at rest: the pressure falls towards the choke by rho g 2.3 m = 0.23 bar; the
    // observer starts at rest from C2, so its profile agrees to well below that.
    EXPECT_GT(p.pressure_barg._buffer[0] - p.pressure_barg._buffer[18], 0.2);
    for (std::uint32_t k = 0; k < 19; ++k) {
      EXPECT_NEAR(p.pressure_est_barg._buffer[k], p.pressure_barg._buffer[k], 0.01) << k;
    }
    profile_counters.push_back(p.sample_counter);
  });
  EXPECT_EQ(profile_counters, (std::vector<std::uint64_t>{0, 10, 20, 30, 40, 50, 60, 70, 80, 90}));
}

// Found by a fault probe: a stall of the real-time clock used to count as one deadline miss,
// whatever its length. A real `mpdrig serve` process is stopped (SIGSTOP) for 1.5 s at 100 Hz: its
// status must report about 150 lost periods, a longest stall of about 1.5 s, the rig time when it
// fell behind and a warning that says so; SIGTERM then stops it cleanly.
TEST(ServiceProcessTest, StatusReportsLostPeriodsAndTheLongestStallOfTheRealTimeClock) {
  const dds_domainid_t domain = TestDomain();
  const std::string log_path =
      ::testing::TempDir() + "/serve_stall." + std::to_string(::getpid()) + ".txt";
  std::vector<std::string> args = {
      MPDRIG_EXE,     "serve", "--clock", "realtime", "--rate-hz",
      "100",          "--rig", "rig-1",   "--domain", std::to_string(domain),
      "--no-observer"};
  testing::ChildProcess serve(args, testing::ChildOptions::Stderr(testing::Output::File(log_path)));
  ASSERT_TRUE(serve.started()) << serve.error();

  auto dds_domain = dds::Domain::Create(domain, dds::LoopbackConfig());  // as the service's
  ASSERT_TRUE(dds_domain.ok()) << dds_domain.status().message();
  auto participant = dds::CreateParticipant(domain);
  ASSERT_TRUE(participant.ok());
  auto topic =
      dds::CreateTopic(participant->handle(), dds::topics::kStatus.type, dds::topics::kStatus.name);
  ASSERT_TRUE(topic.ok());
  auto status = dds::Reader<mpdrig_RigStatus>::Create(participant->handle(), topic->handle(),
                                                      dds::StatusQos());
  ASSERT_TRUE(status.ok());
  struct Seen {
    double sim_time_s = 0.0;
    std::uint64_t lost_periods = 0;
    double longest_stall_s = 0.0;
    double last_stall_sim_time_s = -1.0;
    std::string warnings;
  } seen;
  // Waits for a status that satisfies `done` (up to 20 s).
  auto wait_for = [&](const std::function<bool(const Seen&)>& done) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < until) {
      auto ready = status->Wait(DDS_MSECS(100));
      if (!ready.ok() || !*ready) continue;
      bool matched = false;
      (void)status->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
        seen = {s.sim_time_s, s.lost_periods, s.longest_stall_s, s.last_stall_sim_time_s, ""};
        for (std::uint32_t i = 0; i < s.warnings._length; ++i) {
          seen.warnings += std::string(s.warnings._buffer[i]) + "\n";
        }
        matched = matched || done(seen);
      });
      if (matched) return true;
    }
    return false;
  };
  ASSERT_TRUE(wait_for([](const Seen& s) { return s.sim_time_s >= 1.0; }))
      << "the service never ran 1 s of rig time";
  // A loaded machine (a sanitizer build beside two other tests) may already have stalled the
  // service for a period or two here; the 1.5 s stop is counted on top of those (the counting rule
  // itself: pacer_test, on a clock the test moves).
  const std::uint64_t lost_before = seen.lost_periods;
  std::printf("periods lost before the stop: %llu\n", static_cast<unsigned long long>(lost_before));
  EXPECT_LT(lost_before, 50u) << "the service kept real time before it was stopped";
  const double stopped_at_s = seen.sim_time_s;

  ASSERT_TRUE(serve.Signal(SIGSTOP));
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  ASSERT_TRUE(serve.Signal(SIGCONT));
  ASSERT_TRUE(wait_for([&](const Seen& s) { return s.lost_periods >= lost_before + 100; }))
      << "no status reported the stall; last: " << seen.warnings;
  EXPECT_GE(seen.lost_periods - lost_before, 120u) << "1.5 s at 100 Hz";
  EXPECT_LE(seen.lost_periods - lost_before, 400u);
  EXPECT_GE(seen.longest_stall_s, 1.2);
  EXPECT_LE(seen.longest_stall_s, 4.0);
  EXPECT_GE(seen.last_stall_sim_time_s, stopped_at_s);
  EXPECT_NE(seen.warnings.find("fell behind real time at rig time"), std::string::npos)
      << seen.warnings;

  ASSERT_TRUE(serve.Signal(SIGTERM));
  EXPECT_EQ(serve.Wait(), 0);
  std::ifstream log(log_path);
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("periods lost, longest stall"), std::string::npos) << text;
}

}  // namespace
}  // namespace mpdrig::service

namespace mpdrig::service {
namespace {

// VmRSS of process `pid` [bytes], from /proc; 0 if unreadable.
std::uint64_t ResidentBytes(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return 1024ull * std::stoull(line.substr(6));
  }
  return 0;
}

// A stranger sends commands for many distinct rig ids the service does not run, while rig-1's
// own controller is connected. Each id used to cost the service an instance (about 560 B,
// measured: 100 000 ids took its RSS from 16 to 72 MB) for as long as the stranger's writer
// lived, and all of them lost their writer in one tick when it went (a 325 ms stall at 1 kHz).
// Written commands: a topic filter drops them before they become instances, so the service's
// memory does not grow with them. Disposes (key-only messages, which filters do not see) still
// make instances (rig_service.cc says why they are not bounded), but each is refused and
// reported. Either way rig-1's controller still commands its rig.
enum class Stranger { kWrites, kDisposes };

void ExpectAFloodOfUnknownRigIdsIsRefused(Stranger stranger) {
  // Only the written flood asserts on memory; the disposed one asserts on the refusals and the
  // controller, which hold under the sanitizer too.
  if (stranger == Stranger::kWrites && testing::kUnderAddressSanitizer) {
    GTEST_SKIP()
        << "RSS under AddressSanitizer measures its quarantine (tests/support/sanitizer.h)";
  }
  const dds_domainid_t domain = TestDomain();
  std::vector<std::string> args = {
      MPDRIG_EXE,     "serve", "--clock", "realtime", "--rate-hz",
      "100",          "--rig", "rig-1",   "--domain", std::to_string(domain),
      "--no-observer"};
  testing::ChildProcess serve(args, testing::ChildOptions::Stderr(testing::Output::Discard()));
  ASSERT_TRUE(serve.started()) << serve.error();

  auto dds_domain = dds::Domain::Create(domain, dds::LoopbackConfig());
  ASSERT_TRUE(dds_domain.ok()) << dds_domain.status().message();
  auto participant = dds::CreateParticipant(domain);
  ASSERT_TRUE(participant.ok());
  const dds_entity_t p = participant->handle();
  auto status_topic = dds::CreateTopic(p, dds::topics::kStatus.type, dds::topics::kStatus.name);
  auto sensors_topic = dds::CreateTopic(p, dds::topics::kSensors.type, dds::topics::kSensors.name);
  auto pump_topic =
      dds::CreateTopic(p, dds::topics::kPumpCommand.type, dds::topics::kPumpCommand.name);
  ASSERT_TRUE(status_topic.ok() && sensors_topic.ok() && pump_topic.ok());
  auto status = dds::Reader<mpdrig_RigStatus>::Create(p, status_topic->handle(), dds::StatusQos());
  auto sensors =
      dds::Reader<mpdrig_RigSensors>::Create(p, sensors_topic->handle(), dds::SensorQos(false));
  auto controller =
      dds::Writer<mpdrig_PumpCommand>::Create(p, pump_topic->handle(), dds::CommandQos());
  auto flood = dds::Writer<mpdrig_PumpCommand>::Create(p, pump_topic->handle(), dds::CommandQos());
  ASSERT_TRUE(status.ok() && sensors.ok() && controller.ok() && flood.ok());
  std::uint64_t rejected = 0;
  std::string last_rejection;
  auto wait_for_rejected = [&](std::uint64_t at_least) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < until && rejected < at_least) {
      auto ready = status->Wait(DDS_MSECS(100));
      if (!ready.ok() || !*ready) continue;
      (void)status->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
        rejected = s.rejected_commands;
        last_rejection = s.last_rejection;
      });
    }
    return rejected >= at_least;
  };
  // The pump flow rig-1 delivers, as its FT2 reads it (lab noise: 2 % of reading) [L/min].
  auto measured_pump_lpm = [&](double expected) {
    double ft2 = std::numeric_limits<double>::quiet_NaN();
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < until &&
           !(std::abs(ft2 - expected) < 0.05 * expected)) {
      (void)sensors->Wait(DDS_MSECS(100));
      (void)sensors->TakeEach(
          [&](const mpdrig_RigSensors& s, const dds_sample_info_t&) { ft2 = s.FT2_lpm; });
    }
    return ft2;
  };
  for (int waited_ms = 0;; waited_ms += 10) {  // the service's pump reader is there
    dds_publication_matched_status_t matched{};
    dds_get_publication_matched_status(flood->handle(), &matched);
    if (matched.current_count > 0) break;
    ASSERT_LT(waited_ms, 20000) << "the service never matched the pump writer";
    dds_sleepfor(DDS_MSECS(10));
  }
  mpdrig_PumpCommand own{const_cast<char*>("rig-1"), 3.0};
  ASSERT_TRUE(controller->Write(own).ok());
  EXPECT_NEAR(measured_pump_lpm(3.0), 3.0, 0.15) << "rig-1's controller commands its pump";
  dds_sleepfor(DDS_SECS(1));  // the service settles (its buffers, the first statuses)
  const std::uint64_t rss_before = ResidentBytes(serve.pid());
  ASSERT_GT(rss_before, 0u);

  constexpr int kIds = 40000;
  std::string id;
  for (int i = 0; i < kIds; ++i) {
    id = "stranger-" + std::to_string(i);
    mpdrig_PumpCommand command{id.data(), 5.0};
    if (stranger == Stranger::kWrites) {
      ASSERT_TRUE(flood->Write(command).ok());
    } else {
      ASSERT_EQ(dds_dispose(flood->handle(), &command), DDS_RETCODE_OK);
    }
  }
  ASSERT_EQ(dds_wait_for_acks(flood->handle(), DDS_SECS(60)), DDS_RETCODE_OK);
  ASSERT_TRUE(wait_for_rejected(kIds)) << "refused so far: " << rejected;
  EXPECT_EQ(rejected, static_cast<std::uint64_t>(kIds)) << "each unknown id counted once";
  EXPECT_NE(last_rejection.find("unknown rig 'stranger-"), std::string::npos) << last_rejection;
  const std::uint64_t rss_held = ResidentBytes(serve.pid());
  const double grown_mb = (static_cast<double>(rss_held) - static_cast<double>(rss_before)) / 1e6;
  std::printf("service RSS %.1f MB before, %.1f MB with %d unknown ids %s (+%.1f MB)\n",
              rss_before / 1e6, rss_held / 1e6, kIds,
              stranger == Stranger::kWrites ? "written" : "disposed", grown_mb);
  if (stranger == Stranger::kWrites) {
    // Without the filter: about 560 B per id, 22 MB for 40 000. Allow 4 MB of the service's own
    // growth (DDS receive buffers, the allocator's arenas), far below what the ids would cost.
    EXPECT_LT(grown_mb, 4.0);
  }
  own.flow_lpm = 7.0;
  ASSERT_TRUE(controller->Write(own).ok());
  EXPECT_NEAR(measured_pump_lpm(7.0), 7.0, 0.35) << "rig-1's controller still commands its pump";
}

TEST(ServiceProcessTest, CommandsForManyUnknownRigIdsAreRefusedWithoutHoldingMemory) {
  ExpectAFloodOfUnknownRigIdsIsRefused(Stranger::kWrites);
}

TEST(ServiceProcessTest, DisposesOfManyUnknownRigIdsAreRefusedAndReported) {
  ExpectAFloodOfUnknownRigIdsIsRefused(Stranger::kDisposes);
}

// A rig id is the key of every topic: 1 to kMaxRigIdBytes bytes of printable ASCII without
// spaces. The service refuses to serve another (and so refuses any longer id it receives after
// kMaxRigIdBytes + 1 bytes, UnknownRigGate), naming the id and the rule.
TEST(RigIdTest, ServiceServesOnlyShortPrintableIds) {
  EXPECT_TRUE(CheckRigId("rig-1").ok());
  EXPECT_TRUE(CheckRigId("alice.12").ok());
  EXPECT_TRUE(CheckRigId(std::string(kMaxRigIdBytes, 'r')).ok());
  for (const std::string& bad :
       {std::string(), std::string(kMaxRigIdBytes + 1, 'r'), std::string("rig 1"),
        std::string("rig\n1"), std::string("rig\xff")}) {
    const Status checked = CheckRigId(bad);
    ASSERT_FALSE(checked.ok()) << bad;
    EXPECT_NE(checked.message().find(std::to_string(bad.size()) + " bytes): a rig id is 1 to 128"),
              std::string::npos)
        << checked.message();
  }
  std::vector<RigHost> rigs;
  auto rig = RigHost::Create("rig one", RigParams{}, SimulationOptions(), 100.0, {31.0, 5.0, 0.0});
  ASSERT_TRUE(rig.ok()) << rig.status().message();
  rigs.push_back(std::move(rig).value());
  ServeOptions options;
  options.domain = TestDomain();
  auto service = RigService::Create(std::move(rigs), options);
  ASSERT_FALSE(service.ok());
  EXPECT_NE(service.status().message().find("rig id 'rig one' (7 bytes)"), std::string::npos)
      << service.status().message();
}

// Found by a bad-input probe: ten commands with 10 MB rig ids cost a 1 kHz service 1300 lost
// periods, a 0.21 s stall and 55 MB of memory (bench/unknown_id_flood.sh with ID_BYTES): Cyclone
// received, reassembled and copied each in full before the topic filter could refuse it. The
// service now takes no sample over dds::kServiceMaxSampleSize (Cyclone drops it at its first
// fragment), and an id over kMaxRigIdBytes below that is refused after reading kMaxRigIdBytes + 1
// bytes of it, counted and reported as any unknown rig.
TEST(ServiceProcessTest, HugeRigIdsAreDroppedBeforeTheServiceHoldsThem) {
  if (testing::kUnderAddressSanitizer) {
    GTEST_SKIP() << "RSS under AddressSanitizer measures its quarantine";
  }
  const dds_domainid_t domain = TestDomain();
  testing::ChildProcess serve(
      {MPDRIG_EXE, "serve", "--clock", "realtime", "--rate-hz", "100", "--rig", "rig-1", "--domain",
       std::to_string(domain), "--no-observer"},
      testing::ChildOptions::Stderr(testing::Output::Discard()));
  ASSERT_TRUE(serve.started()) << serve.error();
  // The stranger's side has no limit of its own: it sends what it likes.
  auto dds_domain = dds::Domain::Create(domain, dds::LoopbackConfig());
  ASSERT_TRUE(dds_domain.ok()) << dds_domain.status().message();
  auto participant = dds::CreateParticipant(domain);
  ASSERT_TRUE(participant.ok());
  const dds_entity_t p = participant->handle();
  auto status_topic = dds::CreateTopic(p, dds::topics::kStatus.type, dds::topics::kStatus.name);
  auto pump_topic =
      dds::CreateTopic(p, dds::topics::kPumpCommand.type, dds::topics::kPumpCommand.name);
  ASSERT_TRUE(status_topic.ok() && pump_topic.ok());
  auto status = dds::Reader<mpdrig_RigStatus>::Create(p, status_topic->handle(), dds::StatusQos());
  auto flood = dds::Writer<mpdrig_PumpCommand>::Create(p, pump_topic->handle(), dds::CommandQos());
  ASSERT_TRUE(status.ok() && flood.ok());
  for (int waited_ms = 0;; waited_ms += 10) {
    dds_publication_matched_status_t matched{};
    dds_get_publication_matched_status(flood->handle(), &matched);
    if (matched.current_count > 0) break;
    ASSERT_LT(waited_ms, 20000) << "the service never matched the pump writer";
    dds_sleepfor(DDS_MSECS(10));
  }
  dds_sleepfor(DDS_SECS(1));  // the service settles (its buffers, the first statuses)
  const std::uint64_t rss_before = ResidentBytes(serve.pid());
  ASSERT_GT(rss_before, 0u);

  constexpr int kHugeIds = 10;
  constexpr std::size_t kHugeBytes = 10'000'000;
  std::string id;
  for (int i = 0; i < kHugeIds; ++i) {
    id = "stranger-" + std::to_string(i);
    id.resize(kHugeBytes, 'x');
    mpdrig_PumpCommand command{id.data(), 5.0};
    ASSERT_TRUE(flood->Write(command).ok());
  }
  ASSERT_EQ(dds_wait_for_acks(flood->handle(), DDS_SECS(60)), DDS_RETCODE_OK);
  // Then one over kMaxRigIdBytes that Cyclone lets through: the filter refuses and counts it.
  const std::string long_id(1000, 'y');
  mpdrig_PumpCommand command{const_cast<char*>(long_id.c_str()), 5.0};
  ASSERT_TRUE(flood->Write(command).ok());
  ASSERT_EQ(dds_wait_for_acks(flood->handle(), DDS_SECS(10)), DDS_RETCODE_OK);
  std::uint64_t rejected = 0;
  std::string last_rejection;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < until &&
         last_rejection.find("yyy") == std::string::npos) {
    auto ready = status->Wait(DDS_MSECS(100));
    if (!ready.ok() || !*ready) continue;
    (void)status->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
      rejected = s.rejected_commands;
      last_rejection = s.last_rejection;
    });
  }
  EXPECT_NE(last_rejection.find("unknown rig '" + std::string(64, 'y') + "...' (1000 bytes)"),
            std::string::npos)
      << last_rejection.substr(0, 300);
  // The huge ones never reached the service's readers: only the last command was refused.
  EXPECT_EQ(rejected, 1u) << last_rejection.substr(0, 300);
  const double grown_mb =
      (static_cast<double>(ResidentBytes(serve.pid())) - static_cast<double>(rss_before)) / 1e6;
  std::printf("service RSS %.1f MB before, +%.1f MB after %d ids of %zu bytes\n", rss_before / 1e6,
              grown_mb, kHugeIds, kHugeBytes);
  // Received in full they took 55 MB (measured); allow 8 MB of the service's own growth.
  EXPECT_LT(grown_mb, 8.0);
}

}  // namespace
}  // namespace mpdrig::service
