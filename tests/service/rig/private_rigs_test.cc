// Private rigs without DDS: a student gets the rigs they ask for once each, within the limit per
// student and the service's limit of rigs; a private rig asks for none; a rig that cannot be made
// is refused with the reason; every refusal is counted on the student's rig.
#include "service/rig/private_rigs.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig::service {
namespace {

Result<RigHost> MakeRig(const std::string& id) {
  return RigHost::Create(id, RigParams(), SimulationOptions(), 100.0);
}

std::vector<RigHost> Rigs(const std::vector<std::string>& ids) {
  std::vector<RigHost> rigs;
  for (const std::string& id : ids) {
    auto rig = MakeRig(id);
    EXPECT_TRUE(rig.ok()) << rig.status().message();
    rigs.push_back(std::move(rig).value());
  }
  return rigs;
}

std::vector<std::string> Ids(const std::vector<RigHost>& rigs) {
  std::vector<std::string> ids;
  for (const RigHost& rig : rigs) ids.push_back(rig.rig_id());
  return ids;
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(PrivateRigs, AStudentGetsTheRigsAskedForOnceEach) {
  const PrivateRigs policy(3, 0, MakeRig);
  ASSERT_TRUE(policy.enabled());
  std::vector<RigHost> rigs = Rigs({"alice", "bob"});
  std::vector<std::size_t> made;
  auto note = [&](std::size_t index) {
    made.push_back(index);
    return Status::Ok();
  };
  ASSERT_TRUE(policy.Grant(rigs, 0, 2, note).ok());
  EXPECT_EQ(Ids(rigs), (std::vector<std::string>{"alice", "bob", "alice.1", "alice.2"}));
  EXPECT_EQ(made, (std::vector<std::size_t>{2, 3}));
  EXPECT_TRUE(Contains(rigs[2].counters().last_event, "private rig of alice"));
  EXPECT_TRUE(Contains(rigs[0].counters().last_event, "private rig alice.2 runs"));
  // Asking again makes only the missing one.
  ASSERT_TRUE(policy.Grant(rigs, 0, 3, note).ok());
  EXPECT_EQ(Ids(rigs).back(), "alice.3");
  EXPECT_EQ(made.size(), 3u);
  EXPECT_EQ(rigs[0].counters().rejected_commands, 0u);
  EXPECT_FALSE(PrivateRigs(0, 0, MakeRig).enabled());
}

TEST(PrivateRigs, RequestsBeyondTheLimitsAreRefusedOnTheStudentsRig) {
  std::vector<RigHost> rigs = Rigs({"alice"});
  auto ok = [](std::size_t) { return Status::Ok(); };
  // Five asked, two allowed per student: two made, the request refused beyond them.
  ASSERT_TRUE(PrivateRigs(2, 0, MakeRig).Grant(rigs, 0, 5, ok).ok());
  EXPECT_EQ(rigs.size(), 3u);
  EXPECT_EQ(rigs[0].counters().rejected_commands, 1u);
  EXPECT_TRUE(Contains(rigs[0].counters().last_rejection, "for 5 private rigs refused beyond 2"));
  // Four rigs in all at most: alice.3 is made, alice.4 is not.
  ASSERT_TRUE(PrivateRigs(5, 4, MakeRig).Grant(rigs, 0, 5, ok).ok());
  EXPECT_EQ(Ids(rigs).back(), "alice.3");
  EXPECT_EQ(rigs.size(), 4u);
  EXPECT_TRUE(Contains(rigs[0].counters().last_rejection,
                       "private rig alice.4 refused: this service runs its limit of 4 rigs"));
  // A private rig asks for none.
  ASSERT_TRUE(PrivateRigs(5, 0, MakeRig).Grant(rigs, 1, 1, ok).ok());
  EXPECT_EQ(rigs.size(), 4u);
  EXPECT_TRUE(Contains(rigs[1].counters().last_rejection, "alice.1 is a private rig itself"));
}

TEST(PrivateRigs, ARigThatCannotBeMadeIsRefusedWithTheReasonAndATransportFailureEndsIt) {
  std::vector<RigHost> rigs = Rigs({"carol"});
  const PrivateRigs failing(2, 0, [](const std::string& id) -> Result<RigHost> {
    return Status::Error("no configuration for " + id);
  });
  ASSERT_TRUE(failing.Grant(rigs, 0, 2, [](std::size_t) { return Status::Ok(); }).ok());
  EXPECT_EQ(rigs.size(), 1u);
  EXPECT_EQ(rigs[0].counters().rejected_commands, 1u);
  EXPECT_EQ(rigs[0].counters().last_rejection, "private rig carol.1: no configuration for carol.1");
  const Status failed = PrivateRigs(2, 0, MakeRig).Grant(rigs, 0, 2, [](std::size_t) {
    return Status::Error("dds_create_writer: out of resources");
  });
  EXPECT_FALSE(failed.ok());
  EXPECT_EQ(rigs.size(), 2u) << "the first rig was made; its endpoints failed";
}

}  // namespace
}  // namespace mpdrig::service
