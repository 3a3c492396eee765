// RenderTarget: FBO creation, colour/depth readback, orientation, errors.
#include <cmath>
#include <vector>

#include "render_test_util.h"

namespace thinlod::render {
namespace {

using testing::backendParamName;
using testing::GlRig;
using testing::makeQuad;
using testing::makeRig;
using testing::orthoCamera;
using testing::pixelNear;
using testing::unlitColor;

class RenderTargetTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override { ASSERT_TRUE(makeRig(GetParam(), kSize, kSize, rig_)); }

  Result<MeshHandle> upload(const IndexedMesh& mesh) { return rig_.renderer->uploadMesh(mesh); }

  static constexpr int kSize = 64;
  GlRig rig_;
};

TEST_P(RenderTargetTest, ClearedTargetIsTransparentBlack) {
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  RgbaImage image;
  ASSERT_TRUE(rig_.target->readColor(image).ok());
  ASSERT_EQ(image.width, kSize);
  ASSERT_EQ(image.height, kSize);
  for (std::uint8_t value : image.pixels) ASSERT_EQ(value, 0);
}

TEST_P(RenderTargetTest, ClearColourIsConfigurable) {
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.2f, 0.4f, 0.6f, 0.8f)).ok());
  RgbaImage image;
  ASSERT_TRUE(rig_.target->readColor(image).ok());
  EXPECT_TRUE(pixelNear(image, 0, 0, 51, 102, 153, 204, 1));
  EXPECT_TRUE(pixelNear(image, kSize - 1, kSize - 1, 51, 102, 153, 204, 1));
}

// Triangle (-1,-1), (1,-1), (-1,1): covers the pixels below the anti-diagonal,
// i.e. pixel (x, y-from-top) with x + (kSize - 1 - y) < kSize - 1.
TEST_P(RenderTargetTest, RedTriangleCoversKnownRegion) {
  IndexedMesh triangle;
  triangle.positions = {{-1, -1, 0}, {1, -1, 0}, {-1, 1, 0}};
  triangle.indices = {0, 1, 2};
  auto mesh = upload(triangle);
  ASSERT_TRUE(mesh.ok()) << mesh.status().toString();
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  DrawItem item{*mesh, glm::mat4(1.0f), unlitColor(1, 0, 0)};
  ASSERT_TRUE(rig_.renderer->draw(&item, 1, orthoCamera(), {}).ok());
  RgbaImage image;
  ASSERT_TRUE(rig_.target->readColor(image).ok());
  int covered = 0;
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const int fromBottom = kSize - 1 - y;
      const int diagonal = x + fromBottom - (kSize - 1);  // < 0 inside, > 0 outside
      if (image.at(x, y)[3] != 0) ++covered;
      if (diagonal <= -2) {
        ASSERT_TRUE(pixelNear(image, x, y, 255, 0, 0, 255, 1));
      } else if (diagonal >= 2) {
        ASSERT_TRUE(pixelNear(image, x, y, 0, 0, 0, 0, 0));
      }
    }
  }
  const int expected = kSize * kSize / 2;
  EXPECT_NEAR(covered, expected, kSize) << "coverage off by more than one diagonal";
}

TEST_P(RenderTargetTest, ReadbackRowsAreTopDown) {
  auto top = upload(makeQuad(-1, 0, 1, 1, 0));  // world y > 0 is the top of the picture
  ASSERT_TRUE(top.ok());
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  DrawItem item{*top, glm::mat4(1.0f), unlitColor(0, 1, 0)};
  ASSERT_TRUE(rig_.renderer->draw(&item, 1, orthoCamera(), {}).ok());
  RgbaImage image;
  ASSERT_TRUE(rig_.target->readColor(image).ok());
  for (int x = 0; x < kSize; x += 7) {
    EXPECT_TRUE(pixelNear(image, x, 0, 0, 255, 0, 255, 1));
    EXPECT_TRUE(pixelNear(image, x, kSize / 2 - 1, 0, 255, 0, 255, 1));
    EXPECT_TRUE(pixelNear(image, x, kSize / 2, 0, 0, 0, 0, 0));
    EXPECT_TRUE(pixelNear(image, x, kSize - 1, 0, 0, 0, 0, 0));
  }
}

TEST_P(RenderTargetTest, DepthReadbackMatchesGeometryAndUnprojects) {
  // Quad at world z = 1 covering the left half; camera at z = 5, near 1, far 9.
  auto quad = upload(makeQuad(-1, -1, 0, 1, 1.0f));
  ASSERT_TRUE(quad.ok());
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  DrawItem item{*quad, glm::mat4(1.0f), unlitColor(1, 1, 1)};
  const Camera camera = orthoCamera();
  ASSERT_TRUE(rig_.renderer->draw(&item, 1, camera, {}).ok());
  std::vector<float> depth;
  ASSERT_TRUE(rig_.target->readDepth(depth).ok());
  ASSERT_EQ(depth.size(), static_cast<std::size_t>(kSize * kSize));
  const float expected = (4.0f - 1.0f) / (9.0f - 1.0f);  // orthographic: linear in eye distance
  const int row = 10;
  EXPECT_NEAR(depth[row * kSize + 5], expected, 1e-5f);
  EXPECT_EQ(depth[row * kSize + kSize - 5], 1.0f);  // background keeps the cleared depth
  const glm::vec3 world =
      unprojectPixel(camera, 5.5f, row + 0.5f, depth[row * kSize + 5], kSize, kSize);
  EXPECT_NEAR(world.z, 1.0f, 1e-3f);
  EXPECT_NEAR(world.x, -1.0f + 2.0f * 5.5f / kSize, 1e-4f);
  EXPECT_NEAR(world.y, 1.0f - 2.0f * (row + 0.5f) / kSize, 1e-4f);
}

TEST_P(RenderTargetTest, CallerBufferOverloadsCheckSize) {
  std::vector<std::uint8_t> small(kSize * kSize * 4 - 1);
  Status status = rig_.target->readColor(small.data(), small.size());
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  std::vector<float> depth(10);
  EXPECT_EQ(rig_.target->readDepth(depth.data(), depth.size()).code(), ErrorCode::kInvalidArgument);
  std::vector<std::uint8_t> exact(kSize * kSize * 4);
  EXPECT_TRUE(rig_.target->readColor(exact.data(), exact.size()).ok());
}

TEST_P(RenderTargetTest, ZeroSizeTargetIsInvalidArgument) {
  auto target = RenderTarget::create(*rig_.context, 0, 16);
  ASSERT_FALSE(target.ok());
  EXPECT_EQ(target.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(target.status().message().find("0x16"), std::string::npos);
}

TEST_P(RenderTargetTest, OversizedTargetIsInvalidArgument) {
  const int tooBig = rig_.context->maxRenderTargetSize() + 1;
  auto target = RenderTarget::create(*rig_.context, tooBig, 4);
  ASSERT_FALSE(target.ok());
  EXPECT_EQ(target.status().code(), ErrorCode::kInvalidArgument);
}

TEST_P(RenderTargetTest, TargetLargerThanContextSurfaceWorks) {
  auto target = RenderTarget::create(*rig_.context, 300, 200);
  ASSERT_TRUE(target.ok()) << target.status().toString();
  auto quad = upload(makeQuad(-1, -1, 1, 1, 0));
  ASSERT_TRUE(quad.ok());
  ASSERT_TRUE(rig_.renderer->beginFrame(**target, glm::vec4(0.0f)).ok());
  DrawItem item{*quad, glm::mat4(1.0f), unlitColor(0, 0, 1)};
  ASSERT_TRUE(rig_.renderer->draw(&item, 1, orthoCamera(), {}).ok());
  RgbaImage image;
  ASSERT_TRUE((*target)->readColor(image).ok());
  ASSERT_EQ(image.width, 300);
  ASSERT_EQ(image.height, 200);
  EXPECT_TRUE(pixelNear(image, 299, 199, 0, 0, 255, 255, 1));
  EXPECT_TRUE(pixelNear(image, 0, 0, 0, 0, 255, 255, 1));
}

INSTANTIATE_TEST_SUITE_P(Backends, RenderTargetTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

}  // namespace
}  // namespace thinlod::render
