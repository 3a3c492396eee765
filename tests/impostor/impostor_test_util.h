// Shared helpers for impostor tests: a finely tessellated UV sphere.
#pragma once

#include <cmath>
#include <memory>

#include "thinlod/common/core/indexed_mesh.h"

namespace thinlod::simplifier::testing {

// UV sphere, counter-clockwise from outside, analytic normals.
inline std::shared_ptr<IndexedMesh> makeSphere(float radius, int segments = 64, int rings = 32) {
  auto mesh = std::make_shared<IndexedMesh>();
  const float pi = 3.14159265358979f;
  for (int r = 0; r <= rings; ++r) {
    const float theta = pi * r / rings;  // from +y down
    for (int s = 0; s <= segments; ++s) {
      const float phi = 2.0f * pi * s / segments;
      const glm::vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta),
                        -std::sin(theta) * std::sin(phi));
      mesh->positions.push_back(n * radius);
      mesh->normals.push_back(n);
      mesh->uvs.push_back({static_cast<float>(s) / segments, 1.0f - static_cast<float>(r) / rings});
    }
  }
  const int row = segments + 1;
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      const std::uint32_t a = r * row + s;
      const std::uint32_t b = a + row;
      if (r != 0) mesh->indices.insert(mesh->indices.end(), {a, b, a + 1});
      if (r != rings - 1) mesh->indices.insert(mesh->indices.end(), {a + 1, b, b + 1});
    }
  }
  return mesh;
}

}  // namespace thinlod::simplifier::testing
