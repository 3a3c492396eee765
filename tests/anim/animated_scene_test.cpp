// Animated scene objects (docs/scene-format.md "Animated Inline"): the skin
// palette (core/skinning.h compactSkin, paletteMatricesAt) and an Inline
// whose `animation` field names a clip of a skinned file from
// assimp-testmodels, with its refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <glm/vector_relational.hpp>

#include "articulated_figure.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

const std::string kModels = "/usr/share/assimp/models";

std::string packageDir(const std::string& relative) {
  const std::string path = kModels + "/" + relative;
  EXPECT_TRUE(std::filesystem::exists(path))
      << path << " is missing: deploy/setup installs the Debian package assimp-testmodels";
  return path;
}

// Writes `text` as a scene file in the test's temporary directory.
std::string writeScene(const std::string& name, const std::string& text) {
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / ("anim_scene_" + name + ".wrl")).string();
  std::ofstream(path) << text;
  return path;
}

Result<Scene> loadAnimated(const std::string& inlineBody, const std::string& searchDir) {
  SceneLoadOptions options;
  options.meshSearchPaths = {searchDir};
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return loadSceneFile(
      writeScene(info->name(),
                 "#VRML V2.0 utf8\nTransform { translation 1 0 0 children [ Inline { " +
                     inlineBody + " } ] }\n"),
      options);
}

const ShapeNode* onlyShape(const Scene& scene) {
  Result<std::vector<SceneObject>> objects = collectSceneObjects(scene);
  EXPECT_TRUE(objects.ok()) << objects.status().toString();
  if (!objects.ok() || objects->size() != 1) return nullptr;
  return (*objects)[0].shape;
}

TEST(SkinPalette, HoldsTheSkinsBonesAndDeformsAsTheFullSkin) {
  const anim::testing::ArticulatedFigure figure = anim::testing::makeArticulatedFigure();
  // Pad the skeleton with bones no vertex names: the palette must leave them out.
  anim::Skeleton skeleton = figure.skeleton;
  for (int i = 0; i < 3; ++i)
    skeleton.bones.push_back({"unused", 0, glm::mat4(1.0f), glm::mat4(1.0f)});
  const anim::SkinPalette palette = anim::compactSkin(figure.skin);
  ASSERT_EQ(palette.skin.size(), figure.skin.size());
  EXPECT_EQ(palette.bones, (std::vector<std::uint32_t>{0, 1, 2}));
  ASSERT_TRUE(
      anim::validateSkin(palette.skin, figure.mesh.vertexCount(), palette.bones.size(), "palette")
          .ok());
  for (const double t : {0.0, 0.37, 1.5}) {
    std::vector<glm::vec3> full(figure.mesh.vertexCount()), viaPalette(full.size());
    anim::deform(figure.mesh.positions, figure.skin,
                 anim::skinningMatrices(
                     skeleton, anim::samplePose(skeleton, figure.clip, t, anim::ClipWrap::kLoop)),
                 {}, full);
    const std::vector<glm::mat4> matrices =
        anim::paletteMatricesAt(skeleton, figure.clip, palette, t, anim::ClipWrap::kLoop);
    ASSERT_EQ(matrices.size(), palette.bones.size());
    anim::deform(figure.mesh.positions, palette.skin, matrices, {}, viaPalette);
    for (std::size_t v = 0; v < full.size(); ++v)
      ASSERT_EQ(full[v], viaPalette[v]) << v << " " << t;
  }
}

TEST(SkinPalette, RigidVerticesNameOneBone) {
  // Bone 7 is only the unused second bone of a rigid vertex (weight 0).
  const std::vector<anim::VertexSkin> skin{{2, 7, 0.0f}, {4, 2, 0.25f}, {4, 4, 0.0f}};
  const anim::SkinPalette palette = anim::compactSkin(skin);
  EXPECT_EQ(palette.bones, (std::vector<std::uint32_t>{2, 4}));
  EXPECT_EQ(palette.skin[0].boneA, 0u);
  EXPECT_EQ(palette.skin[0].boneB, 0u);
  EXPECT_EQ(palette.skin[1].boneA, 1u);
  EXPECT_EQ(palette.skin[1].boneB, 0u);
  EXPECT_EQ(palette.skin[1].weightB, 0.25f);
  EXPECT_TRUE(palette.skin[2].rigid());
}

TEST(MotionBound, IsTheLargestDeviationFromBindAtTheSampledTimes) {
  const anim::testing::ArticulatedFigure figure = anim::testing::makeArticulatedFigure();
  const std::size_t steps = 16;
  const double bound = anim::sampledMaxDeviationFromBind(figure.skeleton, figure.clip,
                                                         figure.mesh.positions, figure.skin, steps);
  double direct = 0.0;
  std::vector<glm::vec3> out(figure.mesh.vertexCount());
  for (std::size_t i = 0; i <= steps; ++i) {
    const double t = figure.clip.duration * double(i) / double(steps);
    anim::deform(
        figure.mesh.positions, figure.skin,
        anim::skinningMatrices(figure.skeleton, anim::samplePose(figure.skeleton, figure.clip, t,
                                                                 anim::ClipWrap::kClamp)),
        {}, out);
    for (std::size_t v = 0; v < out.size(); ++v)
      direct = std::max(direct, double(glm::length(out[v] - figure.mesh.positions[v])));
  }
  EXPECT_GT(bound, 0.0);
  EXPECT_EQ(bound, direct);
}

TEST(MotionBound, AnimatedAccuracyShrinksWithTheMotion) {
  EXPECT_EQ(anim::animatedRelativeAccuracy(50.0, 0.0), 50.0);
  // L = 1, m = 0.1, rest error 0.02: error <= 0.22 against a sphere of diameter 1.2.
  EXPECT_DOUBLE_EQ(anim::animatedRelativeAccuracy(50.0, 0.2), 1.2 / 0.22);
  double previous = 50.0;
  for (const double ratio : {0.01, 0.1, 1.0, 10.0}) {
    const double a = anim::animatedRelativeAccuracy(50.0, ratio);
    EXPECT_LT(a, previous);
    EXPECT_LE(a, (1.0 + ratio) / ratio);  // even an exact level cannot beat the motion
    previous = a;
  }
}

TEST(AnimatedInline, TheObjectsSphereAndBoundsEncloseEveryPose) {
  Result<Scene> scene =
      loadAnimated("url \"Testwuson.X\" animation \"Wuson_Run\"", packageDir("X"));
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  Result<std::vector<SceneObject>> objects = collectSceneObjects(*scene);
  ASSERT_TRUE(objects.ok());
  const SceneObject& object = (*objects)[0];
  const SkinnedAnimation& animation = *object.shape->geometry.animation;
  const BoundingSphere bind = referenceSphere(*object.fullMesh);
  EXPECT_GT(animation.motionBound, 0.0);
  EXPECT_FLOAT_EQ(object.contentSphere.radius, bind.radius + float(animation.motionBound));
  // At times between the 128 sampled ones too (looped, several laps): the
  // bound is measured, so allow what motion between samples may add.
  double worstExcess = 0.0;
  std::vector<glm::vec3> out(object.fullMesh->vertexCount());
  for (int i = 0; i < 40; ++i) {
    const double t = 0.0377 * i * animation.clip.duration;
    anim::deform(object.fullMesh->positions, animation.skin,
                 anim::skinningMatrices(animation.skeleton,
                                        anim::samplePose(animation.skeleton, animation.clip, t,
                                                         anim::ClipWrap::kLoop)),
                 {}, out);
    for (const glm::vec3& p : out) {
      worstExcess = std::max(worstExcess, double(glm::length(p - object.contentSphere.center) -
                                                 object.contentSphere.radius));
      const glm::vec3 world(object.objectToWorld * glm::vec4(p, 1.0f));
      EXPECT_TRUE(glm::all(glm::greaterThanEqual(world, object.worldBounds.min - 1e-3f)) &&
                  glm::all(glm::lessThanEqual(world, object.worldBounds.max + 1e-3f)));
    }
  }
  EXPECT_LE(worstExcess, 1e-3 * object.contentSphere.radius);
}

TEST(AnimatedInline, ParsesTheClipField) {
  Result<Scene> scene =
      parseScene("#VRML V2.0 utf8\nInline { url \"a.gltf\" animation \"Wuson_Run\" }\n", "s.wrl");
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  const ShapeNode* shape = scene->roots.at(0)->as<ShapeNode>();
  ASSERT_NE(shape, nullptr);
  EXPECT_EQ(shape->geometry.animationClip, "Wuson_Run");
  EXPECT_EQ(shape->geometry.animation, nullptr);  // loaded by resolveMeshes
}

TEST(AnimatedInline, EmptyClipNameIsAnError) {
  Result<Scene> scene =
      parseScene("#VRML V2.0 utf8\nInline { url \"a.gltf\" animation \"\" }\n", "s.wrl");
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("animation is empty"), std::string::npos)
      << scene.status().toString();
}

TEST(AnimatedInline, LoadsTheSkinnedMeshAndTheNamedClip) {
  Result<Scene> scene =
      loadAnimated("url \"Testwuson.X\" animation \"Wuson_Run\"", packageDir("X"));
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  const ShapeNode* shape = onlyShape(*scene);
  ASSERT_NE(shape, nullptr);
  const Geometry& g = shape->geometry;
  ASSERT_NE(g.animation, nullptr);
  ASSERT_NE(g.mesh, nullptr);
  EXPECT_EQ(g.animation->clip.name, "Wuson_Run");
  EXPECT_GT(g.animation->clip.duration, 0.0);
  EXPECT_EQ(g.animation->skin.size(), g.mesh->vertexCount());
  EXPECT_EQ(g.animation->palette.skin.size(), g.mesh->vertexCount());
  EXPECT_GT(g.animation->palette.bones.size(), 1u);
  EXPECT_LT(g.animation->palette.bones.size(), g.animation->skeleton.bones.size());
  // The clip moves the mesh: two instants give different palettes.
  const auto at = [&](double t) {
    return anim::paletteMatricesAt(g.animation->skeleton, g.animation->clip, g.animation->palette,
                                   t, anim::ClipWrap::kLoop);
  };
  EXPECT_NE(at(0.0), at(0.5 * g.animation->clip.duration));
}

TEST(AnimatedInline, ClipByIndexAndFilesWithoutANamedClip) {
  Result<Scene> scene =
      loadAnimated("url \"simple_skin.gltf\" animation \"#0\"", packageDir("glTF2/simple_skin"));
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  const ShapeNode* shape = onlyShape(*scene);
  ASSERT_NE(shape, nullptr);
  ASSERT_NE(shape->geometry.animation, nullptr);
  EXPECT_EQ(shape->geometry.animation->palette.skin.size(), shape->geometry.mesh->vertexCount());
}

TEST(AnimatedInline, UnknownClipIsNotFoundNamingTheClips) {
  Result<Scene> scene = loadAnimated("url \"Testwuson.X\" animation \"Dance\"", packageDir("X"));
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.status().code(), ErrorCode::kNotFound);
  EXPECT_NE(scene.status().message().find("'Dance'"), std::string::npos);
  EXPECT_NE(scene.status().message().find("'Wuson_Run'"), std::string::npos)
      << scene.status().toString();

  Result<Scene> past = loadAnimated("url \"Testwuson.X\" animation \"#99\"", packageDir("X"));
  ASSERT_FALSE(past.ok());
  EXPECT_EQ(past.status().code(), ErrorCode::kNotFound);
  EXPECT_NE(past.status().message().find("clips"), std::string::npos) << past.status().toString();
}

// animationOffset shifts an instance's clip (pose time + offset), so two
// instances of one clip need not move in step; it needs the clip it shifts,
// a finite number, within a day.
TEST(AnimatedInline, AnimationOffsetIsReadAndChecked) {
  Result<Scene> scene = loadAnimated(
      "url \"Testwuson.X\" animation \"Wuson_Run\" animationOffset 0.37", packageDir("X"));
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  const ShapeNode* shape = onlyShape(*scene);
  ASSERT_NE(shape, nullptr);
  EXPECT_FLOAT_EQ(shape->geometry.animationOffset, 0.37f);
  Result<Scene> plain =
      loadAnimated("url \"Testwuson.X\" animation \"Wuson_Run\"", packageDir("X"));
  ASSERT_TRUE(plain.ok()) << plain.status().toString();
  EXPECT_EQ(onlyShape(*plain)->geometry.animationOffset, 0.0f);
  EXPECT_NE(plain->fingerprint, scene->fingerprint);  // a frontend with the other phase is told
  for (const char* bad : {"url \"Testwuson.X\" animationOffset 0.5",
                          "url \"Testwuson.X\" animation \"Wuson_Run\" animationOffset 1e6",
                          "url \"Testwuson.X\" animation \"Wuson_Run\" animationOffset nan",
                          "url \"Testwuson.X\" animation \"Wuson_Run\" animationOffset \"1\""}) {
    Result<Scene> r = loadAnimated(bad, packageDir("X"));
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_EQ(r.status().code(), ErrorCode::kParseError) << bad << ": " << r.status().toString();
  }
  Result<Scene> noClip = loadAnimated("url \"Testwuson.X\" animationOffset 0.5", packageDir("X"));
  EXPECT_NE(noClip.status().message().find("animationOffset needs animation"), std::string::npos)
      << noClip.status().toString();
}

TEST(AnimatedInline, FileWithoutClipsIsRefused) {
  // WusonSMD.smd is skinned but has no clip.
  Result<Scene> scene = loadAnimated("url \"WusonSMD.smd\" animation \"#0\"", packageDir("SMD"));
  ASSERT_FALSE(scene.ok());
  EXPECT_EQ(scene.status().code(), ErrorCode::kNotFound) << scene.status().toString();
}

TEST(AnimatedInline, UrlRulesHoldAsForMeshes) {
  Result<Scene> scene = loadAnimated("url \"../X/Testwuson.X\" animation \"#0\"", packageDir("X"));
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("'..'"), std::string::npos) << scene.status().toString();
}

TEST(AnimatedInline, TheSkinIsInTheFingerprint) {
  // The same file static and animated: the animated one adds its skin.
  Result<Scene> animated =
      loadAnimated("url \"simple_skin.gltf\" animation \"#0\"", packageDir("glTF2/simple_skin"));
  ASSERT_TRUE(animated.ok()) << animated.status().toString();
  const ShapeNode* shape = onlyShape(*animated);
  ASSERT_NE(shape, nullptr);
  const std::uint64_t withSkin = sceneFingerprint("text", *animated);
  auto changed = std::make_shared<SkinnedAnimation>(*shape->geometry.animation);
  changed->skin[0].weightB = changed->skin[0].weightB == 0.5f ? 0.25f : 0.5f;
  const_cast<ShapeNode*>(shape)->geometry.animation = changed;
  EXPECT_NE(sceneFingerprint("text", *animated), withSkin);
}

}  // namespace
}  // namespace thinlod::scene
