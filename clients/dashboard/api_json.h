// The dashboard's small answers as JSON text, for the server's files (json_out.cc writes them
// with nlohmann-json under json_out.h's rule; this header keeps the library out of theirs).
#pragma once

#include <cstdint>
#include <string>

#include "clients/dashboard/rig_feed.h"

namespace mpdrig::dashboard {

// {"ok":false,"error":message}: every refusal's body.
std::string ErrorJson(const std::string& message);
// {"ok":true,"command_id":"..."}: a shadow command sent. The id is a 64-bit number: a string,
// since JavaScript's numbers hold 53 bits.
std::string CommandSentJson(std::uint64_t command_id);
// GET /api/health: {"dds", "sessions_opened", "samples_taken", "frames", "cpu_s"}.
std::string HealthJson(const FeedHealth& health, double cpu_s);

}  // namespace mpdrig::dashboard
