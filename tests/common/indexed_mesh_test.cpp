#include "thinlod/common/core/indexed_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace thinlod {
namespace {

IndexedMesh unitTriangle() {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  return m;
}

TEST(IndexedMesh, ValidTriangleValidates) { EXPECT_TRUE(unitTriangle().validate("tri").ok()); }

TEST(IndexedMesh, OutOfRangeIndexIsNamed) {
  IndexedMesh m = unitTriangle();
  m.indices[2] = 7;
  Status s = m.validate("tri");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(s.message().find("vertex 7"), std::string::npos) << s.message();
}

TEST(IndexedMesh, NaNPositionRejected) {
  IndexedMesh m = unitTriangle();
  m.positions[1].y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(m.validate("tri").ok());
}

TEST(IndexedMesh, IndexCountNotMultipleOfThreeRejected) {
  IndexedMesh m = unitTriangle();
  m.indices.push_back(0);
  EXPECT_FALSE(m.validate("tri").ok());
}

TEST(IndexedMesh, AttributeSizeMismatchRejected) {
  IndexedMesh m = unitTriangle();
  m.uvs.resize(2);
  EXPECT_FALSE(m.validate("tri").ok());
}

TEST(IndexedMesh, BoundingSphereContainsAllVertices) {
  IndexedMesh m;
  for (int i = 0; i < 100; ++i) {
    const float t = static_cast<float>(i) * 0.37f;
    m.positions.push_back({std::sin(t) * 3.0f, std::cos(t * 1.3f), std::sin(t * 0.7f) * 2.0f});
  }
  const BoundingSphere s = m.boundingSphere();
  for (const auto& p : m.positions) {
    const glm::vec3 d = p - s.center;
    EXPECT_LE(std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z), s.radius);
  }
  EXPECT_LE(s.radius, m.diameter());  // never worse than the bbox diagonal
}

TEST(IndexedMesh, NormalsOfFlatTrianglePointUp) {
  IndexedMesh m = unitTriangle();
  m.computeNormals();
  ASSERT_EQ(m.normals.size(), 3u);
  for (const auto& n : m.normals) EXPECT_NEAR(n.z, 1.0f, 1e-6f);
}

// Fuzz finding (fuzz/corpus/mesh/crash-stl-normal-overflow.stl): with
// coordinates near FLT_MAX the float cross product overflowed and the normal
// became NaN, failing validate() on a mesh the loader had accepted.
TEST(IndexedMesh, ComputeNormalsStaysFiniteAtExtremeMagnitudes) {
  for (const float scale : {3e38f, 1e30f, 1e-30f, 1e-44f}) {
    IndexedMesh m;
    m.positions = {{-scale, -scale, 0.0f}, {scale, -scale, 0.0f}, {scale, scale, 0.0f}};
    m.indices = {0, 1, 2};
    m.computeNormals();
    ASSERT_TRUE(m.validate("extreme").ok()) << scale;
    for (const glm::vec3& n : m.normals) {
      EXPECT_NEAR(glm::length(n), 1.0f, 1e-6f) << scale;
      EXPECT_NEAR(n.z, 1.0f, 1e-6f) << scale;  // the triangle's normal
    }
  }
}

}  // namespace
}  // namespace thinlod
