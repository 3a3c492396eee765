// MeshRenderer: textures, depth test, lighting, alpha modes, batching, errors.
#include <cmath>
#include <vector>

#include "render_test_util.h"
#include "thinlod/common/render/mesh_batch.h"

namespace thinlod::render {
namespace {

using testing::backendParamName;
using testing::GlRig;
using testing::makeQuad;
using testing::makeRig;
using testing::orthoCamera;
using testing::pixelNear;
using testing::unlitColor;

class MeshRendererTest : public ::testing::TestWithParam<Backend> {
 protected:
  void SetUp() override { ASSERT_TRUE(makeRig(GetParam(), kSize, kSize, rig_)); }

  MeshHandle upload(const IndexedMesh& mesh, const std::vector<std::uint16_t>& layers = {}) {
    auto handle = rig_.renderer->uploadMesh(mesh, layers);
    EXPECT_TRUE(handle.ok()) << handle.status().toString();
    return handle.ok() ? *handle : MeshHandle{};
  }

  RgbaImage render(const std::vector<DrawItem>& items, const Lighting& lighting = {},
                   const glm::vec4& clear = glm::vec4(0.0f)) {
    RgbaImage image;
    Status status = rig_.renderer->beginFrame(*rig_.target, clear);
    if (status.ok()) status = rig_.renderer->draw(items, orthoCamera(), lighting);
    if (status.ok()) status = rig_.target->readColor(image);
    EXPECT_TRUE(status.ok()) << status.toString();
    return image;
  }

  static RgbaImage checkerImage() {  // texel (i, j-from-top) = (60 i, 60 j, 100, 255)
    RgbaImage image(4, 4);
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 4; ++i) {
        std::uint8_t* p = image.at(i, j);
        p[0] = static_cast<std::uint8_t>(60 * i);
        p[1] = static_cast<std::uint8_t>(60 * j);
        p[2] = 100;
        p[3] = 255;
      }
    }
    return image;
  }

  static constexpr int kSize = 64;
  GlRig rig_;
};

TEST_P(MeshRendererTest, TexturedQuadReproducesTexelsUpright) {
  TextureOptions nearest;
  nearest.linearFilter = false;
  auto texture = rig_.renderer->uploadTexture(checkerImage(), nearest);
  ASSERT_TRUE(texture.ok()) << texture.status().toString();
  Material material = unlitColor(1, 1, 1);
  material.texture = *texture;
  const RgbaImage image = render({{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material}});
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const int i = x / 16;
      const int j = y / 16;
      ASSERT_TRUE(pixelNear(image, x, y, 60 * i, 60 * j, 100, 255, 1));
    }
  }
}

TEST_P(MeshRendererTest, DepthTestHidesFartherQuadWhateverTheOrder) {
  const MeshHandle near = upload(makeQuad(-1, -1, 1, 1, 1.0f));
  const MeshHandle far = upload(makeQuad(-0.5f, -0.5f, 0.5f, 0.5f, -1.0f));
  const DrawItem green{near, glm::mat4(1.0f), unlitColor(0, 1, 0)};
  const DrawItem red{far, glm::mat4(1.0f), unlitColor(1, 0, 0)};
  for (const auto& items : {std::vector<DrawItem>{green, red}, std::vector<DrawItem>{red, green}}) {
    const RgbaImage image = render(items);
    EXPECT_TRUE(pixelNear(image, kSize / 2, kSize / 2, 0, 255, 0, 255, 1));
    EXPECT_TRUE(pixelNear(image, 2, 2, 0, 255, 0, 255, 1));
  }
}

TEST_P(MeshRendererTest, DirectionalLightFacingAddsToAmbient) {
  Material material;
  material.diffuse = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
  Lighting lighting;
  lighting.ambient = glm::vec3(0.2f);
  Light light;
  light.vector = glm::vec3(0, 0, -1);  // travels towards -z: hits the +z-facing quad head on
  light.color = glm::vec3(1.0f, 0.5f, 0.0f);
  lighting.lights = {light};
  const DrawItem item{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material};
  const RgbaImage lit = render({item}, lighting);
  // colour = diffuse * (ambient + light colour * cos 0) = 0.5 * (1.2, 0.7, 0.2)
  EXPECT_TRUE(pixelNear(lit, 20, 20, 153, 89, 26, 255, 2));

  lighting.lights[0].vector = glm::vec3(0, 0, 1);  // from behind: back face of the light
  const RgbaImage ambientOnly = render({item}, lighting);
  EXPECT_TRUE(pixelNear(ambientOnly, 20, 20, 26, 26, 26, 255, 2));
}

TEST_P(MeshRendererTest, PointLightFallsOffWithDistance) {
  Material material;
  material.diffuse = glm::vec4(1.0f);
  Lighting lighting;
  lighting.ambient = glm::vec3(0.0f);
  Light light;
  light.type = Light::Type::kPoint;
  light.vector = glm::vec3(0.0f, 0.0f, 1.0f);  // 1 m in front of the quad centre
  light.color = glm::vec3(1.0f);
  light.attenuation = 1.0f;
  lighting.lights = {light};
  const RgbaImage image =
      render({{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material}}, lighting);
  // Centre pixel (31.5 -> world x,y ~ -0.016): d^2 ~ 1, cos ~ 1: 1/(1+1) = 0.5.
  EXPECT_TRUE(pixelNear(image, kSize / 2, kSize / 2, 128, 128, 128, 255, 3));
  // Corner pixel: farther and more oblique, so darker.
  EXPECT_LT(image.at(0, 0)[0], image.at(kSize / 2, kSize / 2)[0] / 2);
}

TEST_P(MeshRendererTest, SpecularHighlightOnlyWhenTheMaterialHasOne) {
  Material material;
  material.diffuse = glm::vec4(0.5f, 0.5f, 0.5f, 1.0f);
  material.shininess = 32.0f;
  Lighting lighting;
  lighting.ambient = glm::vec3(0.0f);
  Light light;
  light.vector = glm::vec3(0, 0, -1);
  lighting.lights = {light};
  const MeshHandle quad = upload(makeQuad(-1, -1, 1, 1, 0));
  const RgbaImage matte = render({{quad, glm::mat4(1.0f), material}}, lighting);
  EXPECT_TRUE(pixelNear(matte, kSize / 2, kSize / 2, 128, 128, 128, 255, 2));
  // At the centre light, normal and eye (0,0,5) line up: the half vector is
  // the normal, so the specular term is specular * 1^shininess.
  material.specular = glm::vec3(0.3f, 0.0f, 0.0f);
  const RgbaImage shiny = render({{quad, glm::mat4(1.0f), material}}, lighting);
  EXPECT_TRUE(pixelNear(shiny, kSize / 2, kSize / 2, 204, 128, 128, 255, 3));
  // Off-centre the eye is oblique, so the highlight is weaker but not gone.
  EXPECT_GT(shiny.at(2, 2)[0], matte.at(2, 2)[0]);
  EXPECT_LT(shiny.at(2, 2)[0], shiny.at(kSize / 2, kSize / 2)[0]);
}

TEST_P(MeshRendererTest, LightsOfMixedTypesAddUpInEitherOrder) {
  Material material;
  material.diffuse = glm::vec4(1.0f);
  Lighting lighting;
  lighting.ambient = glm::vec3(0.0f);
  Light directional;
  directional.vector = glm::vec3(0, 0, -1);
  directional.color = glm::vec3(0.25f, 0.0f, 0.0f);
  Light point;
  point.type = Light::Type::kPoint;
  point.vector = glm::vec3(0.0f, 0.0f, 1.0f);
  point.color = glm::vec3(0.0f, 1.0f, 0.0f);
  point.attenuation = 1.0f;
  const DrawItem item{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material};
  for (const auto& lights :
       {std::vector<Light>{directional, point}, std::vector<Light>{point, directional}}) {
    lighting.lights = lights;
    const RgbaImage image = render({item}, lighting);
    // 0.25 red from the directional light; 1 / (1 + 1 * 1^2) = 0.5 green from the point light.
    EXPECT_TRUE(pixelNear(image, kSize / 2, kSize / 2, 64, 128, 0, 255, 3));
  }
}

TEST_P(MeshRendererTest, ItemsOfDifferentShaderVariantsKeepTheirOwnSettings) {
  IndexedMesh redVertices = makeQuad(0, -1, 1, 1, 0);
  redVertices.colors.assign(4, {255, 0, 0, 255});
  Material lit;
  lit.diffuse = glm::vec4(0.0f, 0.5f, 0.0f, 1.0f);
  Material unlitIgnoringVertexColours = unlitColor(0, 0, 1);  // useVertexColors is false
  Lighting lighting;
  lighting.ambient = glm::vec3(1.0f);
  const RgbaImage image =
      render({{upload(makeQuad(-1, -1, 0, 0, 0)), glm::mat4(1.0f), lit},
              {upload(redVertices), glm::mat4(1.0f), unlitIgnoringVertexColours},
              {upload(makeQuad(-1, 0, 0, 1, 0)), glm::mat4(1.0f), lit}},
             lighting);
  EXPECT_TRUE(pixelNear(image, 16, 48, 0, 128, 0, 255, 2));  // first lit quad (bottom left)
  EXPECT_TRUE(pixelNear(image, 48, 32, 0, 0, 255, 255, 1));  // unlit, vertex colours unused
  EXPECT_TRUE(pixelNear(image, 16, 16, 0, 128, 0, 255, 2));  // lit again after the switch
  EXPECT_EQ(rig_.renderer->stats().drawCalls, 3u);
}

TEST_P(MeshRendererTest, VertexColoursMultiplyDiffuse) {
  IndexedMesh quad = makeQuad(-1, -1, 1, 1, 0);
  quad.colors.assign(4, {255, 128, 0, 255});
  Material material = unlitColor(1.0f, 0.5f, 1.0f);
  material.useVertexColors = true;
  const RgbaImage image = render({{upload(quad), glm::mat4(1.0f), material}});
  EXPECT_TRUE(pixelNear(image, 10, 50, 255, 64, 0, 255, 2));
}

TEST_P(MeshRendererTest, AlphaMaskDiscardsTransparentTexels) {
  RgbaImage halfTransparent(2, 1);  // left texel opaque white, right texel alpha 0
  halfTransparent.pixels = {255, 255, 255, 255, 255, 255, 255, 0};
  TextureOptions nearest;
  nearest.linearFilter = false;
  auto texture = rig_.renderer->uploadTexture(halfTransparent, nearest);
  ASSERT_TRUE(texture.ok());
  Material material = unlitColor(1, 1, 1);
  material.texture = *texture;
  material.alphaMode = AlphaMode::kMask;
  const RgbaImage image = render({{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material}});
  EXPECT_TRUE(pixelNear(image, 10, 30, 255, 255, 255, 255, 1));
  EXPECT_TRUE(pixelNear(image, 50, 30, 0, 0, 0, 0, 0));
  // Masked fragments write no depth either: a farther quad shows through the hole.
  const MeshHandle behind = upload(makeQuad(-1, -1, 1, 1, -1.0f));
  const RgbaImage layered = render({{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), material},
                                    {behind, glm::mat4(1.0f), unlitColor(0, 0, 1)}});
  EXPECT_TRUE(pixelNear(layered, 50, 30, 0, 0, 255, 255, 1));
  EXPECT_TRUE(pixelNear(layered, 10, 30, 255, 255, 255, 255, 1));
}

TEST_P(MeshRendererTest, BlendedItemsMixOverOpaqueOnesDrawnLater) {
  Material glass = unlitColor(1, 0, 0, 0.25f);
  glass.alphaMode = AlphaMode::kBlend;
  // Blended item listed first: the renderer still draws opaque items first.
  const RgbaImage image =
      render({{upload(makeQuad(-1, -1, 1, 1, 1.0f)), glm::mat4(1.0f), glass},
              {upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), unlitColor(0, 0, 1)}});
  // 0.25 red over opaque blue; alpha: 0.25 + 1 * 0.75 = 1.
  EXPECT_TRUE(pixelNear(image, 32, 32, 64, 0, 191, 255, 2));
}

TEST_P(MeshRendererTest, BatchOfArrayLayersDrawsInOneCall) {
  auto array = rig_.renderer->createTextureArray(2, 2, 3);
  ASSERT_TRUE(array.ok()) << array.status().toString();
  const std::uint8_t colours[3][4] = {{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}};
  for (int layer = 0; layer < 3; ++layer) {
    RgbaImage image(2, 2);
    for (int p = 0; p < 4; ++p) {
      for (int c = 0; c < 4; ++c) image.pixels[p * 4 + c] = colours[layer][c];
    }
    ASSERT_TRUE(rig_.renderer->setTextureLayer(*array, layer, image).ok());
  }
  MeshBatch batch;
  const IndexedMesh unit = makeQuad(0, 0, 1, 1, 0);
  for (int layer = 0; layer < 3; ++layer) {  // three strips, left to right, with layers 2, 1, 0
    MeshBatch::Part part;
    part.model = glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f + 2.0f * layer / 3.0f, -1, 0)) *
                 glm::scale(glm::mat4(1.0f), glm::vec3(2.0f / 3.0f, 2.0f, 1.0f));
    part.textureLayer = 2 - layer;
    ASSERT_TRUE(batch.append(unit, part, "strip").ok());
  }
  const MeshHandle merged = upload(batch.mesh(), batch.textureLayers());
  Material material = unlitColor(1, 1, 1);
  material.texture = *array;
  const RgbaImage image = render({{merged, glm::mat4(1.0f), material}});
  EXPECT_EQ(rig_.renderer->stats().drawCalls, 1u);
  EXPECT_EQ(rig_.renderer->stats().textureBinds, 1u);
  EXPECT_EQ(rig_.renderer->stats().triangles, 6u);
  EXPECT_TRUE(pixelNear(image, 10, 32, 0, 0, 255, 255, 1));
  EXPECT_TRUE(pixelNear(image, 32, 32, 0, 255, 0, 255, 1));
  EXPECT_TRUE(pixelNear(image, 54, 32, 255, 0, 0, 255, 1));
}

TEST_P(MeshRendererTest, SmallerImageInLayerCoversItsUvCorner) {
  auto array = rig_.renderer->createTextureArray(4, 4, 1, TextureOptions{false, false, true});
  ASSERT_TRUE(array.ok());
  RgbaImage image(2, 1);  // top row: left red, right green
  image.pixels = {255, 0, 0, 255, 0, 255, 0, 255};
  ASSERT_TRUE(rig_.renderer->setTextureLayer(*array, 0, image).ok());
  IndexedMesh quad = makeQuad(-1, -1, 1, 1, 0);
  for (auto& uv : quad.uvs) uv *= glm::vec2(0.5f, 0.25f);  // the 2x1 corner of the 4x4 layer
  Material material = unlitColor(1, 1, 1);
  material.texture = *array;
  const RgbaImage out = render({{upload(quad), glm::mat4(1.0f), material}});
  EXPECT_TRUE(pixelNear(out, 16, 32, 255, 0, 0, 255, 1));
  EXPECT_TRUE(pixelNear(out, 48, 32, 0, 255, 0, 255, 1));
}

TEST_P(MeshRendererTest, UpdateMeshReplacesGeometry) {
  const MeshHandle mesh = upload(makeQuad(-1, -1, 0, 1, 0));                    // left half
  ASSERT_TRUE(rig_.renderer->updateMesh(mesh, makeQuad(0, -1, 1, 1, 0)).ok());  // right half
  const RgbaImage image = render({{mesh, glm::mat4(1.0f), unlitColor(1, 1, 0)}});
  EXPECT_TRUE(pixelNear(image, 10, 32, 0, 0, 0, 0, 0));
  EXPECT_TRUE(pixelNear(image, 54, 32, 255, 255, 0, 255, 1));
}

TEST_P(MeshRendererTest, BackFacesCulledOnlyWhenSingleSided) {
  IndexedMesh clockwise = makeQuad(-1, -1, 1, 1, 0);
  clockwise.indices = {0, 2, 1, 0, 3, 2};
  const MeshHandle mesh = upload(clockwise);
  Material material = unlitColor(1, 1, 1);
  EXPECT_TRUE(
      pixelNear(render({{mesh, glm::mat4(1.0f), material}}), 32, 32, 255, 255, 255, 255, 1));
  material.doubleSided = false;
  EXPECT_TRUE(pixelNear(render({{mesh, glm::mat4(1.0f), material}}), 32, 32, 0, 0, 0, 0, 0));
}

TEST_P(MeshRendererTest, DrawBeforeBeginFrameIsRejected) {
  const DrawItem item{upload(makeQuad(-1, -1, 1, 1, 0)), glm::mat4(1.0f), unlitColor(1, 1, 1)};
  Status status = rig_.renderer->draw(&item, 1, orthoCamera(), {});
  EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(status.message().find("beginFrame"), std::string::npos);
}

TEST_P(MeshRendererTest, DeletedAndUnknownHandlesAreNotFound) {
  const MeshHandle mesh = upload(makeQuad(-1, -1, 1, 1, 0));
  rig_.renderer->deleteMesh(mesh);
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  DrawItem item{mesh, glm::mat4(1.0f), unlitColor(1, 1, 1)};
  EXPECT_EQ(rig_.renderer->draw(&item, 1, orthoCamera(), {}).code(), ErrorCode::kNotFound);
  item.mesh = upload(makeQuad(-1, -1, 1, 1, 0));
  item.material.texture = TextureHandle{9999};
  EXPECT_EQ(rig_.renderer->draw(&item, 1, orthoCamera(), {}).code(), ErrorCode::kNotFound);
  EXPECT_EQ(rig_.renderer->updateMesh(mesh, makeQuad(0, 0, 1, 1, 0)).code(), ErrorCode::kNotFound);
}

TEST_P(MeshRendererTest, InvalidDrawInputsAreRejectedBeforeDrawing) {
  const MeshHandle mesh = upload(makeQuad(-1, -1, 1, 1, 0));
  ASSERT_TRUE(rig_.renderer->beginFrame(*rig_.target, glm::vec4(0.0f)).ok());
  Lighting tooMany;
  tooMany.lights.resize(kMaxLights + 1);
  DrawItem item{mesh, glm::mat4(1.0f), unlitColor(1, 1, 1)};
  EXPECT_EQ(rig_.renderer->draw(&item, 1, orthoCamera(), tooMany).code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(rig_.renderer->prepare(Material(), false, tooMany).code(), ErrorCode::kInvalidArgument);
  Lighting two;
  two.lights.resize(2);
  EXPECT_TRUE(rig_.renderer->prepare(Material(), true, two).ok());
  auto texture = rig_.renderer->uploadTexture(checkerImage());
  ASSERT_TRUE(texture.ok());
  item.material.texture = *texture;
  item.material.textureLayer = 1;  // a 1-layer texture
  EXPECT_EQ(rig_.renderer->draw(&item, 1, orthoCamera(), {}).code(), ErrorCode::kInvalidArgument);
  item.material.textureLayer = 0;
  item.model[3][0] = std::nanf("");
  // The valid first item must not be drawn when the second is bad.
  const DrawItem valid{mesh, glm::mat4(1.0f), unlitColor(1, 1, 1)};
  const std::vector<DrawItem> items = {valid, item};
  EXPECT_EQ(rig_.renderer->draw(items, orthoCamera(), {}).code(), ErrorCode::kInvalidArgument);
  RgbaImage image;
  ASSERT_TRUE(rig_.target->readColor(image).ok());
  EXPECT_TRUE(pixelNear(image, 32, 32, 0, 0, 0, 0, 0));
}

TEST_P(MeshRendererTest, InvalidUploadsAreRejected) {
  IndexedMesh bad = makeQuad(-1, -1, 1, 1, 0);
  bad.indices[4] = 17;
  auto mesh = rig_.renderer->uploadMesh(bad);
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(mesh.status().message().find("vertex 17"), std::string::npos);
  EXPECT_EQ(rig_.renderer->uploadMesh(makeQuad(0, 0, 1, 1, 0), {1, 2}).status().code(),
            ErrorCode::kInvalidArgument);
  RgbaImage inconsistent(4, 4);
  inconsistent.pixels.pop_back();
  EXPECT_EQ(rig_.renderer->uploadTexture(inconsistent).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(rig_.renderer->createTextureArray(0, 4, 1).status().code(),
            ErrorCode::kInvalidArgument);
  auto array = rig_.renderer->createTextureArray(4, 4, 2);
  ASSERT_TRUE(array.ok());
  EXPECT_EQ(rig_.renderer->setTextureLayer(*array, 2, RgbaImage(4, 4)).code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(rig_.renderer->setTextureLayer(*array, 0, RgbaImage(8, 4)).code(),
            ErrorCode::kInvalidArgument);
}

TEST_P(MeshRendererTest, EmptyMeshDrawsNothing) {
  const MeshHandle empty = upload(IndexedMesh());
  const RgbaImage image = render({{empty, glm::mat4(1.0f), unlitColor(1, 1, 1)}});
  EXPECT_TRUE(pixelNear(image, 32, 32, 0, 0, 0, 0, 0));
  EXPECT_EQ(rig_.renderer->stats().drawCalls, 0u);
}

INSTANTIATE_TEST_SUITE_P(Backends, MeshRendererTest,
                         ::testing::Values(Backend::kEgl, Backend::kOsMesa), backendParamName);

}  // namespace
}  // namespace thinlod::render
