// Private: the QEM half-edge collapse loop. Greedy by collapse cost (quadric
// plus fan term) with an indexed binary heap over vertices: each vertex is
// keyed by an estimate of its cheapest outgoing collapse, replaced by the
// exact legal cost when it reaches the top. Vertex -> corner adjacency in
// flat arrays. Pure; the input is a CleanMesh (no repeated corners, no
// duplicate triangles, vertices in spatial order).
#pragma once

#include <cstdint>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <vector>

#include "qem_cleanup.h"
#include "thinlod/simplifier/progressive_mesh.h"

namespace thinlod::simplifier::qem {

inline constexpr std::uint32_t kNone = 0xffffffffu;

// Version of the collapse order: bump it whenever a change can reorder the
// collapses of some input. Cached measured curves (mesh_curve_cache.cpp) are
// keyed by it, so a curve measured on another order is never reused.
// 2: border term in the cost (distance of a border vertex to its new border).
// 3: uv / colour seams kept (BuildOptions::preserveSeams): vertices at one
//    place with other attributes are no longer welded, seam pairs move together.
inline constexpr std::uint32_t kCollapseOrderVersion = 3;

// The collapse order, in CleanMesh numbering. Steps are 1-based: step s is
// the s-th collapse; "step 0" is the input.
struct CollapseRecord {
  // Every vertex removal in order: collapsed vertices (parent = the vertex
  // that substituted them) and vertices left without triangles (parent kNone).
  std::vector<std::uint32_t> removedVertex;
  std::vector<std::uint32_t> removedParent;
  // Per step s >= 1 (index s - 1): removals so far, triangles left, cost.
  std::vector<std::uint32_t> removalsAfterStep;
  std::vector<std::uint32_t> trianglesAfterStep;
  std::vector<float> costOfStep;
  // Per triangle: the step that removed it, 0 when it survives.
  std::vector<std::uint32_t> triangleRemovedAtStep;
};

// Optional per-vertex attributes for attribute-aware costs (dimension 0..6
// floats per vertex, each roughly in [0, 1]).
struct VertexAttributes {
  std::size_t dimension = 0;
  std::vector<float> values;  // dimension floats per clean vertex
};

// constraints: empty or one per clean vertex (see VertexConstraint).
CollapseRecord runCollapses(const CleanMesh& mesh, const VertexAttributes& attributes,
                            const std::vector<VertexConstraint>& constraints,
                            const BuildOptions& options);

}  // namespace thinlod::simplifier::qem
