// Impostors of textured objects are captured with their base-colour texture
// (ImpostorScene::textures, drawn by the common renderer).
#include <gtest/gtest.h>

#include <memory>

#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

// A unit quad facing +z: left half of the texture red, right half blue.
ImpostorScene texturedQuad(bool withTexture) {
  auto mesh = std::make_shared<IndexedMesh>();
  mesh->positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  mesh->normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  mesh->uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  mesh->indices = {0, 1, 2, 0, 2, 3};
  ImpostorScene scene;
  ImpostorPart part;
  part.mesh = mesh;
  part.material.lit = false;
  part.material.diffuse = glm::vec4(1.0f);
  scene.parts.push_back(part);
  if (withTexture) {
    auto image = std::make_shared<RgbaImage>(8, 8);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        std::uint8_t* p = image->at(x, y);
        p[0] = x < 4 ? 255 : 0;
        p[1] = 0;
        p[2] = x < 4 ? 0 : 255;
        p[3] = 255;
      }
    }
    scene.textures.push_back(image);
  }
  return scene;
}

class ImpostorTextureTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto context = render::createOffscreenContext(render::Backend::kAuto, 16, 16);
    ASSERT_TRUE(context.ok()) << context.status().toString();
    context_ = std::move(context).value();
    auto impostors = ImpostorRenderer::create(*context_);
    ASSERT_TRUE(impostors.ok()) << impostors.status().toString();
    impostors_ = std::move(impostors).value();
  }
  void TearDown() override {
    impostors_.reset();
    context_.reset();
  }
  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<ImpostorRenderer> impostors_;
};

TEST_F(ImpostorTextureTest, TexturedPartsAreCapturedWithTheirTexture) {
  auto textured = impostors_->renderSimple(texturedQuad(true), glm::vec3(0, 0, 10));
  ASSERT_TRUE(textured.ok()) << textured.status().toString();
  const RgbaImage& t = textured->texture;
  // The quad fills the texture but its padding: left quarter red, right quarter blue.
  const std::uint8_t* left = t.at(t.width / 4, t.height / 2);
  const std::uint8_t* right = t.at(3 * t.width / 4, t.height / 2);
  EXPECT_EQ(left[3], 255);
  EXPECT_GT(left[0], 200);
  EXPECT_LT(left[2], 50);
  EXPECT_GT(right[2], 200);
  EXPECT_LT(right[0], 50);

  // Without the texture the same quad is the material's white.
  auto plain = impostors_->renderSimple(texturedQuad(false), glm::vec3(0, 0, 10));
  ASSERT_TRUE(plain.ok()) << plain.status().toString();
  const std::uint8_t* white = plain->texture.at(t.width / 4, t.height / 2);
  EXPECT_GT(white[0], 200);
  EXPECT_GT(white[2], 200);

  // The meshed impostor draws it the same way.
  auto meshed = impostors_->renderMeshed(texturedQuad(true), glm::vec3(0, 0, 10));
  ASSERT_TRUE(meshed.ok()) << meshed.status().toString();
  EXPECT_GT(meshed->texture.at(t.width / 4, t.height / 2)[0], 200);
  EXPECT_LT(meshed->texture.at(t.width / 4, t.height / 2)[2], 50);
}

TEST_F(ImpostorTextureTest, BadTexturesAreRefusedBeforeDrawing) {
  ImpostorScene noUvs = texturedQuad(true);
  auto mesh = std::make_shared<IndexedMesh>(*noUvs.parts[0].mesh);
  mesh->uvs.clear();
  noUvs.parts[0].mesh = mesh;
  auto refused = impostors_->renderSimple(noUvs, glm::vec3(0, 0, 10));
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("no uvs"), std::string::npos)
      << refused.status().message();

  ImpostorScene wrongCount = texturedQuad(true);
  wrongCount.textures.push_back(nullptr);
  auto count = impostors_->renderSimple(wrongCount, glm::vec3(0, 0, 10));
  ASSERT_FALSE(count.ok());
  EXPECT_NE(count.status().message().find("2 textures for 1 parts"), std::string::npos);

  ImpostorScene inconsistent = texturedQuad(true);
  auto broken = std::make_shared<RgbaImage>(4, 4);
  broken->pixels.resize(3);
  inconsistent.textures[0] = broken;
  EXPECT_FALSE(impostors_->renderSimple(inconsistent, glm::vec3(0, 0, 10)).ok());
}

}  // namespace
}  // namespace thinlod::simplifier
