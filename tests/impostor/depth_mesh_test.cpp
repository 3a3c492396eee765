// buildDepthMesh on synthetic depth buffers (no GL).
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <vector>

#include "thinlod/common/render/camera.h"
#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

constexpr int kSize = 64;

ImpostorFraming cubeFraming() {
  const std::vector<glm::vec3> cube = {{-1, -1, -1}, {1, 1, 1}, {-1, 1, -1}, {1, -1, 1}};
  ImpostorOptions options;
  options.textureSize = kSize;
  auto framing = frameImpostor(cube, glm::vec3(0, 0, 10), options);
  EXPECT_TRUE(framing.ok());
  return *framing;
}

// Window depth of the point at eye depth z on pixel (x, y)'s ray.
float windowDepth(const ImpostorFraming& f, int x, int y, float z) {
  const glm::vec3 a = render::unprojectPixel(f.camera, x + 0.5f, y + 0.5f, 0.0f, kSize, kSize);
  const glm::vec3 b = render::unprojectPixel(f.camera, x + 0.5f, y + 0.5f, 1.0f, kSize, kSize);
  const float za = glm::dot(a - f.viewpoint, f.forward);
  const float zb = glm::dot(b - f.viewpoint, f.forward);
  const glm::vec3 p = a + (b - a) * ((z - za) / (zb - za));
  return render::projectToPixel(f.camera, p, kSize, kSize).z;
}

float eyeDepth(const ImpostorFraming& f, const glm::vec3& p) {
  return glm::dot(p - f.viewpoint, f.forward);
}

TEST(DepthMesh, StepInDepthIsSplitAndBackgroundDropped) {
  const ImpostorFraming f = cubeFraming();
  const float nearZ = 9.2f;
  const float farZ = 10.8f;
  std::vector<float> depth(kSize * kSize, 1.0f);
  for (int y = 8; y < kSize; ++y) {  // rows 0..7 stay background
    for (int x = 0; x < kSize; ++x)
      depth[y * kSize + x] = windowDepth(f, x, y, x < 32 ? nearZ : farZ);
  }
  MeshedImpostorOptions options;
  options.textureSize = kSize;
  options.gridStep = 4;
  options.snapToSilhouette = false;
  DepthMeshStats stats;
  auto mesh = buildDepthMesh(depth, f, options, &stats);
  ASSERT_TRUE(mesh.ok()) << mesh.status().toString();
  ASSERT_GT(mesh->triangleCount(), 100u);
  for (const glm::vec3& p : mesh->positions) {
    const float z = eyeDepth(f, p);
    EXPECT_TRUE(std::fabs(z - nearZ) < 1e-3f || std::fabs(z - farZ) < 1e-3f) << z;
    const glm::vec3 pixel = render::projectToPixel(f.camera, p, kSize, kSize);
    EXPECT_GE(pixel.y, 8.0f) << "vertex in the background rows";
  }
  for (std::size_t t = 0; t < mesh->indices.size(); t += 3) {
    const bool a = eyeDepth(f, mesh->positions[mesh->indices[t]]) < 10.0f;
    const bool b = eyeDepth(f, mesh->positions[mesh->indices[t + 1]]) < 10.0f;
    const bool c = eyeDepth(f, mesh->positions[mesh->indices[t + 2]]) < 10.0f;
    ASSERT_TRUE(a == b && b == c) << "triangle " << t / 3 << " spans the step";
  }
  EXPECT_GT(stats.splitEdges, 0u);
  EXPECT_NEAR(stats.maxDepthJump, farZ - nearZ, 1e-3);
}

TEST(DepthMesh, SteepButContinuousSurfaceStaysConnected) {
  const ImpostorFraming f = cubeFraming();
  std::vector<float> depth(kSize * kSize);
  // Depth grows 0.8x as fast as the lateral distance (a 39 degree slope).
  const float pixelWidth = f.quad.width / kSize;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      depth[y * kSize + x] = windowDepth(f, x, y, 9.1f + 0.8f * pixelWidth * x);
    }
  }
  MeshedImpostorOptions options;
  options.textureSize = kSize;
  options.maxSlope = 0.5f;  // steeper than allowed: every horizontal edge splits
  DepthMeshStats steep;
  ASSERT_TRUE(buildDepthMesh(depth, f, options, &steep).ok());
  EXPECT_GT(steep.splitEdges, 200u);
  options.maxSlope = 1.0f;
  DepthMeshStats stats;
  auto mesh = buildDepthMesh(depth, f, options, &stats);
  ASSERT_TRUE(mesh.ok());
  EXPECT_EQ(stats.splitEdges, 0u);
  const std::size_t cells = (kSize - 1 + 3) / 4;
  EXPECT_EQ(mesh->triangleCount(), 2 * cells * cells);
  // Texture coordinates follow the pixels: the first vertex is pixel (0, 0)'s centre.
  EXPECT_NEAR(mesh->uvs[0].x, 0.5f / kSize, 1e-6f);
  EXPECT_NEAR(mesh->uvs[0].y, 1.0f - 0.5f / kSize, 1e-6f);
  // Normals face the viewpoint.
  for (const glm::vec3& n : mesh->normals) EXPECT_LT(glm::dot(n, f.forward), 0.0f);
}

TEST(DepthMesh, SnappingPullsTheRimOntoCoveredPixels) {
  const ImpostorFraming f = cubeFraming();
  std::vector<float> depth(kSize * kSize, 1.0f);
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x <= 30; ++x) depth[y * kSize + x] = windowDepth(f, x, y, 10.0f);
  }
  MeshedImpostorOptions options;
  options.textureSize = kSize;
  options.gridStep = 4;
  options.snapToSilhouette = false;
  auto plain = buildDepthMesh(depth, f, options, nullptr);
  options.snapToSilhouette = true;
  auto snapped = buildDepthMesh(depth, f, options, nullptr);
  ASSERT_TRUE(plain.ok() && snapped.ok());
  auto maxX = [&](const IndexedMesh& m) {
    float x = 0.0f;
    for (const glm::vec3& p : m.positions)
      x = std::max(x, render::projectToPixel(f.camera, p, kSize, kSize).x);
    return x;
  };
  EXPECT_NEAR(maxX(*plain), 28.5f, 0.01f);    // last covered grid column: x = 28
  EXPECT_NEAR(maxX(*snapped), 30.5f, 0.01f);  // the node at x = 32 snapped 2 pixels to x = 30
}

TEST(DepthMesh, RejectsMismatchedInput) {
  const ImpostorFraming f = cubeFraming();
  MeshedImpostorOptions options;
  options.textureSize = kSize;
  EXPECT_EQ(buildDepthMesh(std::vector<float>(10), f, options, nullptr).status().code(),
            ErrorCode::kInvalidArgument);
  options.gridStep = kSize;
  EXPECT_EQ(
      buildDepthMesh(std::vector<float>(kSize * kSize, 1.0f), f, options, nullptr).status().code(),
      ErrorCode::kInvalidArgument);
  options.gridStep = 4;
  options.maxSlope = -1.0f;
  EXPECT_EQ(
      buildDepthMesh(std::vector<float>(kSize * kSize, 1.0f), f, options, nullptr).status().code(),
      ErrorCode::kInvalidArgument);
}

TEST(DepthMesh, AllBackgroundGivesEmptyMesh) {
  const ImpostorFraming f = cubeFraming();
  MeshedImpostorOptions options;
  options.textureSize = kSize;
  auto mesh = buildDepthMesh(std::vector<float>(kSize * kSize, 1.0f), f, options, nullptr);
  ASSERT_TRUE(mesh.ok());
  EXPECT_EQ(mesh->triangleCount(), 0u);
  EXPECT_EQ(mesh->vertexCount(), 0u);
}

}  // namespace
}  // namespace thinlod::simplifier
