// IndexedMesh: the plain triangle-soup-with-indices that pure algorithms,
// the renderer and the wire encoders exchange. No OpenMesh types here.
//
// Contract:
// - positions.size() == vertexCount(); normals, uvs, colors are either empty
//   or the same size as positions (per-vertex attributes).
// - indices.size() is a multiple of 3; every index < vertexCount().
// - Units: metres in the object's local frame; uvs in [0,1]; colors RGBA8.
// - validate() checks all of the above plus finiteness, and names the first
//   offending element. Code that receives a mesh from outside calls it.
#pragma once

#include <array>
#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod {

struct Bounds {
  glm::vec3 min{0.0f};
  glm::vec3 max{0.0f};
  bool empty = true;

  void extend(const glm::vec3& p);
  glm::vec3 center() const { return (min + max) * 0.5f; }
  float diagonal() const;  // 0 when empty
};

struct BoundingSphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
};

struct IndexedMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;                   // optional, per vertex
  std::vector<glm::vec2> uvs;                       // optional, per vertex
  std::vector<std::array<std::uint8_t, 4>> colors;  // optional, per vertex
  std::vector<std::uint32_t> indices;               // 3 per triangle

  std::size_t vertexCount() const { return positions.size(); }
  std::size_t triangleCount() const { return indices.size() / 3; }

  // `what` names the mesh in the error ("cow.obj", "message 12 mesh").
  Status validate(const std::string& what) const;
  Bounds bounds() const;
  // Smallest-ish enclosing sphere (Ritter); radius >= true minimum.
  BoundingSphere boundingSphere() const;
  // Bbox diagonal (a size for tolerances and codec bounds). Relative accuracy
  // refers to the reference sphere instead (relative_accuracy.h).
  float diameter() const { return bounds().diagonal(); }
  // Area-weighted per-vertex normals (replaces `normals`).
  void computeNormals();
};

}  // namespace thinlod
