// The dashboard's DDS side (clients/dashboard/rig_feed.h) in one process over loopback: it has no
// reader (so a rig's writer has nobody to send to) until a browser asks and again soon after the
// last request; it shows a rig's newest sample with a channel the rig does not measure as null;
// it gives the history only once per sequence number; and its shadow commands reach the wire
// with their action and argument, while a bad one is refused with a reason.
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "clients/dashboard/api_json.h"
#include "clients/dashboard/json_out.h"
#include "clients/dashboard/rig_feed.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"
#include "tests/support/test_domain.h"

namespace mpdrig::dashboard {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

// Polls `done` every 50 ms (calling `each` first) until it holds or `timeout_s` passes.
template <typename Done, typename Each>
bool Eventually(double timeout_s, Done done, Each each) {
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < end) {
    each();
    if (done()) return true;
    std::this_thread::sleep_for(milliseconds(50));
  }
  return false;
}

TEST(DashboardJson, NanIsNullAndStringsAreEscaped) {
  EXPECT_EQ(JsonText(JsonNumbers({1.5, std::numeric_limits<double>::quiet_NaN(), -2e-9,
                                  std::numeric_limits<double>::infinity()})),
            "[1.5,null,-2e-09,null]");
  EXPECT_EQ(JsonText("refused: \"x\"\\\n\x01"), "\"refused: \\\"x\\\"\\\\\\n\\u0001\"");
  // 7 significant digits; counters are integers and exact.
  EXPECT_EQ(JsonText(JsonNumbers({13.0, 1.23456789, 1234567.89})), "[13,1.234568,1234568]");
  EXPECT_EQ(JsonText(Json(std::uint64_t{12345678901234567})), "12345678901234567");
}

class RigFeedTest : public ::testing::Test {
 protected:
  void SetUp() override {
    domain_ = testing::ClaimTestDomain();
    ASSERT_GT(domain_, 0);
    FeedOptions options;
    options.domain = domain_;  // loopback only (the default configuration)
    options.idle_s = 0.6;
    options.frame_hz = 20.0;
    auto feed = RigFeed::Create(options);
    ASSERT_TRUE(feed.ok()) << feed.status().message();
    feed_ = std::move(feed).value();
    // The rig's side: a participant of its own on the domain the feed configured.
    auto participant = dds::CreateParticipant(domain_);
    ASSERT_TRUE(participant.ok()) << participant.status().message();
    participant_ = std::move(participant).value();
  }

  dds_entity_t Topic(const dds_topic_descriptor_t* descriptor, const char* name) {
    auto topic = dds::CreateTopic(participant_.handle(), descriptor, name);
    EXPECT_TRUE(topic.ok()) << topic.status().message();
    topics_.push_back(std::move(topic).value());
    return topics_.back().handle();
  }

  int domain_ = -1;
  std::unique_ptr<RigFeed> feed_;
  dds::Entity participant_;
  std::vector<dds::Entity> topics_;
};

// A rig id from a URL (`/api/state?rig=%ff`) is not UTF-8: it must not make the JSON invalid.
// Well-formed UTF-8 passes as it is; each stray, overlong or surrogate byte sequence is U+FFFD.
TEST(DashboardJson, InvalidUtf8BecomesTheReplacementCharacter) {
  const std::string replacement = "\xef\xbf\xbd";  // U+FFFD
  EXPECT_EQ(Json::parse(JsonText("rig-\xff")), "rig-" + replacement);
  const std::string utf8 = "Tr\xc3\xb8ndheim \xe2\x82\xac \xf0\x9f\x8c\x8a";  // ø, euro, a wave
  EXPECT_EQ(JsonText(utf8), "\"" + utf8 + "\"");
  // Overlong '/', a surrogate, a truncated sequence at the end: each byte of them U+FFFD.
  const std::string out = JsonText("\xc0\xaf|\xed\xa0\x80|\xe2\x82");
  Json parsed;
  ASSERT_NO_THROW(parsed = Json::parse(out)) << out;
  const std::string& r = replacement;
  const std::string expected = r + r + "|" + r + r + r + "|" + r;
  EXPECT_EQ(parsed, expected) << out;
}

// A rig id with quotes, backslashes, control characters and non-ASCII UTF-8 comes back from the
// API's JSON as it was (escaping was the bug class of the hand-written writers).
TEST_F(RigFeedTest, AnyRigIdRoundTripsThroughTheJson) {
  const std::string id = "rig \"A\"\\b\n\t\x01 \xc3\xb6";  // ", \, newline, tab, U+0001, ö
  const Json state = Json::parse(feed_->StateJson(id, 0));
  EXPECT_EQ(state["rig"], id);
  EXPECT_EQ(state["known"], false);
  const Json refusal = Json::parse(ErrorJson("unknown rig " + id));
  EXPECT_EQ(refusal["error"], "unknown rig " + id);
  EXPECT_EQ(refusal["ok"], false);
}

TEST_F(RigFeedTest, ReadsOnlyWhileWatched) {
  auto sensors = dds::Writer<mpdrig_RigSensors>::Create(
      participant_.handle(), Topic(dds::topics::kSensors.type, dds::topics::kSensors.name),
      dds::SensorQos());
  ASSERT_TRUE(sensors.ok()) << sensors.status().message();
  auto matched = [&] {
    dds_publication_matched_status_t m{};
    EXPECT_EQ(dds_get_publication_matched_status(sensors->handle(), &m), DDS_RETCODE_OK);
    return m.current_count;
  };
  // Nobody has asked: no participant, no reader.
  std::this_thread::sleep_for(milliseconds(500));
  EXPECT_FALSE(feed_->Health().open);
  EXPECT_EQ(matched(), 0u);

  mpdrig_RigSensors sample{};
  std::string rig_id = "rig-a";
  sample.rig_id = rig_id.data();
  for (double& pt : sample.PT_barg) pt = 13.0;
  sample.PT_barg[3] = std::nan("");  // PT4 not measured
  std::string state;
  // Generous timeouts: discovery on a machine busy with other builds can take seconds.
  const bool shown = Eventually(
      30.0, [&] { return state.find("\"sensors\"") != std::string::npos; },
      [&] {
        feed_->Touch();  // a browser polling
        ++sample.sample_counter;
        sample.sim_time_s = 0.01 * static_cast<double>(sample.sample_counter);
        ASSERT_TRUE(sensors->Write(sample).ok());
        std::this_thread::sleep_for(milliseconds(60));  // a frame
        state = feed_->StateJson("rig-a", 0);
      });
  ASSERT_TRUE(shown) << state;
  EXPECT_TRUE(feed_->Health().open);
  EXPECT_GE(matched(), 1u);
  EXPECT_NE(state.find("\"known\":true"), std::string::npos) << state;
  EXPECT_NE(state.find("\"PT\":[13,13,13,null,13"), std::string::npos) << state;
  EXPECT_NE(feed_->RigsJson().find("\"rig-a\""), std::string::npos) << feed_->RigsJson();
  EXPECT_NE(feed_->StateJson("rig-b", 0).find("\"known\":false"), std::string::npos);

  // History: every point once. Asking again from the newest sequence number gives no rig point.
  EXPECT_EQ(state.find("\"hist\":{\"rig\":[]"), std::string::npos) << state;
  const auto seq_at = state.find("\"seq\":") + 6;
  const std::uint64_t seq = std::stoull(state.substr(seq_at));
  EXPECT_NE(feed_->StateJson("rig-a", seq).find("\"hist\":{\"rig\":[]"), std::string::npos);

  // Nobody watches any more: after the idle time (0.6 s) and a frame, the reader is gone again.
  EXPECT_TRUE(Eventually(
      10.0, [&] { return !feed_->Health().open && matched() == 0; }, [] {}));
  EXPECT_EQ(feed_->Health().sessions_opened, 1u);
}

TEST_F(RigFeedTest, ShadowCommandsReachTheWireOrAreRefusedWithAReason) {
  auto bad = feed_->SendShadowCommand("rig-a", "explode", "");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("unknown action"), std::string::npos);
  auto no_argument = feed_->SendShadowCommand("rig-a", "effect_on", "");
  ASSERT_FALSE(no_argument.ok());
  EXPECT_NE(no_argument.status().message().find("needs an argument"), std::string::npos);
  auto nobody = feed_->SendShadowCommand("rig-a", "reset", "");
  ASSERT_FALSE(nobody.ok());
  EXPECT_NE(nobody.status().message().find("no shadow model is listening"), std::string::npos)
      << nobody.status().message();

  // A shadow's command reader (as `mpdrig shadow` has: reliable, keep all).
  dds::Qos qos;
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, 0);
  auto commands = dds::Reader<mpdrig_ShadowCommand>::Create(
      participant_.handle(),
      Topic(dds::topics::kShadowCommand.type, dds::topics::kShadowCommand.name), qos);
  ASSERT_TRUE(commands.ok()) << commands.status().message();
  auto sent = feed_->SendShadowCommand("rig-a", "effect_on", "unsteady_friction:k=2");
  ASSERT_TRUE(sent.ok()) << sent.status().message();
  bool seen = false;
  EXPECT_TRUE(Eventually(
      5.0, [&] { return seen; },
      [&] {
        (void)commands->TakeEach([&](const mpdrig_ShadowCommand& c, const dds_sample_info_t&) {
          EXPECT_STREQ(c.rig_id, "rig-a");
          EXPECT_EQ(c.action, mpdrig_SHADOW_EFFECT_ON);
          EXPECT_STREQ(c.argument, "unsteady_friction:k=2");
          EXPECT_EQ(c.command_id, *sent);
          seen = true;
        });
      }));
}

}  // namespace
}  // namespace mpdrig::dashboard
