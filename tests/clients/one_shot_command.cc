// Test helper: one pump command from a process of its own, then exit, the way a script sends a
// single command. How it goes about it is the MODE:
//   careless - write as soon as the service's reader has matched, then exit() at once: no
//              acknowledgement awaited, no entity deleted (what a quick C or Python script does);
//   acked    - the same, but exit() only once the write is acknowledged: delivered, yet the
//              writer was never deleted, so it keeps owning the instance until its lease ends;
//   reliable - dds::SendOnce: wait for the match, write, wait for the acknowledgement, delete the
//              writer (unregistering its instance) before exit.
//   library  - the client library (clients/client/rig_client.h), as a script would use it:
//              connect, one Pump command, leave (Close keeps SendOnce's rule).
//   one_shot_command DOMAIN RIG_ID FLOW_LPM careless|acked|reliable|library
#include <cstdio>
#include <cstdlib>
#include <string>

#include "clients/client/rig_client.h"
#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(
        stderr, "usage: one_shot_command DOMAIN RIG_ID FLOW_LPM careless|acked|reliable|library\n");
    return 2;
  }
  const int domain = std::atoi(argv[1]);
  std::string rig_id = argv[2];
  const double flow_lpm = std::atof(argv[3]);
  const std::string mode = argv[4];
  using namespace mpdrig;
  if (mode == "library") {
    client::RigOptions options;
    options.rig_id = rig_id;
    options.domain = domain;
    auto rig = client::Rig::Connect(options);
    const Status sent = rig.ok() ? (*rig)->Pump(flow_lpm) : rig.status();
    if (!sent.ok()) std::fprintf(stderr, "one_shot_command: %s\n", sent.message().c_str());
    return sent.ok() ? 0 : 1;  // the Rig leaves here: acknowledged, then unregistered
  }
  auto created = dds::Domain::Create(domain, dds::LoopbackConfig());
  auto participant = dds::CreateParticipant(domain);
  if (!created.ok() || !participant.ok()) return 1;
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kPumpCommand);
  if (!topic.ok()) return 1;
  mpdrig_PumpCommand command{rig_id.data(), flow_lpm};
  if (mode == "reliable") {
    const Status sent = dds::SendOnce<mpdrig_PumpCommand>(participant->handle(), topic->handle(),
                                                          command, DDS_SECS(10));
    if (!sent.ok()) std::fprintf(stderr, "one_shot_command: %s\n", sent.message().c_str());
    return sent.ok() ? 0 : 1;
  }
  auto writer = dds::Writer<mpdrig_PumpCommand>::Create(participant->handle(), topic->handle(),
                                                        dds::CommandQos());
  if (!writer.ok()) return 1;
  for (int waited_ms = 0;; waited_ms += 1) {
    dds_publication_matched_status_t matched{};
    dds_get_publication_matched_status(writer->handle(), &matched);
    if (matched.current_count > 0) break;
    if (waited_ms > 10000) return 1;
    dds_sleepfor(DDS_MSECS(1));
  }
  if (!writer->Write(command).ok()) return 1;
  if (mode == "acked" && dds_wait_for_acks(writer->handle(), DDS_SECS(10)) != DDS_RETCODE_OK) {
    return 1;
  }
  std::exit(0);  // no deletion: the writer is never unregistered
}
