// loadFrontendScene: the reference objects carry the scene's textures.
#include "scene_setup.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace thinlod::frontend::daemon {
namespace {

// From the Debian package assimp-testmodels (deploy/setup installs it); a
// missing file fails the test, naming the package.
const std::string kBoxTextured = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";

TEST(FrontendScene, ReferenceObjectsCarryTheirDecodedBaseColourTexture) {
  ASSERT_TRUE(std::filesystem::is_regular_file(kBoxTextured))
      << kBoxTextured << " is missing: install assimp-testmodels (deploy/setup does)";
  Result<LoadedScene> loaded = loadFrontendScene(kBoxTextured, "");
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  EXPECT_EQ(loaded->textures, 1u);
  for (const std::string& w : loaded->warnings) {
    EXPECT_EQ(w.find("untextured"), std::string::npos) << w;
  }
  ASSERT_EQ(loaded->reference.size(), 1u);
  const ReferenceObject& box = loaded->reference[0].object;
  ASSERT_NE(box.texture, nullptr);
  EXPECT_GT(box.texture->width, 0);
  EXPECT_GT(box.texture->height, 0);
  EXPECT_TRUE(box.texture->consistent());
  ASSERT_NE(box.mesh, nullptr);
  EXPECT_EQ(box.mesh->uvs.size(), box.mesh->vertexCount());
}

TEST(FrontendScene, TheUntexturedPaperRoomHasNoTextures) {
  Result<LoadedScene> loaded =
      loadFrontendScene(std::string(THINLOD_SOURCE_DIR) + "/deploy/data/paper-room.wrl",
                        std::string(THINLOD_SHARED_DIR) + "/models");
  ASSERT_TRUE(loaded.ok()) << loaded.status().toString();
  EXPECT_EQ(loaded->textures, 0u);
  for (const ReferenceItem& item : loaded->reference) EXPECT_EQ(item.object.texture, nullptr);
}

}  // namespace
}  // namespace thinlod::frontend::daemon
