// How a record prints a value that is not set: an empty text is null, never "" (DESIGN §6: "reason null
// unless waiting or failed").
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace cell::records {

inline nlohmann::json TextOrNull(const std::string& s) {
  return s.empty() ? nlohmann::json(nullptr) : nlohmann::json(s);
}

}  // namespace cell::records
