// ReferenceRenderer: agrees with the frontend for the same geometry, caches
// uploads by identity, draws textures, rejects bad objects.
#include "thinlod/frontend/reference_renderer.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>

#include "frontend_test_util.h"
#include "thinlod/frontend/frame_metrics.h"
#include "thinlod/frontend/frontend_renderer.h"

namespace thinlod::frontend {
namespace {

using render::Backend;
using testing::addOp;
using testing::backendParamName;
using testing::orthoCamera;
using testing::pixelNear;
using testing::quadMesh;
using testing::solidImage;
using testing::sphereMesh;

constexpr int kSize = 96;

render::Lighting sunAndAmbient() {
  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.25f);
  lighting.lights.push_back({render::Light::Type::kDirectional,
                             glm::normalize(glm::vec3(-1, -2, -3)), glm::vec3(0.9f), 0.0f});
  return lighting;
}

class ReferenceRendererTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(GetParam(), kSize, kSize);
    ASSERT_TRUE(context.ok()) << context.status().toString();
    context_ = std::move(context).value();
    ReferenceRendererOptions options;
    options.width = kSize;
    options.height = kSize;
    auto reference = ReferenceRenderer::create(*context_, options);
    ASSERT_TRUE(reference.ok()) << reference.status().toString();
    reference_ = std::move(reference).value();
  }
  void TearDown() override {
    if (context_) (void)context_->makeCurrent();
    reference_.reset();
    context_.reset();
  }

  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<ReferenceRenderer> reference_;
};

TEST_P(ReferenceRendererTest, AgreesWithTheFrontendForTheSameMesh) {
  const auto sphere = sphereMesh(0.6f, 24, 16);
  const glm::mat4 transform =
      glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0.1f, -0.1f, 0.0f)), 0.7f,
                  glm::vec3(1, 1, 0)) *
      glm::scale(glm::mat4(1.0f), glm::vec3(1.2f, 0.8f, 1.0f));
  const glm::vec4 colour(0.8f, 0.2f, 0.4f, 1.0f);

  ReferenceObject object;
  object.mesh = sphere;
  object.material.diffuse = colour;
  object.transform = transform;
  RgbaImage reference;
  auto report = reference_->render({object}, orthoCamera(), sunAndAmbient(), reference);
  ASSERT_TRUE(report.ok()) << report.status().toString();
  EXPECT_EQ(report->triangles, sphere->triangleCount());

  FrontendRendererOptions options;
  options.width = kSize;
  options.height = kSize;
  options.layersPerPage = 2;
  auto frontend = FrontendRenderer::create(*context_, options);
  ASSERT_TRUE(frontend.ok()) << frontend.status().toString();
  SceneBatch batch;
  batch.operations.push_back(
      addOp(1, RepresentationKind::kMesh, sphere, nullptr, transform, colour));
  ASSERT_TRUE((*frontend)->submit(batch).ok());
  RgbaImage frame;
  ASSERT_TRUE((*frontend)->renderFrame(orthoCamera(), sunAndAmbient(), frame).ok());

  int maxDifference = 0;
  for (std::size_t i = 0; i < frame.pixels.size(); ++i) {
    maxDifference = std::max(maxDifference, std::abs(frame.pixels[i] - reference.pixels[i]));
  }
  EXPECT_LE(maxDifference, 2);  // colour quantised to a byte per vertex; otherwise the same
  auto comparison = compareFrames(frame, reference);
  ASSERT_TRUE(comparison.ok());
  EXPECT_GT(comparison->psnrDb, 50.0);
  EXPECT_GT(comparison->variance, 100.0);  // the sphere really is in the frame
}

TEST_P(ReferenceRendererTest, CachesMeshesWhileTheCallerHoldsThem) {
  ReferenceObject object;
  object.mesh = quadMesh(-0.5f, -0.5f, 0.5f, 0.5f, 0);
  RgbaImage frame;
  auto first = reference_->render({object, object}, orthoCamera(), {}, frame);
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(first->cachedMeshes, 1u);
  EXPECT_EQ(first->drawCalls, 2u);
  object.mesh = quadMesh(-0.2f, -0.2f, 0.2f, 0.2f, 0);  // the first mesh is released here
  auto second = reference_->render({object}, orthoCamera(), testing::flatLighting(), frame);
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(second->cachedMeshes, 1u);
  // The smaller quad is what is drawn (not a stale cache entry): diffuse 0.8 at ambient 1.
  EXPECT_TRUE(pixelNear(frame, 48, 48, 204, 204, 204, 2));
  EXPECT_TRUE(pixelNear(frame, 20, 20, 0, 0, 0, 0));
}

TEST_P(ReferenceRendererTest, DrawsObjectTextures) {
  ReferenceObject object;
  object.mesh = quadMesh(-1, -1, 1, 1, 0);
  object.material.lit = false;
  object.material.diffuse = glm::vec4(1.0f);
  object.texture = solidImage(4, 4, 30, 60, 90);
  RgbaImage frame;
  ASSERT_TRUE(reference_->render({object}, orthoCamera(), {}, frame).ok());
  EXPECT_TRUE(pixelNear(frame, 48, 48, 30, 60, 90, 0));
}

TEST_P(ReferenceRendererTest, RejectsBadObjectsNamingThem) {
  RgbaImage frame;
  ReferenceObject good;
  good.mesh = quadMesh(-1, -1, 1, 1, 0);
  ReferenceObject noMesh;
  auto status = reference_->render({good, noMesh}, orthoCamera(), {}, frame).status();
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(status.message().find("reference object 1"), std::string::npos);

  ReferenceObject handle = good;
  handle.material.texture.id = 5;
  EXPECT_EQ(reference_->render({handle}, orthoCamera(), {}, frame).status().code(),
            ErrorCode::kInvalidArgument);

  auto nan = std::make_shared<IndexedMesh>(*quadMesh(-1, -1, 1, 1, 0));
  nan->positions[0].x = std::numeric_limits<float>::quiet_NaN();
  ReferenceObject broken;
  broken.mesh = nan;
  EXPECT_EQ(reference_->render({broken}, orthoCamera(), {}, frame).status().code(),
            ErrorCode::kInvalidArgument);
}

INSTANTIATE_TEST_SUITE_P(Backends, ReferenceRendererTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

}  // namespace
}  // namespace thinlod::frontend
