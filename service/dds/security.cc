#include "service/dds/security.h"

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <sys/stat.h>

#include <cstdio>
#include <memory>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace mpdrig::dds {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHowToMake =
    " (deploy/security/make-class OUT NAME... makes the directories OUT/service, "
    "OUT/instructor and OUT/NAME)";

// Whether the private key in `key_path` belongs to the certificate in `certificate_path`: else
// Cyclone accepts the pair, the handshake fails on every peer, and the client only times out
// ("the rig is not running") instead of saying what is wrong.
Status CheckKeyMatchesCertificate(const std::string& certificate_path,
                                  const std::string& key_path) {
  auto read = [](const std::string& path, auto reader) {
    std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "r"), &std::fclose);
    return file ? reader(file.get()) : nullptr;
  };
  std::unique_ptr<X509, void (*)(X509*)> certificate(
      read(certificate_path, [](FILE* f) { return PEM_read_X509(f, nullptr, nullptr, nullptr); }),
      &X509_free);
  if (!certificate) return Status::Error(certificate_path + " is not a readable PEM certificate");
  std::unique_ptr<EVP_PKEY, void (*)(EVP_PKEY*)> key(
      read(key_path,
           [](FILE* f) {
             // Without a passphrase callback OpenSSL would prompt on the terminal: refuse instead.
             pem_password_cb* no_passphrase = [](char*, int, int, void*) { return 0; };
             return PEM_read_PrivateKey(f, nullptr, no_passphrase, nullptr);
           }),
      &EVP_PKEY_free);
  if (!key) {
    return Status::Error(key_path + " is not a readable PEM private key (or it has a passphrase)");
  }
  if (X509_check_private_key(certificate.get(), key.get()) != 1) {
    return Status::Error(key_path + " does not match the certificate " + certificate_path +
                         ": the key belongs to another identity (copy both from one directory "
                         "that deploy/security/make-class made)");
  }
  return Status::Ok();
}

// Reads a file of the directory, or says what is wrong with it.
Result<std::string> ReadPart(const fs::path& path) {
  std::error_code error;
  if (!fs::exists(path, error)) return Status::Error("missing " + path.string() + kHowToMake);
  if (!fs::is_regular_file(path, error)) return Status::Error(path.string() + " is not a file");
  std::ifstream file(path);
  if (!file) return Status::Error(path.string() + ": cannot read it");
  std::ostringstream text;
  text << file.rdbuf();
  if (text.str().empty()) return Status::Error(path.string() + " is empty");
  return text.str();
}

// The file must contain every one of `marks` (what tells a certificate from a key, a signed
// document from a plain one, governance from permissions).
Result<std::string> CheckPart(const fs::path& dir, const char* name, const char* what,
                              std::initializer_list<const char*> marks) {
  const fs::path path = dir / name;
  auto text = ReadPart(path);
  if (!text.ok()) return text.status();
  for (const char* mark : marks) {
    if (text->find(mark) == std::string::npos) {
      return Status::Error(path.string() + " is not " + what + " (no '" + mark + "' in it)");
    }
  }
  return path.string();
}

}  // namespace

Result<SecurityFiles> LoadSecurityDirectory(const std::string& dir) {
  std::error_code error;
  const fs::path root = fs::absolute(dir, error);
  if (dir.empty() || error) return Status::Error("security directory '" + dir + "': bad path");
  if (!fs::exists(root, error)) {
    return Status::Error("security directory " + root.string() + " does not exist" + kHowToMake);
  }
  if (!fs::is_directory(root, error)) {
    return Status::Error("security directory " + root.string() + " is not a directory");
  }
  SecurityFiles files;
  files.dir = root.string();
  const char* certificate = "-----BEGIN CERTIFICATE-----";
  const char* signed_mime = "Content-Type: multipart/signed";
  struct Part {
    std::string* out;
    const char* name;
    const char* what;
    std::initializer_list<const char*> marks;
  };
  const Part parts[] = {
      {&files.identity_ca, "identity_ca.pem", "a PEM certificate (the class's CA)", {certificate}},
      {&files.identity_certificate, "identity.pem", "a PEM certificate", {certificate}},
      {&files.private_key, "identity_key.pem", "a PEM private key", {"-----BEGIN", "PRIVATE KEY"}},
      {&files.permissions_ca, "permissions_ca.pem", "a PEM certificate", {certificate}},
      {&files.governance,
       "governance.p7s",
       "signed DDS Security governance (S/MIME)",
       {signed_mime, "<domain_access_rules>"}},
      {&files.permissions,
       "permissions.p7s",
       "signed DDS Security permissions (S/MIME)",
       {signed_mime, "<permissions>", "<subject_name>"}},
  };
  for (const Part& part : parts) {
    auto path = CheckPart(root, part.name, part.what, part.marks);
    if (!path.ok()) return path.status();
    *part.out = *path;
  }
  MPDRIG_RETURN_IF_ERROR(CheckKeyMatchesCertificate(files.identity_certificate, files.private_key));
  // The private key is the identity: one that others on the machine can read is no identity.
  struct stat key_stat {};
  if (::stat(files.private_key.c_str(), &key_stat) == 0 && (key_stat.st_mode & 077) != 0) {
    return Status::Error(files.private_key +
                         " is readable by other users: chmod 600 it (it is the identity)");
  }
  for (const char* plugin :
       {"libdds_security_auth.so", "libdds_security_ac.so", "libdds_security_crypto.so"}) {
    const fs::path path = fs::path(files.plugin_dir) / plugin;
    if (!fs::exists(path, error)) {
      return Status::Error("DDS Security plugin " + path.string() +
                           " not found (Debian's libddsc0debian ships it)");
    }
  }
  return files;
}

Result<Entity> CreateParticipant(dds_domainid_t domain, const SecurityFiles* security) {
  if (security == nullptr) return CreateParticipant(domain);
  Qos qos;
  dds_qos_t* q = qos.get();
  const std::string lib = security->plugin_dir + "/";
  dds_qset_prop(q, "dds.sec.auth.library.path", (lib + "libdds_security_auth.so").c_str());
  dds_qset_prop(q, "dds.sec.auth.library.init", "init_authentication");
  dds_qset_prop(q, "dds.sec.auth.library.finalize", "finalize_authentication");
  dds_qset_prop(q, "dds.sec.access.library.path", (lib + "libdds_security_ac.so").c_str());
  dds_qset_prop(q, "dds.sec.access.library.init", "init_access_control");
  dds_qset_prop(q, "dds.sec.access.library.finalize", "finalize_access_control");
  dds_qset_prop(q, "dds.sec.crypto.library.path", (lib + "libdds_security_crypto.so").c_str());
  dds_qset_prop(q, "dds.sec.crypto.library.init", "init_crypto");
  dds_qset_prop(q, "dds.sec.crypto.library.finalize", "finalize_crypto");
  dds_qset_prop(q, "dds.sec.auth.identity_ca", ("file:" + security->identity_ca).c_str());
  dds_qset_prop(q, "dds.sec.auth.identity_certificate",
                ("file:" + security->identity_certificate).c_str());
  dds_qset_prop(q, "dds.sec.auth.private_key", ("file:" + security->private_key).c_str());
  dds_qset_prop(q, "dds.sec.access.permissions_ca", ("file:" + security->permissions_ca).c_str());
  dds_qset_prop(q, "dds.sec.access.governance", ("file:" + security->governance).c_str());
  dds_qset_prop(q, "dds.sec.access.permissions", ("file:" + security->permissions).c_str());
  const dds_entity_t handle = dds_create_participant(domain, q, nullptr);
  if (handle < 0) {
    return Status::Error(
        "DDS Security refused the identity in " + security->dir + " (" + dds_strretcode(handle) +
        "; Cyclone's message above says why: e.g. a certificate not signed by the class's CA, "
        "expired permissions, or permissions of another identity)");
  }
  return Entity(handle);
}

std::string RigPartition(const std::string& rig_id) { return "rig." + rig_id; }

Status CheckSecureRigId(const std::string& rig_id) {
  // NAME, or NAME.N for a private rig (the service names those; make-class refuses a '.').
  const std::size_t dot = rig_id.find('.');
  const std::string name = rig_id.substr(0, dot);
  bool ok = !name.empty() && name.size() <= 64;
  for (char c : name) {
    ok = ok && ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                c == '_' || c == '-');
  }
  if (dot != std::string::npos) {
    const std::string number = rig_id.substr(dot + 1);
    ok = ok && !number.empty() && number.size() <= 4 && number[0] != '0';
    for (char c : number) ok = ok && c >= '0' && c <= '9';
  }
  if (ok) return Status::Ok();
  return Status::Error("rig id '" + rig_id +
                       "': with --security a rig id names a partition and a permission, so it "
                       "is 1-64 of A-Z a-z 0-9 _ - (make-class names students the same way), or "
                       "NAME.N for a private rig");
}

Result<Entity> CreatePublisher(dds_entity_t participant, const std::string& partition) {
  Qos qos;
  const char* name = partition.c_str();
  dds_qset_partition(qos.get(), 1, &name);
  const dds_entity_t handle = dds_create_publisher(participant, qos.get(), nullptr);
  if (handle < 0) return Check(handle, ("dds_create_publisher " + partition).c_str());
  return Entity(handle);
}

Result<Entity> CreateSubscriber(dds_entity_t participant, const std::string& partition) {
  Qos qos;
  const char* name = partition.c_str();
  dds_qset_partition(qos.get(), 1, &name);
  const dds_entity_t handle = dds_create_subscriber(participant, qos.get(), nullptr);
  if (handle < 0) return Check(handle, ("dds_create_subscriber " + partition).c_str());
  return Entity(handle);
}

Result<ClientScope> CreateClientScope(dds_domainid_t domain, const std::string& security_dir,
                                      const std::string& rig_id) {
  ClientScope scope;
  if (security_dir.empty()) {
    auto participant = CreateParticipant(domain);
    if (!participant.ok()) return participant.status();
    scope.participant = std::move(participant).value();
    return scope;
  }
  auto files = LoadSecurityDirectory(security_dir);
  if (!files.ok()) return files.status().Within("--security");
  MPDRIG_RETURN_IF_ERROR(CheckSecureRigId(rig_id));
  auto participant = CreateParticipant(domain, &*files);
  if (!participant.ok()) return participant.status();
  scope.participant = std::move(participant).value();
  auto publisher = CreatePublisher(scope.participant.handle(), RigPartition(rig_id));
  if (!publisher.ok()) return publisher.status();
  scope.publisher = std::move(publisher).value();
  auto subscriber = CreateSubscriber(scope.participant.handle(), RigPartition(rig_id));
  if (!subscriber.ok()) return subscriber.status();
  scope.subscriber = std::move(subscriber).value();
  return scope;
}

}  // namespace mpdrig::dds
