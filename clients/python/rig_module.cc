// The Python binding of clients/client/rig_client.h and its control loop (control_loop.h):
// module mpdrig._mpdrig, wrapped by the package mpdrig (clients/python/mpdrig/__init__.py), which
// adds stream() and ticks() on the loop, and the context manager.
// Failures become exceptions here and only here: TimeoutError, mpdrig.RigLost (the rig restarted,
// left or went silent) and mpdrig.RigError for the rest. Blocking calls release the GIL and
// check for Ctrl-C every 100 ms.
#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <string>

#include "clients/client/control_loop.h"
#include "clients/client/rig_client.h"

namespace py = pybind11;
using mpdrig::client::ControlLoop;
using mpdrig::client::Failure;
using mpdrig::client::LoopEnd;
using mpdrig::client::Rig;

namespace {

// Owned by the module for the life of the process (not py::object: no destructor after the
// interpreter has gone).
PyObject* g_rig_error = nullptr;
PyObject* g_rig_lost = nullptr;

// Raises the Python exception for a failed call of `rig` (with the GIL held).
[[noreturn]] void Raise(const Rig* rig, Failure failure, const std::string& message) {
  switch (failure) {
    case Failure::kTimeout:
      PyErr_SetString(PyExc_TimeoutError, message.c_str());
      break;
    case Failure::kLost:
      PyErr_SetString(g_rig_lost, message.c_str());
      break;
    case Failure::kInterrupted:
      PyErr_SetNone(PyExc_KeyboardInterrupt);
      break;
    default:
      PyErr_SetString(g_rig_error, message.c_str());
      break;
  }
  (void)rig;
  throw py::error_already_set();
}

// Checks for Ctrl-C while a call waits without the GIL.
bool Interrupted() {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  PyErr_Clear();  // raised again as KeyboardInterrupt by Raise
  return true;
}

// Runs `call(interrupt)` on `rig` without the GIL and returns its value or raises.
template <typename Call>
auto Blocking(Rig& rig, Call call) {
  decltype(call(Rig::Interrupt{})) result = [&] {
    py::gil_scoped_release release;
    return call(Rig::Interrupt(Interrupted));
  }();
  if constexpr (std::is_same_v<decltype(result), mpdrig::Status>) {
    if (!result.ok()) Raise(&rig, rig.last_failure(), result.message());
    return;
  } else {
    if (!result.ok()) Raise(&rig, rig.last_failure(), result.status().message());
    return std::move(result).value();
  }
}

py::array_t<double> Array(const double* data, std::size_t n) {
  py::array_t<double> out(static_cast<py::ssize_t>(n));
  std::copy(data, data + n, out.mutable_data());
  return out;
}

// The rig-log columns (rig-log-format.md) of a sample, in rig_echo's order.
py::dict AsRow(const mpdrig::client::Sensors& s) {
  py::dict row;
  row["time_s"] = s.time_s;
  row["piston_position_m"] = s.piston_position_m;
  row["choke_position_deg"] = s.choke_position_deg;
  row["FT2_lpm"] = s.FT2_lpm;
  row["C1_barg"] = s.C1_barg;
  row["P1_barg"] = s.P1_barg;
  row["P2_barg"] = s.P2_barg;
  for (int i = 0; i < 10; ++i) row[py::str("PT{}_barg").format(i + 1)] = s.PT_barg[i];
  row["C2_barg"] = s.C2_barg;
  row["FT1_lpm"] = s.FT1_lpm;
  row["FT3_lpm"] = s.FT3_lpm;
  row["FT4_lpm"] = s.FT4_lpm;
  return row;
}

// The module's exceptions: RigError and its RigLost.
void BindErrors(py::module_& m) {
  g_rig_error =
      PyErr_NewExceptionWithDoc("mpdrig.RigError",
                                "A call to the rig failed: no such rig, a DDS error, a bad "
                                "argument. The message says what and why.",
                                PyExc_RuntimeError, nullptr);
  g_rig_lost = PyErr_NewExceptionWithDoc(
      "mpdrig.RigLost",
      "The rig is lost: its time or sample counter went back (the service restarted), its "
      "sensor writer left (the service exited) or no sample came for `timeout` seconds. The Rig "
      "object is finished: a controller's state belongs to the lost run; connect anew.",
      g_rig_error, nullptr);
  if (g_rig_error == nullptr || g_rig_lost == nullptr) throw py::error_already_set();
  m.attr("RigError") = py::handle(g_rig_error);
  m.attr("RigLost") = py::handle(g_rig_lost);
}

// mpdrig.Sensors: one sample of every lab channel.
void BindSensors(py::module_& m) {
  using mpdrig::client::Sensors;
  py::class_<Sensors> sensors(
      m, "Sensors",
      "One sample of every lab channel of the rig, in lab units: pressures in "
      "bar gauge (barg), flows in L/min (lpm), the choke in degrees (0 closed .. "
      "90 open), positions in metres, time in seconds of rig time.");
  sensors
      .def_readonly("sample_counter", &Sensors::sample_counter,
                    "0, 1, 2, ... per rig, without gaps unless samples were dropped")
      .def_readonly("time_s", &Sensors::time_s, "the rig's own clock [s]")
      .def_readonly("piston_position_m", &Sensors::piston_position_m,
                    "heave generator (BHA) position [m], positive up")
      .def_readonly("choke_position_deg", &Sensors::choke_position_deg,
                    "measured choke opening [deg], 0 closed .. 90 open")
      .def_readonly("P1_barg", &Sensors::P1_barg, "below the BHA (floor level) [barg]")
      .def_readonly("P2_barg", &Sensors::P2_barg, "above the BHA, pipe inlet [barg]")
      .def_property_readonly(
          "PT_barg", [](const Sensors& s) { return Array(s.PT_barg.data(), s.PT_barg.size()); },
          "numpy array of PT1..PT10 [barg] at x = 0, 100, ..., 900 m (PT1 is the bottom-hole "
          "pressure, PT10 topside)")
      .def_property_readonly(
          "BHP_barg", [](const Sensors& s) { return s.PT_barg[0]; },
          "bottom-hole pressure [barg]: PT1, the pipe inlet pressure p(0)")
      .def_readonly("C1_barg", &Sensors::C1_barg, "choke outlet pressure [barg]")
      .def_readonly("C2_barg", &Sensors::C2_barg, "choke inlet pressure [barg]")
      .def_readonly("FT1_lpm", &Sensors::FT1_lpm, "pipe outlet flow [L/min]")
      .def_readonly("FT2_lpm", &Sensors::FT2_lpm, "back-pressure pump flow [L/min]")
      .def_readonly("FT3_lpm", &Sensors::FT3_lpm, "flow through the choke [L/min]")
      .def_readonly("FT4_lpm", &Sensors::FT4_lpm, "pipe inlet flow [L/min]")
      .def("as_dict", &AsRow,
           "The sample as {column: value} with rig-log column names (time_s, ..., PT1_barg, "
           "..., FT4_lpm), in the column order rig_echo writes.")
      .def("__repr__", [](const Sensors& s) {
        char text[256];
        std::snprintf(text, sizeof text,
                      "<mpdrig.Sensors #%llu t=%.3f s PT1=%.4f barg C2=%.4f barg choke=%.2f deg "
                      "FT1=%.3f lpm piston=%.4f m>",
                      static_cast<unsigned long long>(s.sample_counter), s.time_s, s.PT_barg[0],
                      s.C2_barg, s.choke_position_deg, s.FT1_lpm, s.piston_position_m);
        return std::string(text);
      });
  // PT1_barg .. PT10_barg, one property each, so a sample reads like the rig log's columns.
  {
    static std::deque<std::string> texts;  // names and docs live as long as the module
    for (int i = 0; i < 10; ++i) {
      const std::string& name = texts.emplace_back("PT" + std::to_string(i + 1) + "_barg");
      const std::string& doc =
          texts.emplace_back("pressure transmitter PT" + std::to_string(i + 1) +
                             " at x = " + std::to_string(100 * i) + " m [barg]");
      sensors.def_property_readonly(
          name.c_str(), [i](const Sensors& s) { return s.PT_barg[i]; }, doc.c_str());
    }
  }
}

// mpdrig.Estimate: the observer's estimate for a sample.
void BindEstimate(py::module_& m) {
  using mpdrig::client::Estimate;
  py::class_<Estimate>(m, "Estimate",
                       "The backstepping observer's estimate for one sensor sample (thesis ch. "
                       "10), from the topside channels C2 and FT1 only.")
      .def_readonly("sample_counter", &Estimate::sample_counter,
                    "the Sensors sample this estimate goes with")
      .def_readonly("time_s", &Estimate::time_s, "that sample's time [s]")
      .def_readonly("observer_time_s", &Estimate::observer_time_s,
                    "the observer's last step [s] (time_s minus less than one step)")
      .def_readonly("BHP_est_barg", &Estimate::BHP_est_barg,
                    "estimated bottom-hole pressure [barg] (compare with PT1)")
      .def_readonly("piston_velocity_est_mps", &Estimate::piston_velocity_est_mps,
                    "estimated heave velocity [m/s], positive up")
      .def_readonly("piston_position_est_m", &Estimate::piston_position_est_m,
                    "estimated zero-mean heave position [m]")
      .def_readonly("FT4_est_lpm", &Estimate::FT4_est_lpm, "estimated pipe inlet flow [L/min]")
      .def_readonly("disturbance_frequency_hz", &Estimate::disturbance_frequency_hz,
                    "heave frequency of the disturbance model [Hz]")
      .def_readonly("frequency_source", &Estimate::frequency_source,
                    "'piston_sine' (the commanded sine), 'tracked' or 'unlocked'")
      .def("__repr__", [](const Estimate& e) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "<mpdrig.Estimate #%llu t=%.3f s BHP_est=%.4f barg v_d=%.4f m/s f=%.3f Hz>",
                      static_cast<unsigned long long>(e.sample_counter), e.time_s, e.BHP_est_barg,
                      e.piston_velocity_est_mps, e.disturbance_frequency_hz);
        return std::string(text);
      });
}

// mpdrig.Profile: the pressure along the pipe.
void BindProfile(py::module_& m) {
  using mpdrig::client::Profile;
  py::class_<Profile>(m, "Profile",
                      "Pressure along the pipe at one sample, for plots of the waves.")
      .def_readonly("sample_counter", &Profile::sample_counter)
      .def_readonly("time_s", &Profile::time_s, "rig time [s]")
      .def_property_readonly(
          "position_m",
          [](const Profile& p) { return Array(p.position_m.data(), p.position_m.size()); },
          "numpy array: positions [m] from the inlet (x = 0, bottom) to the choke (900 m)")
      .def_property_readonly(
          "pressure_barg",
          [](const Profile& p) { return Array(p.pressure_barg.data(), p.pressure_barg.size()); },
          "numpy array: the rig's pressure [barg] at position_m")
      .def_property_readonly(
          "pressure_est_barg",
          [](const Profile& p) {
            return Array(p.pressure_est_barg.data(), p.pressure_est_barg.size());
          },
          "numpy array: the observer's estimate [barg] there (empty without an observer)");
}

// mpdrig.Status: what the rig reports about itself.
void BindStatus(py::module_& m) {
  using mpdrig::client::RigStatus;
  py::class_<RigStatus>(m, "Status", "What the rig reports about itself (topic mpdrig_status).")
      .def_readonly("clock", &RigStatus::clock, "'realtime', 'fast' or 'lockstep'")
      .def_readonly("sim_time_s", &RigStatus::sim_time_s, "rig time [s]")
      .def_readonly("real_time_factor", &RigStatus::real_time_factor)
      .def_readonly("deadline_misses", &RigStatus::deadline_misses)
      .def_readonly("lost_periods", &RigStatus::lost_periods,
                    "real time: the sensor periods the late ticks skipped")
      .def_readonly("longest_stall_s", &RigStatus::longest_stall_s,
                    "real time: the longest stall [s of wall time]")
      .def_readonly("last_stall_sim_time_s", &RigStatus::last_stall_sim_time_s,
                    "real time: the rig time of the last stall (-1: never)")
      .def_readonly("rejected_commands", &RigStatus::rejected_commands,
                    "commands the rig refused so far (NaN, out of range, unknown rig)")
      .def_readonly("last_rejection", &RigStatus::last_rejection,
                    "why the last refused command was refused, with its topic")
      .def_readonly("last_completed_step_request", &RigStatus::last_completed_step_request)
      .def_readonly("warnings", &RigStatus::warnings)
      .def_readonly("active_effects", &RigStatus::active_effects)
      .def_readonly("actuator_owners", &RigStatus::actuator_owners,
                    "per actuator, the ownership strength and writer of the command in force")
      .def_readonly("sensor_noise", &RigStatus::sensor_noise)
      .def_readonly("atmospheric_pressure_pa", &RigStatus::atmospheric_pressure_pa)
      .def("__repr__", [](const RigStatus& s) {
        return "<mpdrig.Status clock=" + s.clock + " t=" + std::to_string(s.sim_time_s) +
               " s rejected=" + std::to_string(s.rejected_commands) + ">";
      });
}

// mpdrig._Rig's reads: the latest and the next samples, estimates, profile, status, refusals.
void BindRigReads(py::class_<Rig>& rig) {
  rig.def(
         "sensors",
         [](Rig& r, bool fresh) {
           return Blocking(r, [&](const Rig::Interrupt& i) { return r.Latest(fresh, i); });
         },
         py::arg("fresh") = false)
      .def("next_sensors",
           [](Rig& r) { return Blocking(r, [&](const Rig::Interrupt& i) { return r.Next(i); }); })
      .def("pending",
           [](Rig& r) {
             return Blocking(r, [&](const Rig::Interrupt&) { return r.TakeArrived(); });
           })
      .def(
          "estimate",
          [](Rig& r, std::optional<std::uint64_t> counter) {
            return Blocking(r, [&](const Rig::Interrupt& i) { return r.EstimateFor(counter, i); });
          },
          py::arg("sample_counter") = py::none())
      .def("profile",
           [](Rig& r) {
             return Blocking(r, [&](const Rig::Interrupt& i) { return r.LatestProfile(i); });
           })
      .def("status",
           [](Rig& r) {
             return Blocking(r, [&](const Rig::Interrupt& i) { return r.LatestStatus(i); });
           })
      .def("rejections", [](Rig& r) {
        return Blocking(r, [&](const Rig::Interrupt& i) { return r.NewRejections(i); });
      });
}

// mpdrig._Rig's commands: choke, pump, outlet, piston, and a lockstep rig's steps.
void BindRigCommands(py::class_<Rig>& rig) {
  rig.def(
         "choke",
         [](Rig& r, double deg) {
           Blocking(r, [&](const Rig::Interrupt& i) { return r.Choke(deg, i); });
         },
         py::arg("opening_deg"))
      .def(
          "pump",
          [](Rig& r, double lpm) {
            Blocking(r, [&](const Rig::Interrupt& i) { return r.Pump(lpm, i); });
          },
          py::arg("flow_lpm"))
      .def(
          "outlet",
          [](Rig& r, double barg) {
            Blocking(r, [&](const Rig::Interrupt& i) { return r.Outlet(barg, i); });
          },
          py::arg("pressure_barg"))
      .def("_piston",
           [](Rig& r, int mode, double position_m, double mean_m, double amplitude_m,
              double frequency_hz, double sweep_end_hz, double sweep_duration_s) {
             mpdrig::client::PistonCommand c;
             if (mode < 0 || mode > 3) Raise(&r, Failure::kError, "piston mode must be 0..3");
             c.mode = static_cast<mpdrig::client::PistonCommand::Mode>(mode);
             c.position_m = position_m;
             c.mean_m = mean_m;
             c.amplitude_m = amplitude_m;
             c.frequency_hz = frequency_hz;
             c.sweep_end_hz = sweep_end_hz;
             c.sweep_duration_s = sweep_duration_s;
             Blocking(r, [&](const Rig::Interrupt& i) { return r.Piston(c, i); });
           })
      .def(
          "step",
          [](Rig& r, long long steps) {
            if (steps < 1 || steps > 0xffffffffLL) {
              Raise(&r, Failure::kError, "steps must be in 1 .. 2^32 - 1");
            }
            return Blocking(r, [&](const Rig::Interrupt& i) {
              return r.Step(static_cast<std::uint32_t>(steps), i);
            });
          },
          py::arg("steps") = 1);
}

// mpdrig._Rig: the connection and its properties, then its reads and commands (mpdrig.Rig wraps
// it).
void BindRig(py::module_& m) {
  py::class_<Rig> rig(m, "_Rig");
  rig.def(py::init([](const std::string& rig_id, int domain, int strength, double timeout,
                      const std::string& dds_config, const std::string& security) {
            mpdrig::client::RigOptions options;
            options.rig_id = rig_id;
            options.domain = domain;
            options.strength = strength;
            options.timeout_s = timeout;
            options.dds_config = dds_config;
            options.security_dir = security;
            auto connected = [&] {
              py::gil_scoped_release release;
              return Rig::Connect(options, Interrupted);
            }();
            if (!connected.ok()) {
              const std::string message = connected.status().message();
              Raise(nullptr,
                    message == "interrupted"            ? Failure::kInterrupted
                    : message.rfind("no rig '", 0) == 0 ? Failure::kTimeout
                                                        : Failure::kError,
                    message);
            }
            return std::move(connected).value();
          }),
          py::arg("rig_id") = "rig-1", py::arg("domain") = 0, py::kw_only(),
          py::arg("strength") = 0, py::arg("timeout") = 10.0, py::arg("dds_config") = "",
          py::arg("security") = "")
      .def_property_readonly("rig_id", [](const Rig& r) { return r.options().rig_id; })
      .def_property_readonly("domain", [](const Rig& r) { return r.options().domain; })
      .def_property_readonly("strength", [](const Rig& r) { return r.options().strength; })
      .def_property_readonly("timeout", [](const Rig& r) { return r.options().timeout_s; })
      .def_property_readonly("security", [](const Rig& r) { return r.options().security_dir; })
      .def_property_readonly("lockstep", &Rig::lockstep)
      .def_property_readonly("lost", [](const Rig& r) { return r.lost(); })
      .def_property_readonly("closed", &Rig::closed)
      .def("close", &Rig::Close, py::call_guard<py::gil_scoped_release>(),
           "Leave the rig: commands written are acknowledged first (up to the timeout, 10 s at "
           "most), then the writers are deleted, so another controller takes over at once.");
  BindRigReads(rig);
  BindRigCommands(rig);
}

// mpdrig._Loop: the client library's control loop (clients/client/control_loop.h) over a _Rig;
// mpdrig.Rig.stream() and ticks() iterate it. next() returns the next Tick, None when the run is
// over as asked (its duration), and raises for the rest: KeyboardInterrupt (Ctrl-C, checked
// every 100 ms while it waits), RigLost (lost, or the service ended its run), TimeoutError (no
// sample within the timeout) and RigError.
void BindLoop(py::module_& m) {
  using mpdrig::client::LoopOptions;
  using mpdrig::client::Tick;
  py::class_<Tick>(m, "Tick",
                   "One tick of a control loop: the sample, the observer's estimate that goes "
                   "with it (or None) and the rig time since the last tick.")
      .def_readonly("sensors", &Tick::sensors)
      .def_readonly("estimate", &Tick::estimate)
      .def_readonly("dt_s", &Tick::dt_s, "rig time since the last tick [s] (0 at the first)")
      .def_readonly("index", &Tick::index, "0, 1, 2, ... ticks of this loop")
      .def("__repr__", [](const Tick& t) {
        return "<mpdrig.Tick #" + std::to_string(t.index) +
               " t=" + std::to_string(t.sensors.time_s) +
               " s estimate=" + (t.estimate ? "yes" : "no") + ">";
      });
  py::class_<ControlLoop>(m, "_Loop")
      .def(py::init([](Rig& rig, double duration_s, bool every_sample, int estimates) {
             if (estimates < 0 || estimates > 2) {
               Raise(&rig, Failure::kError, "estimates must be 0 (none), 1 (newest), 2 (paired)");
             }
             if (!(duration_s >= 0.0)) {
               Raise(&rig, Failure::kError, "the duration must be a number of seconds >= 0");
             }
             LoopOptions options;
             options.duration_s = duration_s;
             options.samples =
                 every_sample ? LoopOptions::Samples::kEvery : LoopOptions::Samples::kNewest;
             options.estimates = static_cast<LoopOptions::Estimates>(estimates);
             options.interrupt = Interrupted;  // Ctrl-C, not the loop's own signal handlers
             return std::make_unique<ControlLoop>(rig, std::move(options));
           }),
           py::arg("rig"), py::arg("duration_s") = 0.0, py::arg("every_sample") = false,
           py::arg("estimates") = 0, py::keep_alive<1, 2>())
      .def("next", [](ControlLoop& loop, Rig& rig) -> std::optional<Tick> {
        std::optional<Tick> tick;
        {
          py::gil_scoped_release release;
          tick = loop.Next();
        }
        if (tick) return tick;
        const auto& result = loop.result();
        switch (result.end) {
          case LoopEnd::kSignal:
            Raise(&rig, Failure::kInterrupted, "");
          case LoopEnd::kRigEnded:
          case LoopEnd::kRigLost:
            Raise(&rig, Failure::kLost, "rig " + rig.options().rig_id + " lost: " + result.message);
          case LoopEnd::kError:
            Raise(&rig, result.failure == Failure::kTimeout ? Failure::kTimeout : Failure::kError,
                  result.message);
          default:
            return std::nullopt;
        }
      });
}

}  // namespace

PYBIND11_MODULE(_mpdrig, m) {
  m.doc() = "Binding of the mpdrig client library (clients/client/rig_client.h); use `mpdrig`.";
  BindErrors(m);
  BindSensors(m);
  BindEstimate(m);
  BindProfile(m);
  BindStatus(m);
  BindRig(m);
  BindLoop(m);
}
