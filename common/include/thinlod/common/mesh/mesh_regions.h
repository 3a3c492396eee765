// Mesh regions: the vertex partition and triangle ownership of ASLOD's
// coarse view dependence (Schmalstieg & Fuhrmann, section 4), and the split
// of one mesh into region submeshes that the scene makes into separate
// objects (an Inline's `regions N`, docs/scene-format.md; docs/regions.md,
// "In the running system"). The simplifier's RegionMesh (regions.h) builds
// on the same partition and ownership.
//
// Contract:
// - triangleRegion: the majority region of a triangle's corners, the lowest
//   id when all three differ (a function of the ids only).
// - partitionVertices: recursive bisection at the longest bbox axis, regions
//   split ceil(k/2) : floor(k/2), ties by vertex index (deterministic).
// - splitMeshIntoRegions: vertices at one exact position share a label (a uv
//   or normal seam's copies land in one region); only referenced vertices are
//   partitioned; each triangle goes to triangleRegion of its corners' labels.
//   Region r's mesh holds its owned triangles in input order, its vertices
//   renumbered in order of first use, every per-vertex attribute kept;
//   sourceVertex maps them back. The regions' triangles are the input's, each
//   exactly once. Errors (kInvalidArgument): an invalid mesh, regionCount 0 or
//   above the distinct referenced positions, a region left owning no triangle.
// - openBoundaryVertices: one flag per vertex, set when the vertex (by exact
//   position, so seam copies count as one) ends an edge used by exactly one
//   triangle. For a region's submesh of a manifold input these are its
//   borders with other regions plus the input's own outer border.
// - Pure: no I/O, no globals; thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod {

std::uint32_t triangleRegion(std::uint32_t a, std::uint32_t b, std::uint32_t c);

// One label in [0, regionCount) per position. Errors: regionCount 0 or
// > positions.size(), a non-finite position.
Result<std::vector<std::uint32_t>> partitionVertices(const std::vector<glm::vec3>& positions,
                                                     std::size_t regionCount);

struct MeshRegion {
  IndexedMesh mesh;                         // the region's owned triangles
  std::vector<std::uint32_t> sourceVertex;  // region vertex -> input vertex
};

Result<std::vector<MeshRegion>> splitMeshIntoRegions(const IndexedMesh& mesh,
                                                     std::size_t regionCount);

std::vector<bool> openBoundaryVertices(const IndexedMesh& mesh);

}  // namespace thinlod
