// The ASLOD terrain experiment of issue 18 (docs/results/aslod-terrain.md):
// a height-grid terrain cut into grid-cell regions, each region one leaf of a
// SchedulingScene with its own measured curves, a frontend that receives at
// once what a plan asks for, and the crack check of an assembled terrain.
// Shared by backbone/bench/bench_aslod_terrain.cpp and aslod_terrain_test.cpp.
//
// Contract:
// - Units: metres; the terrain lies in [0, side]^2 in x and y, heights in z.
// - Region r of the RegionMesh is object r and node r + 1 of the scene (node
//   0 is the group root); one simplified-mesh option per object whose curves
//   are the region's measured relative curves; its leaf sphere is the
//   reference sphere the curves refer to (L = 2 r).
// - Levels: a region the plan renders gets floor(decision triangles) as its
//   owned-triangle target; a region it does not render (culled, dropped)
//   gets 0, the coarsest state, for the lookups of its neighbours' border
//   triangles (the assembled mesh then holds it at its coarsest).
// - checkCracks counts what is wrong with an assembled terrain; a crack-free
//   manifold terrain has violations() == 0.
// - Pure: no I/O, no logging. Errors are passed on from the libraries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "thinlod/backbone/scheduler.h"
#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/regions.h"

namespace thinlod::aslodterrain {

struct Terrain {
  IndexedMesh mesh;                   // n x n vertices, two triangles per grid square
  std::vector<std::uint32_t> labels;  // per vertex: its grid cell, cells x cells regions
  int n = 0;
  int cells = 0;
  double side = 0.0;
};

// Heights: three sines (the bench_regions terrain scaled by `side`):
// side * (0.08 sin(6.1 x) cos(4.3 y) + 0.03 sin(17 x + 3 y) + 0.01 cos(41 y - 13 x)),
// x, y in [0, 1]. Cell of vertex (i, j): min(cells - 1, i * cells / (n - 1)).
Terrain makeTerrain(int n, int cells, double side);
double terrainHeight(double x01, double y01, double side);

struct RegionLeaf {
  simplifier::MeshCurves curves;
  backbone::Sphere sphere;
};
// measureRegionCurves for every region, and the sphere its curves refer to.
Result<std::vector<RegionLeaf>> measureRegionLeaves(const simplifier::RegionMesh& regions,
                                                    const simplifier::MeshCurveOptions& options);

// Bytes of a region representation (no link budget in this experiment; a
// Draco-like size so the scene is valid): kBytesOverhead + kBytesPerTriangle t.
inline constexpr double kBytesOverhead = 64.0;
inline constexpr double kBytesPerTriangle = 14.0;
Result<backbone::SchedulingScene> regionScene(const std::vector<RegionLeaf>& leaves);

// The frontend: removals drop copies; requested representations arrive at
// once and replace the object's displayed copy; leaf and root versions bumped.
void deliver(backbone::SchedulingScene& scene, const backbone::Plan& plan);

struct RegionLevels {
  std::vector<std::size_t> targets;  // per region, for RegionMesh::assemble
  std::vector<bool> rendered;        // the plan shows the region
};
RegionLevels levelsOfPlan(std::size_t regionCount, const backbone::Plan& plan);

// Solid angle (sr) of a sphere whose surface is `distanceToSurface` away
// (the schedulers' projected-area measure, allocation_schedulers.h).
double sphereSolidAngle(double radius, double distanceToSurface);

struct CrackCheck {
  std::size_t triangles = 0;
  std::size_t vertices = 0;  // referenced by a triangle
  std::size_t edges = 0;
  std::size_t unknownVertices = 0;         // position not in the input grid
  std::size_t degenerateTriangles = 0;     // a corner repeated
  std::size_t duplicateDirectedEdges = 0;  // a directed edge on two triangles
  std::size_t edgesOnMoreThanTwo = 0;      // non-manifold edges
  std::size_t boundaryEdges = 0;           // on one triangle
  // A boundary edge with an end off the grid's outer border: a crack, a hole
  // or a T-junction (a vertex on the other side's edge leaves both open).
  std::size_t boundaryEdgesInside = 0;
  // Both ends on the outer border but not on one side: the outline was
  // simplified at a corner of the grid (a corner vertex collapsed). Not a
  // crack; the terrain loses the corner's area (projectedArea < domainArea).
  std::size_t boundaryEdgesCuttingCorners = 0;
  std::size_t boundaryLoops = 0;             // connected pieces of the boundary; 1 for a disc
  std::size_t boundaryVerticesNotOnTwo = 0;  // on != 2 boundary edges (bow tie)
  std::size_t regionBorderEdges = 0;         // interior edges between two regions' triangles
  long long euler = 0;                       // V - E + F; 1 for a disc
  double boundaryLength = 0.0;               // of the boundary edges, in the xy plane
  double perimeter = 0.0;                    // of the grid
  double projectedArea = 0.0;                // signed, in the xy plane
  double domainArea = 0.0;
  std::vector<std::size_t> trianglesPerRegion;  // owner (triangleRegion) of each triangle
  glm::vec3 insideExample[2]{};                 // ends of the first boundary edge inside

  // Cracks and T-junctions: an open edge inside, or more than one boundary.
  std::size_t cracks() const { return boundaryEdgesInside + (boundaryLoops != 1 ? 1 : 0); }
  // Everything else that is not a manifold disc.
  std::size_t manifoldViolations() const {
    return unknownVertices + degenerateTriangles + duplicateDirectedEdges + edgesOnMoreThanTwo +
           boundaryVerticesNotOnTwo + (euler != 1 ? 1 : 0);
  }
  std::size_t violations() const { return cracks() + manifoldViolations(); }
};
// `assembled` from regions.assemble(); vertices are matched to the input grid
// by position (every assembled vertex is an input vertex).
CrackCheck checkCracks(const IndexedMesh& assembled, const simplifier::RegionMesh& regions);

}  // namespace thinlod::aslodterrain
