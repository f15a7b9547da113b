// Command intake without DDS: a bad command is refused, counted and reported while the last valid
// one stays in force; a command for an unknown rig is refused on every rig with its id bounded; a
// command from another rig's partition is refused on both with its writer; the owner of each
// actuator is kept, and the safe state is taken when the last one goes; the topic filter's tally
// is exact under concurrent receive threads.
#include "service/rig/command_intake.h"

#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "service/dds/security.h"
#include "service/dds/topics.h"
#include "service/rig/wire.h"

namespace mpdrig::service {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

std::vector<RigHost> MakeRigs(std::vector<std::string> ids) {
  std::vector<RigHost> rigs;
  for (std::string& id : ids) {
    auto rig = RigHost::Create(std::move(id), RigParams(), SimulationOptions(), 100.0);
    EXPECT_TRUE(rig.ok()) << rig.status().message();
    rigs.push_back(std::move(rig).value());
  }
  return rigs;
}

CommandOrigin Writer(const std::string& text, int partition_rig = -1) {
  return CommandOrigin{partition_rig, [text] { return text; }};
}

mpdrig_ChokeCommand Choke(const char* rig_id, double deg) {
  mpdrig_ChokeCommand c{};
  c.rig_id = const_cast<char*>(rig_id);
  c.opening_deg = deg;
  return c;
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CommandIntake, BadCommandsAreRefusedCountedAndTheLastValidOneStays) {
  std::vector<RigHost> rigs = MakeRigs({"a"});
  CommandIntake intake(&rigs, kNan);
  intake.Choke(Choke("a", 40.0), Writer("strength 5, writer 01"));
  ASSERT_EQ(rigs[0].counters().rejected_commands, 0u);
  ASSERT_DOUBLE_EQ(rigs[0].choke_command_deg(), 40.0);
  for (double bad : {kNan, std::numeric_limits<double>::infinity(), -1.0, 95.0}) {
    intake.Choke(Choke("a", bad), Writer("strength 5, writer 01"));
  }
  mpdrig_PumpCommand pump{};
  pump.rig_id = const_cast<char*>("a");
  pump.flow_lpm = kNan;
  intake.Pump(pump, Writer("strength 5, writer 02"));
  mpdrig_OutletCommand outlet{};
  outlet.rig_id = const_cast<char*>("a");
  outlet.pressure_barg = 40.0;
  intake.Outlet(outlet, Writer("strength 5, writer 03"));
  EXPECT_EQ(rigs[0].counters().rejected_commands, 6u);
  EXPECT_TRUE(Contains(rigs[0].counters().last_rejection, "outlet pressure"))
      << rigs[0].counters().last_rejection;
  EXPECT_DOUBLE_EQ(rigs[0].choke_command_deg(), 40.0);
  EXPECT_DOUBLE_EQ(rigs[0].pump_command_lpm(), 0.0);
  // The owner is the writer of the last command, applied or refused by the rig.
  EXPECT_EQ(intake.Owners(0), (std::vector<std::string>{"choke: strength 5, writer 01",
                                                        "outlet: strength 5, writer 03",
                                                        "pump: strength 5, writer 02"}));
}

TEST(CommandIntake, AnUnknownRigIsRefusedOnEveryRigWithItsIdBounded) {
  std::vector<RigHost> rigs = MakeRigs({"a", "b"});
  CommandIntake intake(&rigs, kNan);
  intake.Choke(Choke("ghost", 40.0), Writer("w"));
  const std::string topic = dds::topics::kChokeCommand.name;
  for (const RigHost& rig : rigs) {
    EXPECT_EQ(rig.counters().rejected_commands, 1u);
    EXPECT_TRUE(Contains(rig.counters().last_rejection,
                         topic + " for unknown rig 'ghost' refused (this service runs: a, b)"))
        << rig.counters().last_rejection;
  }
  EXPECT_TRUE(intake.Owners(0).empty());
  // A 201-byte id of 2-byte characters: 64 bytes would end inside one, so 63 are repeated.
  std::string id = "a";
  for (int k = 0; k < 100; ++k) id += "\xc3\xa9";  // é
  EXPECT_EQ(ReportedId(id.c_str()), "'" + id.substr(0, 63) + "...' (201 bytes)");
  intake.Choke(Choke(id.c_str(), 40.0), Writer("w"));
  EXPECT_TRUE(Contains(rigs[1].counters().last_rejection, id.substr(0, 63) + "...' (201 bytes)"));
  EXPECT_FALSE(Contains(rigs[1].counters().last_rejection, id.substr(0, 65)));
  // A dispose carries only the key: one of a known rig is nothing to refuse.
  EXPECT_FALSE(intake.Disposed(topic.c_str(), "a"));
  EXPECT_TRUE(intake.Disposed(topic.c_str(), "ghost"));
  EXPECT_EQ(rigs[0].counters().rejected_commands, 3u);
}

TEST(CommandIntake, ACommandFromAnotherRigsPartitionIsRefusedOnBothWithItsWriter) {
  std::vector<RigHost> rigs = MakeRigs({"a", "b"});
  CommandIntake intake(&rigs, kNan);
  const double b_choke = rigs[1].choke_command_deg();
  intake.Choke(Choke("b", 60.0), Writer("strength 7, writer 0a0b", /*partition_rig=*/0));
  EXPECT_DOUBLE_EQ(rigs[1].choke_command_deg(), b_choke);
  for (const RigHost& rig : rigs) {
    EXPECT_EQ(rig.counters().rejected_commands, 1u);
    const std::string& reason = rig.counters().last_rejection;
    EXPECT_TRUE(Contains(reason, "for rig 'b' refused: it came in rig 'a''s partition " +
                                     dds::RigPartition("a") + " (strength 7, writer 0a0b)"))
        << reason;
  }
  // In its own partition it is applied.
  intake.Choke(Choke("b", 60.0), Writer("strength 7, writer 0a0b", 1));
  EXPECT_DOUBLE_EQ(rigs[1].choke_command_deg(), 60.0);
  EXPECT_TRUE(intake.FromItsPartition("any", "a", Writer("w", -1)));
}

TEST(CommandIntake, TheLastControllerGoingTakesTheSafeState) {
  std::vector<RigHost> rigs = MakeRigs({"a", "b"});
  CommandIntake intake(&rigs, /*safe_choke_deg=*/90.0);
  intake.Choke(Choke("a", 20.0), Writer("strength 1, writer 01"));
  mpdrig_PistonCommand sine{};
  sine.rig_id = const_cast<char*>("a");
  sine.mode = mpdrig_PISTON_SINE;
  sine.amplitude_m = 0.1;
  sine.frequency_hz = 0.5;
  intake.Piston(sine, Writer("strength 1, writer 02"));
  ASSERT_EQ(rigs[0].piston_command().mode, PistonCommandIn::Mode::kSine);
  // Seen in another rig's partition, an instance without writers is not this rig's matter.
  intake.ChokeLost("a", /*partition_rig=*/1);
  EXPECT_DOUBLE_EQ(rigs[0].choke_command_deg(), 20.0);
  intake.ChokeLost("a", -1);
  intake.PistonLost("a", -1);
  EXPECT_DOUBLE_EQ(rigs[0].choke_command_deg(), 90.0);
  EXPECT_EQ(rigs[0].piston_command().mode, PistonCommandIn::Mode::kHold);
  EXPECT_TRUE(Contains(rigs[0].counters().last_event, "piston holds"));
  EXPECT_EQ(intake.Owners(0), (std::vector<std::string>{"choke: none", "piston: none"}));
  // No safe opening configured: the choke keeps its last command, and the status says so.
  CommandIntake keeping(&rigs, kNan);
  keeping.Choke(Choke("b", 25.0), Writer("w"));
  keeping.ChokeLost("b", -1);
  EXPECT_DOUBLE_EQ(rigs[1].choke_command_deg(), 25.0);
  EXPECT_TRUE(Contains(rigs[1].counters().last_event, "keeps its last command"));
}

TEST(CommandIntake, TheTopicFilterCountsEveryRefusalOfItsReceiveThreads) {
  std::vector<RigHost> rigs = MakeRigs({"a"});
  CommandIntake intake(&rigs, kNan);
  UnknownRigGate* gate = intake.AddGate(dds::topics::kPumpCommand.name);
  EXPECT_TRUE(gate->Admit("a"));
  // An id one byte beyond the limit, equal to a served id over its first kMaxRigIdBytes bytes.
  const std::string longest(kMaxRigIdBytes, 'x');
  intake.Allow(longest);
  EXPECT_TRUE(gate->Admit(longest.c_str()));
  EXPECT_FALSE(gate->Admit((longest + "x").c_str()));
  (void)gate->Drain();
  constexpr int kThreads = 4, kEach = 500;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([gate, t] {
      const std::string id = "stranger" + std::to_string(t);
      for (int k = 0; k < kEach; ++k) (void)gate->Admit(k % 2 == 0 ? id.c_str() : "a");
    });
  }
  for (std::thread& thread : threads) thread.join();
  ASSERT_TRUE(intake.RefuseFiltered());
  EXPECT_EQ(rigs[0].counters().rejected_commands, std::uint64_t{kThreads * kEach / 2});
  EXPECT_TRUE(Contains(rigs[0].counters().last_rejection, "for unknown rig 'stranger"));
  EXPECT_FALSE(intake.RefuseFiltered()) << "drained";
  // A rig made later (a private rig) passes once allowed.
  EXPECT_FALSE(gate->Admit("a.1"));
  intake.Allow("a.1");
  EXPECT_TRUE(gate->Admit("a.1"));
}

}  // namespace
}  // namespace mpdrig::service
