#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <tuple>

#include "test_meshes.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::codec {
namespace {

using simplifier::measureSurfaceError;
using simplifier::SurfaceError;
using simplifier::SurfaceErrorOptions;
using thinlod::testing::makeIcosphere;
using thinlod::testing::readObjPositions;
using thinlod::testing::sharedModelPath;

// For every vertex of `a`, the distance to the nearest vertex of `b`
// (uniform grid of cell `cell`, searching the 27 neighbouring cells).
double maxNearestVertexDistance(const IndexedMesh& a, const IndexedMesh& b, double cell) {
  std::map<std::tuple<long, long, long>, std::vector<glm::vec3>> grid;
  auto key = [cell](const glm::vec3& p) {
    return std::make_tuple(static_cast<long>(std::floor(p.x / cell)),
                           static_cast<long>(std::floor(p.y / cell)),
                           static_cast<long>(std::floor(p.z / cell)));
  };
  for (const glm::vec3& p : b.positions) grid[key(p)].push_back(p);
  double worst = 0.0;
  for (const glm::vec3& p : a.positions) {
    const auto [x, y, z] = key(p);
    double best = std::numeric_limits<double>::infinity();
    for (long dx = -1; dx <= 1; ++dx) {
      for (long dy = -1; dy <= 1; ++dy) {
        for (long dz = -1; dz <= 1; ++dz) {
          auto it = grid.find({x + dx, y + dy, z + dz});
          if (it == grid.end()) continue;
          for (const glm::vec3& q : it->second) best = std::min(best, double(glm::length(p - q)));
        }
      }
    }
    worst = std::max(worst, best);
  }
  return worst;
}

IndexedMesh cow() {
  Result<IndexedMesh> mesh = readObjPositions(sharedModelPath("cow.obj"));
  EXPECT_TRUE(mesh.ok()) << mesh.status().toString();
  return mesh.ok() ? *mesh : IndexedMesh{};
}

TEST(MeshEncoding, DracoRoundTripMovesVerticesAtMostTheQuantizationBound) {
  const IndexedMesh mesh = cow();
  ASSERT_GT(mesh.triangleCount(), 0u);
  for (int bits : {8, 11, 14}) {
    MeshEncodeOptions options;
    options.positionBits = bits;
    Result<std::vector<std::uint8_t>> encoded = encodeMesh(mesh, options);
    ASSERT_TRUE(encoded.ok()) << encoded.status().toString();
    Result<IndexedMesh> decoded = decodeMesh(encoded->data(), encoded->size());
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_EQ(decoded->triangleCount(), mesh.triangleCount());
    const double bound = positionErrorBound(mesh, bits);
    const double slack = 1e-6 * mesh.diameter();  // float rounding in dequantization
    EXPECT_LE(maxNearestVertexDistance(*decoded, mesh, 2 * bound), bound + slack) << bits;
    EXPECT_LE(maxNearestVertexDistance(mesh, *decoded, 2 * bound), bound + slack) << bits;
    // Moving every vertex by <= bound moves the surface by <= bound.
    SurfaceErrorOptions few;
    few.samplesPerMesh = 5000;
    Result<SurfaceError> error = measureSurfaceError(mesh, *decoded, few);
    ASSERT_TRUE(error.ok()) << error.status().toString();
    EXPECT_LE(error->max(), bound + slack) << bits;
  }
}

TEST(MeshEncoding, FewerBitsGiveSmallerEncodings) {
  const IndexedMesh mesh = cow();
  std::size_t previous = std::numeric_limits<std::size_t>::max();
  for (int bits : {16, 13, 10, 8}) {
    MeshEncodeOptions options;
    options.positionBits = bits;
    Result<std::vector<std::uint8_t>> encoded = encodeMesh(mesh, options);
    ASSERT_TRUE(encoded.ok()) << encoded.status().toString();
    EXPECT_LT(encoded->size(), previous) << bits;
    previous = encoded->size();
  }
}

TEST(MeshEncoding, AttributesSurviveWithinTheirQuantization) {
  IndexedMesh sphere = makeIcosphere(3, 1.0f);
  sphere.computeNormals();
  for (const glm::vec3& p : sphere.positions) {
    sphere.uvs.emplace_back(0.5f + 0.5f * p.x, 0.5f + 0.5f * p.y);
    sphere.colors.push_back({static_cast<std::uint8_t>(127.5f + 127.f * p.x),
                             static_cast<std::uint8_t>(127.5f + 127.f * p.y),
                             static_cast<std::uint8_t>(127.5f + 127.f * p.z), 200});
  }
  Result<std::vector<std::uint8_t>> encoded = encodeMesh(sphere);
  ASSERT_TRUE(encoded.ok()) << encoded.status().toString();
  Result<IndexedMesh> decoded = decodeMesh(encoded->data(), encoded->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  ASSERT_EQ(decoded->normals.size(), decoded->vertexCount());
  ASSERT_EQ(decoded->uvs.size(), decoded->vertexCount());
  ASSERT_EQ(decoded->colors.size(), decoded->vertexCount());
  // Match vertices by position (they are far apart compared to 14 bits).
  for (std::size_t i = 0; i < decoded->vertexCount(); ++i) {
    std::size_t match = 0;
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t j = 0; j < sphere.vertexCount(); ++j) {
      const float d = glm::length(decoded->positions[i] - sphere.positions[j]);
      if (d < best) best = d, match = j;
    }
    ASSERT_LE(best, positionErrorBound(sphere, 14) * 1.001);
    // 10-bit octahedral normals: well under a degree.
    EXPECT_GT(glm::dot(decoded->normals[i], sphere.normals[match]), std::cos(0.5 * M_PI / 180));
    EXPECT_NEAR(decoded->uvs[i].x, sphere.uvs[match].x, 1.0 / 4095);
    EXPECT_NEAR(decoded->uvs[i].y, sphere.uvs[match].y, 1.0 / 4095);
    EXPECT_EQ(decoded->colors[i], sphere.colors[match]);
  }
}

TEST(MeshEncoding, PositionBitsDecreaseWithLowerAccuracy) {
  int previous = 100;
  for (double accuracy : {1e6, 1e5, 1e4, 1e3, 300.0, 100.0, 30.0, 10.0, 1.0}) {
    const int bits = positionBitsForAccuracy(accuracy);
    EXPECT_LE(bits, previous) << accuracy;
    EXPECT_GE(bits, 8);
    EXPECT_LE(bits, 20);
    previous = bits;
  }
  EXPECT_EQ(positionBitsForAccuracy(1e7), 20);  // clamped
  EXPECT_EQ(positionBitsForAccuracy(1.0), 8);   // clamped
  // a = 100: 100 * sqrt(3) / 0.2 + 1 = 867 levels -> 10 bits.
  EXPECT_EQ(positionBitsForAccuracy(100.0), 10);
  EXPECT_LT(positionBitsForAccuracy(100.0, 0.5), positionBitsForAccuracy(100.0, 0.1));
}

TEST(MeshEncoding, ChosenBitsKeepTheDisplacementWithinTheBudgetFraction) {
  const IndexedMesh mesh = cow();
  for (double accuracy : {20.0, 150.0, 1000.0, 20000.0}) {
    const int bits = positionBitsForAccuracy(accuracy, 0.1);
    EXPECT_LE(positionErrorBound(mesh, bits), 0.1 * mesh.diameter() / accuracy) << accuracy;
    if (bits > 8) {  // and one bit fewer would not have been enough in the worst case
      EXPECT_GT(mesh.diameter() / (std::ldexp(1.0, bits - 1) - 1) * std::sqrt(3.0) / 2,
                0.1 * mesh.diameter() / accuracy);
    }
  }
}

TEST(MeshEncoding, DegenerateTrianglesAreDroppedBeforeEncoding) {
  IndexedMesh mesh = makeIcosphere(2, 1.0f);
  const std::size_t triangles = mesh.triangleCount();
  mesh.indices.insert(mesh.indices.end(), {0, 0, 1, 2, 3, 2});
  Result<std::vector<std::uint8_t>> encoded = encodeMesh(mesh);
  ASSERT_TRUE(encoded.ok()) << encoded.status().toString();
  Result<IndexedMesh> decoded = decodeMesh(encoded->data(), encoded->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_EQ(decoded->triangleCount(), triangles);
}

TEST(MeshEncoding, InvalidMeshesAreRejected) {
  IndexedMesh nan = makeIcosphere(1, 1.0f);
  nan.positions[2].x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(encodeMesh(nan).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(encodeMesh(IndexedMesh{}).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh onlyDegenerate;
  onlyDegenerate.positions = {{0, 0, 0}, {1, 0, 0}};
  onlyDegenerate.indices = {0, 0, 1};
  EXPECT_EQ(encodeMesh(onlyDegenerate).status().code(), ErrorCode::kInvalidArgument);
}

TEST(MeshEncoding, OutOfRangeOptionsAreRejected) {
  const IndexedMesh mesh = makeIcosphere(1, 1.0f);
  MeshEncodeOptions options;
  options.positionBits = 21;
  EXPECT_EQ(encodeMesh(mesh, options).status().code(), ErrorCode::kInvalidArgument);
  options.positionBits = 7;
  EXPECT_EQ(encodeMesh(mesh, options).status().code(), ErrorCode::kInvalidArgument);
  options = MeshEncodeOptions{};
  options.encodeSpeed = 11;
  EXPECT_EQ(encodeMesh(mesh, options).status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::codec
