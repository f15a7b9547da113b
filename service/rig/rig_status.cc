#include "service/rig/rig_status.h"

#include <utility>

namespace mpdrig::service {

RigStatusReport ReportStatus(const RigHost& rig, const StatusContext& context) {
  RigStatusReport report;
  report.rig_id = rig.rig_id();
  report.clock = context.clock;
  report.sim_time_s = rig.time_s();
  report.real_time_factor = context.wall_s > 0.0 ? rig.time_s() / context.wall_s : 0.0;
  report.deadline_misses = context.stalls.deadline_misses;
  report.lost_periods = context.stalls.lost_periods;
  report.longest_stall_s = context.stalls.longest_s;
  report.last_stall_sim_time_s = context.stalls.last_sim_time_s;
  report.atmospheric_pressure_pa = rig.params().atmospheric_pressure_pa;
  report.rejected_commands = rig.counters().rejected_commands;
  report.last_rejection = rig.counters().last_rejection;
  report.last_completed_step_request = context.last_completed_step_request;

  auto warn = [&report](std::string text) {
    if (!text.empty()) report.warnings.push_back(std::move(text));
  };
  warn(rig.range_event() ? rig.range_event()->Describe() : "");
  warn(context.stalls.Warning());
  warn(context.stopped_reader_warning);
  warn(rig.counters().last_event);

  const std::vector<EffectSetting>& effects = rig.params().effects;
  if (context.hide_effects) {
    if (!effects.empty()) report.active_effects.push_back("a hidden effect is active");
  } else {
    for (const EffectSetting& effect : effects) {
      std::string text = effect.name;
      for (const auto& [key, value] : effect.values) {
        text += " " + key + "=" + std::to_string(value);
      }
      report.active_effects.push_back(std::move(text));
    }
  }
  report.actuator_owners = context.actuator_owners;
  report.sensor_noise = rig.DescribeSensorNoise();
  return report;
}

}  // namespace mpdrig::service
