// Regions: coarse view dependence after Schmalstieg & Fuhrmann (ASLOD,
// section 4). A large mesh is split into regions by partitioning its
// vertices; each region is simplified on its own with the QEM progressive
// mesh (progressive_mesh.h) and any combination of per-region levels is
// assembled into one crack-free mesh. docs/regions.md has the decisions and
// the proof sketch.
//
// Contract:
// - Ownership: a triangle belongs to the region holding at least two of its
//   corners; when its three corners lie in three regions, to the lowest
//   region id (triangleRegion). Collapses keep a vertex in its region, so the
//   owner of a triangle is the same at every level.
// - Border rule (BorderRule::kLowerIdSide, the default): for two
//   neighbouring regions the lower id owns the border. A vertex is kept
//   (never removed) when it has a neighbour in a region with a lower id;
//   every other vertex may collapse, onto any neighbour of its own region,
//   including along the border. kBothSidesKept keeps every vertex with a
//   neighbour in another region (both sides of each border at full
//   resolution). kPaperUnchecked keeps none (the paper's rule: both sides
//   collapse along the border); it cannot crack (see docs/regions.md) but
//   is not guaranteed manifold, and exists for the comparison only.
// - Each region's progressive mesh is built on every input triangle that
//   touches the region; the other regions' vertices in it are pinned (never
//   removed, never a target). Under the first two rules no triangle and no
//   neighbour set read by one region's collapse is changed by another
//   region's collapses, so every combination of levels is the result of a
//   valid sequence of collapses of the whole mesh: no cracks, no
//   T-junctions, no non-manifold edge where the input had none, the input's
//   Euler characteristic.
// - assemble(): each region emits the triangles it owns at its level; a
//   corner in another region (a foreign vertex) is replaced by that vertex's
//   representative in its own region's current level (lookupForeign).
// - Levels are counts of owned triangles (what a region adds to a frame):
//   a target at or above maxTriangles(r) is full resolution, below
//   minTriangles(r) the coarsest state; otherwise the first state with at
//   most that many owned triangles (ProgressiveMesh::extract's rule).
// - Vertex numbering: the cleaned mesh (mesh()), welded and compacted by the
//   progressive mesh's own cleanup (weldEpsilon of the build options).
// - Errors (kInvalidArgument): an invalid mesh (empty, bad indices, NaN/Inf),
//   no regions, more regions than vertices, a label >= regionCount, a region
//   left without a vertex after cleanup, options the builder owns
//   (vertexConstraints, stopAtTriangles) set, a level vector of the wrong
//   size. Accessors taking a region r or a vertex expect r < regionCount()
//   and vertex < mesh().vertexCount() (unchecked, like vector::operator[]);
//   measureRegionCurves checks r. Pure: no I/O, no logging; immutable after
//   build, concurrent const calls are safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/mesh/mesh_regions.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"

namespace thinlod::simplifier {

// Owner of a triangle with corners in regions a, b, c: the majority region,
// or min(a, b, c) when all three differ (a function of the ids only, so
// collapses, which keep vertices in their region, never change it).
// Recursive bisection partitionVertices: the vertex set is cut at the
// longest axis of its bounding box, at the count that splits the regions
// ceil(k/2) : floor(k/2), until one region is left; ties on a coordinate go
// by vertex index (deterministic). Both live in common (mesh_regions.h),
// where the scene splits an Inline's `regions N` into objects with them.
using thinlod::partitionVertices;
using thinlod::triangleRegion;

enum class BorderRule : std::uint8_t { kLowerIdSide, kBothSidesKept, kPaperUnchecked };

struct RegionBuildOptions {
  // Per-region simplification (vertexConstraints and stopAtTriangles must
  // stay empty / 0: the builder sets the constraints, and every region
  // simplifies as far as its rules allow).
  BuildOptions mesh{};
  BorderRule borderRule = BorderRule::kLowerIdSide;
};

// What one assemble() call did (for benchmarks and tests).
struct AssembleStats {
  std::size_t foreignLookups = 0;       // foreign corners replaced by lookupForeign
  std::size_t lookupsThatMoved = 0;     // ... whose representative was another vertex
  std::size_t droppedForeignOwned = 0;  // extracted triangles owned by another region
};

class RegionMesh {
 public:
  RegionMesh() = default;  // no regions

  // labels: one region per input vertex (a weld group takes the label of its
  // first vertex), regionCount regions, each must keep a vertex.
  static Result<RegionMesh> build(const IndexedMesh& mesh, const std::vector<std::uint32_t>& labels,
                                  std::size_t regionCount, const RegionBuildOptions& options = {});
  // partitionVertices on the cleaned mesh, then build.
  static Result<RegionMesh> buildPartitioned(const IndexedMesh& mesh, std::size_t regionCount,
                                             const RegionBuildOptions& options = {});

  std::size_t regionCount() const { return regions_.size(); }
  const IndexedMesh& mesh() const { return mesh_; }  // cleaned, full resolution
  std::uint32_t regionOf(std::uint32_t vertex) const { return regionOfVertex_[vertex]; }

  // Owned triangles of region r at full resolution / at its coarsest level.
  std::size_t maxTriangles(std::size_t r) const;
  std::size_t minTriangles(std::size_t r) const;
  // Owned triangles region r emits for a target (see the level rule above).
  std::size_t triangleCountAt(std::size_t r, std::size_t targetTriangles) const;
  std::size_t keptVertices(std::size_t r) const { return regions_[r].keptVertices; }
  const ProgressiveMesh& progressiveMesh(std::size_t r) const { return regions_[r].pm; }

  // The vertex (cleaned numbering) that stands for `vertex` when its own
  // region is at `targetTriangles`: the crack-free lookup of a foreign corner.
  std::uint32_t lookupForeign(std::uint32_t vertex, std::size_t targetTriangles) const;

  // Every region at its level (targets.size() == regionCount()): one mesh;
  // vertices region by region, each region's live vertices in its
  // progressive mesh's order (coarse first); attributes of the cleaned mesh.
  Result<IndexedMesh> assemble(const std::vector<std::size_t>& targets,
                               AssembleStats* stats = nullptr) const;
  Status assembleInto(const std::vector<std::size_t>& targets, IndexedMesh& out,
                      AssembleStats* stats = nullptr) const;

  // Region r alone at a target, its foreign corners at full resolution (its
  // neighbours' finest level): the mesh its accuracy curve is measured on.
  IndexedMesh extractRegion(std::size_t r, std::size_t targetTriangles) const;

  std::size_t memoryBytes() const;

 private:
  struct Region {
    ProgressiveMesh pm;
    std::size_t foreignOwned = 0;  // triangles in pm owned by other regions (never removed)
    std::size_t keptVertices = 0;
    std::vector<std::uint32_t> vertexOfTom;  // pm's TOM vertex -> cleaned vertex
    // Per TOM vertex, what assembly needs in one load: its region and, for
    // an own vertex, its place among the region's output vertices (own
    // vertices before it in TOM order), for a foreign one its TOM index in
    // its own region's mesh.
    struct Corner {
      std::uint32_t region;
      std::uint32_t index;
    };
    std::vector<Corner> corners;
    std::vector<std::uint32_t> ownRank;  // own vertices before each TOM index (size + 1)
  };
  static Result<RegionMesh> buildClean(IndexedMesh clean, std::vector<std::uint32_t> labels,
                                       std::size_t regionCount, const RegionBuildOptions& options);
  std::size_t pmTarget(std::size_t r, std::size_t targetTriangles) const;
  void compactInto(const std::vector<std::uint32_t>& indices, IndexedMesh& out) const;

  IndexedMesh mesh_;
  std::vector<std::uint32_t> regionOfVertex_;
  std::vector<std::uint32_t> tomOfVertex_;  // cleaned vertex -> TOM index in its region's pm
  std::vector<Region> regions_;
};

// Accuracy curves of region r (mesh_curve.h): measured on extractRegion()
// against the region at full resolution, so each region is a leaf with its
// own curve. kInvalidArgument when r is out of range or owns no triangle.
Result<MeshCurves> measureRegionCurves(const RegionMesh& regions, std::size_t r,
                                       const MeshCurveOptions& options = {});

}  // namespace thinlod::simplifier
