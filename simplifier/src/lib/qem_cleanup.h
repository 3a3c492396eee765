// Private: input cleanup before QEM simplification. Validates the mesh, welds
// vertices closer than a tolerance, drops degenerate (repeated corner) and
// duplicate (same three vertices, any order) triangles and every vertex no
// triangle uses, then renumbers vertices along a space-filling curve (the
// collapse loop's memory traffic follows neighbourhoods). Pure; errors are
// kInvalidArgument with a readable message.
#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::simplifier::qem {

struct CleanMesh {
  std::vector<glm::vec3> positions;
  // For each clean vertex, the input vertex it came from (the first of those
  // welded together): its attributes are the ones kept.
  std::vector<std::uint32_t> sourceVertex;
  // Per clean vertex: its place (vertices welded by position share one).
  // With splitSeams, vertices at one place whose uv or colour differ stay
  // separate clean vertices of one group, at exactly the same position: the
  // two sides of a seam. Group ids are < positions.size(), not contiguous.
  std::vector<std::uint32_t> positionGroup;
  std::vector<std::uint32_t> indices;  // 3 per triangle, into positions
  std::size_t weldedVertices = 0;      // input vertices merged into another
  std::size_t droppedDegenerate = 0;   // triangles with a repeated corner after welding
  std::size_t droppedDuplicate = 0;    // triangles repeating another's vertex set
  std::size_t seamVertices = 0;        // clean vertices that share a place with another
};

// weldEpsilon is relative to the bounding-box diagonal of the input.
// splitSeams: weld only vertices whose uv and colour agree too (uv within
// 1e-6, colour exactly); a triangle with two corners at one place is dropped
// as degenerate either way. weldKeys (empty, or one per input vertex; the
// caller checks the size): vertices whose keys differ are never welded and
// split like a seam, with or without splitSeams.
Result<CleanMesh> cleanMesh(const IndexedMesh& mesh, float weldEpsilon, bool splitSeams = false,
                            const std::vector<std::uint64_t>& weldKeys = {});

}  // namespace thinlod::simplifier::qem
