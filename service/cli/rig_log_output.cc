#include "service/cli/rig_log_output.h"

#include "model/riglog/rig_log_writer.h"

namespace mpdrig::cli {

namespace {
// Inputs first (what drove the rig), then the measurements from the bottom up.
constexpr Channel kOutputOrder[] = {Channel::kPistonPosition,
                                    Channel::kChokePosition,
                                    Channel::kFT2,
                                    Channel::kC1,
                                    Channel::kP1,
                                    Channel::kP2,
                                    Channel::kPT1,
                                    Channel::kPT2,
                                    Channel::kPT3,
                                    Channel::kPT4,
                                    Channel::kPT5,
                                    Channel::kPT6,
                                    Channel::kPT7,
                                    Channel::kPT8,
                                    Channel::kPT9,
                                    Channel::kPT10,
                                    Channel::kC2,
                                    Channel::kFT1,
                                    Channel::kFT3,
                                    Channel::kFT4};
}  // namespace

Result<std::vector<riglog::ColumnSpec>> SimulatedColumns(
    const std::vector<double>& pressure_positions_m) {
  std::vector<riglog::ColumnSpec> columns;
  for (Channel channel : kOutputOrder) columns.push_back(riglog::LabColumn(channel));
  for (double x : pressure_positions_m) {
    auto column = riglog::MakeColumn("p_" + riglog::FormatNumber(x) + "m", riglog::Unit::kBarg);
    if (!column.ok()) return column.status();
    columns.push_back(*column);
  }
  return columns;
}

Status WriteSamples(const std::string& path, riglog::Metadata metadata,
                    double atmospheric_pressure_pa, const std::vector<RigSample>& samples,
                    const std::vector<double>& pressure_positions_m) {
  bool has_atmosphere = false;
  for (const auto& [key, value] : metadata)
    has_atmosphere |= key == riglog::kAtmosphericPressureKey;
  if (!has_atmosphere) {
    metadata.emplace_back(std::string(riglog::kAtmosphericPressureKey),
                          riglog::FormatNumber(atmospheric_pressure_pa));
  }
  auto columns = SimulatedColumns(pressure_positions_m);
  if (!columns.ok()) return columns.status();
  auto writer = riglog::RigLogWriter::Open(path, std::move(metadata), *columns);
  if (!writer.ok()) return writer.status();
  const std::size_t fixed = std::size(kOutputOrder);
  std::vector<double> row(fixed + pressure_positions_m.size());
  for (const RigSample& sample : samples) {
    for (std::size_t i = 0; i < fixed; ++i) row[i] = sample[kOutputOrder[i]];
    for (std::size_t i = 0; i < pressure_positions_m.size(); ++i) {
      row[fixed + i] = sample.pressure_at_positions_pa[i];
    }
    MPDRIG_RETURN_IF_ERROR(writer->WriteRow(sample.time_s, row));
  }
  return writer->Close();
}

}  // namespace mpdrig::cli
