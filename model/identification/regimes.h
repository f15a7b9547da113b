// Regimes of a log: the parts where the rig runs differently (the back-pressure pump stopped, the
// choke closed, the heave stopped), told from the log's inputs, and a split of the log into
// fitting and scoring data that leaves each regime on both sides, or says which it cannot.
//
// Each input is in one of two states at every sample (the reconstructed inputs, log_inputs.h):
//   pump (FT2, q_b):   "pump stopped" where q_b < kPumpOffFraction of its running level (the log's
//                      90th percentile of q_b), else "pump running";
//   choke (u_c):       "choke closed" where G(u_c) <= kClosedLeakFactor leak, the orifice passing
//                      little more than its leak (thesis Table 8.4.1 floored at the tuned leak,
//                      9.4), else "choke open";
//   piston (x_p):      "heave stopped" where the RMS of the piston velocity over kPistonWindowS
//                      about the sample is below kPistonStillFraction of its moving level (the
//                      90th percentile of that RMS over the log), else "heave running".
// A run of one state shorter than kMinRegimeS is given to the state around it (a transition, the
// taper between two heave tests). An input whose state changes in the log gives two regimes, one
// per state; one that keeps its state gives none: a log of step tests has no regime at all.
//
// Split (diagnose.h, step 1): fitting data [t0, s), scoring data [s, t1]. A regime is on a side
// when at least kMinRegimeShare of its time, and kMinRegimeSideS, lie there. Of the split points
// between kMinFitFraction and kMaxFitFraction of the log (and the requested fraction), the one
// nearest the requested fraction that puts every regime on both sides; if none does, the one that
// puts the most regimes on both sides (nearest the requested fraction among those), and the
// regimes left on one side are named. Without regimes the split is the requested fraction's.
#pragma once

#include <string>
#include <vector>

#include "model/analysis/measured_log.h"
#include "model/params/rig_params.h"

namespace mpdrig {

// Pump stopped: below a tenth of its running flow (a running pump never falls that low in a step
// test, and a stopped one reads its noise).
inline constexpr double kPumpOffFraction = 0.1;
// Choke closed: the orifice passes at most twice its leak (on the thesis's table, below ~25 deg).
inline constexpr double kClosedLeakFactor = 2.0;
// Heave stopped: the piston velocity's RMS over kPistonWindowS below 5 % of its moving level. The
// window spans the turning points of a heave down to 0.06 Hz (there the RMS over the window is
// still ~40 % of the moving level), so a slow heave is not taken for a stop.
inline constexpr double kPistonStillFraction = 0.05;
inline constexpr double kPistonWindowS = 4.0;
// A state must hold this long to be a regime (a step's or a taper's transition does not).
inline constexpr double kMinRegimeS = 3.0;
// On a side: at least this share of the regime's time there (half of what an even spread would
// put on the scoring side at the default split, 40 %) and at least kMinRegimeSideS.
inline constexpr double kMinRegimeShare = 0.2;
inline constexpr double kMinRegimeSideS = 1.0;
// Where the split may move: the fitting data at least 40 % of the log (the base parameters need
// the excitation), the scoring data at least 20 % (its blocks need samples).
inline constexpr double kMinFitFraction = 0.4;
inline constexpr double kMaxFitFraction = 0.8;

struct TimeInterval {
  double begin_s = 0.0;
  double end_s = 0.0;  // [begin_s, end_s); the log's last sample belongs to the last interval
};

struct Regime {
  std::string name;   // "pump stopped", "pump running", "choke closed", "choke open", ...
  std::string input;  // the input that tells it: "FT2", "choke_position", "piston_position"
  std::vector<TimeInterval> intervals;  // in time order, disjoint
  double duration_s = 0.0;
  // After the split: its time in the fitting and in the scoring data.
  double fit_s = 0.0;
  double score_s = 0.0;
  bool Contains(double t_s) const;
  // Its time in [begin_s, end_s).
  double TimeIn(double begin_s, double end_s) const;
};

// The regimes of `log` (above), in the order pump, choke, piston; the stopped/closed state of each
// input first. `params`: the choke's characteristic and leak.
std::vector<Regime> DetectRegimes(const MeasuredLog& log, const RigParams& params);

struct RegimeSplit {
  double split_s = 0.0;                // fitting data [t0, split_s), scoring data [split_s, t1]
  double requested_s = 0.0;            // t0 + fit_fraction (t1 - t0)
  std::vector<Regime> regimes;         // with fit_s and score_s
  std::vector<std::string> one_sided;  // "pump stopped: only in the scoring data (12.0 s)"
};

// The split (above) of [t0, t1] for `regimes`, near `fit_fraction`.
RegimeSplit SplitByRegimes(std::vector<Regime> regimes, double t0_s, double t1_s,
                           double fit_fraction);

// The regimes' time on each side of a given split, and those left on one side (requested_s =
// split_s).
RegimeSplit SplitAt(std::vector<Regime> regimes, double t0_s, double t1_s, double split_s);

// Whether `regime` counts as on a side holding `side_s` of its time.
bool OnSide(const Regime& regime, double side_s);

}  // namespace mpdrig
