#include "tools/report/json.h"

namespace mpdrig::report {

std::string JsonText(const Json& value, int indent) {
  return value.dump(indent, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace mpdrig::report
