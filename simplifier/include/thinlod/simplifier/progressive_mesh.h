// ProgressiveMesh: QEM (Garland-Heckbert) edge collapses recorded once, any
// resolution extracted later in time linear in the output.
//
// Contract (seed; the owner refines it):
// - build() simplifies all the way down once and records the collapse order
//   (a totally ordered mesh: vertices renumbered by removal order, each face
//   tagged with the collapse that removes it).
// - extract(n) returns a mesh with at most n triangles (exactly n when the
//   collapse order passes through n; otherwise the next lower count) without
//   re-simplifying. extractInto() reuses the caller's buffers.
// - Pure: no I/O, no logging. Thread-safe for concurrent const use.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "thinlod/common/indexed_mesh.h"
#include "thinlod/common/status.h"

namespace thinlod::simplifier {

struct BuildOptions {
  bool preserveBoundaries = true;  // weight boundary edges with perpendicular planes
  bool preventFlips = true;        // reject collapses that flip a face normal
  float attributeWeight = 0.0f;    // > 0: attribute-aware quadrics (uv/color)
};

class ProgressiveMesh {
 public:
  static Result<ProgressiveMesh> build(const IndexedMesh& mesh, const BuildOptions& options);

  std::size_t maxTriangles() const;  // the input's triangle count (after cleanup)
  std::size_t minTriangles() const;  // where simplification stopped
  IndexedMesh extract(std::size_t targetTriangles) const;
  void extractInto(std::size_t targetTriangles, IndexedMesh& out) const;
  // The QEM error (squared distance units) of the collapse that reaches n triangles.
  double quadricErrorAt(std::size_t targetTriangles) const;

 private:
  // Owner defines the storage.
};

}  // namespace thinlod::simplifier
