// A stranger's flood of commands for rig ids the service does not run: `count` pump commands,
// each for a distinct unknown id, from one writer that then stays `hold_s` seconds and goes
// (deleting the writer unregisters every one of those instances at once). bench/unknown_id_flood.sh
// reads the service's memory while the writer lives and its longest stall after it has gone.
//   mpdrig_unknown_id_flood --domain 79 --count 100000 --hold 3
// With --id-bytes N each id is padded to N bytes (issue 23: ten 10 MB ids cost a 1 kHz service 322
// lost periods): what a huge key costs the service before it can refuse it.
//   mpdrig_unknown_id_flood --domain 79 --count 10 --id-bytes 10000000
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "mpdrig.h"
#include "service/dds/dds.h"
#include "service/dds/topics.h"

int main(int argc, char** argv) {
  CLI::App app("mpdrig_unknown_id_flood - pump commands for many unknown rig ids, then leave");
  int domain = 79;
  long count = 100000;
  double hold_s = 3.0;
  std::string prefix = "stranger-";
  bool dispose = false;
  long id_bytes = 0;
  app.add_option("--domain", domain, "DDS domain id")->capture_default_str();
  app.add_option("--count", count, "distinct unknown rig ids")->capture_default_str();
  app.add_option("--hold", hold_s, "seconds to keep the writer after the last write")
      ->capture_default_str();
  app.add_option("--prefix", prefix, "rig id prefix (ids are prefix + number)")
      ->capture_default_str();
  app.add_flag("--dispose", dispose,
               "dispose each id (a key-only message, which topic filters do not see) instead of "
               "writing a command for it");
  app.add_option("--id-bytes", id_bytes,
                 "pad each id with 'x' to this many bytes (0: prefix + number only)")
      ->check(CLI::Range(0L, 1L << 30))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  using namespace mpdrig;
  auto fail = [](const Status& s) {
    std::fprintf(stderr, "mpdrig_unknown_id_flood: %s\n", s.message().c_str());
    return 1;
  };
  auto created = dds::Domain::Create(domain, dds::LoopbackConfig());
  if (!created.ok()) return fail(created.status());
  auto participant = dds::CreateParticipant(domain);
  if (!participant.ok()) return fail(participant.status());
  auto topic = dds::CreateTopic(participant->handle(), dds::topics::kPumpCommand);
  if (!topic.ok()) return fail(topic.status());
  auto writer = dds::Writer<mpdrig_PumpCommand>::Create(participant->handle(), topic->handle(),
                                                        dds::CommandQos(0));
  if (!writer.ok()) return fail(writer.status());
  // The service's reader must be there first, or the commands go nowhere.
  for (int waited_ms = 0;; waited_ms += 10) {
    dds_publication_matched_status_t matched{};
    dds_get_publication_matched_status(writer->handle(), &matched);
    if (matched.current_count > 0) break;
    if (waited_ms > 10000) return fail(Status::Error("no service on the domain"));
    dds_sleepfor(DDS_MSECS(10));
  }
  std::string id;
  for (long i = 0; i < count; ++i) {
    id = prefix + std::to_string(i);
    if (static_cast<long>(id.size()) < id_bytes) id.resize(static_cast<std::size_t>(id_bytes), 'x');
    mpdrig_PumpCommand command{id.data(), 5.0};
    const Status written = dispose
                               ? dds::Check(dds_dispose(writer->handle(), &command), "dds_dispose")
                               : writer->Write(command);
    if (!written.ok()) return fail(written);
  }
  const dds_return_t acked = dds_wait_for_acks(writer->handle(), DDS_SECS(60));
  std::fprintf(stderr, "mpdrig_unknown_id_flood: %ld ids %s%s\n", count,
               dispose ? "disposed" : "written",
               acked == DDS_RETCODE_OK ? " and acknowledged" : ", not all acknowledged");
  std::fflush(stderr);
  dds_sleepfor(static_cast<dds_duration_t>(hold_s * 1e9));
  // Deleting the writer unregisters all its instances in one go (the service sees them lose
  // their last writer together). The Writer's own delete later finds the handle gone: harmless.
  const dds_return_t deleted = dds_delete(writer->handle());
  if (deleted < 0) return fail(dds::Check(deleted, "dds_delete"));
  std::fprintf(stderr, "mpdrig_unknown_id_flood: writer deleted\n");
  return 0;
}
