// rig_request: a student asks a class's service for private rigs, NAME.1 .. NAME.N,
// which only they may command and read (make-class's permissions: rig.NAME.*). The service must
// run with `--security ... --private-rigs N`; it makes the rigs within its limits and says on the
// student's rig's status what it made or refused. A client: it speaks only the DDS topics.
//
//   rig_request --security class/alice --rig alice --private-rigs 1
//   bhp_controller --security class/alice --rig alice.1      # then use it like any rig
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/security.h"
#include "service/dds/topics.h"

namespace {

int Fail(const std::string& what) {
  std::fprintf(stderr, "rig_request: %s\n", what.c_str());
  return 1;
}

struct Args {
  std::string security;
  std::string rig_id;
  unsigned private_rigs = 1;
  int domain = 0;
  std::string dds_config;
  double timeout_s = 20.0;
};

void AddOptions(CLI::App& app, Args& args) {
  app.add_option("--security", args.security,
                 "this student's identity directory (deploy/security/make-class OUT NAME: "
                 "OUT/NAME)")
      ->required();
  app.add_option("--rig", args.rig_id, "this student's rig id (NAME)")->required();
  app.add_option("--private-rigs", args.private_rigs, "how many private rigs in all (NAME.1 ..)")
      ->check(CLI::Range(1u, 9999u))
      ->capture_default_str();
  app.add_option("--domain", args.domain, "DDS domain id")
      ->check(CLI::Range(0, 230))
      ->capture_default_str();
  app.add_option("--dds-config", args.dds_config, "Cyclone DDS XML (default: loopback only)");
  app.add_option("--timeout", args.timeout_s, "give up after this long [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

using StatusReader = mpdrig::dds::Reader<mpdrig_RigStatus>;
using Clock = std::chrono::steady_clock;

// What the rig's status said last: its newest event and refusal, so only news is reported.
struct LastSaid {
  std::string event, rejection;
};

LastSaid ReadLastSaid(StatusReader& status, const std::string& rig_id) {
  LastSaid said;
  (void)status.Wait(DDS_MSECS(500));
  (void)status.TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
    if (rig_id != s.rig_id) return;
    said.rejection = s.last_rejection;
    for (std::uint32_t i = 0; i < s.warnings._length; ++i) said.event = s.warnings._buffer[i];
  });
  return said;
}

// The service publishes the rig's status after a request: prints what changed. The exit code: 1
// if it refused some or all of it.
int ReportAnswer(StatusReader& status, const std::string& rig_id, const LastSaid& before,
                 Clock::time_point until) {
  bool refused = false;
  while (Clock::now() < until) {
    auto ready = status.Wait(DDS_MSECS(200));
    if (!ready.ok()) return Fail(ready.status().message());
    bool answered = false;
    (void)status.TakeEach([&](const mpdrig_RigStatus& s, const dds_sample_info_t&) {
      if (rig_id != s.rig_id) return;
      if (s.last_rejection != before.rejection) {
        std::printf("refused: %s\n", s.last_rejection);
        refused = answered = true;
      }
      for (std::uint32_t i = 0; i < s.warnings._length; ++i) {
        if (before.event != s.warnings._buffer[i]) {
          std::printf("%s\n", s.warnings._buffer[i]);
          answered = true;
        }
      }
    });
    if (answered) return refused ? 1 : 0;
  }
  std::printf("sent; the service reported nothing new (the rigs may run already: %s.1 ..)\n",
              rig_id.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("rig_request - ask a class's mpdrig service for private rigs NAME.1 .. NAME.N");
  Args args;
  AddOptions(app, args);
  CLI11_PARSE(app, argc, argv);

  using namespace mpdrig;
  auto created = dds::Domain::Create(
      args.domain, args.dds_config.empty() ? dds::LoopbackConfig() : args.dds_config);
  if (!created.ok()) return Fail(created.status().message());
  auto scope = dds::CreateClientScope(args.domain, args.security, args.rig_id);
  if (!scope.ok()) return Fail(scope.status().message());
  const dds_entity_t p = scope->participant.handle();
  auto request_topic = dds::CreateTopic(p, dds::topics::kRigRequest);
  auto status_topic = dds::CreateTopic(p, dds::topics::kStatus);
  if (!request_topic.ok()) return Fail(request_topic.status().message());
  if (!status_topic.ok()) return Fail(status_topic.status().message());
  auto writer = dds::Writer<mpdrig_RigRequest>::Create(scope->pub(), request_topic->handle(),
                                                       dds::RequestQos());
  if (!writer.ok()) return Fail(writer.status().message());
  auto status = StatusReader::Create(scope->sub(), status_topic->handle(), dds::StatusQos());
  if (!status.ok()) return Fail(status.status().message());

  // The service's request reader must have matched (authentication, secure discovery) first.
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(args.timeout_s));
  const auto matched = dds::AwaitReader(writer->handle(), dds::DeadlineAfter(args.timeout_s));
  if (!matched.ok()) return Fail(matched.status().message());
  if (!*matched) {
    return Fail("no service takes private-rig requests for rig '" + args.rig_id + "' on domain " +
                std::to_string(args.domain) + " (mpdrig serve --security ... --private-rigs N)");
  }
  const LastSaid before = ReadLastSaid(*status, args.rig_id);
  mpdrig_RigRequest request{args.rig_id.data(), args.private_rigs};
  const Status written = writer->Write(request);
  if (!written.ok()) return Fail(written.message());
  if (dds_wait_for_acks(writer->handle(), DDS_SECS(5)) != DDS_RETCODE_OK) {
    return Fail("the service did not acknowledge the request");
  }
  return ReportAnswer(*status, args.rig_id, before, until);
}
