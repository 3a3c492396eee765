// Test fixtures shared by tests/simplifier_error and tests/encoding: small
// analytic meshes, a minimal OBJ reader for the shared models, and a
// meshoptimizer-based simplification used as an independent "other
// simplifier" (so these tests do not depend on ProgressiveMesh).
#pragma once

#include <cstddef>
#include <string>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/status.h"

namespace thinlod::testing {

// Square [0,size]^2 in the z = height plane, cells x cells quads, 2 tris each.
IndexedMesh makeGrid(int cells, float size, float height);
// Icosahedron subdivided `level` times, vertices projected onto the sphere.
// 20 * 4^level triangles.
IndexedMesh makeIcosphere(int level, float radius);
// The largest distance from the centre to a triangle's plane deficit, i.e.
// max over triangles of (radius - distance from the centre to the triangle):
// the sagitta, the exact Hausdorff distance between a sphere and an
// inscribed tessellation.
double maxSagitta(const IndexedMesh& sphere, float radius);

// Path of a shared model ("cow.obj").
std::string sharedModelPath(const std::string& name);
// Reads "v" and "f" lines (polygons fan-triangulated, v/vt/vn refs allowed).
Result<IndexedMesh> readObjPositions(const std::string& path);
// meshoptimizer 0.18 meshopt_simplify down to about targetTriangles
// (unreferenced vertices kept; positions are shared with the input).
IndexedMesh simplifyWithMeshoptimizer(const IndexedMesh& mesh, std::size_t targetTriangles);

}  // namespace thinlod::testing
