// DDS Security for a class (docs/service.md, "Security for a class"): an identity directory made by
// deploy/security/make-class, turned into the participant QoS that loads Cyclone's
// authentication, access-control and cryptography plugins; and the partition per rig that lets
// permissions say who may command and read which rig. Transport only: no model types.
//
// Why partitions: permissions can name topics and partitions, not keys, so with security on
// each rig's topics live in partition "rig.<rig id>" (the service has one set of endpoints per
// rig; a client joins its rig's partition). The unsecured default keeps the default partition,
// so every client of before still works unchanged.
#pragma once

#include <string>

#include "model/common/status.h"
#include "service/dds/dds.h"

namespace mpdrig::dds {

// Where Debian 12 installs Cyclone's security plugins (in libddsc0debian, not on the loader's
// path: the full path is needed, platform notes section 1).
inline constexpr const char* kSecurityPluginDir = "/usr/lib/x86_64-linux-gnu/libddsc0debian";

// The files of one identity directory (OUT/NAME/ of make-class), as absolute paths.
struct SecurityFiles {
  std::string dir;
  std::string identity_ca;           // identity_ca.pem: the class's CA certificate
  std::string identity_certificate;  // identity.pem: this identity, signed by the CA
  std::string private_key;           // identity_key.pem
  std::string permissions_ca;        // permissions_ca.pem
  std::string governance;            // governance.p7s: signed by the permissions CA
  std::string permissions;           // permissions.p7s: this identity's grant, signed
  std::string plugin_dir = kSecurityPluginDir;
};

// Checks `dir` before DDS sees it, so a wrong directory is refused with a reason a student can
// act on: the directory, each file (present, readable, the PEM or S/MIME it should be, the key
// not readable by others), and the plugins. What it cannot check (a certificate not signed by
// the CA, expired permissions, a subject the permissions do not name) Cyclone's plugins refuse
// when the participant is created (CreateSecureParticipant says so).
Result<SecurityFiles> LoadSecurityDirectory(const std::string& dir);

// A participant with those files (nullptr: without security, as before). A participant the
// plugins refuse gives an error naming the directory; Cyclone prints the plugin's reason.
Result<Entity> CreateParticipant(dds_domainid_t domain, const SecurityFiles* security);

// The partition of a rig's topics when security is on.
std::string RigPartition(const std::string& rig_id);
// With security, a rig id becomes a partition name and a permissions pattern: only 1-64 of
// [A-Za-z0-9_-], so that no wildcard (* ?) or separator hides in one; or NAME.N (N = 1..9999),
// a private rig of student NAME (mpdrig serve --private-rigs).
Status CheckSecureRigId(const std::string& rig_id);
// A publisher or subscriber in one partition: its writers or readers (Writer/Reader::Create
// with it in place of the participant) see only endpoints of that partition.
Result<Entity> CreatePublisher(dds_entity_t participant, const std::string& partition);
Result<Entity> CreateSubscriber(dds_entity_t participant, const std::string& partition);

// A client's participant, and where its endpoints go: without security the participant itself
// (the default partition, as before); with `security_dir` (make-class's OUT/NAME) a publisher
// and a subscriber in partition RigPartition(rig_id). Refuses an invalid directory or rig id,
// saying why.
struct ClientScope {
  Entity participant;
  Entity publisher, subscriber;  // with security only
  dds_entity_t pub() const {
    return publisher.handle() > 0 ? publisher.handle() : participant.handle();
  }
  dds_entity_t sub() const {
    return subscriber.handle() > 0 ? subscriber.handle() : participant.handle();
  }
};
Result<ClientScope> CreateClientScope(dds_domainid_t domain, const std::string& security_dir,
                                      const std::string& rig_id);

}  // namespace mpdrig::dds
