// Names the field a check failed on ("SceneUpdate.operations[3].texture")
// without building strings until there is an error to report.
#pragma once

#include <cstddef>
#include <string>

#include "thinlod/common/core/status.h"

namespace thinlod::protocol::detail {

struct FieldPath {
  const FieldPath* parent = nullptr;
  const char* name = "";
  std::ptrdiff_t index = -1;  // >= 0: "name[index]"

  FieldPath child(const char* field) const { return FieldPath{this, field, -1}; }
  FieldPath element(const char* field, std::size_t i) const {
    return FieldPath{this, field, static_cast<std::ptrdiff_t>(i)};
  }
  std::string str() const {
    std::string prefix = parent ? parent->str() : std::string();
    if (!prefix.empty()) prefix += '.';
    prefix += name;
    if (index >= 0) prefix += "[" + std::to_string(index) + "]";
    return prefix;
  }
};

inline Status fieldError(ErrorCode code, const FieldPath& path, const std::string& what) {
  return Status(code, path.str() + ": " + what);
}
inline Status invalidField(const FieldPath& path, const std::string& what) {
  return fieldError(ErrorCode::kInvalidArgument, path, what);
}
inline Status tooLarge(const FieldPath& path, const std::string& what) {
  return fieldError(ErrorCode::kResourceExhausted, path, what);
}

}  // namespace thinlod::protocol::detail
