// The deterministic contents program_store_put_stream puts, so a test can check what it finds.
#pragma once

#include <cstddef>
#include <string>

#include <fmt/format.h>

namespace cell::testing {

inline std::string StreamName(int i) {
  return fmt::format("S{:06d}", i);
}

// Plain text (a data file: no dialect needed in HOST) of about `size` bytes, different per name.
inline std::string StreamContent(const std::string& name, size_t size) {
  std::string out;
  for (int line = 1; out.size() < size; ++line)
    out += fmt::format("record {} of {}: the quick brown fox jumps over the lazy dog\n", line, name);
  out.resize(size);
  out.back() = '\n';
  return out;
}

}  // namespace cell::testing
