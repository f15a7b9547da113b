// Options every model command shares: the rig configuration and how to simulate it.
//   --config FILE        Protobuf text config (rig_config.proto) on top of the thesis defaults
//   --set key=value      override one parameter (repeatable; `mpdrig params` lists the keys)
//   --model quasilinear|linear, --cells N, --scheme characteristics|mol
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "model/common/status.h"
#include "model/params/rig_params.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::cli {

struct ModelOptions {
  std::string config_path;
  std::vector<std::string> overrides;
  std::string model = "quasilinear";
  std::string scheme = "characteristics";
  int cells = kDefaultCells;

  // Registers --config and --set.
  void AddParamOptions(CLI::App* command);
  // Registers --model, --cells, --scheme as well.
  void AddAll(CLI::App* command);

  Result<RigParams> LoadParams() const;
  Result<SimulationOptions> LoadSimulationOptions() const;
  // "quasilinear, 200 cells, characteristics (dt 5.29 ms)"
  std::string Describe(const RigParams& params) const;
};

// Prints "mpdrig <command>: <message>" to stderr and returns the exit code for a failure.
int Fail(const std::string& command, const Status& status);

}  // namespace mpdrig::cli
