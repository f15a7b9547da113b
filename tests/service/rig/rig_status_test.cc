// A rig's status without DDS: the rig's own units (its atmosphere in Pa, rig time, the real-time
// factor over wall time), the service's account (stalls, the last step request, the owners), the
// warnings in their order, the effects named or hidden, and the wire form pointing at all of it.
#include "service/rig/rig_status.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "service/rig/wire.h"

namespace mpdrig::service {
namespace {

RigHost MakeRig(RigParams params = RigParams()) {
  auto rig = RigHost::Create("rig-7", params, SimulationOptions(), 100.0);
  EXPECT_TRUE(rig.ok()) << rig.status().message();
  return std::move(rig).value();
}

std::vector<std::string> Strings(const dds_sequence_string& sequence) {
  std::vector<std::string> texts;
  for (std::uint32_t k = 0; k < sequence._length; ++k) texts.emplace_back(sequence._buffer[k]);
  return texts;
}

TEST(RigStatus, CarriesTheRigsUnitsAndTheServicesAccount) {
  RigParams params;
  params.atmospheric_pressure_pa = 95000.0;  // a lab at altitude: barg is against this
  RigHost rig = MakeRig(params);
  for (int k = 0; k < 50; ++k) ASSERT_TRUE(rig.Tick().ok());
  (void)rig.SetChokeDeg(120.0);  // refused: out of range
  StatusContext context;
  context.clock = ClockMode::kLockstep;
  context.wall_s = 2.0;
  context.last_completed_step_request = 17;
  context.actuator_owners = {"choke: strength 20, writer 0a"};
  const RigStatusReport report = ReportStatus(rig, context);
  EXPECT_EQ(report.rig_id, "rig-7");
  EXPECT_NEAR(report.sim_time_s, 0.5, 1e-12);  // 50 periods of 10 ms
  EXPECT_NEAR(report.real_time_factor, 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(report.atmospheric_pressure_pa, 95000.0);
  EXPECT_EQ(report.rejected_commands, 1u);
  EXPECT_NE(report.last_rejection.find("choke opening"), std::string::npos);
  EXPECT_EQ(report.last_completed_step_request, 17u);
  EXPECT_EQ(report.deadline_misses, 0u);
  EXPECT_DOUBLE_EQ(report.last_stall_sim_time_s, -1.0);
  EXPECT_TRUE(report.warnings.empty());
  EXPECT_EQ(report.sensor_noise, "none");
  EXPECT_EQ(report.actuator_owners, context.actuator_owners);
  // Before any wall time has passed, no factor (not a division by zero).
  context.wall_s = 0.0;
  EXPECT_EQ(ReportStatus(rig, context).real_time_factor, 0.0);
}

TEST(RigStatus, WarningsComeInTheirOrderAndOnlyWhenThereIsOne) {
  RigHost rig = MakeRig();
  rig.NoteEvent("no choke controller left: the choke keeps its last command");
  StatusContext context;
  context.stalls.deadline_misses = 1;
  context.stalls.lost_periods = 4;
  context.stalls.last_s = context.stalls.longest_s = 0.045;
  context.stalls.last_sim_time_s = 0.02;
  context.stopped_reader_warning = "a reader of the sensors has acknowledged nothing for 2.0 s";
  const RigStatusReport report = ReportStatus(rig, context);
  ASSERT_EQ(report.warnings.size(), 3u);
  EXPECT_EQ(report.warnings[0], context.stalls.Warning());
  EXPECT_EQ(report.warnings[1], context.stopped_reader_warning);
  EXPECT_NE(report.warnings[2].find("keeps its last command"), std::string::npos);
  EXPECT_EQ(report.lost_periods, 4u);
  EXPECT_DOUBLE_EQ(report.longest_stall_s, 0.045);
}

TEST(RigStatus, EffectsAreNamedWithTheirValuesOrHidden) {
  RigParams params;
  params.effects.push_back(EffectSetting{"sensor_lag", {{"time_constant_s", 0.2}}});
  const RigHost rig = MakeRig(params);
  StatusContext context;
  EXPECT_EQ(ReportStatus(rig, context).active_effects,
            (std::vector<std::string>{"sensor_lag time_constant_s=0.200000"}));
  context.hide_effects = true;
  EXPECT_EQ(ReportStatus(rig, context).active_effects,
            (std::vector<std::string>{"a hidden effect is active"}));
  EXPECT_TRUE(ReportStatus(MakeRig(), context).active_effects.empty()) << "no effect to hide";
}

TEST(RigStatus, TheWireFormPointsAtTheReport) {
  RigStatusReport report;
  report.rig_id = "rig-7";
  report.last_rejection = "why";
  report.sensor_noise = "lab, seed 1";
  report.warnings = {"w1", "w2"};
  report.actuator_owners = {"choke: none"};
  report.atmospheric_pressure_pa = 95000.0;
  report.last_stall_sim_time_s = -1.0;
  StatusBuffers buffers;
  const mpdrig_ClockMode clocks[] = {mpdrig_CLOCK_REALTIME, mpdrig_CLOCK_FAST,
                                     mpdrig_CLOCK_LOCKSTEP};
  const ClockMode modes[] = {ClockMode::kRealtime, ClockMode::kFast, ClockMode::kLockstep};
  for (int k = 0; k < 3; ++k) {
    report.clock = modes[k];
    EXPECT_EQ(ToWire(report, &buffers).clock, clocks[k]);
  }
  const mpdrig_RigStatus wire = ToWire(report, &buffers);
  EXPECT_STREQ(wire.rig_id, "rig-7");
  EXPECT_STREQ(wire.last_rejection, "why");
  EXPECT_STREQ(wire.sensor_noise, "lab, seed 1");
  EXPECT_DOUBLE_EQ(wire.atmospheric_pressure_pa, 95000.0);
  EXPECT_DOUBLE_EQ(wire.last_stall_sim_time_s, -1.0);
  EXPECT_EQ(Strings(wire.warnings), report.warnings);
  EXPECT_EQ(Strings(wire.actuator_owners), report.actuator_owners);
  EXPECT_EQ(wire.active_effects._length, 0u);
  EXPECT_EQ(wire.active_effects._buffer, nullptr);
  EXPECT_FALSE(wire.warnings._release) << "DDS must not free the report's text";
}

}  // namespace
}  // namespace mpdrig::service
