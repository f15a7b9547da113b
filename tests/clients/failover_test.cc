// Controllers in other processes that crash: SIGKILL, no clean unregister. The service (here on a
// thread, real-time clock) must hand the choke to the next-strongest live controller, and with
// none left take the safe state, each within one liveliness lease (dds::kCommandLivelinessLease,
// 1 s) plus a margin. Loopback only, a domain of the test's own.
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "mpdrig.h"
#include "service/dds/topics.h"
#include "service/rig/rig_service.h"
#include "service/rig/wire.h"
#include "tests/support/process.h"
#include "tests/support/test_domain.h"

namespace mpdrig::service {
namespace {

using Clock = std::chrono::steady_clock;

// A choke_writer process (stopped when this goes).
testing::ChildProcess ChokeWriter(int domain, int strength, double opening_deg) {
  return testing::ChildProcess({CHOKE_WRITER_EXE, std::to_string(domain), "rig-1",
                                std::to_string(strength), std::to_string(opening_deg)});
}

class Failover : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = testing::ClaimTestDomain();
    ASSERT_GT(domain_, 0);
    auto rig = RigHost::Create("rig-1", RigParams(), SimulationOptions(), 100.0, {31.0, 5.0, 0.0});
    ASSERT_TRUE(rig.ok()) << rig.status().message();
    std::vector<RigHost> rigs;
    rigs.push_back(std::move(rig).value());
    ServeOptions options;
    options.clock = ClockMode::kRealtime;
    options.domain = static_cast<dds_domainid_t>(domain_);
    options.safe_choke_deg = 90.0;
    options.observer = false;  // not what this test is about
    options.status_period_s = 0.1;
    auto service = RigService::Create(std::move(rigs), options);
    ASSERT_TRUE(service.ok()) << service.status().message();
    service_ = std::move(service).value();
    thread_ = std::thread([this] { run_ = service_->Run(stop_); });

    auto participant = dds::CreateParticipant(options.domain);
    ASSERT_TRUE(participant.ok());
    participant_ = std::move(participant).value();
    auto sensors_topic = dds::CreateTopic(participant_.handle(), dds::topics::kSensors.type,
                                          dds::topics::kSensors.name);
    auto status_topic = dds::CreateTopic(participant_.handle(), dds::topics::kStatus.type,
                                         dds::topics::kStatus.name);
    ASSERT_TRUE(sensors_topic.ok() && status_topic.ok());
    sensors_.emplace(*dds::Reader<mpdrig_RigSensors>::Create(
        participant_.handle(), sensors_topic->handle(), dds::SensorQos()));
    status_.emplace(*dds::Reader<mpdrig_RigStatus>::Create(
        participant_.handle(), status_topic->handle(), dds::StatusQos()));
  }

  void TearDown() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    EXPECT_TRUE(run_.ok()) << run_.message();
  }

  // Seconds until the measured choke opening satisfies `reached` (-1 after `timeout_s`).
  double SecondsUntil(const std::function<bool(double)>& reached, double timeout_s) {
    const Clock::time_point start = Clock::now();
    for (;;) {
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      if (elapsed > timeout_s) return -1.0;
      (void)sensors_->Wait(DDS_MSECS(20));
      bool done = false;
      (void)sensors_->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
        if (reached(s.choke_position_deg)) done = true;
      });
      if (done) return std::chrono::duration<double>(Clock::now() - start).count();
    }
  }

  std::string Warnings() {
    std::string out;
    (void)status_->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
      out.clear();
      for (std::uint32_t i = 0; i < s.warnings._length; ++i) out += s.warnings._buffer[i];
    });
    return out;
  }

  int domain_ = -1;
  std::unique_ptr<RigService> service_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  Status run_ = Status::Ok();
  dds::Entity participant_;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors_;
  std::optional<dds::Reader<mpdrig_RigStatus>> status_;
};

TEST_F(Failover, CrashedControllerIsReplacedByTheNextAndNoneLeftMeansSafeStateWithinTheLease) {
  testing::ChildProcess weak = ChokeWriter(domain_, 10, 40.0);
  testing::ChildProcess strong = ChokeWriter(domain_, 20, 50.0);
  ASSERT_TRUE(weak.started() && strong.started());
  // Discovery across processes, then the actuator (lag 0.1 s, 90 deg/s) moves from 31 deg.
  ASSERT_GE(SecondsUntil([](double deg) { return std::fabs(deg - 50.0) < 0.05; }, 20.0), 0.0)
      << "the strongest controller never took the choke";

  // Budget: the lease, plus the actuator's way to the midpoint (a 5 deg step: about 0.1 s of lag),
  // plus scheduling on a loaded 2-core machine (0.9 s).
  const double lease_s = 1e-9 * static_cast<double>(dds::kCommandLivelinessLease);
  const double budget_s = lease_s + 1.0;
  strong.Kill();
  const double takeover_s = SecondsUntil([](double deg) { return deg < 45.0; }, 10.0);
  EXPECT_GE(takeover_s, 0.0) << "the weaker controller never took over";
  EXPECT_LT(takeover_s, budget_s);
  EXPECT_GE(SecondsUntil([](double deg) { return std::fabs(deg - 40.0) < 0.05; }, 5.0), 0.0);

  // The last controller crashes: the safe state (choke to 90 deg). Midpoint 65 deg: 25 deg at
  // 90 deg/s after the lag, about 0.4 s.
  weak.Kill();
  const double safe_s = SecondsUntil([](double deg) { return deg > 65.0; }, 10.0);
  EXPECT_GE(safe_s, 0.0) << "no safe state after the last controller crashed";
  EXPECT_LT(safe_s, budget_s + 0.3);
  std::printf("after SIGKILL: next controller in %.3f s, safe state in %.3f s (lease %.1f s)\n",
              takeover_s, safe_s, lease_s);
  dds_sleepfor(DDS_MSECS(300));  // a status period
  EXPECT_NE(Warnings().find("no choke controller left"), std::string::npos);
}

}  // namespace
}  // namespace mpdrig::service
