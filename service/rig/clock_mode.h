// How the service paces its rigs (rig_service.h tells each mode's rule).
#pragma once

namespace mpdrig::service {

enum class ClockMode { kRealtime, kFast, kLockstep };

}  // namespace mpdrig::service
