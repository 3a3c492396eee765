#include "thinlod/common/core/status.h"

namespace thinlod {

const char* errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kOk:
      return "Ok";
    case ErrorCode::kInvalidArgument:
      return "InvalidArgument";
    case ErrorCode::kNotFound:
      return "NotFound";
    case ErrorCode::kParseError:
      return "ParseError";
    case ErrorCode::kIoError:
      return "IoError";
    case ErrorCode::kUnsupported:
      return "Unsupported";
    case ErrorCode::kVersionMismatch:
      return "VersionMismatch";
    case ErrorCode::kUnavailable:
      return "Unavailable";
    case ErrorCode::kTimeout:
      return "Timeout";
    case ErrorCode::kResourceExhausted:
      return "ResourceExhausted";
    case ErrorCode::kInternal:
      return "Internal";
  }
  return "Unknown";
}

std::string Status::toString() const {
  if (ok()) return "Ok";
  return std::string(errorCodeName(code_)) + ": " + message_;
}

}  // namespace thinlod
