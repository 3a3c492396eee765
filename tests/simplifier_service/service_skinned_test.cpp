// SimplifierService on an animated object (docs/animation.md, "Served"): a
// level of Testwuson.X (assimp-testmodels) comes back with each vertex's
// two-bone skin in the scene's palette indices, the skin of the input vertex
// it came from, so deforming the level deforms exactly its own vertices.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"
#include "thinlod/simplifier/surface_error.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

const std::string kWusonDir = "/usr/share/assimp/models/X";

std::string writeWusonScene() {
  EXPECT_TRUE(std::filesystem::exists(kWusonDir + "/Testwuson.X"))
      << "deploy/setup installs the Debian package assimp-testmodels";
  const std::string path = scratchDir() + "/wuson.wrl";
  std::ofstream(path) << "#VRML V2.0 utf8\n"
                         "Inline { url \"Testwuson.X\" animation \"Wuson_Run\" }\n";
  return path;
}

// Fewer surface samples and poses than the service's defaults for the
// curve and the ladder's bounds under the clip: the tests check skins,
// credits and the guarantee, and must fit the sanitizer build's time limit
// (deploy/test-sanitize: Debug, ASan + UBSan, about 20x slower).
ServiceOptions wusonOptions() {
  ServiceOptions options;
  options.modelSearchPaths = {kWusonDir};
  options.sceneRoot = scratchDir();
  options.curveCacheDir = scratchDir() + "/curves";
  options.curve.error.samplesPerMesh = 4000;
  options.animatedError.maxPoses = 17;
  options.animatedError.surface.samplesPerMesh = 1500;
  return options;
}

TEST(SimplifierServiceSkinned, LevelsCarryTheirVerticesSkins) {
  const std::string path = writeWusonScene();
  SimplifierService service(wusonOptions());
  protocol::SimplifyRequest request = triangles(1, 1000);
  request.sourcePath = path;
  const protocol::SimplifyResult result = service.simplify(request);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  Result<codec::SkinnedMeshFrame> level =
      codec::decodeSkinnedMesh(result.mesh.data(), result.mesh.size());
  ASSERT_TRUE(level.ok()) << level.status().toString();
  ASSERT_EQ(level->skin.size(), level->mesh.vertexCount());
  EXPECT_LE(level->mesh.triangleCount(), 1000u);
  EXPECT_GT(level->mesh.triangleCount(), 0u);

  // The scene as the backbone and the frontend load it.
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {kWusonDir};
  Result<scene::Scene> loaded = scene::loadSceneFile(path, load);
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*loaded);
  ASSERT_TRUE(objects.ok());
  const scene::SkinnedAnimation& animation = *(*objects)[0].shape->geometry.animation;
  const IndexedMesh& full = *(*objects)[0].fullMesh;
  ASSERT_TRUE(anim::validateSkin(level->skin, level->mesh.vertexCount(),
                                 animation.palette.bones.size(), "level")
                  .ok());

  // Each level vertex is an input vertex (within Draco's quantization at the
  // level's bits: 8 bits for a coarse level is 0.34% of the largest side)
  // with that vertex's palette skin; deformed, it lands where that vertex does.
  const std::vector<glm::mat4> matrices = anim::paletteMatricesAt(
      animation.skeleton, animation.clip, animation.palette, 0.4, anim::ClipWrap::kLoop);
  std::vector<glm::vec3> levelDeformed(level->mesh.vertexCount());
  anim::deform(level->mesh.positions, level->skin, matrices, {}, levelDeformed);
  std::vector<glm::vec3> fullDeformed(full.vertexCount());
  anim::deform(full.positions, animation.palette.skin, matrices, {}, fullDeformed);
  const float diagonal = full.bounds().diagonal();
  std::size_t twoBone = 0;
  for (std::size_t v = 0; v < level->mesh.vertexCount(); ++v) {
    const anim::VertexSkin& got = level->skin[v];
    twoBone += got.rigid() ? 0 : 1;
    bool matched = false;
    for (std::size_t u = 0; u < full.vertexCount() && !matched; ++u) {
      if (glm::distance(full.positions[u], level->mesh.positions[v]) > 5e-3f * diagonal) continue;
      const anim::VertexSkin& want = animation.palette.skin[u];
      // Weights travel in 1/65535 steps.
      if (want.boneA != got.boneA ||
          (!want.rigid() && (want.boneB != got.boneB ||
                             std::fabs(want.weightB - got.weightB) > 0.5f / 65535.0f + 1e-7f)))
        continue;
      matched = glm::distance(fullDeformed[u], levelDeformed[v]) <= 1e-2f * diagonal;
    }
    ASSERT_TRUE(matched) << "level vertex " << v << " matches no input vertex and skin";
  }
  EXPECT_GT(twoBone, 0u);
}

// The accuracy a skinned object's level is credited (docs/animation.md,
// "Measured accuracy under motion"): measured under the clip
// (SimplifyResult::motionIncluded), against the reference sphere grown by
// the motion bound m, so its deformed error stays below (L + 2m) / a at
// every pose, here at 24 times of the clip that are not the bound's poses;
// and it is tighter than the bind-pose accuracy converted by the motion
// bound (anim::animatedRelativeAccuracy), which is all the backbone had
// before: 4-17x loose on this figure.
TEST(SimplifierServiceSkinned, LevelsKeepTheirMeasuredAccuracyAtEveryPose) {
  const std::string path = writeWusonScene();
  SimplifierService service(wusonOptions());
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {kWusonDir};
  Result<scene::Scene> loaded = scene::loadSceneFile(path, load);
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*loaded);
  ASSERT_TRUE(objects.ok());
  const scene::SkinnedAnimation& animation = *(*objects)[0].shape->geometry.animation;
  const IndexedMesh& full = *(*objects)[0].fullMesh;
  const double length = referenceLength(referenceSphere(full));
  const double ratio = 2.0 * animation.motionBound / length;
  SurfaceErrorOptions errorOptions;
  errorOptions.samplesPerMesh = 2000;
  for (const std::uint32_t count : {463u, 1866u}) {
    protocol::SimplifyRequest request = triangles(1, count);
    request.sourcePath = path;
    request.curvePoints = 8;
    const protocol::SimplifyResult result = service.simplify(request);
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    EXPECT_TRUE(result.motionIncluded);
    ASSERT_FALSE(result.curve.empty());
    for (std::size_t i = 1; i < result.curve.size(); ++i) {
      EXPECT_GT(result.curve[i].accuracy, result.curve[i - 1].accuracy);
      EXPECT_GT(result.curve[i].resources, result.curve[i - 1].resources);
    }
    Result<codec::SkinnedMeshFrame> level =
        codec::decodeSkinnedMesh(result.mesh.data(), result.mesh.size());
    ASSERT_TRUE(level.ok());
    IndexedMesh levelAtRest = level->mesh;
    levelAtRest.normals.clear();
    Result<SurfaceError> rest = measureSurfaceError(full, levelAtRest, errorOptions);
    ASSERT_TRUE(rest.ok()) << rest.status().toString();
    // The conversion of even this level's measured rest error (the credited
    // one is at least that) is far below what the clip's measurement gives.
    const double converted = anim::animatedRelativeAccuracy(length / rest->max(), ratio);
    EXPECT_GT(result.accuracy, 1.5 * converted) << count << " triangles";
    const double allowed = (length + 2.0 * animation.motionBound) / result.accuracy;
    IndexedMesh fullNow = full, levelNow = level->mesh;
    for (int i = 0; i < 24; ++i) {
      const double t = (0.013 + 0.0411 * i) * animation.clip.duration;
      const std::vector<glm::mat4> bones = anim::paletteMatricesAt(
          animation.skeleton, animation.clip, animation.palette, t, anim::ClipWrap::kLoop);
      anim::deform(full.positions, animation.palette.skin, bones, {}, fullNow.positions);
      anim::deform(level->mesh.positions, level->skin, bones, {}, levelNow.positions);
      fullNow.normals.clear();
      levelNow.normals.clear();
      Result<SurfaceError> error = measureSurfaceError(fullNow, levelNow, errorOptions);
      ASSERT_TRUE(error.ok()) << error.status().toString();
      EXPECT_LE(error->max(), allowed) << count << " triangles at t=" << t;
    }
  }
  // Once for both requests (from the cache directory when an earlier test
  // of this binary measured it).
  EXPECT_EQ(service.stats().animatedLaddersMeasured + service.stats().animatedLaddersFromDisk, 1u);
}

// The bounds are measured once per figure and clip: a second service on the
// same cache directory reads them and credits every rung the same; a file
// that does not parse is measured again and rewritten.
TEST(SimplifierServiceSkinned, LadderBoundsComeFromTheCacheDirectory) {
  const std::string path = writeWusonScene();
  ServiceOptions options = wusonOptions();
  options.curveCacheDir = scratchDir() + "/animated-cache-test";
  // Few poses and samples: this test is about the file, not the bound.
  options.animatedError.initialPoses = 3;
  options.animatedError.maxPoses = 5;
  options.animatedError.surface.samplesPerMesh = 500;
  std::filesystem::remove_all(options.curveCacheDir);
  protocol::SimplifyRequest request = triangles(1, 900);
  request.sourcePath = path;
  request.curvePoints = 16;
  SimplifierService first(options);
  const protocol::SimplifyResult measured = first.simplify(request);
  ASSERT_TRUE(measured.status.ok()) << measured.status.toString();
  EXPECT_EQ(first.stats().animatedLaddersMeasured, 1u);
  EXPECT_EQ(first.stats().animatedLaddersFromDisk, 0u);

  SimplifierService second(options);
  const protocol::SimplifyResult stored = second.simplify(request);
  ASSERT_TRUE(stored.status.ok()) << stored.status.toString();
  EXPECT_EQ(second.stats().animatedLaddersMeasured, 0u);
  EXPECT_EQ(second.stats().animatedLaddersFromDisk, 1u);
  EXPECT_EQ(stored.accuracy, measured.accuracy);
  ASSERT_EQ(stored.curve.size(), measured.curve.size());
  for (std::size_t i = 0; i < stored.curve.size(); ++i) {
    EXPECT_EQ(stored.curve[i].accuracy, measured.curve[i].accuracy);
    EXPECT_EQ(stored.curve[i].resources, measured.curve[i].resources);
  }

  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(options.curveCacheDir)) {
    if (entry.path().filename().string().rfind("animated-", 0) != 0) continue;
    ++files;
    std::ofstream(entry.path()) << "{\"format\": \"thinlod-animated-bounds\", \"bounds\": [";
  }
  EXPECT_EQ(files, 1);
  SimplifierService third(options);
  const protocol::SimplifyResult again = third.simplify(request);
  ASSERT_TRUE(again.status.ok()) << again.status.toString();
  EXPECT_EQ(third.stats().animatedLaddersMeasured, 1u);
  EXPECT_EQ(again.accuracy, measured.accuracy);  // deterministic measurement
}

// The daemon's cold start (answerBeforeCurve): a figure's first level is not
// held up by the ladder's measurement under the clip; it carries its
// bind-pose accuracy (motionIncluded false: the backbone converts it). The
// curve request measures the ladder, and later levels carry the measured one.
// --animated-accuracy=false never measures it.
TEST(SimplifierServiceSkinned, ColdAnswersDoNotWaitForTheClipsMeasurement) {
  const std::string path = writeWusonScene();
  ServiceOptions options = wusonOptions();
  options.curveCacheDir = scratchDir() + "/animated-cold-test";
  std::filesystem::remove_all(options.curveCacheDir);
  options.answerBeforeCurve = true;
  options.animatedError.initialPoses = 3;
  options.animatedError.maxPoses = 5;
  options.animatedError.surface.samplesPerMesh = 500;
  protocol::SimplifyRequest level = triangles(1, 900);
  level.sourcePath = path;
  SimplifierService service(options);
  const protocol::SimplifyResult cold = service.simplify(level);
  ASSERT_TRUE(cold.status.ok()) << cold.status.toString();
  EXPECT_FALSE(cold.motionIncluded);
  EXPECT_EQ(service.stats().animatedLaddersMeasured, 0u);
  EXPECT_EQ(service.stats().levelsMeasuredAlone, 1u);

  protocol::SimplifyRequest curve = level;
  curve.curvePoints = 8;
  const protocol::SimplifyResult measured = service.simplify(curve);
  ASSERT_TRUE(measured.status.ok()) << measured.status.toString();
  EXPECT_TRUE(measured.motionIncluded);
  EXPECT_EQ(service.stats().animatedLaddersMeasured, 1u);
  const protocol::SimplifyResult warm = service.simplify(level);
  EXPECT_TRUE(warm.motionIncluded);
  EXPECT_EQ(warm.accuracy, measured.accuracy);

  // A new worker on the same cache directory answers measured at once.
  SimplifierService second(options);
  const protocol::SimplifyResult stored = second.simplify(level);
  EXPECT_TRUE(stored.motionIncluded);
  EXPECT_EQ(stored.accuracy, measured.accuracy);
  EXPECT_EQ(second.stats().animatedLaddersMeasured, 0u);
  EXPECT_EQ(second.stats().animatedLaddersFromDisk, 1u);

  options.measureAnimatedAccuracy = false;
  SimplifierService off(options);
  const protocol::SimplifyResult converted = off.simplify(curve);
  ASSERT_TRUE(converted.status.ok());
  EXPECT_FALSE(converted.motionIncluded);
  EXPECT_EQ(off.stats().animatedLaddersMeasured + off.stats().animatedLaddersFromDisk, 0u);
}

TEST(SimplifierServiceSkinned, StaticObjectsStayUnskinned) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(triangles(kCow, 300));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  Result<codec::SkinnedMeshFrame> level =
      codec::decodeSkinnedMesh(result.mesh.data(), result.mesh.size());
  ASSERT_TRUE(level.ok());
  EXPECT_TRUE(level->skin.empty());
}

}  // namespace
}  // namespace thinlod::simplifier
