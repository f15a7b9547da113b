#include "model/riglog/rig_log.h"

#include <cmath>
#include <utility>

#include "model/riglog/rig_log_reader.h"
#include "model/riglog/rig_log_writer.h"

namespace mpdrig::riglog {

std::optional<std::size_t> RigLog::FindColumn(std::string_view channel) const {
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (columns[i].channel == channel) return i;
  }
  return std::nullopt;
}

const std::vector<double>* RigLog::Find(std::string_view channel) const {
  if (channel == ChannelName(Channel::kTime)) return &time_s;
  const std::optional<std::size_t> index = FindColumn(channel);
  if (!index.has_value() || *index >= values_si.size()) return nullptr;
  return &values_si[*index];
}

const std::vector<double>* RigLog::Find(Channel channel) const {
  return Find(ChannelName(channel));
}

Status RigLog::AddColumn(ColumnSpec column, std::vector<double> values) {
  Result<ColumnSpec> parsed = ParseColumnName(column.name);
  if (!parsed.ok()) return parsed.status();
  if (*parsed != column) {
    return Status::Error("column " + QuoteForMessage(column.name) + " does not match its channel " +
                         QuoteForMessage(column.channel) + " and unit " +
                         QuoteForMessage(UnitSuffix(column.unit)));
  }
  if (column.channel == ChannelName(Channel::kTime)) {
    return Status::Error("the time column is RigLog::time_s, not a column");
  }
  if (FindColumn(column.channel).has_value()) {
    return Status::Error("duplicate channel " + QuoteForMessage(column.channel));
  }
  if (values.size() != num_rows()) {
    return Status::Error("column " + QuoteForMessage(column.name) + " has " +
                         std::to_string(values.size()) + " values for " +
                         std::to_string(num_rows()) + " rows");
  }
  columns.push_back(std::move(column));
  values_si.push_back(std::move(values));
  return Status::Ok();
}

Result<RigLog> ReadRigLog(const std::string& path, const ReadOptions& options) {
  Result<RigLogReader> reader = RigLogReader::Open(path, options);
  if (!reader.ok()) return reader.status();
  RigLog log;
  log.metadata = reader->metadata();
  log.atmospheric_pressure_pa = reader->atmospheric_pressure_pa();
  const std::vector<ColumnSpec>& columns = reader->columns();
  const std::size_t time_index = reader->time_index();
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i != time_index) log.columns.push_back(columns[i]);
  }
  log.values_si.resize(log.columns.size());
  std::vector<double> sample;
  for (;;) {
    Result<bool> more = reader->Next(&sample);
    if (!more.ok()) return more.status();
    if (!*more) break;
    log.time_s.push_back(sample[time_index]);
    for (std::size_t i = 0, c = 0; i < sample.size(); ++i) {
      if (i != time_index) log.values_si[c++].push_back(sample[i]);
    }
  }
  return log;
}

Status WriteRigLog(const RigLog& log, const std::string& path) {
  if (log.values_si.size() != log.columns.size()) {
    return Status::Error(path + ": RigLog has " + std::to_string(log.columns.size()) +
                         " columns but " + std::to_string(log.values_si.size()) + " value vectors");
  }
  for (std::size_t c = 0; c < log.columns.size(); ++c) {
    if (log.values_si[c].size() != log.num_rows()) {
      return Status::Error(path + ": column " + QuoteForMessage(log.columns[c].name) + " has " +
                           std::to_string(log.values_si[c].size()) + " values for " +
                           std::to_string(log.num_rows()) + " times");
    }
  }
  Metadata metadata = log.metadata;
  bool has_atmosphere_key = false;
  for (const auto& [key, value] : metadata) {
    if (key != kAtmosphericPressureKey) continue;
    has_atmosphere_key = true;
    Result<double> pa = ParseAtmosphericPressure(value);
    if (!pa.ok()) return Status::Error(path + ": metadata " + pa.status().message());
    if (*pa != log.atmospheric_pressure_pa) {
      return Status::Error(path + ": metadata atmospheric_pressure_pa " + QuoteForMessage(value) +
                           " disagrees with RigLog::atmospheric_pressure_pa " +
                           FormatNumber(log.atmospheric_pressure_pa));
    }
  }
  if (!has_atmosphere_key) {
    if (!std::isfinite(log.atmospheric_pressure_pa)) {
      return Status::Error(path + ": RigLog::atmospheric_pressure_pa is not finite");
    }
    Result<double> pa = ParseAtmosphericPressure(FormatNumber(log.atmospheric_pressure_pa));
    if (!pa.ok()) return Status::Error(path + ": RigLog::" + pa.status().message());
    metadata.emplace_back(std::string(kAtmosphericPressureKey),
                          FormatNumber(log.atmospheric_pressure_pa));
  }

  Result<RigLogWriter> writer = RigLogWriter::Open(path, std::move(metadata), log.columns);
  if (!writer.ok()) return writer.status();
  std::vector<double> row(log.columns.size());
  for (std::size_t r = 0; r < log.num_rows(); ++r) {
    for (std::size_t c = 0; c < log.columns.size(); ++c) row[c] = log.values_si[c][r];
    MPDRIG_RETURN_IF_ERROR(writer->WriteRow(log.time_s[r], row));
  }
  return writer->Close();
}

}  // namespace mpdrig::riglog
