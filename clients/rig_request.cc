// rig_request: a student asks a class's service for private rigs, NAME.1 .. NAME.N,
// which only they may command and read (make-class's permissions: rig.NAME.*). The service must
// run with `--security ... --private-rigs N`; it makes the rigs within its limits and says on the
// student's rig's status what it made or refused. A client on the client library
// (clients/client/private_rig_request.h): it speaks only the DDS topics.
//
//   rig_request --security class/alice --rig alice --private-rigs 1
//   bhp_controller --security class/alice --rig alice.1      # then use it like any rig
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "clients/client/participant.h"
#include "clients/client/private_rig_request.h"

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("rig_request - ask a class's mpdrig service for private rigs NAME.1 .. NAME.N");
  Args args;
  AddOptions(app, args);
  CLI11_PARSE(app, argc, argv);

  using namespace mpdrig;
  auto participant = client::Participant::Join(
      {.domain = args.domain, .dds_config = args.dds_config, .security_dir = args.security});
  if (!participant.ok()) return Fail(participant.status().message());
  auto answer =
      client::RequestPrivateRigs(*participant, args.rig_id, args.private_rigs, args.timeout_s);
  if (!answer.ok()) return Fail(answer.status().message());
  for (const std::string& line : answer->said) std::printf("%s\n", line.c_str());
  if (!answer->answered) {
    std::printf("sent; the service reported nothing new (the rigs may run already: %s.1 ..)\n",
                args.rig_id.c_str());
  }
  return answer->refused ? 1 : 0;
}
