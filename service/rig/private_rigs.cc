#include "service/rig/private_rigs.h"

#include <algorithm>
#include <utility>

#include "service/dds/topics.h"

namespace mpdrig::service {

PrivateRigs::PrivateRigs(std::uint32_t per_student, std::size_t max_rigs, MakeRig make_rig)
    : per_student_(per_student), max_rigs_(max_rigs), make_rig_(std::move(make_rig)) {}

Status PrivateRigs::Grant(std::vector<RigHost>& rigs, std::size_t student, std::uint32_t count,
                          const Made& made) const {
  const std::string name = rigs[student].rig_id();
  const std::string topic = dds::topics::kRigRequest.name;
  if (name.find('.') != std::string::npos) {
    (void)rigs[student].Refuse(topic + " refused: " + name + " is a private rig itself");
    return Status::Ok();
  }
  if (count > per_student_) {
    (void)rigs[student].Refuse(topic + " for " + std::to_string(count) +
                               " private rigs refused beyond " + std::to_string(per_student_) +
                               ": this service allows that many per student (--private-rigs)");
    count = per_student_;
  }
  for (std::uint32_t k = 1; k <= count; ++k) {
    const std::string id = name + "." + std::to_string(k);
    if (std::any_of(rigs.begin(), rigs.end(), [&id](const RigHost& r) { return r.rig_id() == id; }))
      continue;
    if (max_rigs_ > 0 && rigs.size() >= max_rigs_) {
      (void)rigs[student].Refuse("private rig " + id + " refused: this service runs its limit of " +
                                 std::to_string(max_rigs_) + " rigs (--max-rigs)");
      break;
    }
    auto rig = make_rig_ ? make_rig_(id) : Result<RigHost>(Status::Error("no rig maker"));
    if (!rig.ok()) {
      (void)rigs[student].Refuse("private rig " + id + ": " + rig.status().message());
      break;
    }
    rigs.push_back(std::move(rig).value());
    rigs.back().NoteEvent("private rig of " + name + ", made on its request");
    rigs[student].NoteEvent("private rig " + id + " runs");
    MPDRIG_RETURN_IF_ERROR(made(rigs.size() - 1));
  }
  return Status::Ok();
}

}  // namespace mpdrig::service
