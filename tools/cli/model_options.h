// Options every model command shares: the rig configuration and how to simulate it.
//   --config FILE        Protobuf text config (rig_config.proto) on top of the thesis defaults
//   --effect NAME[:k=v]  switch a physical effect on (repeatable; `mpdrig effects` lists them)
//   --set key=value      override one parameter (repeatable; `mpdrig params` lists the keys;
//                        an effect's parameter is EFFECT.KEY)
//   --model quasilinear|linear, --cells N, --scheme characteristics|mol
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <CLI/CLI.hpp>

#include "model/analysis/log_replay.h"
#include "model/analysis/measured_log.h"
#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/riglog/rig_log_reader.h"
#include "model/sim/log_inputs.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::cli {

struct ModelOptions {
  std::string config_path;
  std::vector<std::string> effects;
  std::vector<std::string> overrides;
  std::string model = "quasilinear";
  std::string scheme = "characteristics";
  int cells = kDefaultCells;

  // Registers --config, --effect and --set.
  void AddParamOptions(CLI::App* command);
  // Registers --model, --cells, --scheme as well.
  void AddAll(CLI::App* command);

  // The config file, then the effects, then the overrides (so --set can reach an effect).
  Result<RigParams> LoadParams() const;
  // LoadParams, refusing a rig other than the NTNU rig (RigParams::layout: a reservoir - pipe -
  // valve rig runs only in `mpdrig simulate`, driven by its valve's closure law): `command` needs
  // the NTNU rig's piston, choke and pump, or its analytic model, which that rig does not have.
  Result<RigParams> LoadNtnuRigParams(std::string_view command) const;
  Result<SimulationOptions> LoadSimulationOptions() const;
  // "quasilinear, 200 cells, characteristics (dt 5.29 ms)"
  std::string Describe(const RigParams& params) const;
};

// Registers --raw-inputs and --piston-smoothing-s: how a command that replays a log feeds its
// inputs to the model (reconstructed under their noise by default; log_inputs.h).
void AddInputReplayOptions(CLI::App* command, InputReplayOptions* options);

// For a command that replays `log`: lets ChooseWarmup set options->warmup (unless
// --steady-start), corrects the log's reconstructed choke and FT2 levels from its pressures
// (unless --levels-as-measured; EstimateInputLevels; fit and diagnose do it at the parameters
// they fit: kAfterTheFit) and tells stderr how the inputs are fed (unless `quiet`).
Status PrepareReplay(MeasuredLog* log, const RigParams& params, const SimulationOptions& simulation,
                     InputReplayOptions* options, bool quiet,
                     InputLevels levels = InputLevels::kWithTheseParams);

// Tells stderr how a replay feeds the log's inputs (PrepareReplay's report): the reconstruction
// (where given and the inputs are reconstructed), its level correction (kWithTheseParams) and the
// warm-up.
void DescribeReplay(const InputReconstruction* reconstruction, const InputReplayOptions& options,
                    InputLevels levels);

// A command-line number: finite, the whole text. The error names `what` and the text.
Result<double> ParseFiniteNumber(const std::string& text, const std::string& what);
// --bounds KEY=LOWER:UPPER (fit, fit --resonances): the key and a range with LOWER < UPPER.
struct BoundsSpec {
  std::string key;
  double lower = 0.0, upper = 0.0;
};
Result<BoundsSpec> ParseBoundsSpec(const std::string& spec);

// Registers --max-gap-s: the longest gap in time a command accepts in a log it reads
// (riglog::ReadOptions, rig_log_reader.h).
void AddLogReadOptions(CLI::App* command, riglog::ReadOptions* options);

// Writes a command's text output (JSON, HTML, a config) to `path`, or to stdout for "-".
Status WriteText(const std::string& path, const std::string& text);

// Prints "mpdrig <command>: <message>" to stderr and returns the exit code for a failure.
int Fail(const std::string& command, const Status& status);
// A model error message in the command line's words: where the model names a remedy in its own
// terms ("effect 'x' is not switched on", "a longer gap limit"), the flag that applies it.
std::string CommandLineWording(std::string message);

}  // namespace mpdrig::cli
