// Surface error: symmetric Hausdorff distance between two triangle meshes,
// from area-weighted surface samples and an exact closest-point query
// accelerated by a bounding-volume hierarchy (Metro-style, Cignoni et al.).
//
// Contract:
// - Distances in the meshes' units; `relative*` divide by the original's
//   bounding-box diagonal (Metro's convention, for reports and benchmarks).
//   Relative accuracy divides max() by the reference length instead
//   (core/relative_accuracy.h; mesh_curve.h does).
// - "Forward" samples the original and measures each sample's distance to the
//   simplified surface; "backward" the other way round. Each side is sampled
//   with `samplesPerMesh` stratified area-weighted random points; when
//   `includeVerticesAndEdges`, every referenced vertex and points along every
//   unique edge (at least its midpoint; samplesPerMesh/4 in all, spread by
//   length) are measured too, so maxima at corners and creases are not
//   missed. The 16 worst samples are then refined by a local search on their
//   triangle. Means average the random samples only (area-weighted).
// - The closest-point query is exact (point-triangle in double precision);
//   the only approximation is the finite sampling, so max <= true Hausdorff.
// - Both meshes are sampled with the same seed: measure(A, B).maxForward ==
//   measure(B, A).maxBackward exactly. Deterministic for a given seed.
// - Pure: no I/O, no globals, no threads; safe to call concurrently.
// - Errors (kInvalidArgument): a mesh fails IndexedMesh::validate, has no
//   triangles or zero total area, or samplesPerMesh == 0.
#pragma once

#include <cstddef>
#include <cstdint>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::simplifier {

struct SurfaceErrorOptions {
  std::size_t samplesPerMesh = 100000;  // random area-weighted samples per direction
  std::uint64_t seed = 1;
  bool includeVerticesAndEdges = true;
};

struct SurfaceError {
  double maxForward = 0.0;   // original -> simplified
  double maxBackward = 0.0;  // simplified -> original
  double meanForward = 0.0;
  double meanBackward = 0.0;
  double diagonal = 0.0;          // original's bbox diagonal
  std::size_t pointsForward = 0;  // samples measured (random + vertices + edges)
  std::size_t pointsBackward = 0;
  double max() const { return maxForward > maxBackward ? maxForward : maxBackward; }
  double mean() const { return meanForward > meanBackward ? meanForward : meanBackward; }
  double relativeMax() const { return diagonal > 0 ? max() / diagonal : 0.0; }
  double relativeMean() const { return diagonal > 0 ? mean() / diagonal : 0.0; }
};

Result<SurfaceError> measureSurfaceError(const IndexedMesh& original, const IndexedMesh& simplified,
                                         const SurfaceErrorOptions& options = {});

// Texture error of a simplification (docs/simplifier.md, "UV error"):
// `samples` area-weighted points q of the simplified surface, each with its
// interpolated uv s, and two measures per point:
// - uv distance |s - o| (uv units), o the original's uv at the closest
//   point of the original surface. Every original point within
//   (1 + tieFactor) d + tieTolerance * diagonal of q (d: q's distance to the
//   original) is a candidate and the one whose uv is nearest s is taken: on
//   a seam the original has two uvs at one place, and a point on it, or off
//   it by no more than the geometry moved, must not be charged the distance
//   between the charts. Where a seam moved sideways along the surface the
//   points between its old and new place still are (the charts differ
//   there), so this measure's max is a poor bound: see the next.
// - texture displacement |P(s) - q| (object units): P(s) is where the texel
//   s lies on the original surface (the point of the original whose uv is
//   s, or within texelTolerance of s, the one nearest q: texels that close
//   show the same colour, and an atlas packs charts next to each other, so
//   a uv a hair outside its own chart (a simplified chart border cutting a
//   concave corner) lands in a neighbouring chart whose place is anywhere;
//   where s lies farther outside every chart, the preimage of the nearest
//   uv the original has).
//   It is how far from its place a texel is drawn, comparable with (and,
//   since P(s) is on the original, never below) q's geometric distance, and
//   indifferent to seams: both sides of a seam map to the same place.
// Errors (kInvalidArgument): a mesh fails validate, has no triangles, zero
// area or no uvs; samples == 0; bad tie options; the original's uv area is
// zero (uvArea).
struct UvErrorOptions {
  std::size_t samples = 100000;
  std::uint64_t seed = 1;
  double tieFactor = 1.0;
  double tieTolerance = 1e-5;  // relative to the original's bbox diagonal
  // uv units: a texel of a 1024-texel texture.
  double texelTolerance = 1.0 / 1024.0;
};

struct UvError {
  double meanUv = 0.0;  // uv distance, uv units
  double p95Uv = 0.0;   // 95th percentile over the samples
  double maxUv = 0.0;
  double meanDisplacement = 0.0;  // texture displacement, object units
  double p95Displacement = 0.0;
  double maxDisplacement = 0.0;
  double diagonal = 0.0;  // original's bbox diagonal
  std::size_t samples = 0;
};

// Sum of the triangles' areas in uv space (0 for a mesh without uvs).
double uvArea(const IndexedMesh& mesh);

Result<UvError> measureUvError(const IndexedMesh& original, const IndexedMesh& simplified,
                               const UvErrorOptions& options = {});

}  // namespace thinlod::simplifier
