// SNR/PSNR on real rendered frames: a coarse frontend scene (low-poly sphere
// and an impostor) against the full-quality reference, cross-checked with
// OpenImageIO; blank and identical rendered frames behave as documented.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>

#include "frontend_test_util.h"
#include "thinlod/frontend/frame_metrics.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/frontend/reference_renderer.h"
#include "thinlod/frontend/view_camera.h"

namespace thinlod::frontend {
namespace {

using testing::addOp;
using testing::sphereMesh;

constexpr int kWidth = 160;
constexpr int kHeight = 120;

class FrameMetricsGlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(render::Backend::kAuto, kWidth, kHeight);
    ASSERT_TRUE(context.ok()) << context.status().toString();
    context_ = std::move(context).value();
    FrontendRendererOptions frontendOptions;
    frontendOptions.width = kWidth;
    frontendOptions.height = kHeight;
    frontendOptions.layersPerPage = 4;
    auto frontend = FrontendRenderer::create(*context_, frontendOptions);
    ASSERT_TRUE(frontend.ok()) << frontend.status().toString();
    frontend_ = std::move(frontend).value();
    ReferenceRendererOptions referenceOptions;
    referenceOptions.width = kWidth;
    referenceOptions.height = kHeight;
    auto reference = ReferenceRenderer::create(*context_, referenceOptions);
    ASSERT_TRUE(reference.ok()) << reference.status().toString();
    reference_ = std::move(reference).value();
    auto camera =
        cameraFromPose(glm::vec3(0, 0.5f, 4), glm::quat(1, 0, 0, 0), 0.9f, kWidth, kHeight);
    ASSERT_TRUE(camera.ok());
    camera_ = *camera;
    lighting_.ambient = glm::vec3(0.2f);
    lighting_.lights.push_back({render::Light::Type::kDirectional,
                                glm::normalize(glm::vec3(-1, -1, -2)), glm::vec3(0.9f), 0.0f});
  }
  void TearDown() override {
    if (context_) (void)context_->makeCurrent();
    frontend_.reset();
    reference_.reset();
    context_.reset();
  }

  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<FrontendRenderer> frontend_;
  std::unique_ptr<ReferenceRenderer> reference_;
  render::Camera camera_;
  render::Lighting lighting_;
};

OIIO::ImageBuf toImageBuf(const RgbaImage& image) {
  OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::UINT8);
  OIIO::ImageBuf buffer(spec);
  buffer.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, image.pixels.data());
  return buffer;
}

TEST_F(FrameMetricsGlTest, CoarseFrameAgreesWithOpenImageIo) {
  const auto fine = sphereMesh(0.8f, 64, 48);
  const auto coarse = sphereMesh(0.8f, 6, 4);
  const glm::mat4 left = glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f, 0.5f, 0));
  const glm::mat4 right = glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.5f, 0));
  const glm::vec4 colour(0.9f, 0.6f, 0.2f, 1.0f);
  std::vector<ReferenceObject> full(2);
  full[0].mesh = fine;
  full[0].transform = left;
  full[0].material.diffuse = colour;
  full[1] = full[0];
  full[1].transform = right;
  RgbaImage reference;
  ASSERT_TRUE(reference_->render(full, camera_, lighting_, reference).ok());

  // Frontend: a coarse mesh on the left, a flat orange disc impostor on the right.
  auto disc = std::make_shared<RgbaImage>(32, 32);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      std::uint8_t* p = disc->at(x, y);
      const float dx = x + 0.5f - 16, dy = y + 0.5f - 16;
      const bool inside = dx * dx + dy * dy < 15.0f * 15.0f;
      p[0] = 200;
      p[1] = 130;
      p[2] = 45;
      p[3] = inside ? 255 : 0;
    }
  }
  SceneBatch batch;
  batch.operations.push_back(addOp(1, RepresentationKind::kMesh, coarse, nullptr, left, colour));
  batch.operations.push_back(addOp(2, RepresentationKind::kSimpleImpostor, nullptr, disc,
                                   glm::scale(right, glm::vec3(1.6f, 1.6f, 1.0f))));
  ASSERT_TRUE(frontend_->submit(batch).ok());
  RgbaImage frame;
  ASSERT_TRUE(frontend_->renderFrame(camera_, lighting_, frame).ok());

  auto ours = compareFrames(frame, reference);
  ASSERT_TRUE(ours.ok());
  EXPECT_GT(ours->mse, 0.0);
  EXPECT_TRUE(std::isfinite(ours->snrDb));

  OIIO::ROI rgb = OIIO::get_roi(toImageBuf(frame).spec());
  rgb.chbegin = 0;
  rgb.chend = 3;
  const auto oiio =
      OIIO::ImageBufAlgo::compare(toImageBuf(frame), toImageBuf(reference), 1.0f, 1.0f, rgb);
  ASSERT_FALSE(oiio.error);
  EXPECT_NEAR(ours->mse, oiio.rms_error * oiio.rms_error * 255.0 * 255.0, 1e-5 * ours->mse);
  EXPECT_NEAR(ours->psnrDb, oiio.PSNR, 1e-4);
  // Mean absolute error over the same bytes, for the record.
  double absSum = 0.0;
  for (std::size_t i = 0; i < frame.pixels.size(); ++i) {
    if (i % 4 != 3) absSum += std::abs(frame.pixels[i] - reference.pixels[i]);
  }
  EXPECT_NEAR(absSum / ours->samples / 255.0, oiio.meanerror, 1e-6);
}

TEST_F(FrameMetricsGlTest, BlankRenderedFramesAreZeroDecibels) {
  RgbaImage frame, reference;
  ASSERT_TRUE(frontend_->renderFrame(camera_, lighting_, frame).ok());
  ASSERT_TRUE(reference_->render({}, camera_, lighting_, reference).ok());
  auto comparison = compareFrames(frame, reference);
  ASSERT_TRUE(comparison.ok());
  EXPECT_EQ(comparison->snrDb, 0.0);
  EXPECT_EQ(comparison->psnrDb, std::numeric_limits<double>::infinity());
}

TEST_F(FrameMetricsGlTest, IdenticalRenderedFramesAreInfinite) {
  SceneBatch batch;
  batch.operations.push_back(addOp(1, RepresentationKind::kMesh, sphereMesh(0.8f, 16, 12), nullptr,
                                   glm::mat4(1.0f), glm::vec4(0.3f, 0.7f, 0.5f, 1.0f)));
  ASSERT_TRUE(frontend_->submit(batch).ok());
  RgbaImage first, second;
  ASSERT_TRUE(frontend_->renderFrame(camera_, lighting_, first).ok());
  ASSERT_TRUE(frontend_->renderFrame(camera_, lighting_, second).ok());
  auto comparison = compareFrames(second, first);
  ASSERT_TRUE(comparison.ok());
  EXPECT_EQ(comparison->snrDb, std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace thinlod::frontend
