// Skinned levels: a progressive-mesh level of a skinned mesh, deformed vertex
// by vertex, and its geometric error while the model moves (ASLOD 5.4;
// docs/animation.md, "Levels of a skinned mesh").
//
// Contract:
// - tomSkin: the VertexSkin of every TOM vertex, the skin of its source
//   input vertex (ProgressiveMesh::sourceVertexOf). Level n's vertices are
//   the first vertexCountAt(n) TOM vertices, so `deform(level.positions,
//   skin, matrices, {}, out)` skins exactly the current level's vertices.
//   Errors (kInvalidArgument): the skin fails validateSkin for `input`, or
//   a source vertex is not a vertex of `input` (another mesh's PM).
// - deformedLevelBound: the symmetric Hausdorff distance between the
//   deformed level and the deformed full mesh over a clip window, as
//   measured, not proven: at poses the error is measureSurfaceError's
//   (finite surface samples, so <= the true distance at that pose); between
//   two measured poses a and b the error at t is covered by the triangle
//   inequality in a moving frame: for any invertible affine R (the identity,
//   or a bone's motion from a to t), e(t) <= ||R|| (e(a) + mL + mF), mX the
//   largest |R^-1 P_v(t) - P_v(a)| over X's vertices (a point of a triangle
//   moves by a convex combination of its corners' motions), taking the best
//   frame and the smaller of the a- and b-sides, with the motion sampled at
//   motionSteps substeps (as sampledMaxDisplacement). The bound is the
//   worst interval's cover; while it exceeds (1 + relativeTolerance) times
//   the largest measured error (and absoluteTolerance times the rest
//   diagonal), the worst interval is split at its midpoint (one more
//   measured pose), until maxPoses poses are measured: `converged` says
//   whether the bound ended within that tolerance. A level whose triangles are the full
//   mesh's (same positions and skins) is the same surface at every pose:
//   bound 0, `identical`, nothing sampled.
//   Errors (kInvalidArgument): a mesh fails validate or has no triangles,
//   skins that fail validateSkin (the level's: its first vertexCount()
//   entries), a skeleton or clip that fails validation, a non-finite or
//   reversed window, bad options, deformed positions that are not finite.
// - Pure: no I/O, no globals; deterministic for given options.
#pragma once

#include <cstddef>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {

Result<std::vector<anim::VertexSkin>> tomSkin(const ProgressiveMesh& pm, const IndexedMesh& input,
                                              const std::vector<anim::VertexSkin>& inputSkin,
                                              std::size_t boneCount);

struct AnimatedErrorOptions {
  double t0 = 0.0;
  double t1 = -1.0;  // < 0: the clip's duration
  anim::ClipWrap wrap = anim::ClipWrap::kLoop;
  std::size_t initialPoses = 9;  // evenly spaced over [t0, t1], both ends; >= 2
  std::size_t maxPoses = 65;     // measured poses in all (>= initialPoses)
  std::size_t motionSteps = 8;   // interior substeps per interval for the motion terms; >= 1
  double relativeTolerance = 0.25;
  double absoluteTolerance = 1e-3;  // times the full mesh's rest bbox diagonal
  SurfaceErrorOptions surface{20000, 1, true};
};

struct AnimatedLevelError {
  double bound = 0.0;             // mesh units: covers every time of the window (see contract)
  double maxAtPoses = 0.0;        // the largest measured error at a pose
  double worstTime = 0.0;         // the pose of maxAtPoses
  double restError = 0.0;         // undeformed level vs undeformed full mesh (measured)
  double diagonal = 0.0;          // the full mesh's rest bbox diagonal
  std::size_t poses = 0;          // measured poses
  bool converged = true;          // bound <= max((1 + tol) * maxAtPoses, absolute)
  bool identical = false;         // the level is the full mesh's surface: 0, proven
  std::size_t levelVertices = 0;  // vertices deformed per frame for the level
  std::size_t fullVertices = 0;   // ... for the full mesh
  std::vector<double> poseTimes;  // measured poses, ascending
  std::vector<double> poseErrors;
};

// `level` is any level of `full` (e.g. pm.extract(n)) with `levelSkin` its
// vertices' skins (tomSkin(pm, ...): the first level.vertexCount() entries).
Result<AnimatedLevelError> deformedLevelBound(
    const IndexedMesh& full, const std::vector<anim::VertexSkin>& fullSkin,
    const anim::Skeleton& skeleton, const anim::AnimationClip& clip, const IndexedMesh& level,
    const std::vector<anim::VertexSkin>& levelSkin, const AnimatedErrorOptions& options = {});

// The error of `level` at one pose (time `seconds` of the clip), measured
// with measureSurfaceError between the deformed meshes; same checks as
// deformedLevelBound. The tests' and the report's reference.
Result<double> deformedLevelErrorAt(const IndexedMesh& full,
                                    const std::vector<anim::VertexSkin>& fullSkin,
                                    const anim::Skeleton& skeleton, const anim::AnimationClip& clip,
                                    const IndexedMesh& level,
                                    const std::vector<anim::VertexSkin>& levelSkin, double seconds,
                                    anim::ClipWrap wrap,
                                    const SurfaceErrorOptions& surface = {20000, 1, true});

}  // namespace thinlod::simplifier
