#include "thinlod/common/core/indexed_mesh.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

#include "thinlod/common/core/finite.h"

namespace thinlod {

void Bounds::extend(const glm::vec3& p) {
  if (empty) {
    min = max = p;
    empty = false;
    return;
  }
  min = glm::min(min, p);
  max = glm::max(max, p);
}

float Bounds::diagonal() const { return empty ? 0.0f : glm::length(max - min); }

Status IndexedMesh::validate(const std::string& what) const {
  const std::size_t n = positions.size();
  auto attributeSizeOk = [n](std::size_t size) { return size == 0 || size == n; };
  if (!attributeSizeOk(normals.size()) || !attributeSizeOk(uvs.size()) ||
      !attributeSizeOk(colors.size())) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": attribute count differs from vertex count " + std::to_string(n));
  }
  if (indices.size() % 3 != 0) {
    return Status(
        ErrorCode::kInvalidArgument,
        what + ": index count " + std::to_string(indices.size()) + " is not a multiple of 3");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!allFinite(positions[i])) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
    }
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!allFinite(normals[i])) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": normal " + std::to_string(i) + " is NaN or infinite");
    }
  }
  for (std::size_t i = 0; i < uvs.size(); ++i) {
    if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y)) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": texture coordinate " + std::to_string(i) + " is NaN or infinite");
    }
  }
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= n) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": triangle " + std::to_string(i / 3) + " references vertex " +
                        std::to_string(indices[i]) + " (only " + std::to_string(n) + " vertices)");
    }
  }
  return Status();
}

Bounds IndexedMesh::bounds() const {
  Bounds b;
  for (const glm::vec3& p : positions) b.extend(p);
  return b;
}

BoundingSphere IndexedMesh::boundingSphere() const {
  BoundingSphere s;
  if (positions.empty()) return s;
  // Ritter: start from an approximate diameter, grow to include outliers.
  auto farthestFrom = [this](const glm::vec3& q) {
    std::size_t best = 0;
    float bestDist = -1.0f;
    for (std::size_t i = 0; i < positions.size(); ++i) {
      const float d = glm::dot(positions[i] - q, positions[i] - q);
      if (d > bestDist) {
        bestDist = d;
        best = i;
      }
    }
    return positions[best];
  };
  const glm::vec3 a = farthestFrom(positions[0]);
  const glm::vec3 b = farthestFrom(a);
  s.center = (a + b) * 0.5f;
  s.radius = glm::length(b - a) * 0.5f;
  for (const glm::vec3& p : positions) {
    const float d = glm::length(p - s.center);
    if (d > s.radius) {
      const float newRadius = (s.radius + d) * 0.5f;
      s.center += (p - s.center) * ((newRadius - s.radius) / d);
      s.radius = newRadius;
    }
  }
  // Guard against float rounding leaving a point a hair outside.
  s.radius *= 1.0f + 1e-6f;
  return s;
}

void IndexedMesh::computeNormals() {
  // In double: float positions near FLT_MAX overflow a float cross product
  // to inf and the normal to NaN (a binary STL found by fuzz/mesh_file.cpp,
  // seed fuzz/corpus/mesh/crash-stl-normal-overflow.stl); squares of float
  // differences fit a double.
  std::vector<glm::dvec3> sums(positions.size(), glm::dvec3(0.0));
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::dvec3 p0(positions[indices[t]]);
    const glm::dvec3 p1(positions[indices[t + 1]]);
    const glm::dvec3 p2(positions[indices[t + 2]]);
    const glm::dvec3 areaNormal = glm::cross(p1 - p0, p2 - p0);  // length = 2 * area
    for (int k = 0; k < 3; ++k) sums[indices[t + k]] += areaNormal;
  }
  normals.resize(positions.size());
  for (std::size_t v = 0; v < sums.size(); ++v) {
    const double len = glm::length(sums[v]);
    normals[v] =
        len > 0.0 && std::isfinite(len) ? glm::vec3(sums[v] / len) : glm::vec3(0.0f, 0.0f, 1.0f);
  }
}

}  // namespace thinlod
