// A client program's place on a DDS domain: one participant, which may hold several rigs (the
// dashboard shows every rig of a domain through one; a controller of two rigs needs one).
// Rig::Connect, Shadow::Open, RequestPrivateRigs and RigStreams::Open take one; each makes its
// own readers and writers under it, and the participant lives while any of them does.
//
//   auto participant = client::Participant::Join({.domain = 0});
//   auto a = client::Rig::Connect(*participant, {.rig_id = "rig-1"});
//   auto b = client::Rig::Connect(*participant, {.rig_id = "rig-2"});
//
// Rules it keeps:
//   - One domain object per id in a process (Cyclone allows no more): participants of one id
//     share it, and the first one's configuration holds for all (ClientDomain keeps it
//     configured while no participant exists, as the dashboard does between watchers).
//   - With `security_dir` (DDS Security, make-class's OUT/NAME) the participant authenticates
//     with those files, and each rig's endpoints go into its own partition rig.<rig id>, a
//     publisher and a subscriber per rig under the one participant; the permissions decide what
//     the identity may read and command, and a refusal says so (EndpointError).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "model/common/status.h"

namespace mpdrig::dds {
class Domain;
}  // namespace mpdrig::dds

namespace mpdrig::client {

struct ParticipantOptions {
  int domain = 0;
  // Cyclone DDS configuration: an XML fragment, a whole <CycloneDDS> document, or file URIs
  // ("file:///lab.xml", Cyclone's comma-separated list) (empty: loopback only). A fragment or a
  // file list gets dds::FastAckConfig() added, for lockstep acknowledgements.
  std::string dds_config;
  // DDS Security: an identity directory of a class (deploy/security/make-class OUT NAME:
  // OUT/NAME); empty: no security.
  std::string security_dir;
};

// The domain `id` configured with `dds_config` (as ParticipantOptions), shared by every
// participant of the id in this process while any holder keeps it.
class ClientDomain {
 public:
  static Result<std::shared_ptr<ClientDomain>> Configure(int id, const std::string& dds_config);
  ~ClientDomain();
  int id() const { return id_; }

 private:
  ClientDomain(int id, std::unique_ptr<dds::Domain> domain);
  int id_;
  std::unique_ptr<dds::Domain> domain_;
};

class Participant {
 public:
  // Checks the options (the domain id, the security directory) and joins the domain.
  static Result<std::shared_ptr<Participant>> Join(const ParticipantOptions& options);
  // What Join and ScopeOf would refuse, without joining (nothing on the wire): the domain id,
  // and with security the directory's files and each of `rig_ids` as a partition's rig id.
  static Status Check(const ParticipantOptions& options, const std::vector<std::string>& rig_ids);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  const ParticipantOptions& options() const { return options_; }
  bool secure() const { return !options_.security_dir.empty(); }

  // For the client library's classes, not for programs: DDS handles (dds_entity_t).
  std::int32_t handle() const;
  struct Scope {
    std::int32_t publisher = 0, subscriber = 0;  // the participant itself without security
  };
  // Where `rig_id`'s endpoints go: with security its partition's publisher and subscriber (made
  // on the first call for the rig; the id must be one security allows), else the participant.
  Result<Scope> ScopeOf(const std::string& rig_id);
  // `error` of making an endpoint for `rig_id`; with security, a refusal by the permissions says
  // so: "DDS Security: the permissions of DIR do not allow <what> rig 'ID' (partition ...)".
  Status EndpointError(const Status& error, const std::string& rig_id, const char* what) const;

 private:
  struct Dds;
  explicit Participant(const ParticipantOptions& options);

  ParticipantOptions options_;
  std::shared_ptr<ClientDomain> domain_;
  std::unique_ptr<Dds> dds_;
};

}  // namespace mpdrig::client
