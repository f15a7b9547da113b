// Test helper: a minimal choke controller process. Writes `opening_deg` for `rig_id` every 10 ms
// with the given ownership strength (dds::CommandQos) until it is stopped or killed. The failover
// test kills it with SIGKILL, so it never unregisters: the service must notice it by its 1 s
// liveliness lease.
//   choke_writer DOMAIN RIG_ID STRENGTH OPENING_DEG
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: choke_writer DOMAIN RIG_ID STRENGTH OPENING_DEG\n");
    return 2;
  }
  const int domain = std::atoi(argv[1]);
  std::string rig_id = argv[2];
  const int strength = std::atoi(argv[3]);
  const double opening_deg = std::atof(argv[4]);
  using namespace mpdrig;
  auto created = dds::Domain::Create(domain, dds::LoopbackConfig());
  auto participant = dds::CreateParticipant(domain);
  if (!created.ok() || !participant.ok()) return 1;
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kChokeCommand);
  if (!topic.ok()) return 1;
  auto writer = dds::Writer<mpdrig_ChokeCommand>::Create(participant->handle(), topic->handle(),
                                                         dds::CommandQos(strength));
  if (!writer.ok()) return 1;
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGINT, OnSignal);
  mpdrig_ChokeCommand command{rig_id.data(), opening_deg};
  while (!g_stop) {
    const Status written = writer->Write(command);
    if (!written.ok()) {
      std::fprintf(stderr, "choke_writer: %s\n", written.message().c_str());
      return 1;
    }
    dds_sleepfor(DDS_MSECS(10));
  }
  return 0;
}
