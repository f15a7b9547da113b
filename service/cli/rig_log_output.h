// Writing simulated samples as a rig log in the lab's units (rig-log-format.md).
#pragma once

#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/channels.h"
#include "model/sim/rig_simulator.h"

namespace mpdrig::cli {

// Every channel of the rig in its lab unit (m, deg, lpm, barg), inputs first, then a column
// `p_<x>m_barg` for each extra pressure position.
Result<std::vector<riglog::ColumnSpec>> SimulatedColumns(
    const std::vector<double>& pressure_positions_m = {});

// Writes the samples to `path` ("-" for stdout); gauge pressures use `atmospheric_pressure_pa`.
Status WriteSamples(const std::string& path, riglog::Metadata metadata,
                    double atmospheric_pressure_pa, const std::vector<RigSample>& samples,
                    const std::vector<double>& pressure_positions_m = {});

}  // namespace mpdrig::cli
