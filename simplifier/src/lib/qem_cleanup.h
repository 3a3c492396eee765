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
  std::vector<std::uint32_t> indices;  // 3 per triangle, into positions
  std::size_t weldedVertices = 0;      // input vertices merged into another
  std::size_t droppedDegenerate = 0;   // triangles with a repeated corner after welding
  std::size_t droppedDuplicate = 0;    // triangles repeating another's vertex set
};

// weldEpsilon is relative to the bounding-box diagonal of the input.
Result<CleanMesh> cleanMesh(const IndexedMesh& mesh, float weldEpsilon);

}  // namespace thinlod::simplifier::qem
