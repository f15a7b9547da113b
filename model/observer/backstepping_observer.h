// The backstepping observer of thesis 10 (Aamo 2013): a copy of the LINEAR pipe model driven by
// the topside measurements, with output injection (10.1.1)-(10.1.5):
//   u^_t = -epsilon u^_x + c_1(x) v^ + p1(x) (y - u^(1))
//   v^_t =  epsilon v^_x + c_2(x) u^ + p2(x) (y - u^(1))
//   u^(0) = -v^(0) + C X^,    v^(1) = U(t),    dX^/dt = A X^ + exp(A a) L (y - u^(1))
// in the coordinates of observer_gains.h: u, v are the up- and down-going waves built from the
// volumetric flow and the gravity-free pressure; y = u(1) and U = v(1) come from C2 (= p(l)) and
// the outlet flow FT1 (= A u(l), or FT3 - FT2). Written back in the simulator's linear
// invariants (7.0.6)-(7.0.7), the corrective terms are exactly (10.2.26)-(10.2.27); we step the
// (u, v) form directly, which is the same linear system.
//
// Numerics: the characteristic grid of the pipe solvers, N cells, dt = l / (c N), so each wave
// moves exactly one node per step (exact transport). The sources (coupling c_1, c_2 and the
// injection) are integrated with the trapezoidal rule; the new-time terms are linear, so the
// implicit trapezoid is solved in closed form: first the outlet node (which fixes the new output
// error), then each interior node (a 2x2 solve), then X^ (Crank-Nicolson: a pure rotation keeps
// its norm), then the inlet node. Second order in dt. The measurements are taken at the end of
// each step (the caller interpolates a log to the grid times).
//
// With ObserverOptions::quadratic_friction the copy also carries -(f2 / 2A) q^|q^| exp(+-sigma x)
// in the u^ and v^ equations (the plant's f2 u|u| in these coordinates); at the new level it is
// linearised as (f2 / 2A) |q^_old| q^_new, so the node solves stay linear.
//
// With ObserverOptions::track_frequency a FrequencyTracker follows the measured up-going wave y
// and the gains are recomputed (SetDisturbanceFrequency) when its estimate moves.
//
// With GainDesign::kNoise and a noise that limits the design (measurement_noise.h), C2 and FT1
// pass through the zero-lag prefilter before anything else.
//
// Estimates: p^(x) at any x (PT1..PT10, BHP = p^(0)), the inlet flow FT4^ = q^(0), the piston
// velocity v_d^ = C_bar X^ and position -X^_1 / omega (zero-mean part of the heave).
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "model/common/status.h"
#include "model/observer/frequency_tracker.h"
#include "model/observer/observer_gains.h"
#include "model/params/rig_params.h"

namespace mpdrig::observer {

// One topside sample.
struct TopsideMeasurement {
  double outlet_pressure_pa = 0.0;  // C2 = p(l), absolute
  double outlet_flow_m3ps = 0.0;    // FT1 = A u(l) (or FT3 - FT2), positive out of the pipe
};

struct ObserverEstimate {
  double time_s = 0.0;
  double bhp_pa = 0.0;                          // p^(0), absolute (PT1 = P2 in the model)
  std::array<double, 10> pt_pa{};               // PT1..PT10 at x = 0, 100, ..., 900 m, absolute
  double inlet_flow_m3ps = 0.0;                 // FT4^ = q^(0) = u^(0) + v^(0)
  double piston_velocity_mps = 0.0;             // v_d^ = C_bar X^ (10.2.9)
  double piston_position_m = 0.0;               // -X^_1 / omega (zero-mean heave)
  Eigen::Vector2d disturbance_state{0.0, 0.0};  // X^ [m/s]
  double output_error_m3ps = 0.0;               // y - u^(1), the injected innovation
  double disturbance_hz = 0.0;                  // the frequency in use (tracked or given)
};

class BacksteppingObserver {
 public:
  // Starts at rest at the first measurement (u^ = v^ = 0 with p_sp from it, X^ = 0).
  static Result<BacksteppingObserver> Create(const RigParams& params,
                                             const ObserverOptions& options,
                                             const TopsideMeasurement& initial,
                                             double start_time_s = 0.0);

  double time_s() const { return start_time_s_ + steps_ * dt_s_; }
  double time_step_s() const { return dt_s_; }
  const ObserverGains& gains() const { return gains_; }
  const ObserverOptions& options() const { return options_; }

  // Advances one step; `raw` is the measurement at time_s() + time_step_s(), as measured (the
  // prefilter of GainDesign::kNoise, when on, is applied here).
  Status Step(const TopsideMeasurement& raw);
  // New disturbance frequency: recomputes L, exp(A a) L and p1, p2 (the kernels depend on the
  // friction only and are kept). The state is kept. New rig parameters (c, l, f1, areas) change
  // the grid, the time step and the kernels: create a new observer (gains are computed there).
  Status SetDisturbanceFrequency(double frequency_hz);
  // New measurement noise (e.g. estimated over a start-up window): recomputes the gains and the
  // prefilter as SetDisturbanceFrequency does. The state (and the prefilter's) is kept.
  Status SetMeasurementNoise(const MeasurementNoise& noise);

  ObserverEstimate Estimate() const;
  double PressureAtPa(double x_m) const;  // absolute, linear between nodes
  double FlowAtM3ps(double x_m) const;

 private:
  // Recomputes the gains for `options` (SetDisturbanceFrequency, SetMeasurementNoise).
  Status Redesign(const ObserverOptions& options);
  // The grid interval holding x and the weight of its upper node.
  void Locate(double x_m, int* index, double* weight) const;
  BacksteppingObserver(const RigParams& params, const ObserverOptions& options, ObserverGains gains,
                       KernelSolution kernel);
  double MeasuredUp(const TopsideMeasurement& m) const;    // y = u(1)
  double MeasuredDown(const TopsideMeasurement& m) const;  // U = v(1)
  // Step's parts, in their order (thesis 10.1.3-10.1.5 on the characteristics' grid).
  double OldSourceU(int i, double e_old) const;
  double OldSourceV(int i, double e_old) const;
  double StepOutletNode(double y, double big_u, double e_old);
  void StepInteriorNodes(double e_old, double e_new);
  void StepDisturbanceModel(double e_old, double e_new);
  void StepInletNode(double e_old, double e_new);
  Status TrackFrequency(double y);

  RigParams params_;
  ObserverOptions options_;
  ObserverGains gains_;
  KernelSolution kernel_;
  double dt_s_ = 0.0;
  double start_time_s_ = 0.0;
  long steps_ = 0;
  double p_sp_pa_ = 0.0;
  std::vector<double> c1_, c2_;           // c_1(x_i), c_2(x_i)
  std::vector<double> e_plus_, e_minus_;  // exp(+-sigma x_i)
  double half_f2_over_a_ = 0.0;  // (f2 / 2A) when ObserverOptions::quadratic_friction, else 0
  std::vector<double> q_;        // scratch: q^ at the nodes, old level
  std::vector<double> u_, v_, u_next_, v_next_;
  Eigen::Vector2d x_hat_{0.0, 0.0};
  double error_ = 0.0;                           // y - u^(1) at the current time
  std::optional<FrequencyTracker> tracker_;      // ObserverOptions::track_frequency
  ZeroLagFilter pressure_filter_, flow_filter_;  // GainDesign::kNoise prefilter on C2, FT1
};

// A topside record (e.g. from a rig log): strictly increasing times, finite values.
struct TopsideSeries {
  std::vector<double> time_s;
  std::vector<double> outlet_pressure_pa;
  std::vector<double> outlet_flow_m3ps;
};

// Runs the observer over the series (measurements linearly interpolated to the grid times) and
// returns the estimate at each of `output_times` (linear between observer steps); outputs
// outside the series' time span are NaN.
Result<std::vector<ObserverEstimate>> RunObserver(const RigParams& params,
                                                  const ObserverOptions& options,
                                                  const TopsideSeries& series,
                                                  const std::vector<double>& output_times);

}  // namespace mpdrig::observer
