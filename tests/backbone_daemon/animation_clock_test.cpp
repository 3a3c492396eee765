// BackboneCore's animation clock (docs/animation.md, "Served"): a skinned
// object's clip plays looped on pose time, its bone poses are computed for
// the frames in which the frontend holds it, and it is offered as a mesh
// only (an impostor would freeze one pose).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "backbone_core.h"
#include "fake_simplifier.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/codec.h"

namespace thinlod::backbone_daemon {
namespace {

using namespace testing;

const std::string kWusonDir = "/usr/share/assimp/models/X";

// Testwuson.X running (object 1) beside a static sphere (object 2).
// `inlineExtra`: more fields of the figure's Inline (e.g. an animationOffset).
Result<std::unique_ptr<BackboneCore>> animatedCore(CoreOptions options,
                                                   const std::string& inlineExtra = "") {
  EXPECT_TRUE(std::filesystem::exists(kWusonDir + "/Testwuson.X"))
      << "deploy/setup installs the Debian package assimp-testmodels";
  // One file per test and process: ctest runs this file's tests side by side,
  // and a shared name let one test read another's half-written scene.
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) /
       ("animation_clock_" + std::string(info->name()) + "_" + std::to_string(::getpid()) + ".wrl"))
          .string();
  std::ofstream(path) << "#VRML V2.0 utf8\n"
                         "Transform { scale 0.1 0.1 0.1 children [\n"
                         "  Inline { url \"Testwuson.X\" animation \"Wuson_Run\" "
                      << inlineExtra
                      << " } ] }\n"
                         "Transform { translation 1 0 0 children [ Shape { geometry Sphere { "
                         "radius 0.2 } } ] }\n";
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {kWusonDir};
  Result<scene::Scene> loaded = scene::loadSceneFile(path, load);
  if (!loaded.ok()) return loaded.status();
  return BackboneCore::create(std::move(loaded).value(), path, options);
}

const scene::SkinnedAnimation& wuson(const BackboneCore& core) {
  return *core.sceneObjects().at(0).shape->geometry.animation;
}

TEST(BackboneAnimationClock, AnimatedObjectsAreOfferedAsMeshesOnly) {
  CoreOptions options = polygonBudget(5000);
  options.hybridKappa = 4.0;
  auto created = animatedCore(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  const BackboneCore& core = **created;
  EXPECT_EQ(core.animatedObjects(), 1u);
  const backbone::SchedulingScene& scene = core.schedulingScene();
  ASSERT_EQ(scene.objects.size(), 2u);
  ASSERT_EQ(scene.objects[0].optionCount, 1u);
  EXPECT_EQ(scene.options[scene.objects[0].firstOption].kind,
            backbone::OptionKind::kSimplifiedMesh);
  // The static sphere keeps its impostors.
  EXPECT_GT(scene.objects[1].optionCount, 1u);
}

TEST(BackboneAnimationClock, PosesOfHeldAnimatedObjectsFollowPoseTime) {
  auto created = animatedCore(polygonBudget(5000));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));  // the startup curve
  // Nothing held yet: no poses.
  EXPECT_TRUE(core.bonePosesAt(0).empty());

  const glm::vec3 eye(0.3f, 0.3f, 2.0f), figure(0.0f, 0.2f, 0.0f);
  bool held = false;
  for (int step = 0; step < 4 && !held; ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, 0.1 * step, eye, figure)).ok());
    answer(core, fake, submitAll(core));
    ASSERT_TRUE(core.replan().ok());
    const PoseOutcome outcome = core.finishPose();
    held = core.frontendMirror().trianglesOf(0) > 0.0;
    // Every update carries the poses of what the frontend holds, on the link.
    ASSERT_EQ(outcome.update.bonePoses.size(), held ? 1u : 0u);
    EXPECT_TRUE(protocol::validate(protocol::Message(outcome.update)).ok());
    if (held) {
      EXPECT_EQ(outcome.update.bonePoses[0],
                core.bonePosesAt(poseAt(step, 0.1 * step, eye, figure).timestampNs)[0]);
      EXPECT_EQ(outcome.bonePoseBytes,
                std::uint64_t(bonePoseBytes(wuson(core).palette.bones.size())));
      EXPECT_GE(outcome.linkBytes, outcome.bonePoseBytes);
    }
  }
  ASSERT_TRUE(held) << "the backbone never sent the figure";

  const scene::SkinnedAnimation& animation = wuson(core);
  const double duration = animation.clip.duration;
  for (const double t : {0.0, 0.3 * duration, 0.9 * duration}) {
    const auto ns = static_cast<std::int64_t>(std::llround(t * 1e9));
    const std::vector<protocol::BonePose> poses = core.bonePosesAt(ns);
    ASSERT_EQ(poses.size(), 1u);
    EXPECT_EQ(poses[0].objectId, 1u);
    // The clock is pose time: the clip at t (looped), one matrix per palette bone.
    // (The top three rows: deform() drops w, the wire carries those.)
    const std::vector<glm::mat4> expected =
        anim::paletteMatricesAt(animation.skeleton, animation.clip, animation.palette,
                                double(ns) * 1e-9, anim::ClipWrap::kLoop);
    ASSERT_EQ(poses[0].matrices.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r) ASSERT_EQ(poses[0].matrices[i][c][r], expected[i][c][r]);
        ASSERT_EQ(poses[0].matrices[i][c][3], c == 3 ? 1.0f : 0.0f);
      }
    }
    // One lap later: the same pose.
    const auto lap = static_cast<std::int64_t>(std::llround((t + duration) * 1e9));
    const std::vector<protocol::BonePose> again = core.bonePosesAt(lap);
    ASSERT_EQ(again.size(), 1u);
    for (std::size_t i = 0; i < again[0].matrices.size(); ++i) {
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
          EXPECT_NEAR(again[0].matrices[i][c][r], poses[0].matrices[i][c][r],
                      1e-3f * (1.0f + std::fabs(poses[0].matrices[i][c][r])));
        }
      }
    }
  }
  EXPECT_NE(core.bonePosesAt(0)[0].matrices,
            core.bonePosesAt(static_cast<std::int64_t>(0.5 * duration * 1e9))[0].matrices);
}

// Plans until the frontend holds the figure (object 1); false if it never does.
bool sendFigure(BackboneCore& core, FakeSimplifier& fake, int& step) {
  const glm::vec3 eye(0.3f, 0.3f, 2.0f), figure(0.0f, 0.2f, 0.0f);
  for (int tries = 0; tries < 4; ++tries, ++step) {
    if (!core.beginPose(poseAt(step, 0.1 * step, eye, figure)).ok()) return false;
    answer(core, fake, submitAll(core));
    if (!core.replan().ok()) return false;
    core.finishPose();
    if (core.frontendMirror().trianglesOf(0) > 0.0) return true;
  }
  return false;
}

// An Inline's animationOffset: the figure's clip plays at pose time + offset.
TEST(BackboneAnimationClock, AnimationOffsetShiftsTheClip) {
  auto created = animatedCore(polygonBudget(5000), "animationOffset 0.25");
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  const glm::vec3 eye(0.3f, 0.3f, 2.0f), figure(0.0f, 0.2f, 0.0f);
  for (int step = 0; step < 4 && !(core.frontendMirror().trianglesOf(0) > 0.0); ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, 0.1 * step, eye, figure)).ok());
    answer(core, fake, submitAll(core));
    ASSERT_TRUE(core.replan().ok());
    core.finishPose();
  }
  ASSERT_GT(core.frontendMirror().trianglesOf(0), 0.0) << "the backbone never sent the figure";
  const scene::SkinnedAnimation& animation = wuson(core);
  for (const double t : {0.0, 0.4, 1.3}) {
    const std::vector<protocol::BonePose> poses =
        core.bonePosesAt(static_cast<std::int64_t>(std::llround(t * 1e9)));
    ASSERT_EQ(poses.size(), 1u);
    const std::vector<glm::mat4> shifted =
        anim::paletteMatricesAt(animation.skeleton, animation.clip, animation.palette,
                                t + double(0.25f), anim::ClipWrap::kLoop);
    ASSERT_EQ(poses[0].matrices.size(), shifted.size());
    for (std::size_t i = 0; i < shifted.size(); ++i)
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) ASSERT_EQ(poses[0].matrices[i][c][r], shifted[i][c][r]);
  }
}

TEST(BackboneAnimationClock, ReachAndAccuracyAccountForTheMotion) {
  auto created = animatedCore(polygonBudget(5000));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  const scene::SceneObject& figure = core.sceneObjects().at(0);
  const double motion = wuson(core).motionBound;
  const double bindLength = referenceLength(referenceSphere(*figure.fullMesh));
  const double ratio = core.motionRatio(0);
  ASSERT_GT(motion, 0.0);
  EXPECT_DOUBLE_EQ(ratio, 2.0 * motion / bindLength);
  EXPECT_EQ(core.motionRatio(1), 0.0) << "the sphere does not move";
  // Reach: the leaf sphere is the bind sphere grown by the motion (scale 0.1).
  EXPECT_NEAR(core.objects()[0].bounds.radius, 0.1 * (0.5 * bindLength + motion),
              1e-5 * bindLength);
  // No accuracy beats the motion: even the estimate's best is below (1 + r) / r.
  const backbone::SchedulingScene& scene = core.schedulingScene();
  const std::uint32_t option = scene.objects[0].firstOption;
  const double ceiling = (1.0 + ratio) / ratio;
  EXPECT_LE(scene.options[option].relativeTriangles.maxAccuracy(), ceiling);

  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));  // the measured curve, converted
  const AccuracyCurve& measured = scene.options[option].relativeTriangles;
  const double full = double(figure.fullMesh->triangleCount());
  EXPECT_NEAR(measured.maxAccuracy(),
              anim::animatedRelativeAccuracy(FakeSimplifier::meshAccuracy(full), ratio),
              1e-9 * ceiling);
  int step = 0;
  ASSERT_TRUE(sendFigure(core, fake, step));
  // The copy sent is credited what its level keeps while moving, on the wire too.
  const backbone::RepresentationCopy& shown = scene.options[option].atFrontend;
  ASSERT_TRUE(shown.present);
  const double rest = FakeSimplifier::meshAccuracy(shown.triangles);
  EXPECT_DOUBLE_EQ(shown.relativeAccuracy, anim::animatedRelativeAccuracy(rest, ratio));
  EXPECT_LT(shown.relativeAccuracy, rest);
}

// Accuracies the simplifier measured under the clip (motionIncluded) already
// hold at every pose against the grown sphere: the backbone takes them as
// they are, for the curve and for the copy it sends.
TEST(BackboneAnimationClock, AccuraciesMeasuredUnderMotionAreTakenAsTheyAre) {
  auto created = animatedCore(polygonBudget(5000));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  const scene::SceneObject& figure = core.sceneObjects().at(0);
  ASSERT_GT(core.motionRatio(0), 0.0);
  const backbone::SchedulingScene& scene = core.schedulingScene();
  const std::uint32_t option = scene.objects[0].firstOption;
  FakeSimplifier fake(core);
  fake.motionIncluded = true;
  answer(core, fake, submitAll(core));
  const double full = double(figure.fullMesh->triangleCount());
  // The fitted curve is conservative (accuracies at most the samples').
  EXPECT_NEAR(scene.options[option].relativeTriangles.maxAccuracy(),
              FakeSimplifier::meshAccuracy(full), 1e-9 * FakeSimplifier::meshAccuracy(full));
  int step = 0;
  ASSERT_TRUE(sendFigure(core, fake, step));
  const backbone::RepresentationCopy& shown = scene.options[option].atFrontend;
  ASSERT_TRUE(shown.present);
  EXPECT_DOUBLE_EQ(shown.relativeAccuracy, FakeSimplifier::meshAccuracy(shown.triangles));
}

TEST(BackboneAnimationClock, AnUnplannedAnswerCarriesThePosesToo) {
  auto created = animatedCore(polygonBudget(5000));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  int step = 0;
  ASSERT_TRUE(sendFigure(core, fake, step));
  const protocol::ViewerPose pose =
      poseAt(step, 0.1 * step + 0.05, glm::vec3(0.3f, 0.3f, 2.0f), glm::vec3(0.0f));
  const protocol::SceneUpdate update = core.emptyUpdate(pose);
  EXPECT_TRUE(update.operations.empty());
  ASSERT_EQ(update.bonePoses.size(), 1u);
  EXPECT_EQ(update.bonePoses, core.bonePosesAt(pose.timestampNs));
}

TEST(BackboneAnimationClock, PosesPassTheLinkShaperAndWaitWhenItIsEmpty) {
  CoreOptions options = polygonBudget(5000);
  const double rate = 10000.0;  // bytes/s: 1000 a pose step, less than one pose (1840)
  const double burst = 20000.0;
  options.budget.maxLinkBytesPerSecond = rate;
  options.linkBurstBytes = burst;
  auto created = animatedCore(options);
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  int step = 0;
  ASSERT_TRUE(sendFigure(core, fake, step));
  int sent = 0, deferred = 0;
  for (int i = 0; i < 40; ++i, ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, 0.1 * step, glm::vec3(0.3f, 0.3f, 2.0f),
                                      glm::vec3(0.0f, 0.2f, 0.0f)))
                    .ok());
    answer(core, fake, submitAll(core));
    const PoseOutcome outcome = core.finishPose();
    if (outcome.posesDeferredByLink > 0) {
      EXPECT_EQ(outcome.posesDeferredByLink, 1u);
      ++deferred;
      EXPECT_TRUE(outcome.update.bonePoses.empty());
      EXPECT_EQ(outcome.bonePoseBytes, 0u);
    } else if (!outcome.update.bonePoses.empty()) {
      ++sent;
    }
  }
  EXPECT_GT(sent, 0);
  EXPECT_GT(deferred, 0) << "a pose costs more than the link refills between poses";
  // The shaper's guarantee holds with the poses in it (burst grown at most to the largest mesh).
  EXPECT_LE(double(core.shapedLinkBytes()), rate * 0.1 * step + burst + 8192.0);
}

// The scheduler plans geometry with the link rate the poses leave: the
// reserve is the held figure's pose bytes at the pose rate, at most half the
// link, and nothing before the figure is held or without a link budget.
TEST(BackboneAnimationClock, PosesTakeTheirShareOfTheLinkBudgetBeforeGeometry) {
  for (const double rate : {60000.0, 10000.0}) {
    CoreOptions options = polygonBudget(5000);
    options.budget.maxLinkBytesPerSecond = rate;
    options.linkBurstBytes = 200000.0;
    auto created = animatedCore(options);
    ASSERT_TRUE(created.ok()) << created.status().toString();
    BackboneCore& core = **created;
    FakeSimplifier fake(core);
    answer(core, fake, submitAll(core));
    EXPECT_EQ(core.poseLinkReserve(), 0.0) << "no pose seen yet";
    int step = 0;
    ASSERT_TRUE(sendFigure(core, fake, step));
    const double poseBytes =
        bonePoseBytes(wuson(core).palette.bones.size());
    // Poses every 0.1 s of pose time (sendFigure's and the loop's spacing),
    // known from the second pose on.
    const double expected = std::min(poseBytes / 0.1, 0.5 * rate);
    for (int i = 0; i < 5; ++i, ++step) {
      ASSERT_TRUE(core.beginPose(poseAt(step, 0.1 * step, glm::vec3(0.3f, 0.3f, 2.0f),
                                        glm::vec3(0.0f, 0.2f, 0.0f)))
                      .ok());
      answer(core, fake, submitAll(core));
      ASSERT_TRUE(core.replan().ok());
      core.finishPose();
      if (step > 0) {
        EXPECT_NEAR(core.poseLinkReserve(), expected, 1e-6 * expected) << rate;
      }
      // What the scheduler plans with: the rate less the reserve.
      const backbone::Budget planned = core.schedulingBudget();
      ASSERT_TRUE(planned.maxLinkBytesPerSecond.has_value());
      EXPECT_DOUBLE_EQ(*planned.maxLinkBytesPerSecond, rate - core.poseLinkReserve());
    }
  }
  // Without a link budget nothing is reserved.
  auto created = animatedCore(polygonBudget(5000));
  ASSERT_TRUE(created.ok());
  BackboneCore& core = **created;
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));
  int step = 0;
  ASSERT_TRUE(sendFigure(core, fake, step));
  ASSERT_TRUE(core.beginPose(poseAt(step + 1, 0.1 * (step + 1), glm::vec3(0.3f, 0.3f, 2.0f),
                                    glm::vec3(0.0f, 0.2f, 0.0f)))
                  .ok());
  core.finishPose();
  EXPECT_EQ(core.poseLinkReserve(), 0.0);
  EXPECT_FALSE(core.schedulingBudget().maxLinkBytesPerSecond.has_value());
}

}  // namespace
}  // namespace thinlod::backbone_daemon
