#include "clients/dashboard/json_out.h"

#include <cmath>

#include "clients/dashboard/api_json.h"

namespace mpdrig::dashboard {

std::string JsonText(const Json& value) {
  return value.dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::string ErrorJson(const std::string& message) {
  return JsonText({{"ok", false}, {"error", message}});
}

std::string CommandSentJson(std::uint64_t command_id) {
  return JsonText({{"ok", true}, {"command_id", std::to_string(command_id)}});
}

std::string HealthJson(const FeedHealth& health, double cpu_s) {
  return JsonText({{"dds", health.open ? "open" : "closed"},
                   {"sessions_opened", health.sessions_opened},
                   {"samples_taken", health.samples_taken},
                   {"frames", health.frames},
                   {"cpu_s", std::round(cpu_s * 1e3) / 1e3}});  // milliseconds
}

}  // namespace mpdrig::dashboard
