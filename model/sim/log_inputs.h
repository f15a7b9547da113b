// A rig log's inputs as the simulator's time functions (design.md, "Replaying a log"), shared by
// `mpdrig simulate --inputs` and `mpdrig compare`.
//
// Inputs (rig-log-format.md): piston_position and choke_position are required and must be
// measured (finite) on every row; FT2 (pump flow q_b) and C1 (outlet pressure p_0) are optional:
// absent means 0 and atmospheric, present means measured on every row. The piston position is a
// noisy measurement, so it is smoothed by a local quadratic fit over `smoothing_s` (model/signal)
// before the simulator differentiates it; the choke position is used as is (ChokeInput::kMeasured).
// Between samples every input is linear in time, beyond the ends it is held.
// The replay starts from the steady state (5.3.2) of the inputs' mean over the log's first
// kInitialInputWindowS, not of its first row: one noisy sample of FT2 (0.4 % of 8 L/min) would
// set the initial pressure 0.06 bar off, and that offset decays only at the pipe friction's rate
// (seconds), so a fit would bend f1 to follow the noise of one sample.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/rig_log.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig {

// Window over which a replay averages the log's rig inputs for its initial steady state.
inline constexpr double kInitialInputWindowS = 0.5;

// The mean of a log's rig inputs over its first kInitialInputWindowS: what every replay (Simulate
// on SignalsFromColumns, compare's RowPipeline) starts its steady state from. Rows in time order;
// those past the window are ignored.
class InitialInputs {
 public:
  void Add(double time_s, const RigInputs& row);
  RigInputs Mean() const;  // after at least one row

 private:
  double first_time_s_ = 0.0;
  long count_ = 0;
  RigInputs sum_{0.0, 0.0, 0.0};
};

// The input columns of a log, SI, one value per row of `time_s`.
struct LogInputColumns {
  std::vector<double> time_s;
  std::vector<double> piston_position_m;   // as measured (not smoothed)
  std::vector<double> choke_opening_frac;  // u_c
  std::vector<double> pump_flow_m3ps;      // q_b (FT2), 0 if the log has none
  std::vector<double> outlet_pressure_pa;  // p_0 (C1), absolute; atmospheric if the log has none
};

// Takes the input columns out of a whole log, checking them as described above. Errors name
// `path`, the column and the data row.
Result<LogInputColumns> InputColumnsFromLog(const riglog::RigLog& log, const std::string& path);

// Time functions of the inputs; the columns are moved into shared storage (one copy of time).
// Needs at least 2 rows.
Result<InputSignals> SignalsFromColumns(LogInputColumns columns, const std::string& path,
                                        double smoothing_s);

// InputColumnsFromLog + SignalsFromColumns.
Result<InputSignals> SignalsFromLog(const riglog::RigLog& log, const std::string& path,
                                    double smoothing_s);

// The smoothed piston position used by SignalsFromColumns (SmoothLocalQuadratic over
// smoothing_s), for tools that need the same signal the model was fed.
std::vector<double> SmoothedPistonPosition(const LogInputColumns& columns, double smoothing_s);

}  // namespace mpdrig
