#include "thinlod/common/mesh/tri_mesh.h"

#include <gtest/gtest.h>

namespace thinlod {
namespace {

IndexedMesh tetrahedron() {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  return m;
}

TEST(TriMesh, RoundTripKeepsGeometryAndAttributes) {
  IndexedMesh m = tetrahedron();
  m.computeNormals();
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  m.colors = {{{1, 2, 3, 4}}, {{5, 6, 7, 8}}, {{9, 10, 11, 12}}, {{13, 14, 15, 16}}};
  TriMeshConversion conv = fromIndexedMesh(m);
  EXPECT_EQ(conv.nonManifoldTriangles, 0u);
  EXPECT_EQ(conv.mesh.n_faces(), 4u);
  IndexedMesh back = toIndexedMesh(conv.mesh, conv.attributes);
  EXPECT_EQ(back.positions, m.positions);
  EXPECT_EQ(back.normals, m.normals);
  EXPECT_EQ(back.uvs, m.uvs);
  EXPECT_EQ(back.colors, m.colors);
  ASSERT_EQ(back.indices.size(), m.indices.size());
  // Same triangles; OpenMesh may rotate the corner order within a face.
  for (std::size_t t = 0; t < 4; ++t) {
    std::array<std::uint32_t, 3> a{m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
    bool found = false;
    for (int r = 0; r < 3; ++r) {
      found |= back.indices[3 * t] == a[r] && back.indices[3 * t + 1] == a[(r + 1) % 3] &&
               back.indices[3 * t + 2] == a[(r + 2) % 3];
    }
    EXPECT_TRUE(found) << "triangle " << t;
  }
}

TEST(TriMesh, NonManifoldTrianglesAreDuplicatedAndCounted) {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  // Three triangles on the edge 0-1.
  m.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  TriMeshConversion conv = fromIndexedMesh(m);
  EXPECT_EQ(conv.mesh.n_faces(), 3u);
  EXPECT_EQ(conv.nonManifoldTriangles, 1u);
  EXPECT_EQ(conv.mesh.n_vertices(), 8u);
  IndexedMesh back = toIndexedMesh(conv.mesh, conv.attributes);
  EXPECT_TRUE(back.validate("back").ok());
  EXPECT_EQ(back.triangleCount(), 3u);
}

TEST(TriMesh, DegenerateTrianglesAreSkipped) {
  IndexedMesh m = tetrahedron();
  m.indices.insert(m.indices.end(), {1, 1, 2});
  TriMeshConversion conv = fromIndexedMesh(m);
  EXPECT_EQ(conv.degenerateTriangles, 1u);
  EXPECT_EQ(conv.mesh.n_faces(), 4u);
}

TEST(TriMesh, DeletedFacesAreSkipped) {
  TriMeshConversion conv = fromIndexedMesh(tetrahedron());
  conv.mesh.delete_face(*conv.mesh.faces().begin(), false);
  IndexedMesh back = toIndexedMesh(conv.mesh, conv.attributes);
  EXPECT_EQ(back.triangleCount(), 3u);
  EXPECT_EQ(back.vertexCount(), 4u);
  EXPECT_TRUE(back.validate("back").ok());
}

}  // namespace
}  // namespace thinlod
