// bhp_controller: an example controller that holds the bottom-hole pressure of a rig at a set
// point against heave, with the choke. A client: it speaks only the DDS topics (mpdrig_sensors,
// mpdrig_estimate, mpdrig_choke_command, mpdrig_step_request) through the client library
// (clients/client/rig_client.h: QoS, ownership, lockstep acknowledgements, the lost-rig rule)
// and never links model/, so it runs unchanged against the virtual rig or the lab's rig behind
// a bridge. Its loop is the library's (clients/client/control_loop.h: real time or lockstep, the
// end of the run, Ctrl-C); this file holds the control law's options, its log, its summary and
// the ownership check. clients/examples/hello_controller.cc is the same control in under 60 lines.
//
// Control law, choke reference u [deg] (opening the choke lowers the pressure):
// clang-format off
//   e    = BHP - set point           [bar]  (PT1, or BHP_est with --use-estimate)
//   u    = u_I + Kp e + Re{theta z}  [deg]
//   u_I' = Ki e                      [deg/s] (frozen while u is clamped and e pushes further:
//                                             anti-windup)
// clang-format on
// PI feedback alone cannot reject a 0.1-0.2 Hz heave: the choke acts on the bottom through the
// 900 m pipe, l/c = 1.06 s of transport delay plus the 0.1 s actuator lag, which is 40-90 degrees
// of phase at the heave frequency, before the pipe's own resonance at c/4l = 0.24 Hz (thesis 9.3);
// measured at 0.1 Hz and the lab's noise, PT1's periodic RMS is 0.259 bar with the choke fixed and
// 0.263 bar under PI alone. The feed-forward Re{theta z} does that part: adaptive cancellation on
// the observer's heave phasor z = v_d^ + j omega x_d^ (thesis 10, (10.2.8)-(10.2.11)),
//   theta' = -gamma W / G^,   W = 2 e conj(z)/|z|^2,   G^ = -g exp(-j omega tau),
// client::HeaveCanceller (clients/client/heave_control.h, with the derivation). Without a set
// point it learns one with the choke left alone (client::SetpointLearner), and measures PT1's
// periodic swing with client::HeaveFit.
//
//   bhp_controller --rig rig-1                # after 10 s, hold the mean BHP of the next 10 s
//   bhp_controller --rig rig-1 --setpoint-barg 4 --use-estimate
//   bhp_controller --lockstep --duration 120 --measure-last 40 --open-loop   # baseline
#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "clients/client/control_loop.h"
#include "clients/client/heave_control.h"
#include "clients/client/rig_client.h"
#include "clients/rig_watch.h"

namespace {

// The exit code of a run during which another controller had the choke (1: failure to start,
// 2: usage, 3: rig lost).
constexpr int kExitNotOwner = 4;

using Complex = std::complex<double>;
// Ctrl-C while connecting (exit 1); during the run the library's loop handles it.
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

struct ControllerOptions {
  double setpoint_barg = std::numeric_limits<double>::quiet_NaN();  // NaN: learn it
  // Without a set point: command nothing (the choke stays where the rig has it), ignore the first
  // settle_s and two heave periods (the heave's start-up transient; the observer's start-up, when
  // the control reads its estimate), average the BHP and the choke's position over learn_s rounded
  // to whole heave periods (a part period biases the mean by up to the heave's amplitude over pi
  // periods), then hold that mean BHP, starting from that mean opening.
  double settle_s = 10.0;
  double learn_s = 10.0;
  double kp_deg_per_bar = 0.1;
  double ki_deg_per_bar_s = 0.05;
  bool feedforward = true;
  double adapt_per_s = 0.2;  // gamma: the cancellation converges in about 1/gamma s
  double choke_gain_bar_per_deg = 0.7;
  double delay_s = 1.3;
  double choke_min_deg = 2.0, choke_max_deg = 88.0;
};

// The control law above; time and signals are arguments, the transport is elsewhere.
class BhpController {
 public:
  explicit BhpController(const ControllerOptions& options)
      : o_(options),
        learner_({.settle_s = options.settle_s, .learn_s = options.learn_s}),
        canceller_({.adapt_per_s = options.adapt_per_s,
                    .choke_gain_bar_per_deg = options.choke_gain_bar_per_deg,
                    .delay_s = options.delay_s}) {}

  // One sample: the BHP [barg] at time t [s], the choke's measured position [deg], the heave
  // phasor z [m/s] and its frequency [Hz] (z = 0 or frequency <= 0: no feed-forward this
  // sample). Returns the choke reference [deg], or nothing while it learns its set point.
  std::optional<double> Update(double t_s, double bhp_barg, double choke_deg, Complex z,
                               double frequency_hz) {
    const double dt = last_t_s_ ? std::clamp(t_s - *last_t_s_, 0.0, 1.0) : 0.0;
    last_t_s_ = t_s;
    if (std::isnan(o_.setpoint_barg)) {
      // No set point given: watch with the choke held, then hold the mean BHP seen, from the
      // mean opening seen.
      if (!learner_.Add(t_s, bhp_barg, choke_deg, frequency_hz)) return std::nullopt;
      o_.setpoint_barg = learner_.setpoint_barg();
      integral_deg_ = learner_.choke_deg();
    }
    // A set point given: the integrator starts at the choke's first reading (its noise, 0.1 deg
    // at the lab, is what the integral action then corrects).
    if (std::isnan(integral_deg_)) integral_deg_ = choke_deg;
    const double e = bhp_barg - o_.setpoint_barg;
    const double feedforward = o_.feedforward ? canceller_.Update(e, z, frequency_hz, dt) : 0.0;
    const double wanted = integral_deg_ + o_.kp_deg_per_bar * e + feedforward;
    const double command = std::clamp(wanted, o_.choke_min_deg, o_.choke_max_deg);
    // Anti-windup: integrate unless clamped with the error pushing further into the limit.
    const bool pushing_up = wanted > o_.choke_max_deg && e > 0.0;
    const bool pushing_down = wanted < o_.choke_min_deg && e < 0.0;
    if (!pushing_up && !pushing_down) integral_deg_ += o_.ki_deg_per_bar_s * e * dt;
    return command;
  }

  double setpoint_barg() const { return o_.setpoint_barg; }
  Complex theta() const { return canceller_.theta(); }

 private:
  ControllerOptions o_;
  mpdrig::client::SetpointLearner learner_;
  mpdrig::client::HeaveCanceller canceller_;
  double integral_deg_ = std::numeric_limits<double>::quiet_NaN();
  std::optional<double> last_t_s_;
};

struct Args {
  std::string rig_id = "rig-1";
  int domain = 0;
  std::string dds_config;
  std::string security;  // DDS Security identity directory (make-class's OUT/NAME)
  ControllerOptions control;
  bool use_estimate = false;
  bool open_loop = false;
  bool lockstep = false;
  double duration_s = 0.0;
  double measure_last_s = 0.0;
  int strength = 10;
  std::string log_path;
  double timeout_s = 10.0;
};

// One sensor sample and the estimate that goes with it, as the controller uses them.
struct Reading {
  std::uint64_t counter = 0;
  double time_s = 0.0;
  double pt1_barg = 0.0;
  double choke_deg = 0.0;
  bool has_estimate = false;
  double bhp_est_barg = 0.0;
  Complex z{0.0, 0.0};
  double frequency_hz = 0.0;
};

Reading FromSample(const mpdrig::client::Sensors& s,
                   const std::optional<mpdrig::client::Estimate>& e) {
  Reading r;
  r.counter = s.sample_counter;
  r.time_s = s.time_s;
  r.pt1_barg = s.PT_barg[0];
  r.choke_deg = s.choke_position_deg;
  if (e) {
    // The heave phasor z = v_d + j omega x_d (top of this file).
    r.has_estimate = true;
    r.bhp_est_barg = e->BHP_est_barg;
    r.z = mpdrig::client::HeaveCanceller::Phasor(*e);
    r.frequency_hz = e->disturbance_frequency_hz;
  }
  return r;
}

int Fail(const std::string& what) {
  std::fprintf(stderr, "bhp_controller: %s\n", what.c_str());
  return 1;
}

// Half the peak-to-peak swing and the mean of PT1 over the measured window.
struct Swing {
  double lo = 1e300, hi = -1e300, sum = 0.0;
  double choke_lo = 1e300, choke_hi = -1e300;
  long n = 0;
  void Add(double pt1, double choke) {
    lo = std::min(lo, pt1);
    hi = std::max(hi, pt1);
    choke_lo = std::min(choke_lo, choke);
    choke_hi = std::max(choke_hi, choke);
    sum += pt1;
    ++n;
  }
};

// The rig through the client library, as this controller's options ask.
mpdrig::Result<std::unique_ptr<mpdrig::client::Rig>> ConnectRig(const Args& args) {
  mpdrig::client::RigOptions options;
  options.rig_id = args.rig_id;
  options.domain = args.domain;
  options.dds_config = args.dds_config;
  options.strength = args.strength;
  options.timeout_s = args.timeout_s;
  options.security_dir = args.security;
  options.read_profiles = false;
  auto rig = mpdrig::client::Rig::Connect(options, [] { return g_stop.load(); });
  if (!rig.ok()) return rig.status();
  if ((*rig)->lockstep() != args.lockstep) {
    return mpdrig::Status::Error(
        "rig " + args.rig_id +
        ((*rig)->lockstep() ? " runs a lockstep clock: add --lockstep, and this controller "
                              "steps it"
                            : " runs in real time: --lockstep is for `mpdrig serve --clock "
                              "lockstep`"));
  }
  return rig;
}

// The controller's loop: read a sample (stepping a lockstep rig), control, command, measure.
class Session {
 public:
  Session(const Args& args, mpdrig::client::Rig& rig) : args_(args), rig_(rig) {}

  mpdrig::Status OpenLog() {
    if (args_.log_path.empty()) return mpdrig::Status::Ok();
    log_.open(args_.log_path);
    if (!log_) return mpdrig::Status::Error(args_.log_path + ": cannot write");
    log_ << "# rig-log: 1\n# source: bhp_controller, rig " << args_.rig_id
         << "\ntime_s,PT1_barg,BHP_est_barg,choke_position_deg,choke_reference_deg,"
            "BHP_setpoint_barg\n";
    return mpdrig::Status::Ok();
  }

  // Runs until --duration, Ctrl-C or a failure (the library's loop: real time, the newest sample
  // and the newest estimate; lockstep, one step per sample, and the estimate of that very
  // sample when the control uses it): the exit code.
  int Loop() {
    using Estimates = mpdrig::client::LoopOptions::Estimates;
    mpdrig::client::LoopOptions options;
    options.duration_s = args_.duration_s;
    // Real time, --use-estimate: no control before the first estimate.
    const bool paired =
        args_.lockstep ? args_.use_estimate || args_.control.feedforward : args_.use_estimate;
    options.estimates = paired ? Estimates::kPaired : Estimates::kNewest;
    const mpdrig::client::LoopResult result =
        mpdrig::client::RunController(rig_, options, [&](const mpdrig::client::Tick& tick) {
          return Act(FromSample(tick.sensors, tick.estimate));
        });
    return Finish(result);
  }

 private:
  // Handles one complete reading: control, log, measurement; the choke command to send.
  mpdrig::client::Commands Act(const Reading& r) {
    if (!controller_) controller_.emplace(args_.control);
    // Whether the commands sent so far are the ones in force (the status reflects them).
    if (commands_ > 0) {
      const mpdrig::Status owner = CheckOwnership(r.time_s);
      if (!owner.ok()) return mpdrig::client::Commands::Failed(owner);
    }
    const double bhp = args_.use_estimate ? r.bhp_est_barg : r.pt1_barg;
    const std::optional<double> command =
        controller_->Update(r.time_s, bhp, r.choke_deg, r.has_estimate ? r.z : Complex{},
                            r.has_estimate ? r.frequency_hz : 0.0);
    mpdrig::client::Commands commands;
    if (command && !args_.open_loop) {
      commands.choke_deg = *command;
      ++commands_;
    }
    if (log_.is_open()) {
      log_ << r.time_s << ',' << r.pt1_barg << ','
           << (r.has_estimate ? r.bhp_est_barg : std::nan("")) << ',' << r.choke_deg << ','
           << (command && !args_.open_loop ? *command : std::nan("")) << ','
           << controller_->setpoint_barg() << '\n';
    }
    if (args_.duration_s > 0.0 && r.time_s > args_.duration_s - args_.measure_last_s) {
      swing_.Add(r.pt1_barg, r.choke_deg);
      heave_.Add(r.time_s, r.pt1_barg, r.has_estimate ? r.frequency_hz : 0.0);
    }
    return commands;
  }

  // Whether this controller's choke commands are the ones in force, once a second of rig time:
  // under exclusive ownership a stronger writer, or an equal one that wins the tie by its GUID,
  // takes the choke and this controller's commands are dropped without a word. It says so (at
  // once, and again when it gets the choke back) and the run ends with kExitNotOwner.
  mpdrig::Status CheckOwnership(double time_s) {
    if (time_s < next_ownership_check_s_) return mpdrig::Status::Ok();
    next_ownership_check_s_ = time_s + 1.0;
    auto other = rig_.ChokeCommandedByOther();
    if (!other.ok()) return other.status();
    // Twice in a row, a second apart: the status right after this controller's first command may
    // still name the writer before it.
    if (other->has_value() && !other_seen_s_) {
      other_seen_s_ = time_s;
    } else if (other->has_value() && !not_owner_since_s_) {
      not_owner_since_s_ = *other_seen_s_;
      std::fprintf(stderr,
                   "bhp_controller: at rig time %.3f s the choke of %s obeys another controller "
                   "(%s), not this one (strength %d): its commands are dropped. A stronger "
                   "--strength takes it; an equal one may lose the tie\n",
                   time_s, args_.rig_id.c_str(), (*other)->c_str(), args_.strength);
    }
    if (!other->has_value()) other_seen_s_.reset();
    if (!other->has_value() && not_owner_since_s_) {
      not_owner_s_ += time_s - *not_owner_since_s_;
      not_owner_since_s_.reset();
      std::fprintf(stderr,
                   "bhp_controller: at rig time %.3f s the choke obeys this controller again\n",
                   time_s);
    }
    last_time_s_ = time_s;
    return mpdrig::Status::Ok();
  }
  // Rig time during which another controller had the choke, up to the last check.
  double NotOwnerSeconds() const {
    return not_owner_s_ + (not_owner_since_s_ ? last_time_s_ - *not_owner_since_s_ : 0.0);
  }
  // The exit code of a run that ended as asked: 0, or kExitNotOwner if another controller had
  // the choke for part of it (its summary is then not this controller's doing).
  int Ended() const {
    if (NotOwnerSeconds() <= 0.0 && !not_owner_since_s_) return 0;
    std::fprintf(stderr,
                 "bhp_controller: another controller had the choke of %s for %.1f s of the run: "
                 "this controller's summary is not its own doing (exit %d)\n",
                 args_.rig_id.c_str(), NotOwnerSeconds(), kExitNotOwner);
    return kExitNotOwner;
  }

  // How the run ended: as asked (--duration, Ctrl-C) prints the summary; a lost rig
  // (clients/rig_watch.h) says why and exits with kExitRigLost, without the summary (the run did
  // not end as asked).
  int Finish(const mpdrig::client::LoopResult& result) {
    using mpdrig::client::LoopEnd;
    switch (result.end) {
      case LoopEnd::kDuration:
      case LoopEnd::kSignal:
      case LoopEnd::kStopped:
        PrintSummary();
        return Ended();
      case LoopEnd::kRigEnded:
      case LoopEnd::kRigLost:
        std::fprintf(stderr, "bhp_controller: rig %s lost: %s; stopping after %ld choke commands\n",
                     args_.rig_id.c_str(), result.message.c_str(), commands_);
        return result.ExitCode();
      case LoopEnd::kRunning:
      case LoopEnd::kError:
        break;
    }
    if (result.failure == mpdrig::client::Failure::kTimeout && !controller_) {
      return Fail("no sensor samples from " + args_.rig_id + ": " + result.message);
    }
    return Fail(result.message);
  }

  void PrintSummary() const {
    std::fprintf(stderr, "bhp_controller: %s, %ld choke commands, set point %.4f barg\n",
                 args_.rig_id.c_str(), commands_,
                 controller_ ? controller_->setpoint_barg() : std::nan(""));
    if (swing_.n == 0) return;
    // One line, key=value, for scripts (bench/bhp_attenuation.sh).
    const auto [fundamental, periodic_rms] = heave_.Amplitudes();
    std::printf(
        "rig=%s mode=%s window_s=%g samples=%ld PT1_amplitude_bar=%.5f PT1_mean_barg=%.5f "
        "PT1_heave_bar=%.5f PT1_periodic_rms_bar=%.5f choke_min_deg=%.3f choke_max_deg=%.3f\n",
        args_.rig_id.c_str(),
        args_.open_loop              ? "fixed-choke"
        : !args_.control.feedforward ? "pi"
        : args_.use_estimate         ? "pi+ff(estimate)"
                                     : "pi+ff",
        args_.measure_last_s, swing_.n, 0.5 * (swing_.hi - swing_.lo), swing_.sum / swing_.n,
        fundamental, periodic_rms, swing_.choke_lo, swing_.choke_hi);
  }

  const Args& args_;
  mpdrig::client::Rig& rig_;
  std::ofstream log_;
  std::optional<BhpController> controller_;
  Swing swing_;
  mpdrig::client::HeaveFit heave_;  // PT1 at the heave frequency: its periodic part
  long commands_ = 0;
  double next_ownership_check_s_ = -1e300;
  std::optional<double> other_seen_s_;       // another owner at the last check, since then
  std::optional<double> not_owner_since_s_;  // rig time since another controller has the choke
  double not_owner_s_ = 0.0;                 // rig time it had it before
  double last_time_s_ = 0.0;                 // of the last ownership check
};

int Run(const Args& args) {
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  auto rig = ConnectRig(args);
  if (!rig.ok()) return Fail(rig.status().message());
  Session session(args, **rig);
  const mpdrig::Status opened = session.OpenLog();
  if (!opened.ok()) return Fail(opened.message());
  return session.Loop();
}

// The options, in groups for --help: where the rig is, how to control it, what to run and report.
void AddConnectionOptions(CLI::App& app, Args& args) {
  CLI::Option_group* g = app.add_option_group("Rig and connection");
  g->add_option("--rig", args.rig_id, "rig id to control")->capture_default_str();
  g->add_option("--domain", args.domain, "DDS domain id")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  g->add_option("--dds-config", args.dds_config, "Cyclone DDS XML (default: loopback only)");
  g->add_option("--security", args.security,
                "DDS Security: this student's (or the instructor's) identity directory of a "
                "class (deploy/security/make-class OUT NAME: OUT/NAME); the rig's topics are "
                "then in partition rig.<rig id>. Refuses an invalid directory, saying why");
  g->add_option("--strength", args.strength,
                "ownership strength of the choke commands: of several controllers the "
                "strongest live one wins (an instructor taking over a class's rig: 100)")
      ->capture_default_str();
  g->add_flag("--lockstep", args.lockstep,
              "the rig runs `mpdrig serve --clock lockstep`: this controller steps it one "
              "sample at a time (deterministic)");
  g->add_option("--timeout", args.timeout_s,
                "give up after this long without samples [s]: before the first, exit 1 (no "
                "rig); after it, the rig is lost (exit 3, see below)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

void AddControlOptions(CLI::App& app, Args& args, bool* no_feedforward) {
  ControllerOptions& c = args.control;
  CLI::Option_group* g = app.add_option_group("Control (set point, gains, plant model)");
  g->add_option("--setpoint-barg", c.setpoint_barg,
                "bottom-hole pressure to hold [barg] (default: with the choke left as it is, "
                "watch --settle seconds, then hold the mean over the next --learn seconds)");
  g->add_option("--learn", c.learn_s,
                "without --setpoint-barg: watch this long [s], rounded to whole heave "
                "periods when the heave's frequency is known")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  g->add_option("--settle", c.settle_s,
                "without --setpoint-barg: watch at least this long, and two heave periods, "
                "before learning [s] (the heave's start-up transient; the observer's, which "
                "estimates the sensors' noise and converges in about two periods)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  g->add_flag("--use-estimate", args.use_estimate,
              "control the observer's BHP_est (mpdrig_estimate) instead of the PT1 transmitter: "
              "what a controller on a real well, without a downhole sensor, would do");
  g->add_option("--kp", c.kp_deg_per_bar, "proportional gain [deg of choke per bar]")
      ->capture_default_str();
  g->add_option("--ki", c.ki_deg_per_bar_s, "integral gain [deg per bar per s]")
      ->capture_default_str();
  g->add_flag("--no-feedforward", *no_feedforward,
              "PI only: no adaptive cancellation of the heave (it needs mpdrig_estimate)");
  g->add_option("--adapt", c.adapt_per_s,
                "adaptation rate gamma of the heave cancellation [1/s]; above about 0.4 the "
                "adaptation outruns the pipe's delay and oscillates")
      ->check(CLI::Range(0.0, 5.0))
      ->capture_default_str();
  g->add_option("--choke-gain", c.choke_gain_bar_per_deg,
                "plant model: BHP drop per degree of choke opening [bar/deg] (about 2 dp/G "
                "dG/dtheta at the operating point)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  g->add_option("--delay", c.delay_s,
                "plant model: delay from the choke to the bottom [s] (l/c = 1.06 s, plus the "
                "actuator's 0.1 s and the pipe's phase)")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  g->add_option("--choke-min-deg", c.choke_min_deg, "lowest choke reference [deg]")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  g->add_option("--choke-max-deg", c.choke_max_deg, "highest choke reference [deg]")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
}

void AddRunOptions(CLI::App& app, Args& args) {
  CLI::Option_group* g = app.add_option_group("Run and report");
  g->add_flag("--open-loop", args.open_loop,
              "write no commands: only measure (the fixed-choke baseline)");
  g->add_option("--duration", args.duration_s, "stop at this rig time [s] (0: run until Ctrl-C)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g->add_option("--measure-last", args.measure_last_s,
                "report PT1 over the last this many seconds of --duration (stdout, one "
                "key=value line): its half peak-to-peak swing and mean, and, robust to the "
                "sensors' noise, its component at the heave frequency and the RMS of its "
                "periodic part (harmonics 1-3)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  g->add_option("--log", args.log_path,
                "write a CSV of time, PT1, BHP_est, choke position and reference, set point "
                "(rig-log column names)");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "bhp_controller - hold a rig's bottom-hole pressure at a set point against heave with the "
      "choke (an example client: it speaks only the DDS topics)");
  Args args;
  bool no_feedforward = false;
  AddConnectionOptions(app, args);
  AddControlOptions(app, args, &no_feedforward);
  AddRunOptions(app, args);
  app.footer(
      "Control law (details at the top of clients/bhp_controller.cc):\n"
      "  e = BHP - set point;  choke = u_I + Kp e + Re{theta z};  u_I' = Ki e (anti-windup)\n"
      "PI alone cannot reject 0.1-0.2 Hz heave: the choke acts 1.06 s (l/c) away from the\n"
      "bottom. The observer's heave phasor z = v_d + j omega x_d (mpdrig_estimate) gives the\n"
      "phase of the disturbance, and theta adapts until the oscillation at omega is gone.\n"
      "Examples (serve in one terminal, the controller in another):\n"
      "  mpdrig serve --heave-amp-m 0.1 --heave-hz 0.2 --pump-lpm 5 --choke-deg 31\n"
      "  bhp_controller --rig rig-1                 # watches 20 s, then holds the mean BHP\n"
      "  bhp_controller --rig rig-1 --use-estimate  # on the observer's estimate, no PT1\n"
      "  bhp_controller --rig rig-1 --no-feedforward  # PI only: watch it fail at 0.2 Hz\n"
      "Attenuation, fixed choke vs controlled: bench/bhp_attenuation.sh\n"
      "A lost rig: when the rig's time or sample counter goes back (the service restarted), its\n"
      "sensor writer leaves (the service exited, or crashed and its lease ran out) or no sample\n"
      "comes for --timeout s, the controller says why on stderr and exits with status 3, without\n"
      "its summary line: its integrator, set point and adaptation belong to the lost run.\n"
      "Another controller on the same rig: the choke obeys the strongest live writer (a tie goes\n"
      "by GUID) and drops the others' commands without a word. The controller checks the rig's\n"
      "status every second of rig time; while another writer has the choke it says so on stderr,\n"
      "and a run that lost the choke for any part of it ends with status 4 after its summary.");
  CLI11_PARSE(app, argc, argv);
  ControllerOptions& c = args.control;
  c.feedforward = !no_feedforward;
  if (!(c.choke_min_deg < c.choke_max_deg)) {
    std::fprintf(stderr, "bhp_controller: --choke-min-deg must be below --choke-max-deg\n");
    return 2;
  }
  if (args.measure_last_s > args.duration_s) {
    std::fprintf(stderr, "bhp_controller: --measure-last needs a --duration at least as long\n");
    return 2;
  }
  return Run(args);
}
