// MeshEncodeOptions positionOrigin / positionRange: meshes encoded on one
// explicit grid decode a shared vertex to the same floats (the regions of one
// mesh, docs/regions.md), where each mesh's own box generally does not.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

// Two fans that share the vertex `shared`; their boxes differ.
IndexedMesh fan(const glm::vec3& shared, float reach, float tilt) {
  IndexedMesh mesh;
  mesh.positions = {shared, shared + glm::vec3(reach, 0.013f, tilt),
                    shared + glm::vec3(0.37f * reach, reach, -tilt),
                    shared + glm::vec3(-0.71f * reach, 0.29f * reach, 0.5f * tilt)};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  return mesh;
}

IndexedMesh roundTrip(const IndexedMesh& mesh, const MeshEncodeOptions& options) {
  Result<std::vector<std::uint8_t>> bytes = encodeMesh(mesh, options);
  EXPECT_TRUE(bytes.ok()) << bytes.status().toString();
  if (!bytes.ok()) return {};
  Result<IndexedMesh> decoded = decodeMesh(bytes->data(), bytes->size());
  EXPECT_TRUE(decoded.ok()) << decoded.status().toString();
  return decoded.ok() ? std::move(decoded).value() : IndexedMesh();
}

// The decoded position nearest to `p`.
glm::vec3 nearest(const IndexedMesh& mesh, const glm::vec3& p) {
  glm::vec3 best = mesh.positions.front();
  for (const glm::vec3& q : mesh.positions)
    if (glm::length(q - p) < glm::length(best - p)) best = q;
  return best;
}

TEST(PositionGrid, SharedGridDecodesASharedVertexIdentically) {
  const glm::vec3 shared(0.3141f, 0.2718f, 0.1414f);
  const IndexedMesh a = fan(shared, 0.9f, 0.05f);
  const IndexedMesh b = fan(shared, -0.23f, 0.31f);
  MeshEncodeOptions own;
  own.positionBits = 11;
  // Each box on its own: the shared vertex lands on two grids.
  EXPECT_NE(nearest(roundTrip(a, own), shared), nearest(roundTrip(b, own), shared));
  MeshEncodeOptions grid = own;
  grid.positionOrigin = {-1.0f, -1.0f, -1.0f};
  grid.positionRange = 3.0f;
  const glm::vec3 fromA = nearest(roundTrip(a, grid), shared);
  const glm::vec3 fromB = nearest(roundTrip(b, grid), shared);
  EXPECT_EQ(fromA, fromB);
  // Within half a grid step per axis.
  const float step = 3.0f / float((1 << 11) - 1);
  for (int k = 0; k < 3; ++k) EXPECT_LE(std::abs(fromA[k] - shared[k]), 0.5f * step * 1.001f);
}

TEST(PositionGrid, BadGridsAreRefused) {
  const IndexedMesh a = fan(glm::vec3(0.0f), 1.0f, 0.1f);
  MeshEncodeOptions options;
  options.positionOrigin = {-2.0f, -2.0f, -2.0f};
  options.positionRange = -1.0f;
  EXPECT_EQ(encodeMesh(a, options).status().code(), ErrorCode::kInvalidArgument);
  options.positionRange = std::numeric_limits<float>::infinity();
  EXPECT_EQ(encodeMesh(a, options).status().code(), ErrorCode::kInvalidArgument);
  options.positionRange = 4.0f;
  options.positionOrigin[1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(encodeMesh(a, options).status().code(), ErrorCode::kInvalidArgument);
  // A vertex outside the cube.
  options.positionOrigin = {0.5f, -2.0f, -2.0f};
  EXPECT_EQ(encodeMesh(a, options).status().code(), ErrorCode::kInvalidArgument);
  options.positionOrigin = {-2.0f, -2.0f, -2.0f};
  EXPECT_TRUE(encodeMesh(a, options).ok());
}

}  // namespace
}  // namespace thinlod::codec
