// TriMesh: the OpenMesh half-edge triangle mesh used by mesh IO and by
// algorithms that need connectivity (simplification, progressive meshes).
// Other modules exchange IndexedMesh; convert at the edge with the two
// functions below. This is the only public header that names OpenMesh.
//
// Contract:
// - Vertex attributes: normal (Vec3f), RGBA colour (Vec4uc), 2D texcoord
//   (Vec2f) and status; face and edge status (deleted, non-manifold flags).
// - toIndexedMesh skips deleted vertices/faces (no garbage_collection needed)
//   and copies normals/colours/uvs only when the mesh carries them
//   (`has*` flags below, set by the loader or by fromIndexedMesh).
// - fromIndexedMesh never fails on valid input: a triangle OpenMesh refuses
//   (non-manifold edge/vertex, wrong orientation) is added on duplicated
//   vertices and counted; triangles with repeated indices are skipped and
//   counted. Precondition: mesh.validate() is OK (asserted in debug).
// - Pure functions, no I/O; safe from any thread on distinct meshes.
#pragma once

// OpenMesh's VectorT leaves its default-constructed data uninitialised on
// purpose; GCC then warns (-Wmaybe-uninitialized) wherever property vectors
// grow. The warning is about OpenMesh's code, so it is silenced for it only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#pragma GCC diagnostic pop
#include <cstddef>

#include "thinlod/common/core/indexed_mesh.h"

namespace thinlod {

struct TriMeshTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec4uc Color;
  VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Color |
                   OpenMesh::Attributes::TexCoord2D | OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
};

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<TriMeshTraits>;

// Which per-vertex attributes of a TriMesh carry data (OpenMesh always
// allocates them with the traits above).
struct TriMeshAttributes {
  bool normals = false;
  bool colors = false;
  bool uvs = false;
};

struct TriMeshConversion {
  TriMesh mesh;
  TriMeshAttributes attributes;
  std::size_t nonManifoldTriangles = 0;  // added on duplicated vertices
  std::size_t degenerateTriangles = 0;   // repeated index: skipped
};

IndexedMesh toIndexedMesh(const TriMesh& mesh, const TriMeshAttributes& attributes);
TriMeshConversion fromIndexedMesh(const IndexedMesh& mesh);

}  // namespace thinlod
