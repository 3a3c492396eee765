// Fixtures for the ProgressiveMesh tests: analytic meshes and mesh-property
// checks (manifoldness, borders, orientation) computed independently of the
// simplifier's own adjacency code.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::qemtest {

// Square [0,1]^2 at z = 0 with cells x cells quads (an open sheet with one border).
IndexedMesh makeGrid(int cells);
// Icosahedron subdivided `level` times on the unit sphere around `centre`.
IndexedMesh makeIcosphere(int level, const glm::vec3& centre = glm::vec3(0.0f));
// Icosphere with every vertex moved radially by up to `amplitude` (seeded).
IndexedMesh makeBumpySphere(int level, float amplitude, std::uint32_t seed);
// A closed, bumpy, textured sphere cut into uv charts: a cube of 6 faces,
// each split into chartsPerSide x chartsPerSide charts of cellsPerChart x
// cellsPerChart quads, projected onto the unit sphere with radius
// 1 + bump * (a smooth product of sines). Every chart is its own uv island
// of a square atlas (a padded cell); vertices on a chart border are
// duplicated, one per chart (same position, other uv): seams everywhere a
// chart meets another, three or four charts at the chart corners.
// ChartedSphere::chartOf gives the chart of each vertex, and its uv cell.
struct ChartedSphere {
  IndexedMesh mesh;
  std::vector<std::uint32_t> chartOf;  // per vertex
  int atlasColumns = 0;                // the atlas is atlasColumns^2 cells of side 1/atlasColumns
  float padding = 0.0f;                // island inset inside its cell, uv units
};
ChartedSphere makeChartedSphere(int chartsPerSide, int cellsPerChart, float bump);
IndexedMesh concatenate(const IndexedMesh& a, const IndexedMesh& b);
// Every triangle gets its own three vertices (a "soup": welding must undo it).
IndexedMesh unweld(const IndexedMesh& mesh);

// Loads ../shared/models/<name> through thinlod's mesh IO (positions and
// indices only).
Result<IndexedMesh> loadSharedModel(const std::string& name);

using Edge = std::pair<std::uint32_t, std::uint32_t>;  // (min, max)
// Undirected edge -> number of triangles using it.
std::map<Edge, int> edgeTriangleCounts(const IndexedMesh& mesh);
int countEdgesWithMoreThanTwoTriangles(const IndexedMesh& mesh);
// Vertices on an edge with more than two triangles, or whose triangles form
// more than one fan (connected through edges at the vertex): bow ties.
std::set<std::uint32_t> nonManifoldVertices(const IndexedMesh& mesh);
// Vertices on an edge used by exactly one triangle.
std::set<std::uint32_t> borderVertices(const IndexedMesh& mesh);
// Triangles as sorted triples of their corner positions: equal sets mean the
// same surface regardless of vertex numbering and corner rotation.
using PositionTriangle = std::array<std::array<float, 3>, 3>;
std::multiset<PositionTriangle> positionTriangles(const IndexedMesh& mesh);
// Index of the vertex of `reference` at exactly the position of each vertex
// of `mesh` (UINT32_MAX when none).
std::vector<std::uint32_t> matchVertices(const IndexedMesh& mesh, const IndexedMesh& reference);

}  // namespace thinlod::qemtest
