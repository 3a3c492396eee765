// BackboneCore's shared textures (docs/protocol.md, "Shared textures"): a
// textured object's mesh copies name the texture, which travels once per
// frontend session, again after a refused update, and is counted on the link.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "backbone_core.h"
#include "fake_simplifier.h"
#include "scene_textures.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/protocol/codec.h"

namespace thinlod::backbone_daemon {
namespace {

using namespace testing;

const glm::vec3 kEntrance(2.0f, 1.1f, 3.5f);
const glm::vec3 kCow(2.0f, 0.3f, 0.55f);

// Objects 1 and 2 (the spheres) share texture 1.
SceneTextures twoSpheresTextured() {
  SceneTextures textures;
  protocol::SharedTexture t;
  t.textureId = 1;
  t.texture.codec = protocol::TextureCodec::kPng;
  t.texture.width = 8;
  t.texture.height = 8;
  t.texture.data.assign(700, 0x33);
  textures.textures.push_back(t);
  textures.objectTexture = {1, 1, 0, 0};
  return textures;
}

std::size_t texturedOps(const protocol::SceneUpdate& update) {
  std::size_t n = 0;
  for (const auto& op : update.operations) n += op.representation.textureId == 1 ? 1 : 0;
  return n;
}

TEST(BackboneSharedTextures, SentOnceWithTheFirstCopyThatNamesIt) {
  auto created = paperRoomCore(polygonBudget(400));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  BackboneCore& core = **created;
  ASSERT_TRUE(core.setSharedTextures(twoSpheresTextured()).ok());
  FakeSimplifier fake(core);
  answer(core, fake, submitAll(core));  // the cow's curve

  std::size_t carried = 0;
  std::size_t named = 0;
  std::uint64_t carryingPlan = 0;
  std::vector<std::uint64_t> plansSinceCarrying;  // what a frontend without it would refuse
  for (int step = 0; step < 6; ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(core, fake, submitAll(core));
    PoseOutcome outcome = core.finishPose();
    EXPECT_TRUE(protocol::validate(protocol::Message(outcome.update)).ok());
    for (const auto& op : outcome.update.operations) {
      if (op.type != protocol::SceneOperation::Type::kAddOrReplace) continue;
      const bool sphere = op.objectId == 1 || op.objectId == 2;
      const bool mesh = op.representation.kind == protocol::RepresentationKind::kMesh;
      EXPECT_EQ(op.representation.textureId, sphere && mesh ? 1u : 0u) << "object " << op.objectId;
    }
    named += texturedOps(outcome.update);
    if (carryingPlan != 0 || !outcome.update.textures.empty())
      plansSinceCarrying.push_back(outcome.update.plan);
    if (!outcome.update.textures.empty()) {
      ASSERT_EQ(outcome.update.textures.size(), 1u);
      EXPECT_GT(texturedOps(outcome.update), 0u);  // only with a copy that names it
      // Its bytes count on the link like the meshes'.
      std::size_t meshBytes = 0;
      for (const auto& op : outcome.update.operations) meshBytes += op.representation.mesh.size();
      EXPECT_GE(outcome.linkBytes, meshBytes + 700u);
      carryingPlan = outcome.update.plan;
      ++carried;
    }
  }
  ASSERT_GT(named, 0u) << "no sphere mesh was sent";
  EXPECT_EQ(carried, 1u);
  EXPECT_EQ(core.texturesAtFrontend(), 1u);

  // The frontend refused the update that carried it (and so every later one
  // naming it): it goes again with the next copy.
  protocol::FrameStats stats;
  stats.plan = carryingPlan - 1;
  stats.rejectedPlans = plansSinceCarrying;
  core.onFrameStats(stats);
  EXPECT_EQ(core.texturesAtFrontend(), 0u);
  bool resent = false;
  for (int step = 6; step < 12 && !resent; ++step) {
    ASSERT_TRUE(core.beginPose(poseAt(step, step * 0.5, kEntrance, kCow)).ok());
    answer(core, fake, submitAll(core));
    PoseOutcome outcome = core.finishPose();
    resent = !outcome.update.textures.empty();
  }
  EXPECT_TRUE(resent);

  // A new frontend session holds nothing.
  core.resetFrontend();
  EXPECT_EQ(core.texturesAtFrontend(), 0u);
}

TEST(BackboneSharedTextures, TexturesThatDoNotFitTheSceneAreRefused) {
  auto created = paperRoomCore(polygonBudget(400));
  ASSERT_TRUE(created.ok()) << created.status().toString();
  SceneTextures wrongCount = twoSpheresTextured();
  wrongCount.objectTexture.pop_back();
  EXPECT_FALSE((*created)->setSharedTextures(wrongCount).ok());
  SceneTextures badId = twoSpheresTextured();
  badId.objectTexture[3] = 2;
  const Status status = (*created)->setSharedTextures(badId);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("texture 2 of 1"), std::string::npos) << status.message();
  SceneTextures badNumbering = twoSpheresTextured();
  badNumbering.textures[0].textureId = 4;
  EXPECT_FALSE((*created)->setSharedTextures(badNumbering).ok());
}

// loadSceneTextures: one shared texture per file, only for objects with uvs,
// failures as warnings.
TEST(BackboneSharedTextures, SceneTexturesLoadOncePerFileAndWarnOnBadFiles) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "thinlod-backbone-scene-textures";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file("/usr/share/assimp/models/glTF2/BoxTextured-glTF/CesiumLogoFlat.png",
                             dir / "logo.png");
  std::ofstream(dir / "broken.png") << "not a png at all";
  std::ofstream(dir / "scene.wrl") << R"(#VRML V2.0 utf8
Shape { appearance Appearance { texture DEF LOGO ImageTexture { url "logo.png" } } geometry Box {} }
Transform { translation 3 0 0 children Shape { appearance Appearance { texture USE LOGO } geometry Sphere {} } }
Transform { translation 6 0 0 children Shape { appearance Appearance { texture ImageTexture { url "broken.png" } } geometry Box {} } }
Transform { translation 9 0 0 children Shape { geometry Box {} } }
)";
  Result<scene::Scene> scene = scene::loadSceneFile((dir / "scene.wrl").string());
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*scene);
  ASSERT_TRUE(objects.ok()) << objects.status().toString();
  ASSERT_EQ(objects->size(), 4u);
  const SceneTextures textures = loadSceneTextures(*objects);
  ASSERT_EQ(textures.textures.size(), 1u);
  EXPECT_EQ(textures.objectTexture, (std::vector<std::uint64_t>{1, 1, 0, 0}));
  const protocol::SharedTexture& logo = textures.textures[0];
  EXPECT_EQ(logo.textureId, 1u);
  EXPECT_GT(logo.texture.width, 0u);
  // The frame decodes to the file's pixels (lossless).
  Result<RgbaImage> decoded = codec::decodeTexture(logo.texture.data.data(), logo.texture.data.size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  Result<RgbaImage> file = codec::readImageFile((dir / "logo.png").string());
  ASSERT_TRUE(file.ok());
  EXPECT_EQ(decoded->pixels, file->pixels);
  ASSERT_EQ(textures.warnings.size(), 1u);
  EXPECT_NE(textures.warnings[0].find("broken.png"), std::string::npos) << textures.warnings[0];
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace thinlod::backbone_daemon
