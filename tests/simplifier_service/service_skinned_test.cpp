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

ServiceOptions wusonOptions() {
  ServiceOptions options;
  options.modelSearchPaths = {kWusonDir};
  options.sceneRoot = scratchDir();
  options.curveCacheDir = scratchDir() + "/curves";
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

// The validity under motion the backbone credits (docs/animation.md,
// "Served"): a level credited relative accuracy a at rest keeps
// anim::animatedRelativeAccuracy(a, 2m / L) against the sphere grown by the
// motion bound m, i.e. its deformed error stays below L / a + 2m at every
// pose, here at 24 times of the clip that are not the bound's samples.
TEST(SimplifierServiceSkinned, LevelsKeepTheirAnimatedAccuracyAtEveryPose) {
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
    const protocol::SimplifyResult result = service.simplify(request);
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    Result<codec::SkinnedMeshFrame> level =
        codec::decodeSkinnedMesh(result.mesh.data(), result.mesh.size());
    ASSERT_TRUE(level.ok());
    const double moving = anim::animatedRelativeAccuracy(result.accuracy, ratio);
    const double allowed = (length + 2.0 * animation.motionBound) / moving;
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
