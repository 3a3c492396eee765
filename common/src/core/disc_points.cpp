#include "thinlod/common/core/disc_points.h"

#include <cmath>

#include "thinlod/common/core/finite.h"

namespace thinlod {

Status DiscPoints::validate(const std::string& what) const {
  const std::size_t n = centres.size();
  if (radii.size() != n || colors.size() != n || (!normals.empty() && normals.size() != n)) {
    return Status(ErrorCode::kInvalidArgument, what + ": " + std::to_string(radii.size()) +
                                                   " radii, " + std::to_string(colors.size()) +
                                                   " colours, " + std::to_string(normals.size()) +
                                                   " normals for " + std::to_string(n) + " points");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!allFinite(centres[i])) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": point " + std::to_string(i) + " has a NaN or infinite centre");
    }
    if (!std::isfinite(radii[i]) || !(radii[i] > 0.0f)) {
      return Status(ErrorCode::kInvalidArgument, what + ": point " + std::to_string(i) +
                                                     " has radius " + std::to_string(radii[i]) +
                                                     " (must be finite and > 0)");
    }
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!allFinite(normals[i])) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": point normal " + std::to_string(i) + " is NaN or infinite");
    }
  }
  return Status();
}

Bounds DiscPoints::bounds() const {
  Bounds b;
  for (const glm::vec3& c : centres) b.extend(c);
  return b;
}

}  // namespace thinlod
