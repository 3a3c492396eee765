// ProgressiveMesh: QEM (Garland-Heckbert) half-edge collapses recorded once as
// a totally ordered mesh (Gobbetti-Bouvier TOM); any resolution is extracted
// later in time linear in the output, without re-simplifying.
//
// Contract:
// - build() validates the input (NaN/Inf, indices: kInvalidArgument naming the
//   element), welds vertices closer than weldEpsilon * bbox diagonal, drops
//   degenerate and duplicate triangles and unreferenced vertices (error when no
//   triangle is left), then collapses down to stopAtTriangles (0: as far as the
//   topology rules allow) and stores the collapse order. With preserveSeams
//   (the default) vertices at one place with other uvs / colours stay apart
//   (a seam) and keep their pairing and their places through every collapse.
// - Greedy by cost: QEM (Garland-Heckbert, area-weighted planes) plus a fan
//   term (distance of the removed vertex to its new fan) that keeps thin
//   tips, and for a border vertex a border term (its distance to the border
//   segment that replaces it) that keeps small ears on holes. Collapses keep input vertex positions
//   (vertex substitution, see progressive_mesh.cpp for why), keep manifold boundary vertices on the
//   boundary, never create a non-manifold edge or close a hole, never move a
//   vertex on a non-manifold edge of the input, and (preventFlips) reject
//   triangles that turn over or face against the input surface.
// - vertexConstraints (optional, per input vertex) keep vertices (never
//   removed) or pin them (never removed, never a target); regions.h uses
//   them to simplify one region of a larger mesh with its border fixed.
// - extract(n): the state after the first collapse that leaves at most n
//   triangles; exactly n when the order passes through n, else the next lower
//   count (a collapse removes >= 1 triangle). n >= maxTriangles(): the cleaned
//   input; n < minTriangles(): the coarsest state. Output vertices are the
//   active vertices only, in TOM order (coarse first); attributes (normals,
//   uvs, colors) are the input's values of the surviving vertices.
// - Pure: no I/O, no logging, no globals. Immutable after build: concurrent
//   const calls are safe. extractInto() reuses the caller's buffers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::simplifier {

// What a collapse may do with one input vertex (BuildOptions::vertexConstraints).
// Regions (regions.h) keep their border vertices with kKeep and freeze the
// neighbours' vertices they see with kPin.
enum class VertexConstraint : std::uint8_t {
  kFree,  // may collapse onto a neighbour and neighbours may collapse onto it
  kKeep,  // never removed by a collapse; neighbours may collapse onto it
  kPin,   // never removed and never a collapse target
};

struct BuildOptions {
  bool preserveBoundaries = true;  // add perpendicular penalty planes on boundary edges
  float boundaryWeight = 10.0f;    // weight of those planes relative to face planes
  bool preventFlips = true;        // reject collapses that flip a face normal
  // > 0: attribute quadrics (Hoppe 1999) on uvs and colors, a full-range
  // attribute error weighing like a distance of sqrt(weight) * bbox diagonal.
  float attributeWeight = 0.0f;
  float weldEpsilon = 1e-6f;  // weld distance, relative to the bbox diagonal
  // Keep uv and colour seams: vertices within the weld distance are welded
  // only when their uv (within 1e-6) and colour agree too; the two sides of
  // a seam (two vertices at one place) collapse together along the seam, so
  // they never part and the seam stays on itself; places where three or more
  // sides meet, and seam ends, never move. false: weld by position only
  // (one side's attributes win, as before). Normals never split a vertex.
  bool preserveSeams = true;
  // Empty, or one per input vertex: vertices whose keys differ are never
  // welded; at one place they stay two sides of a seam, as above (whatever
  // preserveSeams says). A skinned mesh passes its vertices' skins
  // (anim::skinWeldKeys), so no vertex of a level takes another's skin.
  // Another size: kInvalidArgument.
  std::vector<std::uint64_t> weldKeys;
  std::size_t stopAtTriangles = 0;  // stop once at most this many triangles remain
  // Empty (every vertex kFree) or one per input vertex; a welded group takes
  // the constraint of its first input vertex. Another size: kInvalidArgument.
  // Quadrics and costs are unchanged: constraints only forbid moves.
  std::vector<VertexConstraint> vertexConstraints;
  // Called on the building thread about every 1% of the collapses with the
  // fraction of triangles removed so far (0..1); may be empty.
  std::function<void(double fraction)> progress;
};

class ProgressiveMesh {
 public:
  ProgressiveMesh() = default;  // empty: no triangles at any resolution

  static Result<ProgressiveMesh> build(const IndexedMesh& mesh, const BuildOptions& options = {});

  std::size_t maxTriangles() const;  // the input's triangle count (after cleanup)
  std::size_t minTriangles() const;  // where simplification stopped
  std::size_t vertexCount() const { return positions_.size(); }  // after welding
  std::size_t collapseCount() const { return levels_.empty() ? 0 : levels_.size() - 1; }
  // The triangle / vertex count extract(targetTriangles) returns.
  std::size_t triangleCountAt(std::size_t targetTriangles) const;
  std::size_t vertexCountAt(std::size_t targetTriangles) const;

  IndexedMesh extract(std::size_t targetTriangles) const;
  void extractInto(std::size_t targetTriangles, IndexedMesh& out) const;

  // Largest collapse cost among the collapses that reach targetTriangles
  // (monotone in n; 0 at full resolution). A cost is the QEM error plus the
  // distance of the removed vertex to its new fan, both sums of squared
  // distances weighted by area / mean triangle area: squared mesh units.
  double quadricErrorAt(std::size_t targetTriangles) const;
  std::size_t memoryBytes() const;  // heap bytes held by this object
  // Vertices extract(targetTriangles) visits to resolve its corners: each
  // corner's input vertex plus every hop along its substitution chain to the
  // first live vertex (Gobbetti-Bouvier's traversal cost; 3 per triangle at
  // full resolution, where no chain is followed).
  std::size_t traversedVerticesAt(std::size_t targetTriangles) const;

  // The input vertex TOM vertex `tomVertex` (< vertexCount()) came from: the
  // first input vertex of its weld group. Output vertex i of extract() is TOM
  // vertex i.
  std::uint32_t sourceVertexOf(std::uint32_t tomVertex) const { return sourceVertex_[tomVertex]; }
  // The live vertex that stands for TOM vertex `tomVertex` in a resolution
  // with `liveVertices` (vertexCountAt(n)) vertices: itself when live, else
  // the first live vertex on its substitution chain; kNoRepresentative when
  // the vertex left the mesh without a parent (no triangle used it any more).
  static constexpr std::uint32_t kNoRepresentative = 0xffffffffu;
  std::uint32_t representative(std::uint32_t tomVertex, std::size_t liveVertices) const {
    std::uint32_t v = tomVertex;
    while (v != kNoParent && v >= liveVertices) v = parent_[v];
    return v;
  }

 private:
  // One state of the collapse order: after `collapse` collapses, the first
  // activeVertices vertices and the first activeTriangles triangles are live.
  struct Level {
    std::uint32_t activeVertices = 0;
    std::uint32_t activeTriangles = 0;
    float maxCost = 0.0f;
  };
  static constexpr std::uint32_t kNoParent = 0xffffffffu;

  std::size_t levelFor(std::size_t targetTriangles) const;

  // TOM storage: everything sorted so that one resolution is a prefix.
  std::vector<glm::vec3> positions_;  // vertex i removed after vertex i + 1
  std::vector<glm::vec3> normals_;    // empty or per vertex
  std::vector<glm::vec2> uvs_;
  std::vector<std::array<std::uint8_t, 4>> colors_;
  std::vector<std::uint32_t> sourceVertex_;  // per TOM vertex: its input vertex
  // parent_[v] < v: the vertex v was substituted by; kNoParent when v never
  // was (it survives, or it was dropped once no triangle used it).
  std::vector<std::uint32_t> parent_;
  // 3 corners per triangle, in input (level 0) vertex numbering, triangles
  // sorted by the collapse that removes them (last removed first).
  std::vector<std::uint32_t> indices_;
  std::vector<Level> levels_;  // levels_[c]: after c collapses
};

}  // namespace thinlod::simplifier
