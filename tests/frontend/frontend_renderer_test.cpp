// FrontendRenderer: each representation kind drawn to a known image, atomic
// batches, the per-frame upload bound, batching into few draw calls, texture
// layers (shrink, pad, pages) and errors. Runs on both back-ends.
#include "thinlod/frontend/frontend_renderer.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <limits>

#include "frontend_test_util.h"

namespace thinlod::frontend {
namespace {

using render::Backend;
using testing::addOp;
using testing::backendParamName;
using testing::flatLighting;
using testing::orthoCamera;
using testing::pixelNear;
using testing::quadMesh;
using testing::removeOp;
using testing::solidImage;

constexpr int kSize = 64;
constexpr int kBackground = 51;  // clear colour 0.2

glm::mat4 placeQuad(float cx, float cy, float sx, float sy, float z = 0.0f) {
  return glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(cx, cy, z)), glm::vec3(sx, sy, 1));
}

class FrontendRendererTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(GetParam(), kSize, kSize);
    ASSERT_TRUE(context.ok()) << context.status().toString();
    context_ = std::move(context).value();
    options_.width = kSize;
    options_.height = kSize;
    options_.layerSize = 16;
    options_.layersPerPage = 8;
    options_.linearFilter = false;  // pixel-exact texel checks
    options_.clearColor = glm::vec4(0.2f, 0.2f, 0.2f, 1.0f);
    options_.uploadBytesPerFrame = 1 << 20;
  }
  void TearDown() override {
    if (context_) (void)context_->makeCurrent();
    renderer_.reset();
    context_.reset();
  }

  void makeRenderer() {
    auto renderer = FrontendRenderer::create(*context_, options_);
    ASSERT_TRUE(renderer.ok()) << renderer.status().toString();
    renderer_ = std::move(renderer).value();
  }

  void submit(std::uint64_t plan, std::vector<SceneOperation> ops) {
    SceneBatch batch;
    batch.plan = plan;
    batch.operations = std::move(ops);
    Status status = renderer_->submit(std::move(batch));
    ASSERT_TRUE(status.ok()) << status.toString();
  }

  FrameReport frame(RgbaImage& image, const render::Lighting& lighting = flatLighting()) {
    auto report = renderer_->renderFrame(orthoCamera(), lighting, image);
    EXPECT_TRUE(report.ok()) << report.status().toString();
    return report.ok() ? *report : FrameReport{};
  }

  std::unique_ptr<render::OffscreenContext> context_;
  FrontendRendererOptions options_;
  std::unique_ptr<FrontendRenderer> renderer_;
};

TEST_P(FrontendRendererTest, EmptySceneIsTheClearColour) {
  makeRenderer();
  RgbaImage image;
  const FrameReport report = frame(image);
  ASSERT_EQ(image.width, kSize);
  ASSERT_EQ(image.height, kSize);
  EXPECT_TRUE(pixelNear(image, 0, 0, kBackground, kBackground, kBackground, 0));
  EXPECT_TRUE(pixelNear(image, 63, 63, kBackground, kBackground, kBackground, 0));
  EXPECT_EQ(report.drawCalls, 0u);
}

TEST_P(FrontendRendererTest, WarmUpLeavesNothingBehindAndRejectsBadLighting) {
  makeRenderer();
  render::Lighting tooMany;
  tooMany.lights.resize(render::kMaxLights + 1);
  EXPECT_EQ(renderer_->warmUp(tooMany).code(), ErrorCode::kInvalidArgument);
  ASSERT_TRUE(renderer_->warmUp(flatLighting()).ok());
  // The warm-up triangle is gone from the next frame, and nothing is held.
  RgbaImage image;
  const FrameReport report = frame(image);
  EXPECT_TRUE(pixelNear(image, kSize / 2, kSize / 2, kBackground, kBackground, kBackground, 0));
  EXPECT_EQ(report.drawCalls, 0u);
  EXPECT_EQ(report.triangles, 0u);
  EXPECT_EQ(renderer_->scene().objects().size(), 0u);
  // Without a current context it refuses.
  context_->releaseCurrent();
  EXPECT_EQ(renderer_->warmUp(flatLighting()).code(), ErrorCode::kUnavailable);
  ASSERT_TRUE(context_->makeCurrent().ok());
}

TEST_P(FrontendRendererTest, ColouredMeshIsDrawnLit) {
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kMesh, quadMesh(-1, -1, 0, 1, 0), nullptr,
                   glm::mat4(1.0f), glm::vec4(1.0f, 0.4f, 0.0f, 1.0f))});
  RgbaImage image;
  // Ambient 0.5 plus a head-on directional light of 0.5: exactly the base colour.
  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.5f);
  lighting.lights.push_back(
      {render::Light::Type::kDirectional, glm::vec3(0, 0, -1), glm::vec3(0.5f), 0.0f});
  const FrameReport report = frame(image, lighting);
  EXPECT_TRUE(pixelNear(image, 16, 32, 255, 102, 0, 1));
  EXPECT_TRUE(pixelNear(image, 48, 32, kBackground, kBackground, kBackground, 0));
  EXPECT_EQ(report.triangles, 2u);
  // Ambient only: the lighting really applies to meshes.
  lighting.lights.clear();
  frame(image, lighting);
  EXPECT_TRUE(pixelNear(image, 16, 32, 128, 51, 0, 1));
}

// 8x8: a transparent (yellow, alpha 0) border around a red/blue checker.
std::shared_ptr<const RgbaImage> checkerWithBorder() {
  auto image = std::make_shared<RgbaImage>(8, 8);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      std::uint8_t* p = image->at(x, y);
      const bool border = x == 0 || y == 0 || x == 7 || y == 7;
      const bool red = (x + y) % 2 == 0;
      p[0] = border || red ? 255 : 0;
      p[1] = border ? 255 : 0;
      p[2] = border || red ? 0 : 255;
      p[3] = border ? 0 : 255;
    }
  }
  return image;
}

TEST_P(FrontendRendererTest, SimpleImpostorShowsCheckerAndCutsItsTransparentBorder) {
  makeRenderer();
  // Unit quad scaled to fill the view: one texel = 8x8 pixels. A green mesh behind it.
  submit(1, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, checkerWithBorder(),
                   placeQuad(0, 0, 2, 2)),
             addOp(2, RepresentationKind::kMesh, quadMesh(-1, -1, 1, 1, -1), nullptr,
                   glm::mat4(1.0f), glm::vec4(0, 1, 0, 1))});
  RgbaImage image;
  frame(image);
  EXPECT_TRUE(pixelNear(image, 4, 4, 0, 255, 0, 0));    // border texel: see-through
  EXPECT_TRUE(pixelNear(image, 60, 36, 0, 255, 0, 0));  // right border
  EXPECT_TRUE(pixelNear(image, 12, 12, 255, 0, 0, 0));  // texel (1,1): red
  EXPECT_TRUE(pixelNear(image, 20, 12, 0, 0, 255, 0));  // texel (2,1): blue
  EXPECT_TRUE(pixelNear(image, 12, 52, 0, 0, 255, 0));  // texel (1,6): image row 6 at the bottom
  EXPECT_TRUE(pixelNear(image, 52, 52, 255, 0, 0, 0));  // texel (6,6)
}

TEST_P(FrontendRendererTest, MeshedImpostorIsTexturedAndDepthTested) {
  makeRenderer();
  // 3x3 depth mesh over [-1,1]^2 bulging to z = 0.5 in the middle.
  auto depthMesh = std::make_shared<IndexedMesh>();
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const float x = i - 1.0f, y = j - 1.0f;
      depthMesh->positions.push_back({x, y, i == 1 && j == 1 ? 0.5f : 0.0f});
      depthMesh->uvs.push_back({(x + 1) / 2, (y + 1) / 2});
    }
  }
  for (std::uint32_t j = 0; j < 2; ++j) {
    for (std::uint32_t i = 0; i < 2; ++i) {
      const std::uint32_t a = j * 3 + i;
      depthMesh->indices.insert(depthMesh->indices.end(), {a, a + 1, a + 4, a, a + 4, a + 3});
    }
  }
  auto texture = std::make_shared<RgbaImage>(4, 4);  // texel (c, r-from-top) = (60c, 60r, 200)
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::uint8_t* p = texture->at(c, r);
      p[0] = static_cast<std::uint8_t>(60 * c);
      p[1] = static_cast<std::uint8_t>(60 * r);
      p[2] = 200;
      p[3] = 255;
    }
  }
  // A white wall at z = 0.25 over the right half: in front of the mesh's rim,
  // behind its bulge.
  submit(1, {addOp(1, RepresentationKind::kMeshedImpostor, depthMesh, texture),
             addOp(2, RepresentationKind::kMesh, quadMesh(0, -1, 1, 1, 0.25f), nullptr)});
  RgbaImage image;
  frame(image);
  EXPECT_TRUE(pixelNear(image, 36, 36, 120, 120, 200, 0));  // bulge in front of the wall
  EXPECT_TRUE(pixelNear(image, 60, 4, 255, 255, 255, 0));   // wall in front of the rim
  EXPECT_TRUE(pixelNear(image, 4, 60, 0, 180, 200, 0));     // bottom-left texel (0, 3)
  EXPECT_TRUE(pixelNear(image, 4, 4, 0, 0, 200, 0));        // top-left texel (0, 0)
}

TEST_P(FrontendRendererTest, FirstRepresentationShowsAsSoonAsItsUploadCompletes) {
  options_.uploadBytesPerFrame = 16 * 16 * 4 + 4 * kGpuVertexBytes + 6 * kGpuIndexBytes;
  makeRenderer();
  submit(7, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 255, 0, 0),
                   placeQuad(-0.5f, 0, 1, 2)),
             addOp(2, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 0, 0, 255),
                   placeQuad(0.5f, 0, 1, 2))});
  RgbaImage image;
  FrameReport report = frame(image);
  // Object 1 is uploaded and new to the scene: drawn although its batch is not complete.
  EXPECT_EQ(report.uploadedObjects, 1u);
  EXPECT_EQ(report.committedBatches, 0u);
  EXPECT_EQ(report.pendingBatches, 1u);
  EXPECT_TRUE(pixelNear(image, 16, 32, 255, 0, 0, 0));
  EXPECT_TRUE(pixelNear(image, 48, 32, kBackground, kBackground, kBackground, 0));
  report = frame(image);
  EXPECT_EQ(report.committedBatches, 1u);
  EXPECT_EQ(report.appliedPlan, 7u);
  EXPECT_TRUE(pixelNear(image, 16, 32, 255, 0, 0, 0));
  EXPECT_TRUE(pixelNear(image, 48, 32, 0, 0, 255, 0));
}

TEST_P(FrontendRendererTest, UploadBoundHoldsAndOldRepresentationStaysMeanwhile) {
  const std::size_t oneImpostor = 16 * 16 * 4 + 4 * kGpuVertexBytes + 6 * kGpuIndexBytes;
  options_.uploadBytesPerFrame = oneImpostor + oneImpostor / 2;
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 255, 0, 0),
                   placeQuad(0, 0, 2, 2))});
  RgbaImage image;
  frame(image);
  ASSERT_TRUE(pixelNear(image, 32, 32, 255, 0, 0, 0));
  // Replace it and add three more: four uploads at one per frame.
  std::vector<SceneOperation> ops = {addOp(1, RepresentationKind::kSimpleImpostor, nullptr,
                                           solidImage(16, 16, 0, 0, 255), placeQuad(0, 0, 2, 2))};
  for (ObjectId id = 2; id <= 4; ++id) {
    ops.push_back(addOp(id, RepresentationKind::kSimpleImpostor, nullptr,
                        solidImage(16, 16, 0, 255, 0), placeQuad(0, 0, 0.1f, 0.1f, -1)));
  }
  submit(2, std::move(ops));
  for (int f = 0; f < 3; ++f) {
    const FrameReport report = frame(image);
    EXPECT_LE(report.uploadedBytes, options_.uploadBytesPerFrame);
    EXPECT_EQ(report.uploadedObjects, 1u);
    EXPECT_EQ(report.committedBatches, 0u);
    EXPECT_TRUE(pixelNear(image, 32, 32, 255, 0, 0, 0)) << "frame " << f;
  }
  const FrameReport report = frame(image);
  EXPECT_LE(report.uploadedBytes, options_.uploadBytesPerFrame);
  EXPECT_EQ(report.committedBatches, 1u);
  EXPECT_TRUE(pixelNear(image, 32, 32, 0, 0, 255, 0));
  EXPECT_EQ(renderer_->scene().polygons(), 8u);
}

TEST_P(FrontendRendererTest, RemovedObjectDisappears) {
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kMesh, quadMesh(-1, -1, 1, 1, 0), nullptr)});
  RgbaImage image;
  frame(image);
  ASSERT_TRUE(pixelNear(image, 32, 32, 255, 255, 255, 0));
  submit(2, {removeOp(1)});
  const FrameReport report = frame(image);
  EXPECT_TRUE(pixelNear(image, 32, 32, kBackground, kBackground, kBackground, 0));
  EXPECT_EQ(report.triangles, 0u);
  EXPECT_EQ(renderer_->scene().polygons(), 0u);
}

TEST_P(FrontendRendererTest, ManyObjectsDrawInTwoCalls) {
  options_.layersPerPage = 32;
  makeRenderer();
  std::vector<SceneOperation> ops;
  for (int i = 0; i < 20; ++i) {
    const float x = -0.9f + 0.09f * i;
    ops.push_back(addOp(100 + i, RepresentationKind::kSimpleImpostor, nullptr,
                        solidImage(16, 16, static_cast<std::uint8_t>(10 * i), 0, 0),
                        placeQuad(x, 0.5f, 0.08f, 0.08f)));
  }
  for (int i = 0; i < 5; ++i) {
    const float x = -0.9f + 0.3f * i;
    ops.push_back(addOp(200 + i, RepresentationKind::kMesh, quadMesh(x, -0.5f, x + 0.2f, -0.3f, 0),
                        i % 2 ? solidImage(4, 4, 0, 200, 0) : nullptr));
  }
  submit(1, std::move(ops));
  RgbaImage image;
  const FrameReport report = frame(image);
  EXPECT_EQ(report.drawCalls, 2u);
  EXPECT_EQ(report.textureBinds, 1u);
  EXPECT_EQ(report.triangles, 50u);
  EXPECT_EQ(renderer_->scene().polygons(), 50u);
}

TEST_P(FrontendRendererTest, TexturesSpillIntoMorePages) {
  options_.layersPerPage = 2;  // page 0 keeps one layer for white: 1 + 2 free layers
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 255, 0, 0),
                   placeQuad(-0.66f, 0, 0.5f, 2)),
             addOp(2, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 0, 255, 0),
                   placeQuad(0, 0, 0.5f, 2)),
             addOp(3, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 0, 0, 255),
                   placeQuad(0.66f, 0, 0.5f, 2))});
  RgbaImage image;
  const FrameReport report = frame(image);
  EXPECT_EQ(report.texturePages, 2u);
  EXPECT_EQ(report.drawCalls, 2u);
  EXPECT_TRUE(pixelNear(image, 11, 32, 255, 0, 0, 0));
  EXPECT_TRUE(pixelNear(image, 32, 32, 0, 255, 0, 0));
  EXPECT_TRUE(pixelNear(image, 53, 32, 0, 0, 255, 0));
}

TEST_P(FrontendRendererTest, LargeTextureIsShrunkIntoTheLayer) {
  makeRenderer();
  auto texture = std::make_shared<RgbaImage>(32, 32);  // quadrants: red, green / blue, white
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      std::uint8_t* p = texture->at(x, y);
      const bool right = x >= 16, bottom = y >= 16;
      p[0] = (!right && !bottom) || (right && bottom) ? 255 : 0;
      p[1] = (right && !bottom) || (right && bottom) ? 255 : 0;
      p[2] = bottom ? 255 : 0;
      p[3] = 255;
    }
  }
  submit(1,
         {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, texture, placeQuad(0, 0, 2, 2))});
  RgbaImage image;
  frame(image);
  EXPECT_TRUE(pixelNear(image, 16, 16, 255, 0, 0, 0));
  EXPECT_TRUE(pixelNear(image, 48, 16, 0, 255, 0, 0));
  EXPECT_TRUE(pixelNear(image, 16, 48, 0, 0, 255, 0));
  EXPECT_TRUE(pixelNear(image, 48, 48, 255, 255, 255, 0));
}

TEST_P(FrontendRendererTest, SmallTextureInAReusedLayerDoesNotBleed) {
  options_.linearFilter = true;
  options_.layersPerPage = 2;  // exactly one layer to reuse
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr, solidImage(16, 16, 255, 0, 255),
                   placeQuad(0, 0, 2, 2))});
  RgbaImage image;
  frame(image);
  ASSERT_TRUE(pixelNear(image, 32, 32, 255, 0, 255, 0));
  submit(2, {removeOp(1)});
  frame(image);
  submit(3, {addOp(2, RepresentationKind::kSimpleImpostor, nullptr, solidImage(4, 4, 0, 255, 0),
                   placeQuad(0, 0, 2, 2))});
  const FrameReport report = frame(image);
  EXPECT_EQ(report.texturePages, 1u);  // the magenta layer was reused
  // Edge pixels filter across the texture's right/top edge into the padding.
  EXPECT_TRUE(pixelNear(image, 63, 32, 0, 255, 0, 0));
  EXPECT_TRUE(pixelNear(image, 32, 0, 0, 255, 0, 0));
  EXPECT_TRUE(pixelNear(image, 63, 0, 0, 255, 0, 0));
}

TEST_P(FrontendRendererTest, BlendedImpostorsMixWithWhatIsBehind) {
  options_.impostorAlpha = render::AlphaMode::kBlend;
  makeRenderer();
  submit(1, {addOp(1, RepresentationKind::kSimpleImpostor, nullptr,
                   solidImage(16, 16, 255, 0, 0, 128), placeQuad(0, 0, 2, 2)),
             addOp(2, RepresentationKind::kMesh, quadMesh(-1, -1, 1, 1, -1), nullptr,
                   glm::mat4(1.0f), glm::vec4(0, 1, 0, 1))});
  RgbaImage image;
  frame(image);
  EXPECT_TRUE(pixelNear(image, 32, 32, 128, 127, 0, 2));
}

TEST_P(FrontendRendererTest, RejectsBadCameraAndLighting) {
  makeRenderer();
  RgbaImage image;
  render::Camera camera = orthoCamera();
  camera.view[0][0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(renderer_->renderFrame(camera, flatLighting(), image).status().code(),
            ErrorCode::kInvalidArgument);
  render::Lighting lighting;
  lighting.lights.resize(render::kMaxLights + 1);
  EXPECT_EQ(renderer_->renderFrame(orthoCamera(), lighting, image).status().code(),
            ErrorCode::kInvalidArgument);
}

TEST_P(FrontendRendererTest, RejectsInvalidBatches) {
  makeRenderer();
  SceneBatch batch;
  batch.operations.push_back(addOp(1, RepresentationKind::kSimpleImpostor, nullptr, nullptr));
  EXPECT_EQ(renderer_->submit(batch).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(renderer_->scene().pendingBatches(), 0u);
}

TEST_P(FrontendRendererTest, RejectsBadOptions) {
  FrontendRendererOptions bad = options_;
  bad.width = 0;
  EXPECT_EQ(FrontendRenderer::create(*context_, bad).status().code(), ErrorCode::kInvalidArgument);
  bad = options_;
  bad.layerSize = 1;
  EXPECT_EQ(FrontendRenderer::create(*context_, bad).status().code(), ErrorCode::kInvalidArgument);
  bad = options_;
  bad.uploadBytesPerFrame = 0;
  EXPECT_EQ(FrontendRenderer::create(*context_, bad).status().code(), ErrorCode::kInvalidArgument);
  bad = options_;
  bad.alphaCutoff = std::numeric_limits<float>::infinity();
  EXPECT_EQ(FrontendRenderer::create(*context_, bad).status().code(), ErrorCode::kInvalidArgument);
}

INSTANTIATE_TEST_SUITE_P(Backends, FrontendRendererTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

}  // namespace
}  // namespace thinlod::frontend
