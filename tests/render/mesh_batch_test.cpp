// MeshBatch: merging meshes into one world-space mesh with per-vertex layers (no GL).
#include "thinlod/common/render/mesh_batch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <random>

namespace thinlod::render {
namespace {

IndexedMesh triangle() {
  IndexedMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.uvs = {{0, 0}, {1, 0}, {0, 1}};
  m.indices = {0, 1, 2};
  return m;
}

TEST(MeshBatch, AppendOffsetsIndicesAndTagsLayers) {
  MeshBatch batch;
  MeshBatch::Part part;
  part.textureLayer = 3;
  ASSERT_TRUE(batch.append(triangle(), part, "a").ok());
  part.textureLayer = 7;
  ASSERT_TRUE(batch.append(triangle(), part, "b").ok());
  EXPECT_EQ(batch.partCount(), 2u);
  EXPECT_EQ(batch.mesh().vertexCount(), 6u);
  EXPECT_EQ(batch.mesh().indices, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(batch.textureLayers(), (std::vector<std::uint16_t>{3, 3, 3, 7, 7, 7}));
  EXPECT_TRUE(batch.mesh().validate("batch").ok());
  EXPECT_EQ(batch.mesh().normals.size(), 6u);
  EXPECT_EQ(batch.mesh().colors.size(), 6u);
}

TEST(MeshBatch, TransformsPositionsNormalsAndUvs) {
  MeshBatch batch;
  MeshBatch::Part part;
  part.model = glm::translate(glm::mat4(1.0f), glm::vec3(5, 0, 0)) *
               glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(1, 0, 0)) *
               glm::scale(glm::mat4(1.0f), glm::vec3(2.0f, 1.0f, 1.0f));
  part.uvScale = glm::vec2(0.5f, 0.25f);
  part.uvOffset = glm::vec2(0.1f, 0.2f);
  ASSERT_TRUE(batch.append(triangle(), part, "t").ok());
  const IndexedMesh& m = batch.mesh();
  EXPECT_NEAR(m.positions[1].x, 7.0f, 1e-5f);  // (1,0,0) scaled by 2 then moved by 5
  EXPECT_NEAR(m.positions[2].z, 1.0f, 1e-5f);  // (0,1,0) rotated about x onto +z
  // The face normal +z rotates to -y and stays unit length under the non-uniform scale.
  EXPECT_NEAR(m.normals[0].y, -1.0f, 1e-5f);
  EXPECT_NEAR(glm::length(m.normals[0]), 1.0f, 1e-5f);
  EXPECT_NEAR(m.uvs[1].x, 0.6f, 1e-6f);
  EXPECT_NEAR(m.uvs[2].y, 0.45f, 1e-6f);
}

TEST(MeshBatch, ColoursMultiply) {
  IndexedMesh t = triangle();
  t.colors.assign(3, {255, 128, 0, 255});
  MeshBatch batch;
  MeshBatch::Part part;
  part.color = {128, 255, 255, 255};
  ASSERT_TRUE(batch.append(t, part, "t").ok());
  EXPECT_EQ(batch.mesh().colors[0], (std::array<std::uint8_t, 4>{128, 128, 0, 255}));
}

TEST(MeshBatch, InvalidMeshAppendsNothing) {
  MeshBatch batch;
  IndexedMesh bad = triangle();
  bad.indices[2] = 9;
  Status status = batch.append(bad, {}, "impostor 4");
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(status.message().find("impostor 4"), std::string::npos);
  EXPECT_EQ(batch.mesh().vertexCount(), 0u);
  EXPECT_EQ(batch.partCount(), 0u);
}

TEST(MeshBatch, BadPartsAreRejected) {
  MeshBatch batch;
  MeshBatch::Part singular;
  singular.model = glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 0.0f, 1.0f));
  EXPECT_EQ(batch.append(triangle(), singular, "s").code(), ErrorCode::kInvalidArgument);
  MeshBatch::Part nan;
  nan.model[3][1] = std::nanf("");
  EXPECT_EQ(batch.append(triangle(), nan, "n").code(), ErrorCode::kInvalidArgument);
  MeshBatch::Part layer;
  layer.textureLayer = 70000;
  EXPECT_EQ(batch.append(triangle(), layer, "l").code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(batch.mesh().vertexCount(), 0u);
}

TEST(MeshBatch, RandomPartsKeepTriangleCountAndValidity) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<float> coordinate(-10.0f, 10.0f);
  std::uniform_int_distribution<int> layers(0, 300);
  MeshBatch batch;
  std::size_t triangles = 0;
  for (int i = 0; i < 100; ++i) {
    MeshBatch::Part part;
    part.model = glm::translate(glm::mat4(1.0f),
                                glm::vec3(coordinate(rng), coordinate(rng), coordinate(rng)));
    part.textureLayer = layers(rng);
    ASSERT_TRUE(batch.append(triangle(), part, "random").ok());
    triangles += 1;
  }
  EXPECT_EQ(batch.mesh().triangleCount(), triangles);
  EXPECT_TRUE(batch.mesh().validate("batch").ok());
  batch.clear();
  EXPECT_EQ(batch.mesh().vertexCount(), 0u);
  EXPECT_TRUE(batch.textureLayers().empty());
}

}  // namespace
}  // namespace thinlod::render
