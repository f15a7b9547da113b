// Writing simulated samples as a rig log in the lab's units (rig-log-format.md).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "model/common/status.h"
#include "model/riglog/channels.h"
#include "model/riglog/rig_log_writer.h"
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

// Streams simulated samples into a rig log as they come, so a long run is not held in memory
// (600 s at 1 kHz held whole took 135 MB). The log goes to a temporary file first (beside `path`,
// or in the temporary directory for "-", standard output): a run that fails leaves nothing at
// `path` and writes nothing to standard output, as when the samples were written at the end. Finish
// adds metadata only known after the run (a warning) to the file's metadata, then renames or copies
// it.
class SampleLogStream {
 public:
  static Result<SampleLogStream> Open(const std::string& path, riglog::Metadata metadata,
                                      double atmospheric_pressure_pa,
                                      const std::vector<double>& pressure_positions_m = {});
  SampleLogStream(SampleLogStream&&) noexcept;
  SampleLogStream& operator=(SampleLogStream&&) noexcept;
  ~SampleLogStream();  // removes the temporary file if Finish did not succeed

  Status Write(const RigSample& sample);
  std::size_t samples_written() const;
  // Closes the log, adds `late_metadata` after its other metadata and puts it at `path`.
  Status Finish(const riglog::Metadata& late_metadata = {});

 private:
  struct State;
  explicit SampleLogStream(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace mpdrig::cli
