#include "clients/client/control_loop.h"

#include <atomic>
#include <mutex>
#include <utility>

#include "clients/rig_watch.h"

namespace mpdrig::client {
namespace {

// SIGINT or SIGTERM arrived while a loop that handles signals lived. One flag for the process:
// a signal ends every such loop, as it would end the process. Loops nest (each restores the
// handlers it replaced); the first of a nest clears the flag.
std::atomic<bool> g_signalled{false};
std::mutex g_signal_mutex;
int g_signal_depth = 0;

extern "C" void OnStopSignal(int) { g_signalled.store(true); }

}  // namespace

const char* LoopEndName(LoopEnd end) {
  switch (end) {
    case LoopEnd::kRunning:
      return "running";
    case LoopEnd::kDuration:
      return "duration";
    case LoopEnd::kSignal:
      return "signal";
    case LoopEnd::kStopped:
      return "stopped";
    case LoopEnd::kRigEnded:
      return "rig ended";
    case LoopEnd::kRigLost:
      return "rig lost";
    case LoopEnd::kError:
      return "error";
  }
  return "?";
}

int LoopResult::ExitCode() const {
  switch (end) {
    case LoopEnd::kDuration:
    case LoopEnd::kSignal:
    case LoopEnd::kStopped:
      return 0;
    case LoopEnd::kRigEnded:
    case LoopEnd::kRigLost:
      return clients::kExitRigLost;
    case LoopEnd::kRunning:
    case LoopEnd::kError:
      break;
  }
  return 1;
}

ControlLoop::ControlLoop(Rig& rig, LoopOptions options) : rig_(rig), options_(std::move(options)) {
  if (!(options_.duration_s >= 0.0 && options_.duration_s <= 1e9)) {
    result_.failure = Failure::kError;
    End(LoopEnd::kError,
        "the loop's duration must be a rig time in seconds, >= 0 (0: no end), not " +
            std::to_string(options_.duration_s));
  }
  if (options_.interrupt) return;
  std::lock_guard<std::mutex> lock(g_signal_mutex);
  if (g_signal_depth++ == 0) g_signalled.store(false);
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &old_int_);
  sigaction(SIGTERM, &action, &old_term_);
  handles_signals_ = true;
}

ControlLoop::~ControlLoop() {
  if (!handles_signals_) return;
  std::lock_guard<std::mutex> lock(g_signal_mutex);
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
  --g_signal_depth;
}

bool ControlLoop::Interrupted() {
  if (!interrupted_) {
    interrupted_ = options_.interrupt ? options_.interrupt() : g_signalled.load();
  }
  return interrupted_;
}

Rig::Interrupt ControlLoop::interrupt() {
  return [this] { return Interrupted(); };
}

void ControlLoop::End(LoopEnd end, std::string message) {
  if (over()) return;
  result_.end = end;
  result_.message = std::move(message);
}

void ControlLoop::Fail(const Status& why) {
  if (rig_.lost()) {
    End(rig_.ended() ? LoopEnd::kRigEnded : LoopEnd::kRigLost, *rig_.lost());
  } else if (rig_.last_failure() == Failure::kInterrupted || interrupted_) {
    End(LoopEnd::kSignal);
  } else {
    result_.failure = rig_.last_failure();
    End(LoopEnd::kError, why.message());
  }
}

void ControlLoop::Abort(const Status& why) {
  if (rig_.lost()) return Fail(why);
  result_.failure = Failure::kError;
  End(LoopEnd::kError, why.message());
}

std::optional<Tick> ControlLoop::Next() {
  if (over()) return std::nullopt;
  if (stop_requested_) {
    End(LoopEnd::kStopped);
    return std::nullopt;
  }
  if (Interrupted()) {
    End(LoopEnd::kSignal);
    return std::nullopt;
  }
  if (options_.duration_s > 0.0 && last_time_s_ && *last_time_s_ >= options_.duration_s - 1e-9) {
    End(LoopEnd::kDuration);
    return std::nullopt;
  }
  for (;;) {
    auto read = Read();
    if (!read.ok()) {
      Fail(read.status());
      return std::nullopt;
    }
    if (!*read) {  // real time, paired estimates: none yet
      if (Interrupted()) {
        End(LoopEnd::kSignal);
        return std::nullopt;
      }
      continue;
    }
    Tick tick = std::move(**read);
    tick.dt_s = last_time_s_ ? tick.sensors.time_s - *last_time_s_ : 0.0;
    tick.index = result_.ticks++;
    last_time_s_ = tick.sensors.time_s;
    result_.last_time_s = tick.sensors.time_s;
    return tick;
  }
}

Result<Sensors> ControlLoop::ReadSample() {
  const bool every = options_.samples == LoopOptions::Samples::kEvery;
  if (!rig_.lockstep()) return every ? rig_.Next(interrupt()) : rig_.Latest(true, interrupt());
  if (every) {
    // What arrived before (a Step(100) of the owner's), in order, then one step at a time.
    if (pending_.empty()) {
      auto arrived = rig_.TakeArrived();
      if (!arrived.ok()) return arrived.status();
      pending_.assign(arrived->begin(), arrived->end());
    }
    if (pending_.empty()) {
      auto stepped = rig_.Step(1, interrupt());
      if (!stepped.ok()) return stepped.status();
      auto arrived = rig_.TakeArrived();
      if (!arrived.ok()) return arrived.status();
      pending_.assign(arrived->begin(), arrived->end());
      if (pending_.empty()) pending_.push_back(*stepped);
    }
    Sensors s = pending_.front();
    pending_.pop_front();
    return s;
  }
  // A controller: one step and its one sample, no backlog; a sample out of turn means another
  // client steps this rig too, and this controller's run is no longer its own.
  auto sample = rig_.Step(1, interrupt());
  if (!sample.ok()) return sample.status();
  (void)rig_.TakeArrived();
  if (!next_counter_) next_counter_ = sample->sample_counter;  // the rig may have run before
  if (sample->sample_counter != *next_counter_) {
    return Status::Error("lockstep sample " + std::to_string(sample->sample_counter) +
                         " instead of " + std::to_string(*next_counter_) +
                         " (another client steps this rig?)");
  }
  ++*next_counter_;
  return sample;
}

Result<std::optional<Tick>> ControlLoop::Read() {
  auto sample = ReadSample();
  if (!sample.ok()) return sample.status();
  Tick tick;
  tick.sensors = *sample;
  switch (options_.estimates) {
    case LoopOptions::Estimates::kNone:
      break;
    case LoopOptions::Estimates::kNewest:
      tick.estimate = rig_.NewestEstimate();
      break;
    case LoopOptions::Estimates::kPaired:
      if (rig_.lockstep()) {
        auto paired = rig_.EstimateFor(tick.sensors.sample_counter, interrupt());
        if (!paired.ok()) return paired.status();
        tick.estimate = *paired;
      } else {
        tick.estimate = rig_.NewestEstimate();
        if (!tick.estimate) return std::optional<Tick>();
      }
      break;
  }
  return std::optional<Tick>(std::move(tick));
}

LoopResult RunController(Rig& rig, const LoopOptions& options, const Update& update) {
  ControlLoop loop(rig, options);
  while (auto tick = loop.Next()) {
    const Commands c = update(*tick);
    if (c.failure) {
      loop.Abort(*c.failure);
      break;
    }
    // No interrupt: a signal during the tick stops the run after the tick, its commands sent.
    Status sent = Status::Ok();
    if (c.choke_deg && sent.ok()) sent = rig.Choke(*c.choke_deg);
    if (c.pump_lpm && sent.ok()) sent = rig.Pump(*c.pump_lpm);
    if (c.outlet_barg && sent.ok()) sent = rig.Outlet(*c.outlet_barg);
    if (c.piston && sent.ok()) sent = rig.Piston(*c.piston);
    if (!sent.ok()) {
      loop.Fail(sent);
      break;
    }
    if (c.stop) loop.Stop();
  }
  return loop.result();
}

}  // namespace mpdrig::client
