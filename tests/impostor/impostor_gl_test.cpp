// Simple and meshed impostors rendered offscreen (EGL, the default back-end).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>

#include "impostor_test_util.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

using testing::makeSphere;

class ImpostorTest : public ::testing::Test {
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

  static ImpostorScene sphereScene(float radius, const glm::vec3& center = glm::vec3(0.0f),
                                   const glm::vec4& colour = glm::vec4(0.8f, 0.8f, 0.8f, 1.0f)) {
    ImpostorScene scene;
    ImpostorPart part;
    part.mesh = makeSphere(radius);
    part.model = glm::translate(glm::mat4(1.0f), center);
    part.material.diffuse = colour;
    scene.parts.push_back(part);
    render::Light light;
    light.vector = glm::vec3(-0.3f, -0.5f, -1.0f);
    scene.lighting.lights.push_back(light);
    return scene;
  }

  static double alphaCoverage(const RgbaImage& image) {
    std::size_t covered = 0;
    for (std::size_t i = 3; i < image.pixels.size(); i += 4) covered += image.pixels[i] > 0;
    return static_cast<double>(covered) / (image.pixels.size() / 4);
  }

  std::unique_ptr<render::OffscreenContext> context_;
  std::unique_ptr<ImpostorRenderer> impostors_;
};

// Sphere of radius 1 seen from 10 m: a disc of angular radius asin(0.1).
TEST_F(ImpostorTest, SphereImpostorHasOpaqueObjectAndTransparentBackground) {
  auto impostor = impostors_->renderSimple(sphereScene(1.0f), glm::vec3(0, 0, 10));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const RgbaImage& t = impostor->texture;
  ASSERT_EQ(t.width, 256);
  ASSERT_EQ(t.height, 256);
  EXPECT_GT(impostor->coverage, 0.5);
  EXPECT_EQ(t.at(128, 128)[3], 255);
  for (auto [x, y] : {std::pair{0, 0}, {255, 0}, {0, 255}, {255, 255}, {10, 10}}) {
    EXPECT_EQ(t.at(x, y)[3], 0) << x << "," << y;
  }
  // Transparent texels next to the sphere carry its colour (no dark fringe when filtered).
  int bled = 0;
  for (int y = 1; y < 255; ++y) {
    for (int x = 1; x < 255; ++x) {
      if (t.at(x, y)[3] != 0 || t.at(x + 1, y)[3] == 0) continue;
      EXPECT_GT(t.at(x, y)[0], 0) << x << "," << y;
      ++bled;
    }
  }
  EXPECT_GT(bled, 50);
  // The one-pixel padding keeps the border rows and columns empty.
  for (int i = 0; i < 256; ++i) {
    EXPECT_EQ(t.at(i, 0)[3], 0);
    EXPECT_EQ(t.at(0, i)[3], 0);
    EXPECT_EQ(t.at(i, 255)[3], 0);
    EXPECT_EQ(t.at(255, i)[3], 0);
  }
}

TEST_F(ImpostorTest, AlphaCoverageMatchesProjectedDiscArea) {
  auto impostor = impostors_->renderSimple(sphereScene(1.0f), glm::vec3(0, 0, 10));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  // The plane through the centre (mid depth): disc radius D tan(asin(r / D)).
  const double D = 10.0;
  const double discRadius = D * std::tan(std::asin(1.0 / D));
  const double expected =
      3.14159265358979 * discRadius * discRadius / (impostor->quad.width * impostor->quad.height);
  const double measured = alphaCoverage(impostor->texture);
  EXPECT_NEAR(measured, expected, 0.02 * expected) << "expected " << expected;
  EXPECT_NEAR(impostor->coverage, measured, 1e-12);
}

TEST_F(ImpostorTest, QuadMatchesProjectedSphereAndFacesViewpoint) {
  auto impostor = impostors_->renderSimple(sphereScene(1.0f), glm::vec3(0, 0, 10));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const ImpostorQuad& q = impostor->quad;
  const double discRadius = 10.0 * std::tan(std::asin(0.1));
  const double padded = 2.0 * discRadius * 256.0 / 254.0;  // one empty pixel each side
  // The tessellated sphere is inscribed: up to ~0.2% smaller than the true one.
  EXPECT_NEAR(q.width, padded, 0.005 * padded);
  EXPECT_NEAR(q.height, padded, 0.005 * padded);
  EXPECT_NEAR(glm::length(q.center), 0.0f, 0.01f);
  EXPECT_NEAR(q.normal.z, 1.0f, 1e-5f);
  EXPECT_NEAR(q.up.y, 1.0f, 1e-5f);
  EXPECT_NEAR(q.right.x, 1.0f, 1e-5f);
}

TEST_F(ImpostorTest, OffCentreObjectIsFramedAndKeepsTopUp) {
  // Red sphere above a blue one, both away from the origin, seen from the side.
  ImpostorScene scene = sphereScene(0.5f, glm::vec3(3.0f, 2.0f, -1.0f), glm::vec4(1, 0, 0, 1));
  ImpostorScene blue = sphereScene(0.5f, glm::vec3(3.0f, 0.8f, -1.0f), glm::vec4(0, 0, 1, 1));
  scene.parts.push_back(blue.parts[0]);
  scene.lighting.ambient = glm::vec3(1.0f);
  scene.lighting.lights.clear();
  auto impostor = impostors_->renderSimple(scene, glm::vec3(12.0f, 1.4f, -1.0f));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const RgbaImage& t = impostor->texture;
  // The pair fills the texture vertically: 2.2 m tall, 1 m wide.
  EXPECT_NEAR(impostor->quad.height / impostor->quad.width, 2.2, 0.05);
  EXPECT_NEAR(impostor->quad.center.y, 1.4f, 0.02f);
  EXPECT_GT(t.at(128, 40)[0], 200);  // top: red
  EXPECT_LT(t.at(128, 40)[2], 50);
  EXPECT_GT(t.at(128, 215)[2], 200);  // bottom: blue
  EXPECT_LT(t.at(128, 215)[0], 50);
  // The quad faces the viewpoint.
  EXPECT_NEAR(impostor->quad.normal.x, 1.0f, 1e-3f);
}

// Drawing the textured quad from the capture viewpoint reproduces the object.
TEST_F(ImpostorTest, QuadSeenFromViewpointReproducesTheObject) {
  const ImpostorScene scene = sphereScene(1.0f, glm::vec3(0.5f, -0.2f, 0.3f));
  const glm::vec3 eye(2.0f, 1.0f, 9.0f);
  auto impostor = impostors_->renderSimple(scene, eye);
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  render::MeshRenderer& renderer = impostors_->meshRenderer();
  auto target = render::RenderTarget::create(*context_, 128, 128);
  ASSERT_TRUE(target.ok());
  render::Camera camera;
  camera.view = glm::lookAt(eye, glm::vec3(0.5f, -0.2f, 0.3f), glm::vec3(0, 1, 0));
  camera.projection = glm::perspective(glm::radians(20.0f), 1.0f, 1.0f, 30.0f);

  auto sphere = renderer.uploadMesh(*scene.parts[0].mesh);
  ASSERT_TRUE(sphere.ok());
  ASSERT_TRUE(renderer.beginFrame(**target, glm::vec4(0.0f)).ok());
  render::DrawItem object{*sphere, scene.parts[0].model, scene.parts[0].material};
  ASSERT_TRUE(renderer.draw(&object, 1, camera, scene.lighting).ok());
  RgbaImage direct;
  ASSERT_TRUE((*target)->readColor(direct).ok());

  auto texture = renderer.uploadTexture(impostor->texture);
  auto quad = renderer.uploadMesh(impostor->quad.mesh());
  ASSERT_TRUE(texture.ok() && quad.ok());
  render::Material material;
  material.lit = false;
  material.diffuse = glm::vec4(1.0f);
  material.texture = *texture;
  material.alphaMode = render::AlphaMode::kMask;
  ASSERT_TRUE(renderer.beginFrame(**target, glm::vec4(0.0f)).ok());
  render::DrawItem billboard{*quad, glm::mat4(1.0f), material};
  ASSERT_TRUE(renderer.draw(&billboard, 1, camera, {}).ok());
  RgbaImage viaImpostor;
  ASSERT_TRUE((*target)->readColor(viaImpostor).ok());

  // Compare: same coverage except along the rim, colours close inside.
  int differentCoverage = 0;
  int covered = 0;
  double colourError = 0.0;
  int compared = 0;
  for (int y = 0; y < 128; ++y) {
    for (int x = 0; x < 128; ++x) {
      const bool a = direct.at(x, y)[3] > 0;
      const bool b = viaImpostor.at(x, y)[3] > 0;
      covered += a;
      differentCoverage += a != b;
      if (a && b) {
        for (int c = 0; c < 3; ++c)
          colourError += std::abs(direct.at(x, y)[c] - viaImpostor.at(x, y)[c]);
        compared += 3;
      }
    }
  }
  ASSERT_GT(covered, 1000);
  EXPECT_LT(differentCoverage, covered / 20) << "coverage differs on " << differentCoverage;
  EXPECT_LT(colourError / compared, 6.0) << "mean colour error (of 255)";
}

TEST_F(ImpostorTest, ValidityContainsViewpointAndExcludesFarOffAxis) {
  const glm::vec3 eye(0, 0, 10);
  ImpostorOptions options;
  options.maxAngularError = 2e-3;
  auto impostor = impostors_->renderSimple(sphereScene(1.0f), eye, options);
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const ConicRange& range = impostor->validity;
  EXPECT_NEAR(glm::length(range.center()), 0.0, 1e-3);
  EXPECT_NEAR(range.direction().z, 1.0, 1e-5);
  EXPECT_TRUE(range.containsPoint(glm::dvec3(eye)));
  EXPECT_GT(range.alpha(), 0.0);
  EXPECT_LT(range.alpha(), 0.05);  // parallax over a 2 m deep object: a small cone
  EXPECT_EQ(impostorErrorBound(impostor->framing, impostor->errorModel, eye), 0.0);
  const glm::vec3 offAxis(10.0f * std::sin(0.5f), 0.0f, 10.0f * std::cos(0.5f));
  EXPECT_FALSE(range.containsPoint(glm::dvec3(offAxis)));
  EXPECT_GT(impostorErrorBound(impostor->framing, impostor->errorModel, offAxis),
            options.maxAngularError);
  // Just inside the cone's side the bound holds.
  const float inside = 0.99f * static_cast<float>(range.alpha());
  const glm::vec3 edge(10.0f * std::sin(inside), 0.0f, 10.0f * std::cos(inside));
  EXPECT_TRUE(range.containsPoint(glm::dvec3(edge)));
  EXPECT_LE(impostorErrorBound(impostor->framing, impostor->errorModel, edge),
            options.maxAngularError);
}

TEST_F(ImpostorTest, MeshedSphereVerticesLieOnTheSurface) {
  auto impostor = impostors_->renderMeshed(sphereScene(1.0f), glm::vec3(0, 0, 10));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const IndexedMesh& mesh = impostor->mesh;
  ASSERT_TRUE(mesh.validate("depth mesh").ok());
  // 256 / 4 grid over a disc covering ~75% of the texture: thousands of triangles.
  EXPECT_GT(mesh.triangleCount(), 4000u);
  float worst = 0.0f;
  for (const glm::vec3& p : mesh.positions) {
    worst = std::max(worst, std::fabs(glm::length(p) - 1.0f));
    EXPECT_GT(p.z, -0.05f) << "only the front half is visible from +z";
  }
  // Tessellation sagitta (0.0012) plus depth resolution.
  EXPECT_LT(worst, 0.004f);
  ASSERT_EQ(mesh.uvs.size(), mesh.positions.size());
  for (const glm::vec2& uv : mesh.uvs) {  // every vertex samples a covered texel
    const int x = std::clamp(static_cast<int>(uv.x * 256.0f), 0, 255);
    const int y = std::clamp(static_cast<int>((1.0f - uv.y) * 256.0f), 0, 255);
    ASSERT_GT(impostor->texture.at(x, y)[3], 0);
  }
  for (const glm::vec3& n : mesh.normals) EXPECT_GT(n.z, 0.0f);  // facing the viewpoint side
  // Measured along view rays, the error peaks at the rim: a 4-pixel cell is
  // c = 0.034 m wide there, and the chord from the rim to 4 px inside misses the
  // sphere by sqrt(r^2 - (r - c/2)^2) - sqrt(r^2 - (r - c)^2) / 2 ~ 0.054 m.
  EXPECT_LT(impostor->meshDepthError, 0.06);
  EXPECT_GT(impostor->meshDepthError, 0.0);
  EXPECT_LT(impostor->uncoveredFraction, 0.05);
}

TEST_F(ImpostorTest, MeshedTrianglesNeverSpanTheGapBetweenParts) {
  // A small sphere 1.5 m in front of a big one, overlapping it in the image.
  ImpostorScene scene = sphereScene(1.0f);
  const glm::vec3 frontCentre(0.6f, 0.2f, 2.5f);
  scene.parts.push_back(sphereScene(0.4f, frontCentre).parts[0]);
  auto impostor = impostors_->renderMeshed(scene, glm::vec3(0, 0, 10));
  ASSERT_TRUE(impostor.ok()) << impostor.status().toString();
  const IndexedMesh& mesh = impostor->mesh;
  auto onFront = [&](const glm::vec3& p) {
    return std::fabs(glm::length(p - frontCentre) - 0.4f) < std::fabs(glm::length(p) - 1.0f);
  };
  int front = 0;
  for (const glm::vec3& p : mesh.positions) {
    const float distance = onFront(p) ? std::fabs(glm::length(p - frontCentre) - 0.4f)
                                      : std::fabs(glm::length(p) - 1.0f);
    ASSERT_LT(distance, 0.01f);
    front += onFront(p);
  }
  EXPECT_GT(front, 100);
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const bool a = onFront(mesh.positions[mesh.indices[t]]);
    const bool b = onFront(mesh.positions[mesh.indices[t + 1]]);
    const bool c = onFront(mesh.positions[mesh.indices[t + 2]]);
    ASSERT_TRUE(a == b && b == c) << "triangle " << t / 3 << " joins the two spheres";
  }
  EXPECT_GT(impostor->depthMesh.splitEdges, 10u);
  EXPECT_GT(impostor->depthMesh.maxDepthJump, 1.0);  // the front sphere hovers ~1.5 m ahead
}

TEST_F(ImpostorTest, MeshedValidityIsWiderThanSimple) {
  const ImpostorScene scene = sphereScene(1.0f);
  auto simple = impostors_->renderSimple(scene, glm::vec3(0, 0, 10));
  auto meshed = impostors_->renderMeshed(scene, glm::vec3(0, 0, 10));
  ASSERT_TRUE(simple.ok() && meshed.ok());
  EXPECT_GT(meshed->validity.alpha(), 4.0 * simple->validity.alpha())
      << "meshed " << meshed->validity.alpha() << " simple " << simple->validity.alpha();
}

TEST_F(ImpostorTest, SimplifiedDepthMeshKeepsVerticesOnSurface) {
  MeshedImpostorOptions options;
  options.targetTriangles = 300;
  auto full = impostors_->renderMeshed(sphereScene(1.0f), glm::vec3(0, 0, 10));
  auto coarse = impostors_->renderMeshed(sphereScene(1.0f), glm::vec3(0, 0, 10), options);
  ASSERT_TRUE(full.ok() && coarse.ok()) << coarse.status().toString();
  EXPECT_LE(coarse->mesh.triangleCount(), 300u);
  EXPECT_GT(coarse->mesh.triangleCount(), 100u);
  for (const glm::vec3& p : coarse->mesh.positions) {
    EXPECT_LT(std::fabs(glm::length(p) - 1.0f), 0.004f);  // QEM keeps original vertices
  }
  EXPECT_GT(coarse->meshDepthError, full->meshDepthError);
  EXPECT_LT(coarse->meshDepthError, 0.1);
}

TEST_F(ImpostorTest, ViewpointInsideObjectIsRejected) {
  auto impostor = impostors_->renderSimple(sphereScene(1.0f), glm::vec3(0.2f, 0, 0));
  ASSERT_FALSE(impostor.ok());
  EXPECT_EQ(impostor.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(impostor.status().message().find("bounding radius"), std::string::npos);
}

TEST_F(ImpostorTest, BadScenesAndOptionsAreRejected) {
  EXPECT_EQ(impostors_->renderSimple(ImpostorScene(), glm::vec3(0, 0, 10)).status().code(),
            ErrorCode::kInvalidArgument);
  ImpostorScene noMesh;
  noMesh.parts.resize(1);
  EXPECT_EQ(impostors_->renderSimple(noMesh, glm::vec3(0, 0, 10)).status().code(),
            ErrorCode::kInvalidArgument);
  ImpostorScene broken = sphereScene(1.0f);
  auto bad = std::make_shared<IndexedMesh>(*broken.parts[0].mesh);
  bad->indices[0] = 1u << 30;
  broken.parts[0].mesh = bad;
  auto result = impostors_->renderSimple(broken, glm::vec3(0, 0, 10));
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("impostor part 0"), std::string::npos);
  ImpostorOptions tiny;
  tiny.textureSize = 4;
  EXPECT_EQ(impostors_->renderSimple(sphereScene(1.0f), glm::vec3(0, 0, 10), tiny).status().code(),
            ErrorCode::kInvalidArgument);
  MeshedImpostorOptions coarseGrid;
  coarseGrid.gridStep = 0;
  EXPECT_EQ(
      impostors_->renderMeshed(sphereScene(1.0f), glm::vec3(0, 0, 10), coarseGrid).status().code(),
      ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::simplifier
