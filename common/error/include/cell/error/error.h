// The cell's one error type: a category a caller can act on plus a one-line human reason.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace cell {

enum class Errc {
  kInvalidArgument,   // the caller sent something malformed
  kNotFound,          // the named thing does not exist
  kAlreadyExists,     // would overwrite without permission
  kPermissionDenied,  // protected, read-only
  kFailedPrecondition,
  kTimeout,
  kUnavailable,  // peer not matched / service down
  kIo,           // file system, SQLite
  kInternal,
  kUnimplemented,
};

std::string_view ErrcName(Errc c);

class Error : public std::runtime_error {
 public:
  Error(Errc code, const std::string& what) : std::runtime_error(what), code_(code) {}
  Errc code() const noexcept { return code_; }

 private:
  Errc code_;
};

}  // namespace cell
