// A student's request for private rigs (mpdrig_rig_request): the service, run with `--security
// ... --private-rigs N`, makes NAME.1 .. NAME.N within its limits, each in its own partition that
// only the student's permissions name, and says on the student's rig's status what it made or
// refused. Sent through a Participant with the student's identity (participant.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "clients/client/participant.h"
#include "model/common/status.h"

namespace mpdrig::client {

struct PrivateRigAnswer {
  // What the rig's status said after the request, in order: "refused: <reason>" for a refusal,
  // and each new event ("private rig alice.1 runs").
  std::vector<std::string> said;
  bool refused = false;   // some or all of the request was refused
  bool answered = false;  // false: nothing new within the timeout (the rigs may run already)
};

// Asks for `count` private rigs of `rig_id` (the student's own rig) and waits up to `timeout_s`
// for the service's answer on the rig's status. Fails when no service takes requests for the
// rig (none matched within the timeout) or the request is not acknowledged.
Result<PrivateRigAnswer> RequestPrivateRigs(const std::shared_ptr<Participant>& participant,
                                            const std::string& rig_id, std::uint32_t count,
                                            double timeout_s);

}  // namespace mpdrig::client
