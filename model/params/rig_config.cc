#include "model/params/rig_config.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "model/common/units.h"
#include "model/params/rig_config.pb.h"

namespace mpdrig {
namespace {

namespace pb = google::protobuf;

// Collects the first text-format error with its position (protobuf counts from 0).
class FirstErrorCollector final : public pb::io::ErrorCollector {
 public:
  void AddError(int line, pb::io::ColumnNumber column, const std::string& message) override {
    if (!has_error_) {
      has_error_ = true;
      std::ostringstream out;
      out << line + 1 << ":" << column + 1 << ": " << message;
      error_ = out.str();
    }
  }
  bool has_error() const { return has_error_; }
  const std::string& error() const { return error_; }

 private:
  bool has_error_ = false;
  std::string error_;
};

}  // namespace

Result<RigParams> ParseRigConfig(const std::string& text, const std::string& source_name,
                                 const RigParams& defaults) {
  config::RigConfig message;
  pb::TextFormat::Parser parser;
  FirstErrorCollector errors;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &message)) {
    return Status::Error(source_name + ":" +
                         (errors.has_error() ? errors.error() : std::string("parse error")));
  }

  RigParams params = defaults;
  const pb::Descriptor* descriptor = message.GetDescriptor();
  const pb::Reflection* reflection = message.GetReflection();
  for (int i = 0; i < descriptor->field_count(); ++i) {
    const pb::FieldDescriptor* field = descriptor->field(i);
    if (field->is_repeated() || !reflection->HasField(message, field)) continue;
    const ParamInfo* info = FindParam(field->name());
    MPDRIG_CHECK(info != nullptr);  // rig_params_test keeps the proto and the table in sync
    const double value = reflection->GetDouble(message, field);
    std::ostringstream text_value;
    text_value.precision(17);
    text_value << value;
    if (std::isnan(value)) {
      return Status::Error(source_name + ": " + field->name() + " is NaN");
    }
    MPDRIG_RETURN_IF_ERROR(SetParam(&params, field->name(), text_value.str()).Within(source_name));
  }
  if (message.choke_point_size() > 0) {
    params.choke_characteristic.clear();
    for (const config::ChokePoint& point : message.choke_point()) {
      params.choke_characteristic.push_back(
          {units::ChokeDegToFrac(point.opening_deg()), point.g_m2()});
    }
  }
  MPDRIG_RETURN_IF_ERROR(params.Validate().Within(source_name));
  return params;
}

Result<RigParams> LoadRigConfig(const std::string& path, const RigParams& defaults) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return Status::Error(path + ": cannot open config file");
  std::ostringstream contents;
  contents << file.rdbuf();
  return ParseRigConfig(contents.str(), path, defaults);
}

std::string FormatRigConfig(const RigParams& params) {
  std::ostringstream out;
  out.precision(10);
  out << "# mpdrig rig configuration (Protobuf text format, model/params/rig_config.proto).\n"
      << "# Defaults are the thesis's tuned values. SI units, absolute pressures.\n";
  for (const ParamInfo& info : ParamTable()) {
    out << "\n# " << info.description << " [" << info.unit << "]\n"
        << info.key << ": " << params.*info.member << "\n";
  }
  out << "\n# Choke characteristic G(opening) [m^2], linear between points (Table 8.4.1),\n"
      << "# floored at choke_leak_m2. Listing points replaces the whole default table.\n";
  for (const ChokePoint& point : params.choke_characteristic) {
    out << "choke_point { opening_deg: " << units::ChokeFracToDeg(point.opening_frac)
        << " g_m2: " << point.g_m2 << " }\n";
  }
  return out.str();
}

}  // namespace mpdrig
