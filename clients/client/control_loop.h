// A control loop over one rig (clients/client/rig_client.h), so that a controller writes only
// its update: what to command at this tick, given this tick's sample and estimate. The loop keeps
// the rules every controller of the rig needs, once:
//
//   - the clock: on a lockstep rig (`mpdrig serve --clock lockstep`) each tick steps the rig one
//     sensor period, after the commands of the last tick are acknowledged (Rig::Step), so a run
//     is deterministic however loaded the machine; on a real-time rig each tick is the newest
//     sample (a controller that falls behind skips samples rather than act on old ones), or
//     every sample in order for a recorder or Python's `Rig.stream` (Samples::kEvery);
//   - the estimate: with Estimates::kPaired each tick carries the observer's estimate of that
//     very sample in lockstep (waiting for it), the newest one in real time (published right
//     after its sample; ticks before the first are skipped);
//   - the end: the rig time `duration_s`, the update asking to stop, SIGINT or SIGTERM (after the
//     tick in progress: its commands are sent, the process's handlers are restored when the loop
//     goes), the rig's service ending its run as asked, the rig lost (clients/rig_watch.h: the
//     service restarted, left or went silent), or an error; LoopResult says which, with the
//     reason, and the clients' exit code for it.
//
// Pull form, for a loop of one's own (a recorder, Python's iterator):
//
//   client::LoopOptions options;
//   options.duration_s = 60.0;
//   client::ControlLoop loop(rig, options);
//   while (auto tick = loop.Next()) rig.Choke(30.0 + 0.1 * (tick->sensors.PT_barg[0] - 4.0));
//   return loop.result().ExitCode();
//
// Push form (ros2_control's update()): the update returns the commands of its tick
// (clients/examples/hello_controller.cc is a whole controller in it).
//
//   auto result = client::RunController(rig, options, [](const client::Tick& t) {
//     return client::Commands::Choke(30.0 + 0.1 * (t.sensors.PT_barg[0] - 4.0));
//   });
#pragma once

#include <signal.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <string>

#include "clients/client/rig_client.h"
#include "model/common/status.h"

namespace mpdrig::client {

struct LoopOptions {
  // Rig time [s] at which the run ends, after the tick at or past it (0: no end). The rig's clock
  // starts at 0 with its run, so for a controller started with the rig this is the run's length.
  double duration_s = 0.0;
  // Real time: the newest sample at each tick (a controller), or every sample in order (a
  // recorder; the client keeps the newest 10000 unread). Lockstep: one step per tick either way;
  // kEvery first hands out samples that arrived before (e.g. of a Step(100) of one's own).
  enum class Samples { kNewest, kEvery };
  Samples samples = Samples::kNewest;
  // kNewest: the newest estimate that has arrived, if any (nothing waits). kPaired: the estimate
  // of the tick's own sample in lockstep (waits for it: an error without an observer); in real
  // time the newest, and ticks before the first estimate are skipped.
  enum class Estimates { kNone, kNewest, kPaired };
  Estimates estimates = Estimates::kNone;
  // Called about every 100 ms while the loop waits; true stops the run as a signal does. Empty:
  // the loop handles SIGINT and SIGTERM itself while it lives (Python passes one that checks for
  // Ctrl-C instead).
  Rig::Interrupt interrupt;
};

// One tick: the sample, the estimate that goes with it (LoopOptions::estimates), and the rig time
// since the last tick (0 at the first).
struct Tick {
  Sensors sensors;
  std::optional<Estimate> estimate;
  double dt_s = 0.0;
  std::uint64_t index = 0;  // 0, 1, 2, ... ticks of this loop
};

// How a run ended.
enum class LoopEnd {
  kRunning,   // not yet
  kDuration,  // the tick at LoopOptions::duration_s was the last
  kSignal,    // SIGINT, SIGTERM, or the options' interrupt
  kStopped,   // the update (or the pull form's owner, Stop) asked
  kRigEnded,  // the rig's service ended its run as asked (a stop, its --duration, a playback)
  kRigLost,   // clients/rig_watch.h: restarted, left, or silent for the timeout
  kError,     // no rig samples, a DDS error, another client stepping the rig, ...
};
const char* LoopEndName(LoopEnd end);

struct LoopResult {
  LoopEnd end = LoopEnd::kRunning;
  std::string message;               // why, for kRigEnded, kRigLost and kError
  Failure failure = Failure::kNone;  // the rig's failure kind, for kError (Python's exceptions)
  std::uint64_t ticks = 0;
  double last_time_s = 0.0;  // rig time of the last tick

  // The clients' exit codes (clients/rig_watch.h): 0 for a run that ended as asked (duration,
  // signal, stop), kExitRigLost (3) for a rig lost or ended under the controller (its run did not
  // end as it asked), 1 for an error.
  int ExitCode() const;
};

class ControlLoop {
 public:
  ControlLoop(Rig& rig, LoopOptions options);
  ~ControlLoop();  // restores the signal handlers it replaced
  ControlLoop(const ControlLoop&) = delete;
  ControlLoop& operator=(const ControlLoop&) = delete;

  // The next tick (stepping a lockstep rig once), or nullopt when the run is over: result() says
  // how. A signal that arrives during a tick ends the run at the next call.
  std::optional<Tick> Next();
  // Ends the run at the next call to Next (LoopEnd::kStopped).
  void Stop() { stop_requested_ = true; }
  // Ends the run for a failed call the owner made on the rig between ticks (a command): lost,
  // ended, interrupted or an error, by the rig's state.
  void Fail(const Status& why);
  // Ends the run for a failure of the owner's own (LoopEnd::kError), or the rig's loss if it is
  // lost by now.
  void Abort(const Status& why);
  const LoopResult& result() const { return result_; }
  bool over() const { return result_.end != LoopEnd::kRunning; }
  // What blocking rig calls between ticks should pass, to stop as the loop does.
  Rig::Interrupt interrupt();

 private:
  Result<std::optional<Tick>> Read();
  Result<Sensors> ReadSample();
  void End(LoopEnd end, std::string message = {});
  bool Interrupted();

  Rig& rig_;
  LoopOptions options_;
  LoopResult result_;
  bool stop_requested_ = false;
  bool handles_signals_ = false;
  bool interrupted_ = false;
  std::deque<Sensors> pending_;  // lockstep, kEvery: arrived, not yet handed out
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
  std::optional<std::uint64_t> next_counter_;  // lockstep, kNewest: the sample the next step brings
  std::optional<double> last_time_s_;
};

// The commands of one tick; unset fields command nothing. `stop` ends the run after they are sent.
struct Commands {
  std::optional<double> choke_deg, pump_lpm, outlet_barg;
  std::optional<PistonCommand> piston;
  bool stop = false;
  // The update failed: the run ends with this (as an error, or the rig's loss if it is lost).
  std::optional<Status> failure;

  static Commands Choke(double opening_deg) {
    Commands c;
    c.choke_deg = opening_deg;
    return c;
  }
  static Commands Stop() {
    Commands c;
    c.stop = true;
    return c;
  }
  static Commands Failed(Status why) {
    Commands c;
    c.failure = std::move(why);
    return c;
  }
};

// Runs `update` once per tick of a ControlLoop over `rig` and sends the commands it returns, until
// the run ends (LoopOptions; Commands::stop). The result says how.
using Update = std::function<Commands(const Tick&)>;
LoopResult RunController(Rig& rig, const LoopOptions& options, const Update& update);

}  // namespace mpdrig::client
