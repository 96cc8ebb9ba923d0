// The one wording, in both backends, for an endpoint or topic the DDS Security permissions refuse.
#pragma once

#include <string>
#include <string_view>

#include "cell/error/error.h"

namespace cell::bus {

// action: "publish", "subscribe to", "use topic".
inline Error Refused(const std::string& identity, std::string_view action, const std::string& topic) {
  return Error(Errc::kPermissionDenied, "security identity '" + identity + "' may not " +
                                            std::string(action) + " " + topic + " (docs/security.md)");
}

}  // namespace cell::bus
