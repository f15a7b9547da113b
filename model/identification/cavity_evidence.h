// Evidence of column separation in a log: pressures held on a floor, each hold ended by a steep
// rise (the cavity's collapse), at one absolute level on every channel and every hold.
//
// Where the liquid column separates, the pressure at the cavity is held at the vapour pressure
// p_v (or the higher pressure at which dissolved gas comes out) for as long as the cavity lives,
// and the cavity's collapse is a water hammer: the pressure jumps by rho c du within a travel
// time of a cell (Joukowsky; Wylie & Streeter, Fluid Transients in Systems, 1993, ch. 8; Bergant
// & Simpson 1999). p_v is a property of the liquid, so every hold on every channel sits at the
// same level. Free gas (gas_entrainment, thesis 8.3.5) lowers the wave speed where the pressure is
// low: its pressures fall smoothly, with no level they cannot pass, and a model without cavities
// cannot hold a floor. So a log with floors names column separation only if the candidate's
// model reproduces them.
//
// A hold is found on a pressure channel (P2, PT1..PT10, C2; not P1, which adds the piston's
// velocity-dependent drop to the inlet's pressure) as a run of at least kMinHoldS whose samples,
// averaged over kSmoothingSamples, stay within kLevelBand smoothed noise sigmas of the level, and
// that ends in a rise of at least kMinCollapseRise noise sigmas within kCollapseWindowS. The
// noise sigma is estimated from second differences (median absolute, robust to the rises). The
// level is the channel's low tail (its kLowQuantile quantile), at most kMaxFloorPa absolute: 20
// kPa, water's vapour pressure at 60 degC (2.3 kPa at 20 degC). A free-gas mixture's pressure
// also bottoms out softly where its gas expands (p V = const), and its compression fronts steepen,
// so it can show a short flat trough ended by a jump; measured on 10 synthetic gas_entrainment
// logs at low pressure (120 s, lab noise) those troughs lay at 24-36 kPa, every column separation
// hold at 1.3-4.9 kPa. (column_separation's fit still reaches 0.9 bar, gaseous cavitation; only
// the evidence is bounded.) No pressure channel's low tail may lie
// below the common level by more than kLevelBand of its noise sigma: the vapour pressure is the
// lowest pressure in the liquid (a low-pressure hold that another channel passes is a trough,
// not a floor). The evidence holds when holds are
// found on at least kMinHolds runs in all, and their levels agree across channels within
// kLevelBand sigmas of the noise: a smooth minimum of the heave (the parabola of a sine's trough
// stays within 3 smoothed sigmas of its bottom for up to half a second at the lab's noise) is
// neither ended by a jump nor repeated at one level over changing choke and pump settings.
//
// How it enters diagnose (diagnose.h): every ranked candidate and the base model are scored on
// the floor samples too, as one more "channel" per channel with holds (the RMS of the model's
// residual there over the channel's standard deviation, as NRMSE), averaged with the ordinary
// channels' errors into the ranking score. A model that cannot hold the floor is penalised by its
// misfit where the data hold it; on a log without floors nothing changes.
#pragma once

#include <vector>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/riglog/channels.h"

namespace mpdrig {

inline constexpr double kMinHoldS = 0.15;
inline constexpr int kSmoothingSamples = 5;
inline constexpr double kLevelBand = 3.0;
inline constexpr double kMinCollapseRise = 8.0;
inline constexpr double kCollapseWindowS = 0.06;
inline constexpr double kLowQuantile = 0.01;
inline constexpr double kMaxFloorPa = 2.0e4;
inline constexpr int kMinHolds = 2;

struct PressureHold {
  double start_s = 0.0;
  double end_s = 0.0;     // the collapse: the rise starts here
  double level_pa = 0.0;  // mean of the hold's samples [Pa abs]
  double rise_pa = 0.0;   // the rise within kCollapseWindowS after the hold
};

struct ChannelFloor {
  Channel channel = Channel::kPT1;
  std::size_t index = 0;  // in log.channels
  double noise_pa = 0.0;  // the channel's noise sigma (second differences)
  double level_pa = 0.0;  // the floor: mean over its holds' samples
  double low_pa = 0.0;    // the channel's kLowQuantile quantile
  std::vector<PressureHold> holds;
  std::vector<std::size_t> samples;  // the samples on the floor (the holds'), ascending
};

struct CavityEvidence {
  std::vector<ChannelFloor> floors;  // channels with holds at the common level
  double level_pa = 0.0;             // the common level [Pa abs]
  int holds = 0;                     // over all channels
  bool present() const { return holds >= kMinHolds && !floors.empty(); }
};

// The holds of the log's pressure channels over the whole log.
CavityEvidence FindPressureFloors(const MeasuredLog& log);

// Mean over the channels with a floor of the model's NRMSE on the floor samples (RMS residual
// there over the channel's standard deviation over the whole log); 0 where there is none.
double FloorError(const MeasuredLog& log, const CavityEvidence& evidence, const ModelTraces& model);

// The ranking score with the floors scored as channels of their own: the mean over the
// `channel_count` ordinary channels (error) and the floor channels (FloorError).
double ErrorWithFloors(double error, int channel_count, const CavityEvidence& evidence,
                       double floor_error);

}  // namespace mpdrig
