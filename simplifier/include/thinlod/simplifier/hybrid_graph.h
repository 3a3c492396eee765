// Hybrid triangle + point simplification (Cohen, Aliaga & Zhang, "Hybrid
// Simplification: Combining Multi-resolution Polygon and Point Rendering"):
// a multiresolution graph (MRG) of edge collapses, point replacements of
// triangles and octree point merges, with a conservative two-sided Hausdorff
// bound per node, and cuts through it. docs/hybrid.md has the derivations.
//
// Contract:
// - buildHybridGraph validates the input (kInvalidArgument: NaN/Inf, bad
//   indices, no usable triangle), welds exactly equal positions, drops
//   triangles with a repeated corner or zero area, then simplifies.
// - Errors are absolute, in mesh units. Every primitive p carries error(p)
//   such that, for ANY cut C, the two-sided Hausdorff distance between the
//   union of C's primitives (points as discs or balls) and the input surface
//   is <= max over C of error(p) (a successive-mapping argument: see
//   docs/hybrid.md). A node's error is the max of its produced primitives'
//   errors and of its child nodes' errors: non-decreasing towards the source.
// - kappa = point rate / triangle rate; primitive units = triangles +
//   points / kappa. A triangle is replaced by at most floor(kappa) points and
//   by fewer than kappa (so every node removes > 0 units). kappa <= 1 or
//   enablePoints == false: triangles only (the paper's baseline).
// - Queue value: error increase / units removed; collapses are multiplied by
//   tau (tau > 1 introduces points sooner).
// - Pure: no I/O, no logging, no globals. The graph is immutable after build;
//   HybridCut refers to it (the graph must outlive its cuts).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/disc_points.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {

// Version of what buildHybridGraph and measureHybridLevels compute: part of
// the hybrid curve cache key (hybrid_curve_cache.h). Bump it whenever a
// change to the graph (queue, bounds, sampling, octree) or to the ladder's
// choice of rungs could change a stored ladder.
inline constexpr int kHybridGraphVersion = 1;

struct HybridOptions {
  double kappa = 3.0;  // point rate / triangle rate
  double tau = 1.0;    // transition factor, > 0
  bool enablePoints = true;
  // Relative tolerance of the sample-distance search (paper 5.3.2).
  double sampleDistanceTolerance = 1e-3;
  int octreeMaxDepth = 24;  // deeper cells merge their points in chains of 8
};

enum class HybridNodeKind : std::uint8_t {
  kDrain,             // produces the input triangles
  kEdgeCollapse,      // half-edge collapse: star of u -> fan of w
  kPointReplacement,  // one triangle -> 1..floor(kappa) points
  kPointMerge,        // 2..8 points -> 1 point (octree cell)
  kSource,            // consumes whatever is left (never applied)
};

enum class HybridPrimitiveKind : std::uint8_t { kTriangle, kPoint };

// A point primitive: a disc of `radius` around `centre` in the plane normal
// to `normal` (the bound also holds for the ball). `tangent` is the row
// direction of the sampling (leaf points) or any in-plane unit vector.
struct HybridPoint {
  glm::dvec3 centre{0.0};
  glm::dvec3 normal{0.0, 0.0, 1.0};
  glm::dvec3 tangent{1.0, 0.0, 0.0};
  double radius = 0.0;
  double area = 0.0;  // surface area it stands for (merge weights)
  std::array<std::uint8_t, 4> color{255, 255, 255, 255};
};

struct HybridPrimitive {
  HybridPrimitiveKind kind = HybridPrimitiveKind::kTriangle;
  std::uint32_t index = 0;     // into triangles() or points()
  std::uint32_t producer = 0;  // node id
  std::uint32_t consumer = 0;  // node id (the source when never consumed)
  double error = 0.0;          // bound, mesh units
};

struct HybridNode {
  HybridNodeKind kind = HybridNodeKind::kDrain;
  double error = 0.0;  // monotone bound (see contract)
  glm::dvec3 sphereCentre{0.0};
  double sphereRadius = 0.0;  // contains its primitives and child nodes' spheres
  std::uint32_t consumedBegin = 0, consumedEnd = 0;  // ranges into consumedList()
  std::uint32_t producedBegin = 0, producedEnd = 0;  // ranges into producedList()
};

struct HybridGraphStats {
  std::size_t inputTriangles = 0;  // after cleanup
  std::size_t graphTriangles = 0;  // every triangle in the graph, input included
  std::size_t graphPoints = 0;
  std::size_t edgeCollapses = 0;
  std::size_t pointReplacements = 0;
  std::size_t pointMerges = 0;
};

// One step of the units-vs-error curve: applying every node with error <=
// `error` leaves `units` primitive units.
struct HybridCurveStep {
  double error = 0.0;
  double units = 0.0;
  std::size_t triangles = 0;
  std::size_t points = 0;
};

class HybridGraph {
 public:
  static constexpr std::uint32_t kDrain = 0;

  const std::vector<glm::dvec3>& vertices() const { return vertices_; }
  const std::vector<std::array<std::uint8_t, 4>>& vertexColors() const { return colors_; }
  const std::vector<std::array<std::uint32_t, 3>>& triangles() const { return triangles_; }
  const std::vector<HybridPoint>& points() const { return points_; }
  const std::vector<HybridPrimitive>& primitives() const { return primitives_; }
  const std::vector<HybridNode>& nodes() const { return nodes_; }
  const std::vector<std::uint32_t>& consumedList() const { return consumed_; }
  const std::vector<std::uint32_t>& producedList() const { return produced_; }
  std::uint32_t sourceNode() const { return static_cast<std::uint32_t>(nodes_.size() - 1); }
  double kappa() const { return kappa_; }
  double diagonal() const { return diagonal_; }  // cleaned input's bbox diagonal
  const HybridGraphStats& stats() const { return stats_; }
  // Units removed by applying node n (> 0 for every node but drain/source).
  double unitsRemovedBy(std::uint32_t node) const;
  double primitiveUnits(const HybridPrimitive& p) const {
    return p.kind == HybridPrimitiveKind::kTriangle ? 1.0 : 1.0 / kappa_;
  }

  // Steps in increasing error; units strictly decreasing. The first step is
  // the input (error 0, units = input triangles).
  std::vector<HybridCurveStep> unitsVersusError() const;

 private:
  friend class HybridGraphBuilder;
  std::vector<glm::dvec3> vertices_;
  std::vector<std::array<std::uint8_t, 4>> colors_;  // empty or per vertex
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  std::vector<HybridPoint> points_;
  std::vector<HybridPrimitive> primitives_;
  std::vector<HybridNode> nodes_;
  std::vector<std::uint32_t> consumed_;
  std::vector<std::uint32_t> produced_;
  double kappa_ = 1.0;
  double diagonal_ = 0.0;
  HybridGraphStats stats_;
};

Result<HybridGraph> buildHybridGraph(const IndexedMesh& mesh, const HybridOptions& options = {});

// The relative accuracy curve (Pasman-Jansen form) of a graph: accuracy
// a = diagonal / max(error, minRelativeError * diagonal), resources =
// primitive units, fitted conservatively (AccuracyCurve::fitConservative).
Result<AccuracyCurve> hybridAccuracyCurve(const HybridGraph& graph, double minRelativeError = 1e-4,
                                          int maxSegments = 8);

// A view for screen-space cuts: a primitive's error e at distance z appears
// as e * pixelsPerRadian / z pixels (pixelsPerRadian = viewport height /
// (2 tan(fovY / 2))); z is the distance from the eye to the node's bounding
// sphere, at least nearDistance.
struct HybridView {
  glm::dvec3 eye{0.0};
  double pixelsPerRadian = 1000.0;
  double nearDistance = 1e-3;
};

// Whole-object screen-space tolerance: the object-space error that appears
// as `pixels` at distance `distance` (pass it to HybridCut::adaptToError).
inline double hybridErrorForPixels(double pixels, double distance, double pixelsPerRadian) {
  return pixels * distance / pixelsPerRadian;
}

// A cut through the graph: the set of applied nodes (the drain always, the
// source never), closed under "children first", and the primitives produced
// by applied nodes and consumed by unapplied ones. Adapting starts from the
// current cut and moves only nodes on its frontier (work ~ cut size + changes).
class HybridCut {
 public:
  explicit HybridCut(const HybridGraph& graph);  // the input triangles

  // Every node with error <= maxError applied, no other (max >= 0).
  void adaptToError(double maxError);
  // Every node whose error in pixels (see HybridView) <= tolerancePixels.
  void adaptToScreen(const HybridView& view, double tolerancePixels);

  const std::vector<std::uint32_t>& primitives() const { return cut_; }  // primitive ids
  bool applied(std::uint32_t node) const { return applied_[node] != 0; }
  bool contains(std::uint32_t primitive) const { return slot_[primitive] != kAbsent; }
  std::size_t triangleCount() const { return triangles_; }
  std::size_t pointCount() const { return cut_.size() - triangles_; }
  double units() const;
  double errorBound() const;  // max error of the cut's primitives (0 for the input)
  std::size_t nodesMovedLastAdapt() const { return moved_; }

  // Triangles (graph vertices) and discs of the cut.
  IndexedMesh triangleMesh() const;
  std::vector<HybridPoint> pointList() const;

 private:
  template <typename Allowed>
  void adapt(const Allowed& allowed);
  void add(std::uint32_t primitive);
  void remove(std::uint32_t primitive);

  static constexpr std::uint32_t kAbsent = 0xffffffffu;
  const HybridGraph* graph_;
  std::vector<std::uint8_t> applied_;
  std::vector<std::uint32_t> slot_;  // primitive -> index in cut_
  std::vector<std::uint32_t> cut_;
  std::size_t triangles_ = 0;
  std::size_t moved_ = 0;
};

// The cut in common's terms, for the link encoder and the renderer: its
// triangles (graph vertices, vertex colours when the graph has them) and its
// discs (centre, normal, radius, colour; float).
HybridGeometry hybridGeometry(const HybridCut& cut);

// ---- Building blocks, public for tests -------------------------------------

// Point sampling of one triangle with sample distance d > 0 (paper 5.3.1):
// rows of squares of side d parallel to the longest edge, the last square of
// a row shifted to end at the triangle; each square's part of the triangle
// (its cell) gets one disc of radius d / sqrt(2) centred at the centre of the
// cell's smallest enclosing circle, which lies in the cell, hence in the
// triangle, and keeps the cell covered (see docs/hybrid.md for why the
// paper's "push the square" rule is not used). Zero-area triangle: empty.
struct TriangleSample {
  glm::dvec3 centre{0.0};
  glm::dvec3 barycentric{0.0};  // of the centre, for attribute interpolation
  double cellArea = 0.0;
};
std::vector<TriangleSample> sampleTriangle(const glm::dvec3& a, const glm::dvec3& b,
                                           const glm::dvec3& c, double d);
std::size_t countTriangleSamples(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                 double d);
// The smallest d (within relative tolerance) with at most `maxSamples`
// samples (paper 5.3.2). Precondition: maxSamples >= 1, positive area.
double smallestSampleDistance(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                              std::size_t maxSamples, double relativeTolerance);

// Merged point of the octree phase. Child i has centre c_i, radius r_i,
// error e_i, triangle part t_i = e_i - r_i. The parent ball (centre = area-
// weighted mean, radius R = max |c - c_i| + r_i) gets error
// R + max(max_i t_i, min_i(|c - c_i| + t_i)): the paper's R + max t_i plus
// the distance of an off-surface centre (derived; docs/hybrid.md).
struct MergedPoint {
  HybridPoint point;
  double error = 0.0;
};
MergedPoint mergePoints(const std::vector<HybridPoint>& children,
                        const std::vector<double>& childErrors);

// Sampled two-sided Hausdorff distance between the input surface and a cut
// given as triangles plus discs (HybridPoint: centre, normal, radius), the
// points-as-discs extension of measureSurfaceError: same exact closest-point
// BVH, `samplesPerMesh` area-weighted samples per side plus every vertex, edge
// midpoint, disc centre and 8 rim points per disc; exact point-disc distance.
// Either side may be empty of triangles (not both of the cut's parts).
// Errors: invalid meshes, an empty cut, samplesPerMesh == 0.
Result<SurfaceError> measureHybridSurfaceError(const IndexedMesh& original,
                                               const IndexedMesh& cutTriangles,
                                               const std::vector<HybridPoint>& cutDiscs,
                                               const SurfaceErrorOptions& options = {});

// The measured curve of a graph (the hybrid counterpart of mesh_curve.h's
// measured ladder): `levels` unit targets spaced geometrically
// (geometricLadder) from the coarsest step's units to the input's, each
// mapped to the finest step of unitsVersusError() with at most that many
// units (duplicates merged), and that step's cut measured against
// `original` with measureHybridSurfaceError. Increasing units (like
// CurveLevel: increasing triangles); the last level is the input. The cut is
// adapted incrementally from rung to rung. Errors: levels < 1, and those of
// measureHybridSurfaceError.
struct HybridMeasuredLevel {
  HybridCurveStep step;        // the cut: every node with error <= step.error
  double measuredError = 0.0;  // sampled two-sided Hausdorff max, mesh units
};
// The rungs measureHybridLevels measures (its first step, pure and cheap):
// increasing units, the last one the input (unitsVersusError().front()).
// Empty when the graph is empty or levels < 1.
std::vector<HybridCurveStep> hybridLadderSteps(const HybridGraph& graph, int levels);
Result<std::vector<HybridMeasuredLevel>> measureHybridLevels(const IndexedMesh& original,
                                                             const HybridGraph& graph, int levels,
                                                             const SurfaceErrorOptions& options);

// Generated multi-manifold test model: `parts` separate closed bumpy
// icospheres (subdivision `level`) of random sizes scattered in a unit box.
IndexedMesh generateScatteredParts(int parts, int level, std::uint32_t seed);

}  // namespace thinlod::simplifier
