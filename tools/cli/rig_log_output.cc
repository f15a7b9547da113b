#include "tools/cli/rig_log_output.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

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

namespace {

// The metadata with `atmospheric_pressure_pa` (added if absent), and the columns.
Status PrepareLog(riglog::Metadata* metadata, double atmospheric_pressure_pa,
                  const std::vector<double>& pressure_positions_m,
                  std::vector<riglog::ColumnSpec>* columns) {
  bool has_atmosphere = false;
  for (const auto& [key, value] : *metadata)
    has_atmosphere |= key == riglog::kAtmosphericPressureKey;
  if (!has_atmosphere) {
    metadata->emplace_back(std::string(riglog::kAtmosphericPressureKey),
                           riglog::FormatNumber(atmospheric_pressure_pa));
  }
  auto made = SimulatedColumns(pressure_positions_m);
  if (!made.ok()) return made.status();
  *columns = std::move(made).value();
  return Status::Ok();
}

Status WriteSample(const RigSample& sample, std::size_t extra_positions,
                   riglog::RigLogWriter* writer, std::vector<double>* row) {
  const std::size_t fixed = std::size(kOutputOrder);
  row->resize(fixed + extra_positions);
  for (std::size_t i = 0; i < fixed; ++i) (*row)[i] = sample[kOutputOrder[i]];
  for (std::size_t i = 0; i < extra_positions; ++i) {
    (*row)[fixed + i] = sample.pressure_at_positions_pa[i];
  }
  return writer->WriteRow(sample.time_s, *row);
}

}  // namespace

Status WriteSamples(const std::string& path, riglog::Metadata metadata,
                    double atmospheric_pressure_pa, const std::vector<RigSample>& samples,
                    const std::vector<double>& pressure_positions_m) {
  std::vector<riglog::ColumnSpec> columns;
  MPDRIG_RETURN_IF_ERROR(
      PrepareLog(&metadata, atmospheric_pressure_pa, pressure_positions_m, &columns));
  auto writer = riglog::RigLogWriter::Open(path, std::move(metadata), columns);
  if (!writer.ok()) return writer.status();
  std::vector<double> row;
  for (const RigSample& sample : samples) {
    MPDRIG_RETURN_IF_ERROR(WriteSample(sample, pressure_positions_m.size(), &*writer, &row));
  }
  return writer->Close();
}

struct SampleLogStream::State {
  std::string path;       // where the log goes ("-": standard output)
  std::string temporary;  // where a file is written first (empty for "-")
  // For "-": an unlinked temporary file, so nothing is left behind however the process ends.
  std::unique_ptr<std::fstream> unlinked;
  std::optional<riglog::RigLogWriter> writer;
  std::size_t extra_positions = 0;
  std::vector<double> row;
  std::size_t samples = 0;
  bool finished = false;

  ~State() {
    writer.reset();
    if (!finished && !temporary.empty()) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
    }
  }
};

SampleLogStream::SampleLogStream(std::unique_ptr<State> state) : state_(std::move(state)) {}
SampleLogStream::SampleLogStream(SampleLogStream&&) noexcept = default;
SampleLogStream& SampleLogStream::operator=(SampleLogStream&&) noexcept = default;
SampleLogStream::~SampleLogStream() = default;

Result<SampleLogStream> SampleLogStream::Open(const std::string& path, riglog::Metadata metadata,
                                              double atmospheric_pressure_pa,
                                              const std::vector<double>& pressure_positions_m) {
  std::vector<riglog::ColumnSpec> columns;
  MPDRIG_RETURN_IF_ERROR(
      PrepareLog(&metadata, atmospheric_pressure_pa, pressure_positions_m, &columns));
  auto state = std::make_unique<State>();
  state->path = path;
  const std::string suffix = ".partial." + std::to_string(::getpid());
  std::optional<Result<riglog::RigLogWriter>> writer;
  if (path == "-") {
    std::error_code error;
    const std::filesystem::path dir = std::filesystem::temp_directory_path(error);
    if (error) return Status::Error("no temporary directory for the output: " + error.message());
    const std::string temporary = (dir / ("mpdrig-simulate" + suffix + ".csv")).string();
    state->unlinked = std::make_unique<std::fstream>(
        temporary, std::ios::in | std::ios::out | std::ios::trunc | std::ios::binary);
    if (!state->unlinked->is_open()) return Status::Error(temporary + ": cannot open for writing");
    std::filesystem::remove(temporary, error);
    writer.emplace(riglog::RigLogWriter::ToStream(state->unlinked.get(), "<stdout>",
                                                  std::move(metadata), columns));
  } else {
    state->temporary = path + suffix;
    writer.emplace(riglog::RigLogWriter::Open(state->temporary, std::move(metadata), columns));
  }
  if (!writer->ok()) return writer->status();
  state->writer.emplace(std::move(*writer).value());
  state->extra_positions = pressure_positions_m.size();
  return SampleLogStream(std::move(state));
}

Status SampleLogStream::Write(const RigSample& sample) {
  State& state = *state_;
  if (!state.writer) return Status::Error(state.path + ": the log is closed");
  MPDRIG_RETURN_IF_ERROR(WriteSample(sample, state.extra_positions, &*state.writer, &state.row));
  ++state.samples;
  return Status::Ok();
}

std::size_t SampleLogStream::samples_written() const { return state_->samples; }

Status SampleLogStream::Finish(const riglog::Metadata& late_metadata) {
  State& state = *state_;
  if (!state.writer) return Status::Error(state.path + ": the log is closed");
  Status closed = state.writer->Close();
  state.writer.reset();
  MPDRIG_RETURN_IF_ERROR(closed);
  if (late_metadata.empty() && state.path != "-") {
    std::error_code error;
    std::filesystem::rename(state.temporary, state.path, error);
    if (error) return Status::Error(state.path + ": cannot write: " + error.message());
    state.finished = true;
    return Status::Ok();
  }
  // Copy line by line, the late metadata just before the header (the first line that is not a
  // comment), after the metadata the writer wrote.
  std::ifstream file_in;
  if (state.unlinked) {
    state.unlinked->seekg(0);
  } else {
    file_in.open(state.temporary, std::ios::binary);
    if (!file_in) return Status::Error(state.temporary + ": cannot read back the output");
  }
  std::istream& in = state.unlinked ? static_cast<std::istream&>(*state.unlinked) : file_in;
  std::ofstream file;
  if (state.path != "-") {
    file.open(state.path, std::ios::binary | std::ios::trunc);
    if (!file) return Status::Error(state.path + ": cannot open for writing");
  }
  std::ostream& out = state.path == "-" ? std::cout : file;
  bool header_seen = false;
  std::string line;
  while (std::getline(in, line)) {
    if (!header_seen && (line.empty() || line[0] != '#')) {
      for (const auto& [key, value] : late_metadata) {
        std::string text = value;
        std::replace(text.begin(), text.end(), '\n', ' ');
        out << "# " << key << ": " << text << "\n";
      }
      header_seen = true;
    }
    out << line << "\n";
  }
  out.flush();
  if (!out) return Status::Error(state.path + ": write error");
  if (file.is_open()) {
    file.close();
    if (!file) return Status::Error(state.path + ": write error");
  }
  file_in.close();
  state.unlinked.reset();
  if (!state.temporary.empty()) {
    std::error_code ignored;
    std::filesystem::remove(state.temporary, ignored);
  }
  state.finished = true;
  return Status::Ok();
}

}  // namespace mpdrig::cli
