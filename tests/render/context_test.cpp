// OffscreenContext: back-end creation, selection, errors and thread rules.
#include <thread>

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

class ContextTest : public ::testing::TestWithParam<Backend> {};

TEST_P(ContextTest, CreatesCurrentGl33Context) {
  auto context = createOffscreenContext(GetParam(), 32, 16);
  ASSERT_TRUE(context.ok()) << context.status().toString();
  EXPECT_EQ((*context)->backend(), GetParam());
  EXPECT_TRUE((*context)->isCurrent());
  EXPECT_EQ((*context)->width(), 32);
  EXPECT_EQ((*context)->height(), 16);
  EXPECT_FALSE((*context)->rendererName().empty());
  EXPECT_FALSE((*context)->versionString().empty());
  EXPECT_GE((*context)->maxRenderTargetSize(), 2048);
}

TEST_P(ContextTest, ReleaseAndMakeCurrentRoundTrip) {
  auto context = createOffscreenContext(GetParam(), 8, 8);
  ASSERT_TRUE(context.ok()) << context.status().toString();
  (*context)->releaseCurrent();
  EXPECT_FALSE((*context)->isCurrent());
  ASSERT_TRUE((*context)->makeCurrent().ok());
  EXPECT_TRUE((*context)->isCurrent());
}

TEST_P(ContextTest, ZeroSizeIsInvalidArgument) {
  auto context = createOffscreenContext(GetParam(), 0, 0);
  ASSERT_FALSE(context.ok());
  EXPECT_EQ(context.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(context.status().message().find("0x0"), std::string::npos)
      << context.status().message();
}

TEST_P(ContextTest, AbsurdSizeIsInvalidArgument) {
  auto context = createOffscreenContext(GetParam(), 100000, 100000);
  ASSERT_FALSE(context.ok());
  EXPECT_EQ(context.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(context.status().message().find("100000x100000"), std::string::npos);
}

TEST_P(ContextTest, UsableFromAnotherThreadAfterRelease) {
  GlRig rig;
  ASSERT_TRUE(makeRig(GetParam(), 16, 16, rig));
  auto quad = rig.renderer->uploadMesh(makeQuad(-1, -1, 1, 1, 0));
  ASSERT_TRUE(quad.ok()) << quad.status().toString();
  rig.context->releaseCurrent();

  Status workerStatus;
  RgbaImage image;
  std::thread worker([&] {
    workerStatus = rig.context->makeCurrent();
    if (!workerStatus.ok()) return;
    workerStatus = rig.renderer->beginFrame(*rig.target, glm::vec4(0.0f));
    DrawItem item{*quad, glm::mat4(1.0f), unlitColor(0, 0, 1)};
    if (workerStatus.ok()) workerStatus = rig.renderer->draw(&item, 1, orthoCamera(), {});
    if (workerStatus.ok()) workerStatus = rig.target->readColor(image);
    rig.context->releaseCurrent();
  });
  worker.join();
  ASSERT_TRUE(workerStatus.ok()) << workerStatus.toString();
  EXPECT_TRUE(pixelNear(image, 8, 8, 0, 0, 255, 255, 1));
  ASSERT_TRUE(rig.context->makeCurrent().ok());
}

TEST_P(ContextTest, CallsWithoutCurrentContextAreRejected) {
  GlRig rig;
  ASSERT_TRUE(makeRig(GetParam(), 16, 16, rig));
  rig.context->releaseCurrent();
  Status status = rig.renderer->beginFrame(*rig.target, glm::vec4(0.0f));
  EXPECT_EQ(status.code(), ErrorCode::kUnavailable);
  EXPECT_EQ(rig.target->clear(0, 0, 0, 0).code(), ErrorCode::kUnavailable);
  EXPECT_EQ(rig.renderer->uploadMesh(makeQuad(0, 0, 1, 1, 0)).status().code(),
            ErrorCode::kUnavailable);
}

INSTANTIATE_TEST_SUITE_P(Backends, ContextTest, ::testing::Values(Backend::kEgl, Backend::kOsMesa),
                         backendParamName);

TEST(ContextSelection, AutoPicksAWorkingBackend) {
  auto context = createOffscreenContext(Backend::kAuto, 8, 8);
  ASSERT_TRUE(context.ok()) << context.status().toString();
  // Auto tries EGL first; both work on this machine, so EGL wins.
  EXPECT_EQ((*context)->backend(), Backend::kEgl);
}

TEST(ContextSelection, AutoWithImpossibleSizeNamesTheSize) {
  auto context = createOffscreenContext(Backend::kAuto, -5, 10);
  ASSERT_FALSE(context.ok());
  EXPECT_EQ(context.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(context.status().message().find("-5x10"), std::string::npos);
}

TEST(ContextSelection, BackendNames) {
  EXPECT_STREQ(backendName(Backend::kAuto), "auto");
  EXPECT_STREQ(backendName(Backend::kEgl), "egl");
  EXPECT_STREQ(backendName(Backend::kOsMesa), "osmesa");
}

// libOSMesa and libGL both export gl*; each context must use its own table.
TEST(ContextSelection, EglAndOsMesaCoexistInOneProcess) {
  GlRig egl;
  ASSERT_TRUE(makeRig(Backend::kEgl, 16, 16, egl));
  auto eglQuad = egl.renderer->uploadMesh(makeQuad(-1, -1, 1, 1, 0));
  ASSERT_TRUE(eglQuad.ok());
  egl.context->releaseCurrent();

  GlRig osmesa;
  ASSERT_TRUE(makeRig(Backend::kOsMesa, 16, 16, osmesa));
  auto osQuad = osmesa.renderer->uploadMesh(makeQuad(-1, -1, 1, 1, 0));
  ASSERT_TRUE(osQuad.ok());
  ASSERT_TRUE(osmesa.renderer->beginFrame(*osmesa.target, glm::vec4(0.0f)).ok());
  DrawItem green{*osQuad, glm::mat4(1.0f), unlitColor(0, 1, 0)};
  ASSERT_TRUE(osmesa.renderer->draw(&green, 1, orthoCamera(), {}).ok());
  RgbaImage osImage;
  ASSERT_TRUE(osmesa.target->readColor(osImage).ok());
  osmesa.context->releaseCurrent();

  ASSERT_TRUE(egl.context->makeCurrent().ok());
  ASSERT_TRUE(egl.renderer->beginFrame(*egl.target, glm::vec4(0.0f)).ok());
  DrawItem red{*eglQuad, glm::mat4(1.0f), unlitColor(1, 0, 0)};
  ASSERT_TRUE(egl.renderer->draw(&red, 1, orthoCamera(), {}).ok());
  RgbaImage eglImage;
  ASSERT_TRUE(egl.target->readColor(eglImage).ok());

  EXPECT_TRUE(pixelNear(osImage, 8, 8, 0, 255, 0, 255, 1));
  EXPECT_TRUE(pixelNear(eglImage, 8, 8, 255, 0, 0, 255, 1));
  egl.context->releaseCurrent();
}

}  // namespace
}  // namespace thinlod::render
