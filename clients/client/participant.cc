#include "clients/client/participant.h"

#include <map>
#include <mutex>
#include <optional>
#include <utility>

#include "service/dds/dds.h"
#include "service/dds/security.h"

namespace mpdrig::client {
namespace {

// The domain configuration: loopback by default; FastAckConfig added to a fragment (appended) or
// to a list of files (one more element of Cyclone's comma-separated list).
std::string ClientConfig(const std::string& given) {
  const std::size_t first = given.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return dds::LoopbackConfig() + dds::FastAckConfig();
  if (given[first] != '<') return given + "," + dds::FastAckConfig();
  if (given.find("CycloneDDS") == std::string::npos) return given + dds::FastAckConfig();
  return given;
}

}  // namespace

Result<std::shared_ptr<ClientDomain>> ClientDomain::Configure(int id,
                                                              const std::string& dds_config) {
  if (id < 0 || id > 232) {
    return Status::Error("DDS domain " + std::to_string(id) + " is not in 0..232");
  }
  static std::mutex mutex;
  static std::map<int, std::weak_ptr<ClientDomain>> domains;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto existing = domains[id].lock()) return existing;
  auto created = dds::Domain::Create(id, ClientConfig(dds_config));
  if (!created.ok()) return created.status().Within("DDS domain " + std::to_string(id));
  std::shared_ptr<ClientDomain> shared(
      new ClientDomain(id, std::make_unique<dds::Domain>(std::move(created).value())));
  domains[id] = shared;
  return shared;
}

ClientDomain::ClientDomain(int id, std::unique_ptr<dds::Domain> domain)
    : id_(id), domain_(std::move(domain)) {}

ClientDomain::~ClientDomain() = default;

struct Participant::Dds {
  dds::Entity participant;
  // With security: a publisher and a subscriber per rig, in its partition.
  std::map<std::string, std::pair<dds::Entity, dds::Entity>> partitions;
  std::mutex mutex;  // ScopeOf from several threads (a dashboard's handlers)
  ~Dds() {
    partitions.clear();  // children before their participant
  }
};

Participant::Participant(const ParticipantOptions& options)
    : options_(options), dds_(std::make_unique<Dds>()) {}

Participant::~Participant() {
  dds_.reset();  // the participant, before the domain it is in
  domain_.reset();
}

Result<std::shared_ptr<Participant>> Participant::Join(const ParticipantOptions& options) {
  std::shared_ptr<Participant> joined(new Participant(options));
  std::optional<dds::SecurityFiles> files;
  if (!options.security_dir.empty()) {
    auto loaded = dds::LoadSecurityDirectory(options.security_dir);
    if (!loaded.ok()) return loaded.status().Within("--security");
    files = std::move(loaded).value();
  }
  auto domain = ClientDomain::Configure(options.domain, options.dds_config);
  if (!domain.ok()) return domain.status();
  joined->domain_ = std::move(domain).value();
  auto participant = dds::CreateParticipant(options.domain, files ? &*files : nullptr);
  if (!participant.ok()) return participant.status();
  joined->dds_->participant = std::move(participant).value();
  return joined;
}

Status Participant::Check(const ParticipantOptions& options,
                          const std::vector<std::string>& rig_ids) {
  if (options.domain < 0 || options.domain > 232) {
    return Status::Error("DDS domain " + std::to_string(options.domain) + " is not in 0..232");
  }
  if (options.security_dir.empty()) return Status::Ok();
  for (const std::string& rig_id : rig_ids) MPDRIG_RETURN_IF_ERROR(dds::CheckSecureRigId(rig_id));
  auto files = dds::LoadSecurityDirectory(options.security_dir);
  if (!files.ok()) return files.status().Within("--security");
  return Status::Ok();
}

std::int32_t Participant::handle() const { return dds_->participant.handle(); }

Result<Participant::Scope> Participant::ScopeOf(const std::string& rig_id) {
  const dds_entity_t p = dds_->participant.handle();
  if (!secure()) return Scope{p, p};
  std::lock_guard<std::mutex> lock(dds_->mutex);
  auto found = dds_->partitions.find(rig_id);
  if (found == dds_->partitions.end()) {
    MPDRIG_RETURN_IF_ERROR(dds::CheckSecureRigId(rig_id));
    auto publisher = dds::CreatePublisher(p, dds::RigPartition(rig_id));
    if (!publisher.ok()) return publisher.status();
    auto subscriber = dds::CreateSubscriber(p, dds::RigPartition(rig_id));
    if (!subscriber.ok()) return subscriber.status();
    found =
        dds_->partitions
            .emplace(rig_id, std::pair{std::move(publisher).value(), std::move(subscriber).value()})
            .first;
  }
  return Scope{found->second.first.handle(), found->second.second.handle()};
}

Status Participant::EndpointError(const Status& error, const std::string& rig_id,
                                  const char* what) const {
  if (!secure() || error.message().find(dds_strretcode(DDS_RETCODE_NOT_ALLOWED_BY_SECURITY)) ==
                       std::string::npos) {
    return error;
  }
  return Status::Error("DDS Security: the permissions of " + options_.security_dir +
                       " do not allow " + what + " rig '" + rig_id + "' (partition " +
                       dds::RigPartition(rig_id) + "; make-class NAME:WATCH grants reading)");
}

}  // namespace mpdrig::client
