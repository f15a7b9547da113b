#include "model/config/rig_config.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "model/common/units.h"
#include "model/config/rig_config.pb.h"
#include "model/effects/effect.h"

namespace mpdrig {
namespace {

namespace pb = google::protobuf;

// Collects the first text-format error with its position (protobuf counts from 0).
class FirstErrorCollector final : public pb::io::ErrorCollector {
 public:
  void AddError(int line, pb::io::ColumnNumber column, const std::string& message) override {
    if (has_error_) return;
    has_error_ = true;
    // Protobuf places an unknown field's error after its name; point at the name's start, as
    // every other error here does.
    const std::string marker = "no field named \"";
    const std::size_t at = message.find(marker);
    if (at != std::string::npos) {
      const std::size_t name_end = message.find('"', at + marker.size());
      if (name_end != std::string::npos) {
        column = std::max<pb::io::ColumnNumber>(
            0, column - static_cast<pb::io::ColumnNumber>(name_end - at - marker.size()));
      }
    }
    std::ostringstream out;
    out << line + 1 << ":" << column + 1 << ": " << message;
    error_ = out.str();
  }
  bool has_error() const { return has_error_; }
  const std::string& error() const { return error_; }

 private:
  bool has_error_ = false;
  std::string error_;
};

// The shortest text that reads back as exactly `value`.
std::string ShortestText(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

}  // namespace

Result<RigParams> ParseRigConfig(const std::string& text, const std::string& source_name,
                                 const RigParams& defaults) {
  config::RigConfig message;
  pb::TextFormat::Parser parser;
  FirstErrorCollector errors;
  parser.RecordErrorsTo(&errors);
  pb::TextFormat::ParseInfoTree locations;  // where each field was written, for value errors
  parser.WriteLocationsTo(&locations);
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
    const pb::TextFormat::ParseLocation where = locations.GetLocation(field, -1);
    const std::string position =
        source_name + ":" + std::to_string(where.line + 1) + ":" + std::to_string(where.column + 1);
    Status status = std::isnan(value) ? Status::Error(field->name() + " is NaN")
                                      : SetParam(&params, field->name(), ShortestText(value));
    MPDRIG_RETURN_IF_ERROR(status.Within(position));
  }
  if (message.choke_point_size() > 0) {
    params.choke_characteristic.clear();
    for (const config::ChokePoint& point : message.choke_point()) {
      params.choke_characteristic.push_back(
          {units::ChokeDegToFrac(point.opening_deg()), point.g_m2()});
    }
    // Each point's error at the place it was written.
    for (int i = 0; i < message.choke_point_size(); ++i) {
      const pb::TextFormat::ParseLocation where =
          locations.GetLocation(descriptor->FindFieldByName("choke_point"), i);
      const std::string position = source_name + ":" + std::to_string(where.line + 1) + ":" +
                                   std::to_string(where.column + 1);
      MPDRIG_RETURN_IF_ERROR(
          params.ValidateChokePoint(static_cast<std::size_t>(i)).Within(position));
    }
  }
  const pb::FieldDescriptor* effect_field = descriptor->FindFieldByName("effect");
  const pb::FieldDescriptor* param_field = config::Effect::descriptor()->FindFieldByName("param");
  auto position_of = [&source_name](const pb::TextFormat::ParseLocation& where) {
    return source_name + ":" + std::to_string(where.line + 1) + ":" +
           std::to_string(where.column + 1);
  };
  for (int i = 0; i < message.effect_size(); ++i) {
    const config::Effect& effect = message.effect(i);
    const std::string position = position_of(locations.GetLocation(effect_field, i));
    if (effect.name().empty()) return Status::Error(position + ": effect without a name");
    if (params.FindEffect(effect.name()) != nullptr) {
      return Status::Error(position + ": effect '" + effect.name() + "' is listed twice");
    }
    // The registry checks names, keys and bounds; each error at the place it was written (the
    // effect's name, or the parameter's line), not only once the whole file has been read.
    const EffectInfo* info = FindEffectInfo(effect.name());
    if (info == nullptr) {
      return UnknownEffect(effect.name()).Within(position);
    }
    const pb::TextFormat::ParseInfoTree* effect_tree = locations.GetTreeForNested(effect_field, i);
    EffectSetting setting{effect.name(), {}};
    for (int j = 0; j < effect.param_size(); ++j) {
      const config::EffectParam& param = effect.param(j);
      const std::string param_position =
          effect_tree != nullptr ? position_of(effect_tree->GetLocation(param_field, j)) : position;
      if (!std::isfinite(param.value())) {
        return Status::Error(param_position + ": effect " + effect.name() + ": " + param.key() +
                             " is not a finite number");
      }
      if (setting.Find(param.key()) != nullptr) {
        return Status::Error(param_position + ": effect " + effect.name() + ": " + param.key() +
                             " is given twice");
      }
      const EffectSetting alone{effect.name(), {{param.key(), param.value()}}};
      MPDRIG_RETURN_IF_ERROR(ResolveEffectValues(*info, alone).status().Within(param_position));
      setting.values.emplace_back(param.key(), param.value());
    }
    params.effects.push_back(std::move(setting));
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
  out << "# mpdrig rig configuration (Protobuf text format, model/config/rig_config.proto).\n"
      << "# Defaults are the thesis's tuned values. SI units, absolute pressures.\n";
  for (const ParamInfo& info : ParamTable()) {
    out << "\n# " << info.description << " [" << info.unit << "]\n"
        << info.key << ": " << ShortestText(params.*info.member) << "\n";
  }
  out << "\n# Choke characteristic G(opening) [m^2], linear between points (Table 8.4.1),\n"
      << "# floored at choke_leak_m2. Listing points replaces the whole default table.\n";
  for (const ChokePoint& point : params.choke_characteristic) {
    out << "choke_point { opening_deg: " << ShortestText(units::ChokeFracToDeg(point.opening_frac))
        << " g_m2: " << ShortestText(point.g_m2) << " }\n";
  }
  if (!params.effects.empty()) {
    out << "\n# Physical effects switched on (`mpdrig effects` lists them with units).\n";
  }
  for (const EffectSetting& effect : params.effects) {
    out << "effect { name: \"" << effect.name << "\"";
    for (const auto& [key, value] : effect.values) {
      out << " param { key: \"" << key << "\" value: " << ShortestText(value) << " }";
    }
    out << " }\n";
  }
  return out.str();
}

}  // namespace mpdrig
