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

// The layout's blocks (reservoir, valve, steady_flow) onto `layout`; each error at the block
// (or the valve's point) where it was written. A file without them keeps `layout` as it was.
Status ReadLayout(const config::RigConfig& message, const pb::TextFormat::ParseInfoTree& locations,
                  const std::string& source_name, RigLayout* layout) {
  const pb::Descriptor* descriptor = message.GetDescriptor();
  const auto position = [&](const char* field_name) {
    const pb::TextFormat::ParseLocation where =
        locations.GetLocation(descriptor->FindFieldByName(field_name), -1);
    return source_name + ":" + std::to_string(where.line + 1) + ":" +
           std::to_string(where.column + 1);
  };
  const bool reservoir = message.has_reservoir();
  const bool valve = message.has_valve();
  const bool steady = message.has_steady_flow();
  if (!reservoir && !valve && !steady) return Status::Ok();
  if (!reservoir || !valve || !steady) {
    const char* given = reservoir ? "reservoir" : (valve ? "valve" : "steady_flow");
    return Status::Error(position(given) +
                         ": `reservoir`, `valve` and `steady_flow` go together (the reservoir - "
                         "pipe - valve rig starting from steady flow); give all three");
  }
  RigLayout read;
  read.inlet = RigLayout::Inlet::kReservoir;
  read.outlet = RigLayout::Outlet::kValve;
  read.reservoir_head_m = message.reservoir().head_m();
  read.steady_velocity_mps = message.steady_flow().velocity_mps();
  const config::Valve& v = message.valve();
  read.valve.closure_time_s = v.closure_time_s();
  read.valve.start_s = v.start_s();
  read.valve.exponent = v.has_exponent() ? v.exponent() : 1.0;
  read.valve.downstream_head_m = v.downstream_head_m();
  for (const config::ValveOpeningPoint& point : v.point()) {
    read.valve.points.push_back({point.time_s(), point.opening()});
  }
  if (!read.valve.points.empty() && (v.closure_time_s() != 0.0 || v.has_exponent())) {
    return Status::Error(position("valve") +
                         ": give the valve either `point`s or `closure_time_s` (and `exponent`), "
                         "not both");
  }
  // A bad point at the line where it was written.
  const pb::TextFormat::ParseInfoTree* valve_tree =
      locations.GetTreeForNested(descriptor->FindFieldByName("valve"), -1);
  const pb::FieldDescriptor* point_field = config::Valve::descriptor()->FindFieldByName("point");
  for (std::size_t i = 0; i < read.valve.points.size(); ++i) {
    ValveClosure prefix = read.valve;
    prefix.points.resize(i + 1);
    Status status = prefix.Validate();
    if (!status.ok()) {
      std::string where = position("valve");
      if (valve_tree != nullptr) {
        const pb::TextFormat::ParseLocation at =
            valve_tree->GetLocation(point_field, static_cast<int>(i));
        where =
            source_name + ":" + std::to_string(at.line + 1) + ":" + std::to_string(at.column + 1);
      }
      return status.Within(where);
    }
  }
  if (Status status = read.Validate(); !status.ok()) {
    const std::string message_text = status.message();
    const char* block = message_text.find("reservoir") == 0     ? "reservoir"
                        : message_text.find("steady_flow") == 0 ? "steady_flow"
                                                                : "valve";
    return status.Within(position(block));
  }
  *layout = read;
  return Status::Ok();
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
    if (field->is_repeated() || field->cpp_type() == pb::FieldDescriptor::CPPTYPE_MESSAGE ||
        !reflection->HasField(message, field)) {
      continue;  // lists and the layout's blocks are read below
    }
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
      MPDRIG_RETURN_IF_ERROR(
          CheckEffectParam(*info, param.key(), param.value()).Within(param_position));
      setting.values.emplace_back(param.key(), param.value());
    }
    // The rules between its parameters (EffectInfo::check), at the effect's line.
    MPDRIG_RETURN_IF_ERROR(ResolveEffectValues(*info, setting).status().Within(position));
    params.effects.push_back(std::move(setting));
  }
  MPDRIG_RETURN_IF_ERROR(ReadLayout(message, locations, source_name, &params.layout));
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
  const RigLayout& layout = params.layout;
  if (!layout.is_ntnu_rig()) {
    const ValveClosure& valve = layout.valve;
    out << "\n# The rig's layout: reservoir - pipe - valve, from steady flow (rig_layout.h).\n"
        << "reservoir { head_m: " << ShortestText(layout.reservoir_head_m) << " }\n"
        << "valve {";
    if (valve.points.empty()) {
      out << " closure_time_s: " << ShortestText(valve.closure_time_s)
          << " start_s: " << ShortestText(valve.start_s)
          << " exponent: " << ShortestText(valve.exponent);
    }
    for (const ValveOpeningPoint& point : valve.points) {
      out << " point { time_s: " << ShortestText(point.time_s)
          << " opening: " << ShortestText(point.opening) << " }";
    }
    out << " downstream_head_m: " << ShortestText(valve.downstream_head_m) << " }\n"
        << "steady_flow { velocity_mps: " << ShortestText(layout.steady_velocity_mps) << " }\n";
  }
  return out.str();
}

}  // namespace mpdrig
