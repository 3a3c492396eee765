// The frontend's skinned objects (docs/animation.md, "Served"): a skinned
// mesh with its bone pose is drawn deformed by the vertex shader exactly as
// the CPU-deformed mesh (anim::deform) is drawn; poses apply with their
// batch, only to held skinned objects; without a pose (or with too few
// bones) the object is not drawn; the reference renderer draws a skinned full
// mesh at its pose the same way. FrontendScene's checks of skins and poses.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "articulated_figure.h"
#include "frontend_test_util.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/frontend/reference_renderer.h"

namespace thinlod::frontend {
namespace {

using render::Backend;
using testing::addOp;
using testing::backendParamName;
using testing::flatLighting;
using testing::orthoCamera;
using testing::quadMesh;
using testing::removeOp;
using testing::solidImage;

constexpr int kSize = 96;

anim::testing::ArticulatedFigure figure() {
  anim::testing::FigureShape shape;
  shape.ringsPerUnit = 8;
  shape.around = 12;
  return anim::testing::makeArticulatedFigure(shape);
}

BoneMatrices poseAt(const anim::testing::ArticulatedFigure& f, double t) {
  return anim::skinningMatrices(f.skeleton,
                                anim::samplePose(f.skeleton, f.clip, t, anim::ClipWrap::kLoop));
}

SceneOperation skinnedOp(ObjectId id, const anim::testing::ArticulatedFigure& f,
                         const glm::mat4& transform) {
  SceneOperation op = addOp(id, RepresentationKind::kMesh,
                            std::make_shared<const IndexedMesh>(f.mesh), nullptr, transform);
  op.representation.skin = std::make_shared<const std::vector<anim::VertexSkin>>(f.skin);
  return op;
}

const glm::mat4 kPlace = glm::translate(glm::mat4(1.0f), glm::vec3(-0.6f, -0.1f, 0.0f)) *
                         glm::scale(glm::mat4(1.0f), glm::vec3(0.4f));

class SkinnedFrontendTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(GetParam(), kSize, kSize);
    ASSERT_TRUE(context.ok()) << context.status().toString();
    context_ = std::move(context).value();
    FrontendRendererOptions options;
    options.width = kSize;
    options.height = kSize;
    options.layerSize = 16;
    options.layersPerPage = 4;
    options.uploadBytesPerFrame = 1 << 22;
    auto renderer = FrontendRenderer::create(*context_, options);
    ASSERT_TRUE(renderer.ok()) << renderer.status().toString();
    renderer_ = std::move(renderer).value();
  }
  void TearDown() override {
    if (context_) (void)context_->makeCurrent();
    renderer_.reset();
    context_.reset();
  }

  void submit(std::uint64_t plan, std::vector<SceneOperation> ops,
              std::vector<std::pair<ObjectId, BoneMatrices>> poses = {}) {
    SceneBatch batch;
    batch.plan = plan;
    batch.operations = std::move(ops);
    batch.bonePoses = std::move(poses);
    const Status status = renderer_->submit(std::move(batch));
    ASSERT_TRUE(status.ok()) << status.toString();
  }

  FrameReport frame(RgbaImage& image) {
    auto report = renderer_->renderFrame(orthoCamera(), flatLighting(), image);
    EXPECT_TRUE(report.ok()) << report.status().toString();
    return report.ok() ? *report : FrameReport{};
  }

  static int covered(const RgbaImage& image) {
    int n = 0;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) n += image.at(x, y)[0] > 128 ? 1 : 0;
    }
    return n;
  }
  static int differing(const RgbaImage& a, const RgbaImage& b) {
    int n = 0;
    for (int y = 0; y < a.height; ++y) {
      for (int x = 0; x < a.width; ++x) {
        for (int c = 0; c < 3; ++c) {
          if (std::abs(int(a.at(x, y)[c]) - int(b.at(x, y)[c])) > 8) {
            ++n;
            break;
          }
        }
      }
    }
    return n;
  }

  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<FrontendRenderer> renderer_;
};

TEST_P(SkinnedFrontendTest, DrawsTheLevelAsTheCpuDeformedMesh) {
  const anim::testing::ArticulatedFigure f = figure();
  std::uint64_t plan = 1;
  for (const double t : {0.4, 1.3}) {
    const BoneMatrices bones = poseAt(f, t);
    submit(plan++, {skinnedOp(1, f, kPlace)}, {{1, bones}});
    RgbaImage onGpu;
    const FrameReport skinned = frame(onGpu);
    EXPECT_EQ(skinned.skinnedObjects, 1u);
    EXPECT_EQ(skinned.deformedVertices, f.mesh.vertexCount());
    EXPECT_EQ(skinned.skinnedWithoutPose, 0u);
    ASSERT_NE(renderer_->scene().bonePose(1), nullptr);

    auto deformed = std::make_shared<IndexedMesh>(f.mesh);
    anim::deform(f.mesh.positions, f.skin, bones, {}, deformed->positions);
    submit(plan++, {addOp(1, RepresentationKind::kMesh, deformed, nullptr, kPlace)});
    RgbaImage onCpu;
    const FrameReport plain = frame(onCpu);
    EXPECT_EQ(plain.skinnedObjects, 0u);
    EXPECT_EQ(renderer_->scene().bonePose(1), nullptr) << "an unskinned level drops the pose";

    const int area = covered(onCpu);
    EXPECT_GT(area, kSize * kSize / 50) << "t=" << t;
    EXPECT_LE(differing(onGpu, onCpu), area / 100 + 2) << "t=" << t;
  }
}

TEST_P(SkinnedFrontendTest, WithoutAPoseOrWithTooFewBonesNothingIsDrawn) {
  const anim::testing::ArticulatedFigure f = figure();
  submit(1, {skinnedOp(1, f, kPlace)});
  RgbaImage image;
  FrameReport report = frame(image);
  EXPECT_EQ(report.skinnedWithoutPose, 1u);
  EXPECT_EQ(report.skinnedObjects, 0u);
  EXPECT_EQ(covered(image), 0);
  // Too few bones for the skin.
  BoneMatrices few = poseAt(f, 0.2);
  few.pop_back();
  submit(2, {}, {{1, few}});
  report = frame(image);
  EXPECT_EQ(report.skinnedWithoutPose, 1u);
  EXPECT_EQ(covered(image), 0);
  // A pose-only batch brings it.
  submit(3, {}, {{1, poseAt(f, 0.2)}});
  report = frame(image);
  EXPECT_EQ(report.skinnedObjects, 1u);
  EXPECT_GT(covered(image), 0);
  // Removal drops the pose.
  submit(4, {removeOp(1)});
  report = frame(image);
  EXPECT_EQ(renderer_->scene().bonePose(1), nullptr);
  EXPECT_EQ(report.skinnedObjects, 0u);
}

TEST_P(SkinnedFrontendTest, ReferenceDrawsTheSkinnedFullMeshAtItsPose) {
  const anim::testing::ArticulatedFigure f = figure();
  ReferenceRendererOptions options;
  options.width = kSize;
  options.height = kSize;
  auto reference = ReferenceRenderer::create(*context_, options);
  ASSERT_TRUE(reference.ok()) << reference.status().toString();
  const BoneMatrices bones = poseAt(f, 0.7);
  ReferenceObject skinned;
  skinned.mesh = std::make_shared<const IndexedMesh>(f.mesh);
  skinned.material.lit = false;
  skinned.material.diffuse = glm::vec4(1.0f);
  skinned.transform = kPlace;
  skinned.skin = std::make_shared<const std::vector<anim::VertexSkin>>(f.skin);
  skinned.bones = &bones;
  RgbaImage onGpu;
  ASSERT_TRUE((*reference)->render({skinned}, orthoCamera(), flatLighting(), onGpu).ok());
  ReferenceObject plain = skinned;
  auto deformed = std::make_shared<IndexedMesh>(f.mesh);
  anim::deform(f.mesh.positions, f.skin, bones, {}, deformed->positions);
  plain.mesh = deformed;
  plain.skin = nullptr;
  plain.bones = nullptr;
  RgbaImage onCpu;
  ASSERT_TRUE((*reference)->render({plain}, orthoCamera(), flatLighting(), onCpu).ok());
  const int area = covered(onCpu);
  EXPECT_GT(area, kSize * kSize / 50);
  EXPECT_LE(differing(onGpu, onCpu), area / 100 + 2);
  // A skin without bones draws nothing and says why.
  skinned.bones = nullptr;
  EXPECT_EQ((*reference)->render({skinned}, orthoCamera(), flatLighting(), onGpu).status().code(),
            ErrorCode::kInvalidArgument);
}

// Poses extrapolated to the frame's time: the frame drawn at a time past the
// newest pose is the frame drawn with extrapolateBonePose's matrices.
TEST_P(SkinnedFrontendTest, DrawsTheExtrapolatedPoseAtALaterFrameTime) {
  const anim::testing::ArticulatedFigure f = figure();
  SceneBatch first;
  first.plan = 1;
  first.operations = {skinnedOp(1, f, kPlace)};
  first.bonePoses = {{1, poseAt(f, 0.4)}};
  first.poseTimeS = 0.4;
  ASSERT_TRUE(renderer_->submit(std::move(first)).ok());
  SceneBatch second;
  second.plan = 2;
  second.bonePoses = {{1, poseAt(f, 0.5)}};
  second.poseTimeS = 0.5;
  ASSERT_TRUE(renderer_->submit(std::move(second)).ok());

  RgbaImage ahead;
  auto report = renderer_->renderFrame(orthoCamera(), flatLighting(), ahead, 0.6);
  ASSERT_TRUE(report.ok()) << report.status().toString();
  EXPECT_EQ(report->skinnedObjects, 1u);
  EXPECT_EQ(report->extrapolatedPoses, 1u);
  RgbaImage newest;
  report = renderer_->renderFrame(orthoCamera(), flatLighting(), newest, 0.5);
  ASSERT_TRUE(report.ok()) << report.status().toString();
  EXPECT_EQ(report->extrapolatedPoses, 0u) << "the frame of the newest pose's own time";
  EXPECT_GT(differing(ahead, newest), 0);

  BoneMatrices expected;
  ASSERT_TRUE(extrapolateBonePose(poseAt(f, 0.4), 0.4, poseAt(f, 0.5), 0.5, 0.6, expected));
  // Drawn as they are (an unknown pose time is never extrapolated).
  submit(3, {}, {{1, expected}});
  RgbaImage direct;
  report = renderer_->renderFrame(orthoCamera(), flatLighting(), direct, 0.6);
  ASSERT_TRUE(report.ok()) << report.status().toString();
  EXPECT_EQ(report->extrapolatedPoses, 0u);
  EXPECT_EQ(differing(ahead, direct), 0);
}

INSTANTIATE_TEST_SUITE_P(Backends, SkinnedFrontendTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

TEST(FrontendSceneSkinned, PosesApplyOnlyToHeldSkinnedObjects) {
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  SceneBatch batch;
  batch.plan = 1;
  batch.operations = {skinnedOp(1, f, glm::mat4(1.0f)),
                      addOp(2, RepresentationKind::kMesh, quadMesh(0, 0, 1, 1, 0), nullptr)};
  batch.bonePoses = {{1, poseAt(f, 0.1)}, {2, poseAt(f, 0.1)}, {3, poseAt(f, 0.1)}};
  ASSERT_TRUE(scene.enqueue(std::move(batch)).ok());
  EXPECT_EQ(scene.bonePose(1), nullptr) << "not before the batch commits";
  for (const PendingUpload& upload : scene.planUploads(1 << 30))
    ASSERT_TRUE(scene.markUploaded(upload.key).ok());
  scene.commitReady();
  ASSERT_NE(scene.bonePose(1), nullptr);
  EXPECT_EQ(*scene.bonePose(1), poseAt(f, 0.1));
  EXPECT_EQ(scene.bonePose(2), nullptr) << "object 2 is not skinned";
  EXPECT_EQ(scene.bonePose(3), nullptr) << "object 3 is not held";
}

// The upload budget counts a skinned mesh's skin attribute (its own GPU
// buffer, kGpuSkinBytes a vertex) besides the interleaved vertices.
TEST(FrontendSceneSkinned, UploadBytesCountTheSkin) {
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  SceneBatch batch;
  batch.plan = 1;
  batch.operations = {skinnedOp(1, f, glm::mat4(1.0f))};
  ASSERT_TRUE(scene.enqueue(std::move(batch)).ok());
  const std::vector<PendingUpload> uploads = scene.planUploads(1 << 30);
  ASSERT_EQ(uploads.size(), 1u);
  const IndexedMesh& mesh = f.mesh;
  EXPECT_EQ(uploads[0].object->uploadBytes, mesh.vertexCount() * (kGpuVertexBytes + kGpuSkinBytes) +
                                  mesh.indices.size() * kGpuIndexBytes);
  EXPECT_EQ(uploadBytesOf(mesh, nullptr, true) - uploadBytesOf(mesh, nullptr),
            mesh.vertexCount() * kGpuSkinBytes);
}

TEST(FrontendSceneSkinned, BadSkinsAndPosesRefuseTheBatch) {
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  const auto refused = [&](SceneBatch batch) { return !scene.enqueue(std::move(batch)).ok(); };
  SceneBatch shortSkin;
  shortSkin.operations = {skinnedOp(1, f, glm::mat4(1.0f))};
  auto skin = std::make_shared<std::vector<anim::VertexSkin>>(f.skin);
  skin->pop_back();
  shortSkin.operations[0].representation.skin = skin;
  EXPECT_TRUE(refused(shortSkin));
  SceneBatch impostor;
  impostor.operations = {skinnedOp(1, f, glm::mat4(1.0f))};
  impostor.operations[0].representation.kind = RepresentationKind::kMeshedImpostor;
  impostor.operations[0].representation.texture = solidImage(4, 4, 255, 255, 255, 255);
  EXPECT_TRUE(refused(impostor));
  SceneBatch nan;
  BoneMatrices bad = poseAt(f, 0.1);
  bad[0][3][1] = std::nanf("");
  nan.bonePoses = {{1, bad}};
  EXPECT_TRUE(refused(nan));
  SceneBatch twice;
  twice.bonePoses = {{1, poseAt(f, 0.1)}, {1, poseAt(f, 0.2)}};
  EXPECT_TRUE(refused(twice));
  SceneBatch many;
  many.bonePoses = {{1, BoneMatrices(kMaxBonesPerPose + 1, glm::mat4(1.0f))}};
  EXPECT_TRUE(refused(many));
  EXPECT_EQ(scene.pendingBatches(), 0u);
}

glm::mat4 shifted(float x) { return glm::translate(glm::mat4(1.0f), glm::vec3(x, 0.0f, 0.0f)); }

// Enqueues a batch, uploads everything and commits it.
void apply(FrontendScene& scene, std::vector<SceneOperation> ops,
           std::vector<std::pair<ObjectId, BoneMatrices>> poses, double poseTimeS) {
  SceneBatch batch;
  batch.operations = std::move(ops);
  batch.bonePoses = std::move(poses);
  batch.poseTimeS = poseTimeS;
  ASSERT_TRUE(scene.enqueue(std::move(batch)).ok());
  for (const PendingUpload& upload : scene.planUploads(1 << 30))
    ASSERT_TRUE(scene.markUploaded(upload.key).ok());
  scene.commitReady();
}

// The x translation of bone 1 drawn at `t` (bone 0 stays the identity).
float drawnX(const FrontendScene& scene, double t) {
  BoneMatrices scratch;
  const BoneMatrices* pose = scene.bonePoseAt(1, t, scratch);
  EXPECT_NE(pose, nullptr);
  if (pose == nullptr) return std::nanf("");
  EXPECT_EQ((*pose)[0], glm::mat4(1.0f));
  return (*pose)[1][3][0];
}

TEST(FrontendScenePoseExtrapolation, LinearPastTheNewestPoseWithinTwoSpacings) {
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  apply(scene, {skinnedOp(1, f, glm::mat4(1.0f))}, {{1, {glm::mat4(1.0f), shifted(0.0f)}}}, 1.0);
  EXPECT_FLOAT_EQ(drawnX(scene, 1.05), 0.0f) << "a single pose is never extrapolated";
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(1.0f)}}}, 1.1);
  EXPECT_FLOAT_EQ(drawnX(scene, 1.05), 1.0f) << "between the two poses: the newest";
  EXPECT_FLOAT_EQ(drawnX(scene, 1.1), 1.0f) << "at the newest pose's time: itself";
  EXPECT_FLOAT_EQ(drawnX(scene, 0.9), 1.0f) << "before both: the newest";
  EXPECT_NEAR(drawnX(scene, 1.15), 1.5f, 1e-4f);
  EXPECT_NEAR(drawnX(scene, 1.2), 2.0f, 1e-4f);
  EXPECT_NEAR(drawnX(scene, 1.299), 2.99f, 1e-3f) << "just within two spacings";
  EXPECT_FLOAT_EQ(drawnX(scene, 1.31), 1.0f) << "further than two spacings: the newest";
  EXPECT_FLOAT_EQ(drawnX(scene, std::nan("")), 1.0f) << "no frame time: the newest";
  EXPECT_EQ(*scene.bonePose(1), (BoneMatrices{glm::mat4(1.0f), shifted(1.0f)}))
      << "bonePose stays the newest as received";
  // The next pose pushes the oldest out: the two newest define the line.
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(1.5f)}}}, 1.2);
  EXPECT_NEAR(drawnX(scene, 1.3), 2.0f, 1e-4f);
  // Elements, not positions: a rotation is extrapolated element by element.
  const glm::mat4 turn0 = glm::rotate(glm::mat4(1.0f), 0.0f, glm::vec3(0, 0, 1));
  const glm::mat4 turn1 = glm::rotate(glm::mat4(1.0f), 0.2f, glm::vec3(0, 0, 1));
  BoneMatrices out;
  ASSERT_TRUE(extrapolateBonePose({turn0}, 0.0, {turn1}, 0.1, 0.2, out));
  ASSERT_EQ(out.size(), 1u);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(out[0][c][r], 2 * turn1[c][r] - turn0[c][r], 1e-6f);
}

TEST(FrontendScenePoseExtrapolation, NotFromPosesTooFarApartUnknownOrMismatched) {
  const BoneMatrices a{shifted(0.0f)};
  const BoneMatrices b{shifted(1.0f)};
  BoneMatrices out{shifted(7.0f)};
  EXPECT_TRUE(extrapolateBonePose(a, 0.0, b, 0.5, 0.6, out)) << "0.5 s apart is allowed";
  EXPECT_NEAR(out[0][3][0], 1.2f, 1e-5f);
  out = {shifted(7.0f)};
  EXPECT_FALSE(extrapolateBonePose(a, 0.0, b, 0.51, 0.6, out)) << "over 0.5 s apart";
  EXPECT_FALSE(extrapolateBonePose(a, 0.5, b, 0.5, 0.6, out)) << "same pose time";
  EXPECT_FALSE(extrapolateBonePose(a, 0.6, b, 0.5, 0.7, out)) << "older newest";
  EXPECT_FALSE(extrapolateBonePose(a, std::nan(""), b, 0.5, 0.6, out));
  EXPECT_FALSE(extrapolateBonePose(a, 0.4, b, std::nan(""), 0.6, out));
  EXPECT_FALSE(extrapolateBonePose(a, 0.4, b, 0.5, std::nan(""), out));
  EXPECT_FALSE(extrapolateBonePose({}, 0.4, b, 0.5, 0.6, out)) << "different bone counts";
  EXPECT_FALSE(extrapolateBonePose(a, 0.4, b, 0.5, 0.5, out)) << "not ahead";
  EXPECT_FALSE(extrapolateBonePose(a, 0.4, b, 0.5, 0.7000001, out)) << "past two spacings";
  EXPECT_EQ(out, BoneMatrices{shifted(7.0f)}) << "untouched when refused";

  // In the scene: poses of unknown time (a batch without poseTimeS) are drawn as they are.
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  apply(scene, {skinnedOp(1, f, glm::mat4(1.0f))}, {{1, {glm::mat4(1.0f), shifted(0.0f)}}},
        std::nan(""));
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(1.0f)}}}, std::nan(""));
  EXPECT_FLOAT_EQ(drawnX(scene, 5.0), 1.0f);
  // A second answer for the newest pose's time replaces it and keeps the one before.
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(2.0f)}}}, 1.0);
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(3.0f)}}}, 1.1);
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(4.0f)}}}, 1.1);
  EXPECT_NEAR(drawnX(scene, 1.2), 6.0f, 1e-4f);
}

TEST(FrontendScenePoseExtrapolation, HistoryFollowsThePoseAcrossRepresentations) {
  const anim::testing::ArticulatedFigure f = figure();
  FrontendScene scene;
  apply(scene, {skinnedOp(1, f, glm::mat4(1.0f))}, {{1, {glm::mat4(1.0f), shifted(0.0f)}}}, 1.0);
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(1.0f)}}}, 1.1);
  // Another level of the same skinned object keeps both poses.
  apply(scene, {skinnedOp(1, f, shifted(5.0f))}, {}, std::nan(""));
  EXPECT_NEAR(drawnX(scene, 1.2), 2.0f, 1e-4f);
  // An unskinned replacement drops them; skinned again, one pose is not extrapolated.
  apply(scene, {addOp(1, RepresentationKind::kMesh, quadMesh(0, 0, 1, 1, 0), nullptr)}, {},
        std::nan(""));
  BoneMatrices scratch;
  EXPECT_EQ(scene.bonePoseAt(1, 1.2, scratch), nullptr);
  apply(scene, {skinnedOp(1, f, glm::mat4(1.0f))}, {{1, {glm::mat4(1.0f), shifted(3.0f)}}}, 1.3);
  EXPECT_FLOAT_EQ(drawnX(scene, 1.35), 3.0f);
  // Removal drops them too.
  apply(scene, {}, {{1, {glm::mat4(1.0f), shifted(4.0f)}}}, 1.4);
  EXPECT_NEAR(drawnX(scene, 1.5), 5.0f, 1e-4f);
  apply(scene, {removeOp(1)}, {}, std::nan(""));
  EXPECT_EQ(scene.bonePoseAt(1, 1.5, scratch), nullptr);
  apply(scene, {skinnedOp(1, f, glm::mat4(1.0f))}, {{1, {glm::mat4(1.0f), shifted(6.0f)}}}, 1.6);
  EXPECT_FLOAT_EQ(drawnX(scene, 1.65), 6.0f);
}

}  // namespace
}  // namespace thinlod::frontend
