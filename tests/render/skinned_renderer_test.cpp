// MeshRenderer's skinned meshes (docs/animation.md, "Served"): the vertex
// shader's two-bone skinning draws the generated articulated figure as
// anim::deform (the CPU reference) does, at several poses of its clip, on
// both back-ends; and the bone inputs are checked before anything is drawn.
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <vector>

#include "articulated_figure.h"
#include "render_test_util.h"
#include "thinlod/common/core/skinning.h"

namespace thinlod::render {
namespace {

using testing::backendParamName;
using testing::GlRig;
using testing::makeRig;
using testing::orthoCamera;
using testing::unlitColor;

class SkinnedRendererTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    ASSERT_TRUE(makeRig(GetParam(), kSize, kSize, rig_));
    anim::testing::FigureShape shape;
    shape.ringsPerUnit = 8;
    shape.around = 12;
    figure_ = anim::testing::makeArticulatedFigure(shape);
  }

  std::vector<glm::mat4> bonesAt(double t) const {
    return anim::skinningMatrices(figure_.skeleton, anim::samplePose(figure_.skeleton, figure_.clip,
                                                                     t, anim::ClipWrap::kLoop));
  }

  RgbaImage render(const DrawItem& item) {
    RgbaImage image;
    Status status = rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f));
    if (status.ok()) status = rig_.renderer->draw(&item, 1, orthoCamera(), Lighting());
    if (status.ok()) status = rig_.target->readColor(image);
    EXPECT_TRUE(status.ok()) << status.toString();
    return image;
  }

  // Pixels whose red channel differs by more than 8, and lit pixels of `a`.
  static std::pair<int, int> compare(const RgbaImage& a, const RgbaImage& b) {
    int differ = 0, lit = 0;
    for (int y = 0; y < a.height; ++y) {
      for (int x = 0; x < a.width; ++x) {
        const int pa = a.at(x, y)[0], pb = b.at(x, y)[0];
        differ += std::abs(pa - pb) > 8 ? 1 : 0;
        lit += pa > 128 ? 1 : 0;
      }
    }
    return {differ, lit};
  }

  // The figure (x from 0 to 3) into the view's [-1, 1] square.
  const glm::mat4 model_ = glm::translate(glm::mat4(1.0f), glm::vec3(-0.6f, -0.1f, 0.0f)) *
                           glm::scale(glm::mat4(1.0f), glm::vec3(0.4f));
  static constexpr int kSize = 128;
  GlRig rig_;
  anim::testing::ArticulatedFigure figure_;
};

TEST_P(SkinnedRendererTest, VertexShaderSkinsAsDeformDoes) {
  auto skinned = rig_.renderer->uploadSkinnedMesh(figure_.mesh, figure_.skin);
  ASSERT_TRUE(skinned.ok()) << skinned.status().toString();
  EXPECT_EQ(rig_.renderer->bonesNeeded(*skinned), figure_.skeleton.bones.size());
  const RgbaImage rest = [&] {
    auto restMesh = rig_.renderer->uploadMesh(figure_.mesh);
    EXPECT_TRUE(restMesh.ok());
    return render({*restMesh, model_, unlitColor(1, 1, 1)});
  }();
  for (const double t : {0.3, 0.9, 1.6}) {
    const std::vector<glm::mat4> bones = bonesAt(t);
    DrawItem gpu{*skinned, model_, unlitColor(1, 1, 1)};
    gpu.bones = &bones;
    const RgbaImage onGpu = render(gpu);

    IndexedMesh deformed = figure_.mesh;
    anim::deform(figure_.mesh.positions, figure_.skin, bones, {}, deformed.positions);
    auto reference = rig_.renderer->uploadMesh(deformed);
    ASSERT_TRUE(reference.ok());
    const RgbaImage onCpu = render({*reference, model_, unlitColor(1, 1, 1)});
    rig_.renderer->deleteMesh(*reference);

    const auto [differ, lit] = compare(onGpu, onCpu);
    EXPECT_GT(lit, kSize * kSize / 50) << "t=" << t << ": the figure covers too little";
    // Float rounding may move a silhouette pixel: at most 1 % of the covered ones.
    EXPECT_LE(differ, lit / 100 + 2) << "t=" << t << ": " << differ << " of " << lit;
    // ...and the pose is not the rest pose: skinning moved the figure.
    EXPECT_GT(compare(onGpu, rest).first, lit / 10) << "t=" << t;
  }
}

TEST_P(SkinnedRendererTest, BonesAreCheckedBeforeDrawing) {
  auto skinned = rig_.renderer->uploadSkinnedMesh(figure_.mesh, figure_.skin);
  ASSERT_TRUE(skinned.ok()) << skinned.status().toString();
  auto plain = rig_.renderer->uploadMesh(figure_.mesh);
  ASSERT_TRUE(plain.ok());
  const std::vector<glm::mat4> bones = bonesAt(0.5);
  const std::vector<glm::mat4> tooFew(bones.begin(), bones.end() - 1);
  std::vector<glm::mat4> nan = bones;
  nan[1][3][0] = std::nanf("");
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  const auto drawOne = [&](MeshHandle mesh, const std::vector<glm::mat4>* b) {
    DrawItem item{mesh, model_, unlitColor(1, 1, 1)};
    item.bones = b;
    return rig_.renderer->draw(&item, 1, orthoCamera(), Lighting());
  };
  EXPECT_EQ(drawOne(*skinned, nullptr).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(drawOne(*skinned, &tooFew).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(drawOne(*skinned, &nan).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(drawOne(*plain, &bones).code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(rig_.renderer->stats().drawCalls, 0u);
  EXPECT_TRUE(drawOne(*skinned, &bones).ok());
  EXPECT_EQ(rig_.renderer->stats().drawCalls, 1u);
}

TEST_P(SkinnedRendererTest, BadSkinsAreRefusedAtUpload) {
  std::vector<anim::VertexSkin> shorter(figure_.skin.begin(), figure_.skin.end() - 1);
  EXPECT_EQ(rig_.renderer->uploadSkinnedMesh(figure_.mesh, shorter).status().code(),
            ErrorCode::kInvalidArgument);
  std::vector<anim::VertexSkin> heavy = figure_.skin;
  heavy[0] = {0, 1, 2.0f};
  EXPECT_EQ(rig_.renderer->uploadSkinnedMesh(figure_.mesh, heavy).status().code(),
            ErrorCode::kInvalidArgument);
  // A rigid vertex's unused second bone does not raise the bones a draw needs.
  std::vector<anim::VertexSkin> rigid(figure_.mesh.vertexCount(), anim::VertexSkin{0, 9, 0.0f});
  auto handle = rig_.renderer->uploadSkinnedMesh(figure_.mesh, rigid);
  ASSERT_TRUE(handle.ok());
  EXPECT_EQ(rig_.renderer->bonesNeeded(*handle), 1u);
  EXPECT_EQ(rig_.renderer->updateMesh(*handle, figure_.mesh).code(), ErrorCode::kInvalidArgument);
}

INSTANTIATE_TEST_SUITE_P(Backends, SkinnedRendererTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

}  // namespace
}  // namespace thinlod::render
