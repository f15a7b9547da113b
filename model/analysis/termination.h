// How the rig's line ends for a frequency-response measurement: the configurations in which the
// thesis measured the first resonance of bottom-hole pressure / piston position (9.1, 11.1), all
// with the back-pressure pump off:
//   choke-closed        the choke shut: the copper pipe, then the topside tubes (rubber hose and
//                       PVC pipe, 8.3.2) and a closed choke. Measured 0.44 Hz (Fig. 9.1.2).
//   choke-open          the choke fully open: the outlet held at the outlet pressure p_0.
//                       Measured 0.25 Hz.
//   closed-at-pipe-end  a valve shut right after the copper pipe: u(L) = 0, the topside tubes and
//                       the choke cut off. Measured 0.49 Hz (11.1).
// A termination is one choice applied to the rig's parameters before anything is computed
// (ApplyTermination): the choke setting the response sees, and which topside elements stay on
// the line. The solver, the analytic response and the fits know nothing of terminations.
//
// Lossless bare pipe, closed at the piston (9.3): a closed outlet resonates at c/2L (9.3.4), an
// open one at c/4L (9.3.2); with c = 1173 m/s and L = 900 m, 0.652 and 0.326 Hz.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "model/analysis/frequency_response.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"

namespace mpdrig {

enum class Termination { kChokeClosed, kChokeOpen, kClosedAtPipeEnd };

struct TerminationInfo {
  Termination termination;
  std::string_view name;         // as on the command line and in a resonance list
  std::string_view description;  // one line
};

// Every termination, in the order above.
std::span<const TerminationInfo> TerminationTable();
std::string_view TerminationName(Termination termination);
// "choke-closed, choke-open, closed-at-pipe-end"
std::string TerminationNames();
// The termination called `name`, or an error that quotes it and lists the valid names.
Result<Termination> ParseTermination(std::string_view name);

// The effects that sit between the copper pipe's outlet and the choke (the topside), cut off by
// the valve of closed-at-pipe-end: topside_compliance (the tubes), choke_inertia (the liquid in
// them), pump_curve (the back-pressure pump, which joins at the choke).
bool IsTopsideEffect(std::string_view effect_name);

// The rig as the termination leaves it.
struct TerminatedRig {
  RigParams params;             // choke-closed and closed-at-pipe-end: no leak (a tight shut-off);
                                // closed-at-pipe-end: the topside effects removed
  ChokeSetting choke;           // closed or open
  double pump_flow_m3ps = 0.0;  // the pump is off in every termination
};
TerminatedRig ApplyTermination(const RigParams& params, Termination termination);

}  // namespace mpdrig
