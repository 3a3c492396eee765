// DiscPoints: point primitives drawn as discs (the points of a hybrid
// triangle + point representation, Cohen-Aliaga-Zhang; docs/hybrid.md). The
// plain struct the simplifier, the link codec and the frontend exchange; no
// third-party types.
//
// Contract:
// - centres.size() == size(); radii and colors are the same size; normals
//   are empty or the same size (the frontend draws screen-aligned discs and
//   needs them only to pre-light the colours).
// - Units: metres in the object's local frame (as IndexedMesh); a radius is
//   the disc's world-space radius, finite and > 0; colors are RGBA8 (the
//   base colour before lighting, or pre-lit: the owner says which).
// - validate() checks all of the above plus finiteness and names the first
//   offending element. Code that receives points from outside calls it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod {

struct DiscPoints {
  std::vector<glm::vec3> centres;
  std::vector<glm::vec3> normals;  // optional, unit length when present
  std::vector<float> radii;
  std::vector<std::array<std::uint8_t, 4>> colors;

  std::size_t size() const { return centres.size(); }
  bool empty() const { return centres.empty(); }
  // `what` names the points in errors ("message 12 points").
  Status validate(const std::string& what) const;
  Bounds bounds() const;  // of the centres
};

// Triangles and points of one representation (either part may be empty).
struct HybridGeometry {
  IndexedMesh triangles;
  DiscPoints points;
};

}  // namespace thinlod
