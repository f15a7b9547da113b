// Private rigs (with security): a student asks, with a RigRequest sent in their own rig's
// partition, for N rigs of their own; the service then runs "<student>.1" .. "<student>.N", each
// in its own partition, which only that student's permissions name. N is at most `per_student`
// (a request for more gets that many, and the refusal of the rest on the student's status); the
// service runs at most `max_rigs` rigs in all (0: no limit), and a private rig asks for none.
// Rigs the student already has are not made again. Each refusal is counted and reported on the
// student's rig (RigHost::Refuse); nothing a student sends stops the service.
//
// Transport-free: the service gives each new rig its endpoints and status through `made`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "service/rig/rig_host.h"

namespace mpdrig::service {

class PrivateRigs {
 public:
  using MakeRig = std::function<Result<RigHost>(const std::string& rig_id)>;
  // Called with the index of each rig made, right after it joined `rigs`; an error (of the
  // transport) ends the request with it.
  using Made = std::function<Status(std::size_t rig_index)>;

  // per_student 0: requests are not taken.
  PrivateRigs(std::uint32_t per_student, std::size_t max_rigs, MakeRig make_rig);

  bool enabled() const { return per_student_ > 0; }

  // The request of rig `student` (an index into `rigs`) for `count` private rigs. Refusals go on
  // the student's rig; fails only when `made` fails.
  Status Grant(std::vector<RigHost>& rigs, std::size_t student, std::uint32_t count,
               const Made& made) const;

 private:
  std::uint32_t per_student_;
  std::size_t max_rigs_;
  MakeRig make_rig_;
};

}  // namespace mpdrig::service
