// Loading and writing the rig configuration file (Protobuf text format, rig_config.proto).
#pragma once

#include <string>

#include "model/common/status.h"
#include "model/params/rig_params.h"

namespace mpdrig {

// Reads a text-format RigConfig on top of `defaults`. A syntax error or unknown field is reported
// as "path:line:column: message"; a value out of bounds names its key.
Result<RigParams> LoadRigConfig(const std::string& path, const RigParams& defaults = RigParams());
Result<RigParams> ParseRigConfig(const std::string& text, const std::string& source_name,
                                 const RigParams& defaults = RigParams());

// Every parameter as a complete, commented text-format config that LoadRigConfig accepts.
std::string FormatRigConfig(const RigParams& params);

}  // namespace mpdrig
