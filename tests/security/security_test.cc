// Who may command which rig: a real `mpdrig serve --security` process with a class
// made by deploy/security/make-class (students alice and bob, bob may watch alice's rig), and in
// this process participants of several identities (the instructor, alice, bob, an intruder
// without security). Each participant has a domain instance of its own that speaks the
// service's domain on the wire (Cyclone's Discovery/ExternalDomainId), so every pair talks over
// loopback RTPS through the security plugins, as separate hosts would; nothing is delivered
// in-process. Loopback only, a domain of the test's own.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "clients/dashboard/rig_feed.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/dds/topics.h"
#include "tests/support/process.h"
#include "tests/support/shell.h"
#include "tests/support/test_domain.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using testing::ReadFile;

constexpr double kInitialChokeDeg = 31.0;    // serve's default
constexpr double kChokeToleranceDeg = 0.01;  // noise-free sensors: the position is exact

// A process's options: stdout and stderr into `log_path`; stopped with SIGINT (tshark then
// finishes its capture file), SIGKILL 5 s later.
testing::ChildOptions Logged(const std::string& log_path) {
  testing::ChildOptions options = testing::ChildOptions::Log(log_path);
  options.stop_signal = SIGINT;
  options.stop_grace_s = 5.0;
  return options;
}

// The loopback configuration of a local domain whose participants meet on `wire_domain`: each
// identity of a class needs a domain of its own in one process (its security settings are the
// participant's), and ExternalDomainId puts them all on the service's wire domain.
std::string OnWireDomain(int wire_domain) {
  std::string config = dds::LoopbackConfig();
  const std::string discovery = "<Discovery>";
  config.replace(
      config.find(discovery), discovery.size(),
      discovery + "<ExternalDomainId>" + std::to_string(wire_domain) + "</ExternalDomainId>");
  return config;
}

// A participant with a domain instance of its own that is `wire_domain` on the wire.
class Peer {
 public:
  // `security_dir` empty: no security (an intruder).
  static std::unique_ptr<Peer> Create(int wire_domain, const std::string& security_dir) {
    auto peer = std::unique_ptr<Peer>(new Peer());
    peer->local_domain_ = static_cast<dds_domainid_t>(testing::ClaimTestDomain());
    auto domain = dds::Domain::Create(peer->local_domain_, OnWireDomain(wire_domain));
    EXPECT_TRUE(domain.ok()) << domain.status().message();
    if (!domain.ok()) return nullptr;
    peer->domain_.emplace(std::move(domain).value());
    std::optional<dds::SecurityFiles> files;
    if (!security_dir.empty()) {
      auto loaded = dds::LoadSecurityDirectory(security_dir);
      EXPECT_TRUE(loaded.ok()) << loaded.status().message();
      if (!loaded.ok()) return nullptr;
      files = *loaded;
    }
    auto participant = dds::CreateParticipant(peer->local_domain_, files ? &*files : nullptr);
    EXPECT_TRUE(participant.ok()) << participant.status().message();
    if (!participant.ok()) return nullptr;
    peer->participant_ = std::move(participant).value();
    return peer;
  }

  dds_entity_t Topic(const dds_topic_descriptor_t* descriptor, const char* name) {
    for (auto& [topic_name, entity] : topics_) {
      if (topic_name == name) return entity->handle();
    }
    auto topic = dds::CreateTopic(participant_.handle(), descriptor, name);
    EXPECT_TRUE(topic.ok()) << topic.status().message();
    topics_.emplace_back(name, std::make_unique<dds::Entity>(std::move(topic).value()));
    return topics_.back().second->handle();
  }
  // A publisher or subscriber in `partition` ("" for the default partition: the participant).
  dds_entity_t Publisher(const std::string& partition) { return Scope(partition, true); }
  dds_entity_t Subscriber(const std::string& partition) { return Scope(partition, false); }

  template <typename T>
  Result<dds::Writer<T>> MakeWriter(const std::string& partition,
                                    const dds_topic_descriptor_t* descriptor, const char* topic,
                                    const dds::Qos& qos) {
    return dds::Writer<T>::Create(Publisher(partition), Topic(descriptor, topic), qos);
  }
  template <typename T>
  Result<dds::Reader<T>> MakeReader(const std::string& partition,
                                    const dds_topic_descriptor_t* descriptor, const char* topic,
                                    const dds::Qos& qos) {
    return dds::Reader<T>::Create(Subscriber(partition), Topic(descriptor, topic), qos);
  }

 private:
  Peer() = default;
  dds_entity_t Scope(const std::string& partition, bool publisher) {
    if (partition.empty()) return participant_.handle();
    for (auto& scope : scopes_) {
      if (scope.partition == partition && scope.publisher == publisher)
        return scope.entity->handle();
    }
    auto created = publisher ? dds::CreatePublisher(participant_.handle(), partition)
                             : dds::CreateSubscriber(participant_.handle(), partition);
    EXPECT_TRUE(created.ok()) << created.status().message();
    scopes_.push_back(
        {partition, publisher, std::make_unique<dds::Entity>(std::move(created).value())});
    return scopes_.back().entity->handle();
  }
  struct ScopeEntry {
    std::string partition;
    bool publisher;
    std::unique_ptr<dds::Entity> entity;
  };
  dds_domainid_t local_domain_ = 0;
  std::optional<dds::Domain> domain_;
  dds::Entity participant_;
  std::vector<std::pair<std::string, std::unique_ptr<dds::Entity>>> topics_;
  std::vector<ScopeEntry> scopes_;
};

// Reads one rig's sensors and status, as a peer allowed to.
class RigWatch {
 public:
  RigWatch(Peer& peer, const std::string& rig) : rig_(rig) {
    const std::string partition = dds::RigPartition(rig);
    auto sensors = peer.MakeReader<mpdrig_RigSensors>(partition, dds::topics::kSensors.type,
                                                      dds::topics::kSensors.name, dds::SensorQos());
    EXPECT_TRUE(sensors.ok()) << sensors.status().message();
    if (sensors.ok()) sensors_.emplace(std::move(sensors).value());
    auto status = peer.MakeReader<mpdrig_RigStatus>(partition, dds::topics::kStatus.type,
                                                    dds::topics::kStatus.name, dds::StatusQos());
    EXPECT_TRUE(status.ok()) << status.status().message();
    if (status.ok()) status_.emplace(std::move(status).value());
  }
  // Takes what arrived within `wait_s`; true if `done` held for a sensor sample of this rig.
  bool WaitFor(double wait_s, const std::function<bool(double choke_deg)>& done) {
    const auto until = Clock::now() + std::chrono::duration<double>(wait_s);
    bool met = false;
    while (!met && Clock::now() < until) {
      if (!sensors_) return false;
      (void)sensors_->Wait(DDS_MSECS(50));
      (void)sensors_->TakeEach([&](const mpdrig_RigSensors& s, const dds_sample_info_t&) {
        if (rig_ != s.rig_id) return;
        ++samples_;
        choke_deg_ = s.choke_position_deg;
        if (done(s.choke_position_deg)) met = true;
      });
      TakeStatus();
    }
    return met;
  }
  // The choke over `seconds`: the largest distance from `deg` it reached.
  double MaxDeviation(double seconds, double deg) {
    double worst = 0.0;
    WaitFor(seconds, [&](double choke) {
      worst = std::max(worst, std::fabs(choke - deg));
      return false;
    });
    return worst;
  }
  void TakeStatus() {
    if (!status_) return;
    (void)status_->TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
      if (rig_ != s.rig_id) return;
      rejected_ = s.rejected_commands;
      last_rejection_ = s.last_rejection;
      owners_.clear();
      for (std::uint32_t i = 0; i < s.actuator_owners._length; ++i)
        owners_ += std::string(s.actuator_owners._buffer[i]) + "\n";
    });
  }
  long samples() const { return samples_; }
  double choke_deg() const { return choke_deg_; }
  std::uint64_t rejected() const { return rejected_; }
  const std::string& last_rejection() const { return last_rejection_; }
  const std::string& owners() const { return owners_; }

 private:
  std::string rig_;
  std::optional<dds::Reader<mpdrig_RigSensors>> sensors_;
  std::optional<dds::Reader<mpdrig_RigStatus>> status_;
  long samples_ = 0;
  double choke_deg_ = std::nan("");
  std::uint64_t rejected_ = 0;
  std::string last_rejection_;
  std::string owners_;
};

// A controller's choke writer on one rig's partition.
class Choke {
 public:
  Choke(Peer& peer, const std::string& partition_rig, int strength) {
    auto writer = peer.MakeWriter<mpdrig_ChokeCommand>(
        partition_rig.empty() ? "" : dds::RigPartition(partition_rig),
        dds::topics::kChokeCommand.type, dds::topics::kChokeCommand.name,
        dds::CommandQos(strength));
    status_ = writer.ok() ? Status::Ok() : writer.status();
    if (writer.ok()) writer_.emplace(std::move(writer).value());
  }
  const Status& created() const { return status_; }
  void Send(const std::string& rig, double opening_deg) {
    ASSERT_TRUE(writer_.has_value()) << status_.message();
    mpdrig_ChokeCommand command{const_cast<char*>(rig.c_str()), opening_deg};
    ASSERT_TRUE(writer_->Write(command).ok());
  }
  // The writer's GUID as the service's status prints it (hex).
  std::string Guid() const {
    dds_guid_t guid;
    if (!writer_ || dds_get_guid(writer_->handle(), &guid) != DDS_RETCODE_OK) return "?";
    std::string hex;
    char byte[3];
    for (unsigned char b : guid.v) {
      std::snprintf(byte, sizeof byte, "%02x", b);
      hex += byte;
    }
    return hex;
  }
  void Delete() { writer_.reset(); }

 private:
  Status status_ = Status::Ok();
  std::optional<dds::Writer<mpdrig_ChokeCommand>> writer_;
};

class SecureClass : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("mpdrig-security-test-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    const std::string make = std::string(MAKE_CLASS) + " " + dir_.string() + " alice bob:alice >" +
                             dir_.string() + ".make.log 2>&1";
    ASSERT_EQ(std::system(make.c_str()), 0) << ReadFile(dir_.string() + ".make.log");
    domain_ = testing::ClaimTestDomain();
    ASSERT_GT(domain_, 0);
  }
  void TearDown() override {
    if (service_) service_->Stop();
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
    fs::remove(dir_.string() + ".make.log", ignored);
  }

  // mpdrig serve --security with rigs alice and bob, real time at 100 Hz, noise-free sensors;
  // waits until the instructor sees alice's sensors (authentication, then discovery).
  void StartService(const std::vector<std::string>& extra = {}) {
    service_log_ = dir_.string() + "/serve.log";
    std::vector<std::string> args{MPDRIG_EXE,       "serve",
                                  "--security",     (dir_ / "service").string(),
                                  "--domain",       std::to_string(domain_),
                                  "--rig",          "alice",
                                  "--rig",          "bob",
                                  "--sensor-noise", "none",
                                  "--duration",     "120"};
    args.insert(args.end(), extra.begin(), extra.end());
    service_.emplace(args, Logged(service_log_));
    ASSERT_TRUE(service_->started());
    instructor_ = Peer::Create(domain_, (dir_ / "instructor").string());
    ASSERT_NE(instructor_, nullptr);
    watch_alice_ = std::make_unique<RigWatch>(*instructor_, "alice");
    watch_bob_ = std::make_unique<RigWatch>(*instructor_, "bob");
    ASSERT_TRUE(watch_alice_->WaitFor(30.0, [](double) { return true; }))
        << "the instructor saw no sensor sample of alice's rig in 30 s; serve said:\n"
        << ReadFile(service_log_);
    ASSERT_TRUE(watch_bob_->WaitFor(10.0, [](double) { return true; }));
  }
  std::string Dir(const char* name) const { return (dir_ / name).string(); }

  fs::path dir_;
  int domain_ = 0;
  std::string service_log_;
  std::optional<testing::ChildProcess> service_;
  std::unique_ptr<Peer> instructor_;
  std::unique_ptr<RigWatch> watch_alice_, watch_bob_;
};

TEST_F(SecureClass, ServiceRefusesAnInvalidSecurityDirectorySayingWhy) {
  struct Case {
    std::string dir;
    std::string expected;
  };
  fs::create_directories(dir_ / "broken");
  for (const char* file : {"identity_ca.pem", "identity.pem", "identity_key.pem",
                           "permissions_ca.pem", "governance.p7s", "permissions.p7s"}) {
    fs::copy_file(dir_ / "alice" / file, dir_ / "broken" / file);
  }
  fs::remove(dir_ / "broken" / "identity.pem");
  // alice's files with the governance where the permissions belong.
  fs::create_directories(dir_ / "swapped");
  for (const char* file : {"identity_ca.pem", "identity.pem", "identity_key.pem",
                           "permissions_ca.pem", "governance.p7s"}) {
    fs::copy_file(dir_ / "alice" / file, dir_ / "swapped" / file);
  }
  fs::copy_file(dir_ / "alice" / "governance.p7s", dir_ / "swapped" / "permissions.p7s");
  // alice's certificate with bob's permissions: only Cyclone's access control can tell.
  fs::create_directories(dir_ / "mixed");
  for (const char* file : {"identity_ca.pem", "identity.pem", "identity_key.pem",
                           "permissions_ca.pem", "governance.p7s"}) {
    fs::copy_file(dir_ / "alice" / file, dir_ / "mixed" / file);
  }
  fs::copy_file(dir_ / "bob" / "permissions.p7s", dir_ / "mixed" / "permissions.p7s");
  // alice's files with bob's private key: Cyclone took the pair and every handshake failed, so
  // a client waited 6 s and said the rig was not running.
  fs::create_directories(dir_ / "keyswap");
  for (const char* file : {"identity_ca.pem", "identity.pem", "permissions_ca.pem",
                           "governance.p7s", "permissions.p7s"}) {
    fs::copy_file(dir_ / "alice" / file, dir_ / "keyswap" / file);
  }
  fs::copy_file(dir_ / "bob" / "identity_key.pem", dir_ / "keyswap" / "identity_key.pem");
  const Case cases[] = {
      {(dir_ / "keyswap").string(), "does not match the certificate"},
      {(dir_ / "nowhere").string(), "does not exist"},
      {(dir_ / "broken").string(), "missing " + (dir_ / "broken" / "identity.pem").string()},
      {(dir_ / "swapped").string(), "is not signed DDS Security permissions"},
      {(dir_ / "mixed").string(), "DDS Security refused the identity in"},
  };
  for (const Case& c : cases) {
    const std::string log = dir_.string() + "/refused.log";
    testing::ChildProcess serve({MPDRIG_EXE, "serve", "--security", c.dir, "--domain",
                                 std::to_string(domain_), "--rig", "alice", "--duration", "1"},
                                Logged(log));
    ASSERT_TRUE(serve.started());
    // It must exit by itself with an error (refused), not run.
    const int status = serve.Wait(20.0);
    const std::string said = ReadFile(log);
    EXPECT_GT(status, 0) << c.dir;
    EXPECT_NE(said.find(c.expected), std::string::npos) << c.dir << ":\n" << said;
    EXPECT_EQ(said.find("rigs alice on DDS domain"), std::string::npos) << "it started:\n" << said;
  }
  // A client too, and a rig id that would be a wildcard in a permission.
  const std::string log = dir_.string() + "/client.log";
  {
    testing::ChildProcess echo(
        {RIG_ECHO_EXE, "--security", (dir_ / "swapped").string(), "--rig", "alice", "--domain",
         std::to_string(domain_), "--samples", "1", "--out", "/dev/null"},
        Logged(log));
    EXPECT_GT(echo.Wait(20.0), 0);
  }
  EXPECT_NE(ReadFile(log).find("is not signed DDS Security permissions"), std::string::npos)
      << ReadFile(log);
  {
    testing::ChildProcess echo(
        {RIG_ECHO_EXE, "--security", (dir_ / "keyswap").string(), "--rig", "alice", "--domain",
         std::to_string(domain_), "--samples", "1", "--out", "/dev/null"},
        Logged(log));
    EXPECT_GT(echo.Wait(20.0), 0);
  }
  EXPECT_NE(ReadFile(log).find("does not match the certificate"), std::string::npos)
      << ReadFile(log);
  {
    testing::ChildProcess echo(
        {RIG_ECHO_EXE, "--security", (dir_ / "alice").string(), "--rig", "al*", "--domain",
         std::to_string(domain_), "--samples", "1", "--out", "/dev/null"},
        Logged(log));
    EXPECT_GT(echo.Wait(20.0), 0);
  }
  EXPECT_NE(ReadFile(log).find("rig id 'al*'"), std::string::npos) << ReadFile(log);
}

TEST_F(SecureClass, UnauthenticatedParticipantReadsNothingAndCommandsNothing) {
  StartService();
  auto intruder = Peer::Create(domain_, "");
  ASSERT_NE(intruder, nullptr);
  // Everywhere it could look: alice's partition and the default one.
  RigWatch in_partition(*intruder, "alice");
  auto in_default = intruder->MakeReader<mpdrig_RigSensors>(
      "", dds::topics::kSensors.type, dds::topics::kSensors.name, dds::SensorQos());
  ASSERT_TRUE(in_default.ok());
  Choke forged(*intruder, "alice", 1000);
  Choke forged_default(*intruder, "", 1000);
  ASSERT_TRUE(forged.created().ok());
  for (int i = 0; i < 10; ++i) {
    forged.Send("alice", 80.0);
    forged_default.Send("alice", 80.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  // Meanwhile (and 2 s more) the instructor sees alice's rig run with its choke where it was.
  EXPECT_LT(watch_alice_->MaxDeviation(3.0, kInitialChokeDeg), kChokeToleranceDeg);
  EXPECT_GT(watch_alice_->samples(), 200) << "the rig did not run while the intruder tried";
  (void)in_partition.WaitFor(0.5, [](double) { return false; });
  EXPECT_EQ(in_partition.samples(), 0);
  long in_default_samples = 0;
  (void)in_default->TakeEach(
      [&](const mpdrig_RigSensors&, const dds_sample_info_t&) { ++in_default_samples; });
  EXPECT_EQ(in_default_samples, 0);
  // The same command from alice herself moves her rig's choke (so the path above was open).
  auto alice = Peer::Create(domain_, Dir("alice"));
  ASSERT_NE(alice, nullptr);
  Choke own(*alice, "alice", 10);
  ASSERT_TRUE(own.created().ok()) << own.created().message();
  own.Send("alice", 50.0);
  EXPECT_TRUE(watch_alice_->WaitFor(10.0, [](double c) { return std::fabs(c - 50.0) < 0.01; }))
      << "alice's choke at " << watch_alice_->choke_deg();
}

TEST_F(SecureClass, StudentCannotCommandAnotherStudentsRigAndTheServiceReportsTheWriter) {
  StartService();
  auto alice = Peer::Create(domain_, Dir("alice"));
  auto bob = Peer::Create(domain_, Dir("bob"));
  ASSERT_NE(alice, nullptr);
  ASSERT_NE(bob, nullptr);
  Choke bobs(*bob, "bob", 10);
  ASSERT_TRUE(bobs.created().ok()) << bobs.created().message();
  bobs.Send("bob", 40.0);
  ASSERT_TRUE(watch_bob_->WaitFor(10.0, [](double c) { return std::fabs(c - 40.0) < 0.01; }))
      << "bob's own command did not reach his rig: choke at " << watch_bob_->choke_deg();

  // Permissions: alice may not even open a writer in bob's partition, nor publish sensors,
  // nor read bob's rig; bob may read alice's (make-class ... bob:alice).
  Choke into_bobs(*alice, "bob", 50);
  EXPECT_FALSE(into_bobs.created().ok());
  auto fake_sensors =
      alice->MakeWriter<mpdrig_RigSensors>(dds::RigPartition("alice"), dds::topics::kSensors.type,
                                           dds::topics::kSensors.name, dds::SensorQos());
  EXPECT_FALSE(fake_sensors.ok()) << "a student may publish sensor data";
  auto peek =
      alice->MakeReader<mpdrig_RigSensors>(dds::RigPartition("bob"), dds::topics::kSensors.type,
                                           dds::topics::kSensors.name, dds::SensorQos());
  EXPECT_FALSE(peek.ok()) << "alice may read bob's rig";
  RigWatch bob_watches_alice(*bob, "alice");
  EXPECT_TRUE(bob_watches_alice.WaitFor(10.0, [](double) { return true; }));

  // What alice can do: a command for bob's rig in her own partition, stronger than bob's.
  Choke alices(*alice, "alice", 50);
  ASSERT_TRUE(alices.created().ok());
  const auto sent = Clock::now();
  for (int i = 0; i < 5; ++i) {
    alices.Send("bob", 70.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_LT(watch_bob_->MaxDeviation(2.5, 40.0), kChokeToleranceDeg);
  // The service says whose command it refused, on bob's status (and alice's).
  bool reported = false;
  while (!reported && Clock::now() - sent < std::chrono::seconds(5)) {
    watch_bob_->MaxDeviation(0.2, 40.0);
    reported = watch_bob_->last_rejection().find(alices.Guid()) != std::string::npos;
  }
  EXPECT_TRUE(reported) << "bob's status: rejected " << watch_bob_->rejected() << ", last '"
                        << watch_bob_->last_rejection() << "'; alice's writer " << alices.Guid();
  EXPECT_NE(watch_bob_->last_rejection().find("for rig 'bob' refused"), std::string::npos);
  EXPECT_NE(watch_bob_->last_rejection().find("partition rig.alice"), std::string::npos);
  // Bob still commands his rig (alice's instance lives in her partition, not in his reader).
  bobs.Send("bob", 45.0);
  EXPECT_TRUE(watch_bob_->WaitFor(10.0, [](double c) { return std::fabs(c - 45.0) < 0.01; }))
      << "bob's choke at " << watch_bob_->choke_deg();
}

TEST_F(SecureClass, InstructorTakesOverAStudentsRig) {
  StartService();
  auto bob = Peer::Create(domain_, Dir("bob"));
  ASSERT_NE(bob, nullptr);
  Choke bobs(*bob, "bob", 10);
  ASSERT_TRUE(bobs.created().ok());
  bobs.Send("bob", 40.0);
  ASSERT_TRUE(watch_bob_->WaitFor(10.0, [](double c) { return std::fabs(c - 40.0) < 0.01; }));

  Choke instructors(*instructor_, "bob", 100);
  ASSERT_TRUE(instructors.created().ok()) << instructors.created().message();
  instructors.Send("bob", 70.0);
  EXPECT_TRUE(watch_bob_->WaitFor(10.0, [](double c) { return std::fabs(c - 70.0) < 0.01; }))
      << "bob's choke at " << watch_bob_->choke_deg();
  // Bob keeps commanding; the instructor's command stays in force.
  for (int i = 0; i < 10; ++i) {
    bobs.Send("bob", 41.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_LT(watch_bob_->MaxDeviation(1.0, 70.0), kChokeToleranceDeg);
  EXPECT_NE(watch_bob_->owners().find("choke: strength 100"), std::string::npos)
      << watch_bob_->owners();
  // The instructor lets go: bob's next command applies.
  instructors.Delete();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  bobs.Send("bob", 42.0);
  EXPECT_TRUE(watch_bob_->WaitFor(10.0, [](double c) { return std::fabs(c - 42.0) < 0.01; }))
      << "bob's choke at " << watch_bob_->choke_deg();
}

// A student asks for private rigs in their own partition (mpdrig serve --private-rigs).
void AskForPrivateRigs(Peer& student, const std::string& rig, std::uint32_t how_many) {
  const dds::Qos qos = dds::RequestQos();  // as the service reads requests
  auto writer = student.MakeWriter<mpdrig_RigRequest>(
      dds::RigPartition(rig), dds::topics::kRigRequest.type, dds::topics::kRigRequest.name, qos);
  ASSERT_TRUE(writer.ok()) << writer.status().message();
  // The service's reader must have matched (secure discovery) before the request is written.
  dds_publication_matched_status_t matched{};
  for (int i = 0; i < 100 && matched.current_count == 0; ++i) {
    ASSERT_EQ(dds_get_publication_matched_status(writer->handle(), &matched), DDS_RETCODE_OK);
    if (matched.current_count == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_GT(matched.current_count, 0u) << "the service's request reader did not match";
  mpdrig_RigRequest request{const_cast<char*>(rig.c_str()), how_many};
  ASSERT_TRUE(writer->Write(request).ok());
  ASSERT_EQ(dds_wait_for_acks(writer->handle(), DDS_SECS(5)), DDS_RETCODE_OK);
}

TEST_F(SecureClass, StudentGetsAPrivateRigWithinTheServicesLimits) {
  StartService({"--private-rigs", "1", "--max-rigs", "3"});
  auto alice = Peer::Create(domain_, Dir("alice"));
  auto bob = Peer::Create(domain_, Dir("bob"));
  ASSERT_NE(alice, nullptr);
  ASSERT_NE(bob, nullptr);
  RigWatch instructor_on_private(*instructor_, "alice.1");
  EXPECT_FALSE(instructor_on_private.WaitFor(1.0, [](double) { return true; }))
      << "alice.1 ran before anyone asked";
  AskForPrivateRigs(*alice, "alice", 1);
  EXPECT_TRUE(instructor_on_private.WaitFor(15.0, [](double) { return true; }))
      << "no private rig alice.1; serve said:\n"
      << ReadFile(service_log_);
  // Alice reads and commands it; bob may not even read it.
  RigWatch alice_on_private(*alice, "alice.1");
  Choke choke(*alice, "alice.1", 10);
  ASSERT_TRUE(choke.created().ok()) << choke.created().message();
  choke.Send("alice.1", 55.0);
  EXPECT_TRUE(alice_on_private.WaitFor(10.0, [](double c) { return std::fabs(c - 55.0) < 0.01; }))
      << "alice.1's choke at " << alice_on_private.choke_deg();
  auto peek =
      bob->MakeReader<mpdrig_RigSensors>(dds::RigPartition("alice.1"), dds::topics::kSensors.type,
                                         dds::topics::kSensors.name, dds::SensorQos());
  EXPECT_FALSE(peek.ok()) << "bob may read alice's private rig";

  // The limits: one private rig per student (--private-rigs 1), three rigs in all (--max-rigs 3).
  AskForPrivateRigs(*alice, "alice", 2);
  RigWatch instructor_on_second(*instructor_, "alice.2");
  bool refused = false;
  for (int i = 0; i < 50 && !refused; ++i) {
    watch_alice_->MaxDeviation(0.1, 0.0);
    refused = watch_alice_->last_rejection().find("beyond 1") != std::string::npos;
  }
  EXPECT_TRUE(refused) << "alice's status: '" << watch_alice_->last_rejection() << "'";
  AskForPrivateRigs(*bob, "bob", 1);
  RigWatch instructor_on_bobs(*instructor_, "bob.1");
  refused = false;
  for (int i = 0; i < 50 && !refused; ++i) {
    watch_bob_->MaxDeviation(0.1, 0.0);
    refused = watch_bob_->last_rejection().find("limit of 3 rigs") != std::string::npos;
  }
  EXPECT_TRUE(refused) << "bob's status: '" << watch_bob_->last_rejection() << "'";
  EXPECT_FALSE(instructor_on_second.WaitFor(1.0, [](double) { return true; }));
  EXPECT_FALSE(instructor_on_bobs.WaitFor(1.0, [](double) { return true; }));
  // alice.1 kept running through all that.
  const long before = instructor_on_private.samples();
  EXPECT_TRUE(instructor_on_private.WaitFor(
      2.0, [&](double) { return instructor_on_private.samples() > before + 50; }));
}

// The rig_request client as a student runs it: it says what the service made (exit 0), and
// what it refused (exit 1).
TEST_F(SecureClass, RigRequestSaysWhatTheServiceMadeAndRefused) {
  StartService({"--private-rigs", "1"});
  auto request = [&](int count, const std::string& out) {
    testing::ChildProcess process(
        {RIG_REQUEST_EXE, "--security", Dir("alice"), "--rig", "alice", "--private-rigs",
         std::to_string(count), "--domain", std::to_string(domain_), "--timeout", "20"},
        Logged(out));
    return process.Wait(40.0);
  };
  const std::string made = Dir("request-1.txt");
  EXPECT_EQ(request(1, made), 0) << ReadFile(made) << "\nserve said:\n" << ReadFile(service_log_);
  EXPECT_NE(ReadFile(made).find("private rig alice.1 runs"), std::string::npos) << ReadFile(made);
  RigWatch instructor_on_private(*instructor_, "alice.1");
  EXPECT_TRUE(instructor_on_private.WaitFor(10.0, [](double) { return true; }));
  const std::string beyond = Dir("request-2.txt");
  EXPECT_EQ(request(2, beyond), 1) << ReadFile(beyond);
  EXPECT_NE(ReadFile(beyond).find("refused beyond 1"), std::string::npos) << ReadFile(beyond);
}

// The dashboard's feed under security: with alice's identity it shows her rig, read in its
// partition; without an identity it sees nothing of the secure service; it refuses, saying why,
// two rigs or a directory that is no identity.
TEST_F(SecureClass, DashboardWithAStudentsIdentityShowsHerRigAndNothingWithout) {
  StartService();
  const auto watch = [&](const std::string& security, double seconds) {
    dashboard::FeedOptions options;
    options.domain = testing::ClaimTestDomain();
    options.dds_config = OnWireDomain(domain_);
    options.rigs = {"alice"};
    options.security_dir = security;
    auto feed = dashboard::RigFeed::Create(options);
    EXPECT_TRUE(feed.ok()) << feed.status().message();
    std::string state;
    if (!feed.ok()) return state;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end &&
           state.find("\"sensors\"") == std::string::npos) {
      (*feed)->Touch();  // a browser polling
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      state = (*feed)->StateJson("alice", 0) + (*feed)->Health().error;
    }
    return state;
  };
  const std::string with_identity = watch(Dir("alice"), 30.0);
  EXPECT_NE(with_identity.find("\"sensors\""), std::string::npos) << with_identity;
  const std::string without = watch("", 3.0);
  EXPECT_EQ(without.find("\"sensors\""), std::string::npos) << without;

  dashboard::FeedOptions two;
  two.domain = testing::ClaimTestDomain();
  two.rigs = {"alice", "bob"};
  two.security_dir = Dir("alice");
  auto refused = dashboard::RigFeed::Create(two);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("one rig"), std::string::npos)
      << refused.status().message();
  two.rigs = {"alice"};
  two.security_dir = Dir("nobody");
  refused = dashboard::RigFeed::Create(two);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("--security"), std::string::npos)
      << refused.status().message();
}

// A shadow model under security: alice runs `mpdrig shadow` of her rig with her identity (its
// topics in her rig's partition) and switches it with shadow_ctl; bob, who may watch alice's rig,
// reads her shadow's status but may not switch it (his permissions publish only in his own
// partitions); without security nobody sees it.
TEST_F(SecureClass, StudentRunsAShadowOfHerRigThatOnlySheSwitches) {
  StartService();
  const std::string shadow_log = Dir("shadow.log");
  testing::ChildProcess shadow(
      {MPDRIG_EXE, "shadow", "--security", Dir("alice"), "--rig", "alice", "--domain",
       std::to_string(domain_), "--warmup-s", "1", "--window-s", "2", "--duration", "60"},
      Logged(shadow_log));
  ASSERT_TRUE(shadow.started());
  auto ctl = [&](const std::string& who, const std::vector<std::string>& extra,
                 const std::string& out) {
    std::vector<std::string> args{SHADOW_CTL_EXE,          "--rig",     "alice", "--domain",
                                  std::to_string(domain_), "--timeout", "20"};
    if (!who.empty()) args.insert(args.end(), {"--security", Dir(who.c_str())});
    args.insert(args.end(), extra.begin(), extra.end());
    testing::ChildProcess process(args, Logged(out));
    return process.Wait(30.0);
  };
  const std::string alice_out = Dir("ctl-alice.txt");
  EXPECT_EQ(ctl("alice", {"--effect-on", "unsteady_friction"}, alice_out), 0)
      << ReadFile(alice_out) << "\nshadow said:\n"
      << ReadFile(shadow_log);
  EXPECT_NE(ReadFile(alice_out).find("effects: [unsteady_friction"), std::string::npos)
      << ReadFile(alice_out);
  // Bob reads it (alice's rig is one he watches) but cannot switch it.
  const std::string bob_read = Dir("ctl-bob-read.txt");
  EXPECT_EQ(ctl("bob", {}, bob_read), 0) << ReadFile(bob_read);
  EXPECT_NE(ReadFile(bob_read).find("shadow 'shadow' of alice"), std::string::npos)
      << ReadFile(bob_read);
  const std::string bob_switch = Dir("ctl-bob-switch.txt");
  EXPECT_NE(ctl("bob", {"--effect-off", "unsteady_friction"}, bob_switch), 0)
      << ReadFile(bob_switch);
  // Without security: no answer at all.
  const std::string intruder = Dir("ctl-intruder.txt");
  std::vector<std::string> args{SHADOW_CTL_EXE,          "--rig",     "alice", "--domain",
                                std::to_string(domain_), "--timeout", "3"};
  testing::ChildProcess open(args, Logged(intruder));
  EXPECT_EQ(open.Wait(15.0), 1) << ReadFile(intruder);
  // Alice's shadow still has its effect: bob's command never reached it.
  const std::string alice_again = Dir("ctl-alice-again.txt");
  EXPECT_EQ(ctl("alice", {}, alice_again), 0) << ReadFile(alice_again);
  EXPECT_NE(ReadFile(alice_again).find("effects: [unsteady_friction"), std::string::npos)
      << ReadFile(alice_again);
}

// The 8 bytes of a double as it goes on the wire (little-endian CDR on this machine).
std::string Bytes(double value) {
  std::string bytes(sizeof value, '\0');
  std::memcpy(bytes.data(), &value, sizeof value);
  return bytes;
}
// A CDR string as it goes on the wire: length (with the terminator), the text, the terminator.
std::string CdrString(const std::string& text) {
  const std::uint32_t length = static_cast<std::uint32_t>(text.size() + 1);
  std::string bytes(sizeof length, '\0');
  std::memcpy(bytes.data(), &length, sizeof length);
  return bytes + text + std::string(1, '\0');
}

TEST_F(SecureClass, PayloadsAreNotReadableOnTheWire) {
  if (std::system("command -v tshark >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "tshark is not installed (deploy/install-deps.sh installs it): the wire "
                    "is not checked";
  }
  const std::string capture = dir_.string() + "/wire.pcapng";
  const std::string tshark_log = dir_.string() + "/tshark.log";
  testing::ChildProcess tshark({"/usr/bin/tshark", "-i", "lo", "-f", "udp", "-w", capture},
                               Logged(tshark_log));
  ASSERT_TRUE(tshark.started());
  for (int i = 0; i < 100 && ReadFile(tshark_log).find("Capturing on") == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ASSERT_NE(ReadFile(tshark_log).find("Capturing on"), std::string::npos) << ReadFile(tshark_log);

  // Secured: alice's command with an opening nothing else sends, and her rig's sensor samples
  // (each carries the key "alice" as a CDR string).
  StartService();
  auto alice = Peer::Create(domain_, Dir("alice"));
  ASSERT_NE(alice, nullptr);
  RigWatch alice_watches(*alice, "alice");
  Choke alices(*alice, "alice", 10);
  const double secret_deg = 37.0123456789;
  alices.Send("alice", secret_deg);
  ASSERT_TRUE(
      alice_watches.WaitFor(10.0, [&](double c) { return std::fabs(c - secret_deg) < 1e-6; }))
      << "alice's choke at " << alice_watches.choke_deg();
  EXPECT_GT(alice_watches.samples(), 50);

  // Unsecured, in the same capture (the control that shows the capture sees payloads): two
  // plain participants on another domain, a command with another opening for rig "carol".
  const int plain_domain = testing::ClaimTestDomain();
  auto plain_writer = Peer::Create(plain_domain, "");
  auto plain_reader = Peer::Create(plain_domain, "");
  ASSERT_NE(plain_writer, nullptr);
  ASSERT_NE(plain_reader, nullptr);
  auto reader = plain_reader->MakeReader<mpdrig_ChokeCommand>(
      "", dds::topics::kChokeCommand.type, dds::topics::kChokeCommand.name, dds::CommandQos());
  ASSERT_TRUE(reader.ok());
  Choke plain(*plain_writer, "", 10);
  const double plain_deg = 38.0123456789;
  bool received = false;
  for (int i = 0; i < 100 && !received; ++i) {
    plain.Send("carol", plain_deg);
    (void)reader->Wait(DDS_MSECS(100));
    (void)reader->TakeEach([&](const mpdrig_ChokeCommand& c, const dds_sample_info_t&) {
      received = received || c.opening_deg == plain_deg;
    });
  }
  ASSERT_TRUE(received);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  tshark.Stop();

  const std::string wire = ReadFile(capture);
  ASSERT_GT(wire.size(), 1000u) << ReadFile(tshark_log);
  EXPECT_NE(wire.find(Bytes(plain_deg)), std::string::npos) << "the control is not on the wire";
  EXPECT_NE(wire.find(CdrString("carol")), std::string::npos) << "the control is not on the wire";
  EXPECT_EQ(wire.find(Bytes(secret_deg)), std::string::npos) << "alice's command is readable";
  EXPECT_EQ(wire.find(CdrString("alice")), std::string::npos) << "alice's samples are readable";
  // tshark's RTPS dissector: the secured traffic goes in SEC_BODY submessages (id 0x30).
  const std::string count_log = dir_.string() + "/sec_body.txt";
  const std::string count =
      "tshark -r " + capture + " -Y 'rtps.sm.id == 0x30' 2>/dev/null | wc -l >" + count_log;
  ASSERT_EQ(std::system(count.c_str()), 0);
  EXPECT_GT(std::atol(ReadFile(count_log).c_str()), 50) << "no encrypted RTPS submessages decoded";
}

}  // namespace
}  // namespace mpdrig
