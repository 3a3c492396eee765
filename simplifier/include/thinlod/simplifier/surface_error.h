// Surface error: symmetric Hausdorff distance between two triangle meshes,
// from area-weighted surface samples and an accelerated closest-point query.
//
// Contract (seed; the owner refines it):
// - Distances in the meshes' units; `relative*` divide by the original's
//   bounding-box diagonal (the "object size" of relative accuracy).
// - Deterministic for a given seed. Pure: no I/O, no globals.
// - Errors: either mesh invalid or without triangles -> kInvalidArgument.
#pragma once

#include <cstdint>

#include "thinlod/common/indexed_mesh.h"
#include "thinlod/common/status.h"

namespace thinlod::simplifier {

struct SurfaceErrorOptions {
  std::size_t samplesPerMesh = 100000;
  std::uint64_t seed = 1;
};

struct SurfaceError {
  double maxForward = 0.0;   // original -> simplified
  double maxBackward = 0.0;  // simplified -> original
  double meanForward = 0.0;
  double meanBackward = 0.0;
  double diagonal = 0.0;  // original's bbox diagonal
  double max() const { return maxForward > maxBackward ? maxForward : maxBackward; }
  double mean() const { return meanForward > meanBackward ? meanForward : meanBackward; }
  double relativeMax() const { return diagonal > 0 ? max() / diagonal : 0.0; }
  double relativeMean() const { return diagonal > 0 ? mean() / diagonal : 0.0; }
};

Result<SurfaceError> measureSurfaceError(const IndexedMesh& original,
                                         const IndexedMesh& simplified,
                                         const SurfaceErrorOptions& options = {});

}  // namespace thinlod::simplifier
