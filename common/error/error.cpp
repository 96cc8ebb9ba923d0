#include "cell/error/error.h"

namespace cell {

std::string_view ErrcName(Errc c) {
  switch (c) {
    case Errc::kInvalidArgument:
      return "invalid argument";
    case Errc::kNotFound:
      return "not found";
    case Errc::kAlreadyExists:
      return "already exists";
    case Errc::kPermissionDenied:
      return "permission denied";
    case Errc::kFailedPrecondition:
      return "failed precondition";
    case Errc::kTimeout:
      return "timeout";
    case Errc::kUnavailable:
      return "unavailable";
    case Errc::kIo:
      return "i/o error";
    case Errc::kInternal:
      return "internal error";
    case Errc::kUnimplemented:
      return "unimplemented";
  }
  return "unknown";
}

}  // namespace cell
