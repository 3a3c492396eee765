// GL tests of the disc renderer (common/render/disc_renderer.h) and of a
// hybrid cut rendered against its full mesh (docs/hybrid.md, "Rendering").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <tuple>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/render/disc_renderer.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"
#include "thinlod/frontend/frame_metrics.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/simplifier/hybrid_graph.h"

namespace thinlod {
namespace {

using render::Camera;

struct Rig {
  std::unique_ptr<render::OffscreenContext> context;
  std::unique_ptr<render::RenderTarget> target;
  std::unique_ptr<render::MeshRenderer> meshes;
  std::unique_ptr<render::DiscRenderer> discs;
  ~Rig() {
    if (context) (void)context->makeCurrent();
    discs.reset();
    meshes.reset();
    target.reset();
    context.reset();
  }
};

::testing::AssertionResult makeRig(render::Backend backend, int size, Rig& rig,
                                   render::DiscStyle style = render::DiscStyle::kInstancedQuads) {
  auto context = render::createOffscreenContext(backend, size, size);
  if (!context.ok()) return ::testing::AssertionFailure() << context.status().toString();
  rig.context = std::move(context).value();
  auto target = render::RenderTarget::create(*rig.context, size, size);
  if (!target.ok()) return ::testing::AssertionFailure() << target.status().toString();
  rig.target = std::move(target).value();
  auto meshes = render::MeshRenderer::create(*rig.context);
  if (!meshes.ok()) return ::testing::AssertionFailure() << meshes.status().toString();
  rig.meshes = std::move(meshes).value();
  auto discs = render::DiscRenderer::create(*rig.context, style);
  if (!discs.ok()) return ::testing::AssertionFailure() << discs.status().toString();
  rig.discs = std::move(discs).value();
  return ::testing::AssertionSuccess();
}

Camera orthoCamera() {
  Camera camera;
  camera.view = glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
  camera.projection = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 9.0f);
  return camera;
}

DiscPoints oneDisc(glm::vec3 centre, float radius, std::array<std::uint8_t, 4> color) {
  DiscPoints p;
  p.centres = {centre};
  p.radii = {radius};
  p.colors = {color};
  return p;
}

class DiscRendererTest
    : public ::testing::TestWithParam<std::tuple<render::Backend, render::DiscStyle>> {
 protected:
  ::testing::AssertionResult rig(int size, Rig& out) {
    return makeRig(std::get<0>(GetParam()), size, out, std::get<1>(GetParam()));
  }
};

TEST_P(DiscRendererTest, DrawsARoundDiscOfTheWorldRadius) {
  Rig rig;
  ASSERT_TRUE(this->rig(64, rig));
  auto handle = rig.discs->upload(oneDisc(glm::vec3(0.0f), 0.5f, {255, 0, 0, 255}));
  ASSERT_TRUE(handle.ok()) << handle.status().toString();
  ASSERT_TRUE(rig.meshes->beginFrame(*rig.target, glm::vec4(0, 0, 0, 1)).ok());
  const render::DiscDrawItem item{*handle, glm::mat4(1.0f)};
  ASSERT_TRUE(rig.discs->draw(&item, 1, orthoCamera()).ok());
  RgbaImage image;
  ASSERT_TRUE(rig.target->readColor(image).ok());
  // Radius 0.5 of the 2-unit view = 16 pixels: inside at 14, outside at the
  // square's corner (distance 16 * sqrt 2 - 2).
  EXPECT_EQ(image.at(32, 32)[0], 255);
  EXPECT_EQ(image.at(32 + 14, 32)[0], 255);
  EXPECT_EQ(image.at(32, 32 - 14)[0], 255);
  EXPECT_EQ(image.at(32 + 13, 32 + 13)[0], 0);
  EXPECT_EQ(image.at(32 + 18, 32)[0], 0);
  EXPECT_EQ(rig.discs->stats().discs, 1u);
  // Coverage about pi r^2 = 804 pixels.
  int covered = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) covered += image.at(x, y)[0] > 128;
  EXPECT_NEAR(covered, 804, 40);
}

TEST_P(DiscRendererTest, DiscsLandWhereTheCameraProjectsThem) {
  Rig rig;
  ASSERT_TRUE(this->rig(64, rig));
  // Up-left of the centre, under a perspective camera (rows top-down).
  Camera camera;
  camera.view = glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0));
  camera.projection = glm::perspective(0.8f, 1.0f, 1.0f, 9.0f);
  const glm::vec3 centre(-0.8f, 0.6f, 0.5f);
  auto handle = rig.discs->upload(oneDisc(centre, 0.1f, {0, 255, 0, 255}));
  ASSERT_TRUE(handle.ok());
  ASSERT_TRUE(rig.meshes->beginFrame(*rig.target, glm::vec4(0, 0, 0, 1)).ok());
  const render::DiscDrawItem item{*handle, glm::mat4(1.0f)};
  ASSERT_TRUE(rig.discs->draw(&item, 1, camera).ok());
  RgbaImage image;
  ASSERT_TRUE(rig.target->readColor(image).ok());
  const glm::vec3 pixel = render::projectToPixel(camera, centre, 64, 64);
  ASSERT_LT(pixel.y, 28.0f) << "the disc is in the upper half";
  EXPECT_EQ(image.at(static_cast<int>(pixel.x), static_cast<int>(pixel.y))[1], 255);
  EXPECT_EQ(image.at(static_cast<int>(pixel.x), 63 - static_cast<int>(pixel.y))[1], 0);
}

TEST_P(DiscRendererTest, DiscsAreDepthTestedAgainstTriangles) {
  Rig rig;
  ASSERT_TRUE(this->rig(32, rig));
  IndexedMesh quad;
  quad.positions = {{-1, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-1, 1, 0}};  // the left half, z = 0
  quad.indices = {0, 1, 2, 0, 2, 3};
  auto mesh = rig.meshes->uploadMesh(quad);
  ASSERT_TRUE(mesh.ok());
  // Behind the quad (z = -1) on the left, in front (z = 1) on the right.
  DiscPoints points = oneDisc(glm::vec3(-0.5f, 0.0f, -1.0f), 0.3f, {255, 0, 0, 255});
  points.centres.push_back(glm::vec3(0.5f, 0.0f, 1.0f));
  points.radii.push_back(0.3f);
  points.colors.push_back({0, 0, 255, 255});
  auto discs = rig.discs->upload(points);
  ASSERT_TRUE(discs.ok());
  ASSERT_TRUE(rig.meshes->beginFrame(*rig.target, glm::vec4(0, 0, 0, 1)).ok());
  render::Material green;
  green.lit = false;
  green.diffuse = glm::vec4(0, 1, 0, 1);
  render::DrawItem draw{*mesh, glm::mat4(1.0f), green};
  ASSERT_TRUE(rig.meshes->draw(&draw, 1, orthoCamera(), render::Lighting()).ok());
  const render::DiscDrawItem item{*discs, glm::mat4(1.0f)};
  ASSERT_TRUE(rig.discs->draw(&item, 1, orthoCamera()).ok());
  RgbaImage image;
  ASSERT_TRUE(rig.target->readColor(image).ok());
  EXPECT_EQ(image.at(8, 16)[1], 255) << "the disc behind the quad is hidden";
  EXPECT_EQ(image.at(8, 16)[0], 0);
  EXPECT_EQ(image.at(24, 16)[2], 255) << "the disc in front is drawn";
}

TEST_P(DiscRendererTest, TinyDiscsStillCoverAPixel) {
  Rig rig;
  ASSERT_TRUE(this->rig(32, rig));
  auto discs =
      rig.discs->upload(oneDisc(glm::vec3(0.03125f, 0.03125f, 0.0f), 1e-6f, {255, 255, 255, 255}));
  ASSERT_TRUE(discs.ok());
  ASSERT_TRUE(rig.meshes->beginFrame(*rig.target, glm::vec4(0, 0, 0, 1)).ok());
  const render::DiscDrawItem item{*discs, glm::mat4(1.0f)};
  ASSERT_TRUE(rig.discs->draw(&item, 1, orthoCamera()).ok());
  RgbaImage image;
  ASSERT_TRUE(rig.target->readColor(image).ok());
  int covered = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) covered += image.at(x, y)[0] > 0;
  EXPECT_GE(covered, 1);
  EXPECT_LE(covered, 4);
}

TEST_P(DiscRendererTest, RejectsBadInputAndUnknownHandles) {
  Rig rig;
  ASSERT_TRUE(this->rig(16, rig));
  DiscPoints bad = oneDisc(glm::vec3(0.0f), -1.0f, {1, 2, 3, 4});
  EXPECT_EQ(rig.discs->upload(bad).status().code(), ErrorCode::kInvalidArgument);
  const render::DiscDrawItem unknown{render::DiscHandle{99}, glm::mat4(1.0f)};
  EXPECT_EQ(rig.discs->draw(&unknown, 1, orthoCamera()).code(), ErrorCode::kNotFound);
  auto ok = rig.discs->upload(oneDisc(glm::vec3(0.0f), 1.0f, {1, 2, 3, 4}));
  ASSERT_TRUE(ok.ok());
  render::DiscDrawItem nan{*ok, glm::mat4(1.0f)};
  nan.model[3][0] = std::nanf("");
  EXPECT_EQ(rig.discs->draw(&nan, 1, orthoCamera()).code(), ErrorCode::kInvalidArgument);
  rig.discs->remove(*ok);
  const render::DiscDrawItem removed{*ok, glm::mat4(1.0f)};
  EXPECT_EQ(rig.discs->draw(&removed, 1, orthoCamera()).code(), ErrorCode::kNotFound);
}

INSTANTIATE_TEST_SUITE_P(
    BackendsAndStyles, DiscRendererTest,
    ::testing::Combine(::testing::Values(render::Backend::kEgl, render::Backend::kOsMesa),
                       ::testing::Values(render::DiscStyle::kInstancedQuads,
                                         render::DiscStyle::kPointSprites)),
    [](const ::testing::TestParamInfo<DiscRendererTest::ParamType>& info) {
      return std::string(render::backendName(std::get<0>(info.param))) +
             (std::get<1>(info.param) == render::DiscStyle::kPointSprites ? "_sprites" : "_quads");
    });

TEST(DiscRendering, PreLightingMatchesTheLambertTerm) {
  DiscPoints p = oneDisc(glm::vec3(0.0f), 1.0f, {200, 100, 50, 255});
  p.normals = {glm::vec3(0.0f, 0.0f, 1.0f)};
  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.2f);
  render::Light light;
  light.vector = glm::normalize(glm::vec3(0.0f, -1.0f, -1.0f));  // 45 degrees onto +z
  lighting.lights = {light};
  const DiscPoints lit = render::preLightDiscs(p, glm::mat4(1.0f), glm::vec4(1.0f), lighting);
  const float factor = 0.2f + std::sqrt(0.5f);
  EXPECT_NEAR(lit.colors[0][0], 200 * factor, 1.0);
  EXPECT_NEAR(lit.colors[0][1], 100 * factor, 1.0);
  EXPECT_NEAR(lit.colors[0][2], 50 * factor, 1.0);
  p.normals = {glm::vec3(0.0f, 0.0f, -1.0f)};  // facing away: ambient only
  const DiscPoints away = render::preLightDiscs(p, glm::mat4(1.0f), glm::vec4(1.0f), lighting);
  EXPECT_NEAR(away.colors[0][0], 200 * 0.2f, 1.0);
}

TEST(DiscRendering, WorldDiscsScaleRadiiAndMoveCentres) {
  DiscPoints out;
  const glm::mat4 model =
      glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(1, 2, 3)), glm::vec3(2.0f, 3.0f, 1.0f));
  render::appendWorldDiscs(out, oneDisc(glm::vec3(1.0f, 1.0f, 1.0f), 0.5f, {1, 2, 3, 4}), model);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out.centres[0], glm::vec3(3.0f, 5.0f, 4.0f));
  EXPECT_FLOAT_EQ(out.radii[0], 1.5f);
  EXPECT_TRUE(out.validate("world").ok());
}

// --- A hybrid cut against its full mesh ---

struct View {
  Camera camera;
  glm::vec3 eye;
};

View viewOf(const IndexedMesh& mesh, int size, float distanceInRadii) {
  const BoundingSphere sphere = mesh.boundingSphere();
  View v;
  v.eye = sphere.center + glm::vec3(0.3f, 0.25f, 1.0f) * (sphere.radius * distanceInRadii);
  v.camera.view = glm::lookAt(v.eye, sphere.center, glm::vec3(0, 1, 0));
  const float distance = glm::length(v.eye - sphere.center);
  v.camera.projection = glm::perspective(0.8f, 1.0f, distance - sphere.radius * 1.5f,
                                         distance + sphere.radius * 1.5f);
  (void)size;
  return v;
}

render::Lighting sceneLighting() {
  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.25f);
  render::Light light;
  light.vector = glm::normalize(glm::vec3(-0.4f, -1.0f, -0.6f));
  light.color = glm::vec3(0.8f);
  lighting.lights = {light};
  return lighting;
}

struct Frame {
  RgbaImage image;
  std::size_t covered = 0;
};

// Draws triangles (lit, computed normals as the frontend does for meshes
// without normals) and pre-lit discs; returns the frame.
Frame renderGeometry(Rig& rig, const IndexedMesh& triangles, const DiscPoints& points,
                     const View& view) {
  Frame frame;
  render::Material material;
  material.diffuse = glm::vec4(0.9f, 0.75f, 0.6f, 1.0f);
  const render::Lighting lighting = sceneLighting();
  EXPECT_TRUE(rig.meshes->beginFrame(*rig.target, glm::vec4(0.1f, 0.1f, 0.3f, 1.0f)).ok());
  render::MeshHandle mesh;
  if (triangles.triangleCount() > 0) {
    auto uploaded = rig.meshes->uploadMesh(triangles);
    EXPECT_TRUE(uploaded.ok()) << uploaded.status().toString();
    mesh = *uploaded;
    const render::DrawItem item{mesh, glm::mat4(1.0f), material};
    EXPECT_TRUE(rig.meshes->draw(&item, 1, view.camera, lighting).ok());
  }
  render::DiscHandle discs;
  if (!points.empty()) {
    const DiscPoints lit =
        render::preLightDiscs(points, glm::mat4(1.0f), material.diffuse, lighting);
    auto uploaded = rig.discs->upload(lit);
    EXPECT_TRUE(uploaded.ok()) << uploaded.status().toString();
    discs = *uploaded;
    const render::DiscDrawItem item{discs, glm::mat4(1.0f)};
    EXPECT_TRUE(rig.discs->draw(&item, 1, view.camera).ok());
  }
  EXPECT_TRUE(rig.target->readColor(frame.image).ok());
  for (int y = 0; y < frame.image.height; ++y) {
    for (int x = 0; x < frame.image.width; ++x) {
      const std::uint8_t* p = frame.image.at(x, y);
      const std::uint8_t* b = frame.image.at(0, 0);  // the view leaves the corners empty
      frame.covered += !(p[0] == b[0] && p[1] == b[1] && p[2] == b[2]);
    }
  }
  if (mesh.valid()) rig.meshes->deleteMesh(mesh);
  if (discs.valid()) rig.discs->remove(discs);
  return frame;
}

// Pixels covered in `full` and background in `other` (holes).
std::size_t holes(const RgbaImage& full, const RgbaImage& other) {
  std::size_t n = 0;
  for (int y = 0; y < full.height; ++y) {
    for (int x = 0; x < full.width; ++x) {
      const std::uint8_t* f = full.at(x, y);
      const std::uint8_t* o = other.at(x, y);
      const std::uint8_t* b = full.at(0, 0);  // the view leaves the corners empty
      const bool fullBackground = f[0] == b[0] && f[1] == b[1] && f[2] == b[2];
      const bool otherBackground = o[0] == b[0] && o[1] == b[1] && o[2] == b[2];
      n += !fullBackground && otherBackground;
    }
  }
  return n;
}

// The cow seen whole at 256 x 256, the hybrid graph (kappa 10, tau 5: points
// early) cut at a 2-pixel screen tolerance: the frame is within the stated
// SNR floor of the full mesh's, has (almost) no holes, fewer than without
// its discs, and saves primitive units against the full mesh. Measured
// (docs/results/hybrid.md, the printed line): 19.7 dB, 14 holes of 9479
// pixels (43 without the discs); the floor, 16 dB, is below that by the
// margin llvmpipe vs a GPU rasterisation may move it. A vertically mirrored
// disc pass (the first version) measured 14.0 dB.
class HybridRendering : public ::testing::TestWithParam<render::DiscStyle> {};

TEST_P(HybridRendering, ACowCutAtTwoPixelsRendersCloseToTheFullMesh) {
  Result<LoadedMesh> cow = loadMeshFile(std::string(THINLOD_SHARED_DIR) + "/models/cow.obj");
  ASSERT_TRUE(cow.ok()) << cow.status().toString();
  simplifier::HybridOptions options;
  options.kappa = 10.0;
  options.tau = 5.0;
  Result<simplifier::HybridGraph> graph = simplifier::buildHybridGraph(cow->mesh, options);
  ASSERT_TRUE(graph.ok()) << graph.status().toString();

  constexpr int kSize = 256;
  Rig rig;
  ASSERT_TRUE(makeRig(render::Backend::kAuto, kSize, rig, GetParam()));
  const View view = viewOf(cow->mesh, kSize, 3.0f);
  simplifier::HybridView hybridView;
  hybridView.eye = glm::dvec3(view.eye);
  hybridView.pixelsPerRadian = kSize / (2.0 * std::tan(0.4));
  simplifier::HybridCut cut(*graph);
  cut.adaptToScreen(hybridView, 2.0);
  ASSERT_GT(cut.pointCount(), 0u) << "the cut must exercise the disc renderer";

  const Frame full = renderGeometry(rig, cow->mesh, DiscPoints(), view);
  const HybridGeometry geometry = simplifier::hybridGeometry(cut);
  const Frame hybrid = renderGeometry(rig, geometry.triangles, geometry.points, view);
  // The same cut with its discs dropped: what the points contribute.
  const Frame trianglesOnly = renderGeometry(rig, geometry.triangles, DiscPoints(), view);

  // THINLOD_HYBRID_DUMP=<dir>: the three frames as PPM files, to look at.
  if (const char* dump = std::getenv("THINLOD_HYBRID_DUMP")) {
    for (auto [name, image] : {std::pair<const char*, const RgbaImage*>{"full", &full.image},
                               {"hybrid", &hybrid.image},
                               {"triangles", &trianglesOnly.image}}) {
      std::FILE* f = std::fopen((std::string(dump) + "/" + name + ".ppm").c_str(), "wb");
      if (f == nullptr) continue;
      std::fprintf(f, "P6 %d %d 255\n", image->width, image->height);
      for (int i = 0; i < image->width * image->height; ++i)
        std::fwrite(&image->pixels[4 * i], 1, 3, f);
      std::fclose(f);
    }
  }
  Result<double> snr = frontend::frameSnr(hybrid.image, full.image);
  Result<double> snrWithoutDiscs = frontend::frameSnr(trianglesOnly.image, full.image);
  ASSERT_TRUE(snr.ok() && snrWithoutDiscs.ok());
  const std::size_t hybridHoles = holes(full.image, hybrid.image);
  const std::size_t holesWithoutDiscs = holes(full.image, trianglesOnly.image);
  std::printf(
      "%s: cow hybrid cut at 2 px: %zu triangles + %zu points = %.1f units (full %zu); "
      "SNR %.2f dB (discs dropped: %.2f dB); holes %zu of %zu covered pixels "
      "(discs dropped: %zu)\n",
      GetParam() == render::DiscStyle::kPointSprites ? "sprites" : "quads", cut.triangleCount(),
      cut.pointCount(), cut.units(), cow->mesh.triangleCount(), *snr, *snrWithoutDiscs, hybridHoles,
      full.covered, holesWithoutDiscs);
  EXPECT_GT(*snr, 16.0);
  // The discs' job: fill what the replaced triangles left open. (They need
  // not raise the SNR: flat pre-lit discs vs smooth-shaded triangles.)
  EXPECT_LT(hybridHoles, holesWithoutDiscs);
  EXPECT_LT(static_cast<double>(hybridHoles), 0.01 * static_cast<double>(full.covered));
  EXPECT_LT(cut.units(), 0.5 * static_cast<double>(cow->mesh.triangleCount()));
}

// The frontend's renderer holds a Hybrid representation (triangles in the lit
// batch, discs pre-lit in one disc draw) and renders it close to the full
// mesh held as a Mesh; a points-only hybrid draws only discs.
TEST(FrontendHybridRendering, FrontendRendererDrawsHybridRepresentations) {
  Result<LoadedMesh> cow = loadMeshFile(std::string(THINLOD_SHARED_DIR) + "/models/cow.obj");
  ASSERT_TRUE(cow.ok()) << cow.status().toString();
  simplifier::HybridOptions options;
  options.kappa = 10.0;
  options.tau = 5.0;
  Result<simplifier::HybridGraph> graph = simplifier::buildHybridGraph(cow->mesh, options);
  ASSERT_TRUE(graph.ok()) << graph.status().toString();
  constexpr int kSize = 256;
  auto context = render::createOffscreenContext(render::Backend::kAuto, kSize, kSize);
  ASSERT_TRUE(context.ok()) << context.status().toString();
  frontend::FrontendRendererOptions rendererOptions;
  rendererOptions.width = rendererOptions.height = kSize;
  rendererOptions.uploadBytesPerFrame = 64u << 20;
  auto renderer = frontend::FrontendRenderer::create(**context, rendererOptions);
  ASSERT_TRUE(renderer.ok()) << renderer.status().toString();

  const View view = viewOf(cow->mesh, kSize, 3.0f);
  simplifier::HybridView hybridView;
  hybridView.eye = glm::dvec3(view.eye);
  hybridView.pixelsPerRadian = kSize / (2.0 * std::tan(0.4));
  simplifier::HybridCut cut(*graph);
  cut.adaptToScreen(hybridView, 2.0);
  const HybridGeometry geometry = simplifier::hybridGeometry(cut);
  ASSERT_GT(geometry.points.size(), 0u);

  auto show = [&](std::uint64_t plan, frontend::Representation rep, RgbaImage& image) {
    frontend::SceneBatch batch;
    batch.plan = plan;
    frontend::SceneOperation op;
    op.id = 1;
    op.representation = std::move(rep);
    batch.operations.push_back(std::move(op));
    const Status submitted = (*renderer)->submit(std::move(batch));
    EXPECT_TRUE(submitted.ok()) << submitted.toString();
    auto report = (*renderer)->renderFrame(view.camera, sceneLighting(), image);
    EXPECT_TRUE(report.ok()) << report.status().toString();
    return report.ok() ? *report : frontend::FrameReport{};
  };
  const glm::vec4 colour(0.9f, 0.75f, 0.6f, 1.0f);
  frontend::Representation full;
  full.mesh = std::make_shared<const IndexedMesh>(cow->mesh);
  full.color = colour;
  RgbaImage fullFrame, hybridFrame, pointsFrame;
  const frontend::FrameReport fullReport = show(1, full, fullFrame);
  EXPECT_EQ(fullReport.discs, 0u);

  frontend::Representation hybrid;
  hybrid.kind = RepresentationKind::kHybrid;
  hybrid.mesh = std::make_shared<const IndexedMesh>(geometry.triangles);
  hybrid.points = std::make_shared<const DiscPoints>(geometry.points);
  hybrid.color = colour;
  const frontend::FrameReport hybridReport = show(2, hybrid, hybridFrame);
  EXPECT_EQ(hybridReport.discs, geometry.points.size());
  EXPECT_EQ(hybridReport.triangles, geometry.triangles.triangleCount());
  Result<double> snr = frontend::frameSnr(hybridFrame, fullFrame);
  ASSERT_TRUE(snr.ok());
  std::printf(
      "frontend renderer: hybrid cow %zu triangles + %zu discs, SNR %.2f dB vs the full "
      "mesh\n",
      geometry.triangles.triangleCount(), geometry.points.size(), *snr);
  EXPECT_GT(*snr, 16.0);

  // A coarse cut of points only (all triangles replaced): discs only.
  simplifier::HybridCut coarse(*graph);
  coarse.adaptToError(0.05 * graph->diagonal());
  const HybridGeometry coarseGeometry = simplifier::hybridGeometry(coarse);
  ASSERT_GT(coarseGeometry.points.size(), 0u);
  frontend::Representation pointsOnly;
  pointsOnly.kind = RepresentationKind::kHybrid;
  pointsOnly.points = std::make_shared<const DiscPoints>(coarseGeometry.points);
  pointsOnly.color = colour;
  const frontend::FrameReport pointsReport = show(3, pointsOnly, pointsFrame);
  EXPECT_EQ(pointsReport.triangles, 0u);
  EXPECT_EQ(pointsReport.discs, coarseGeometry.points.size());
  std::size_t covered = 0;
  const std::uint8_t* background = pointsFrame.at(0, 0);
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      const std::uint8_t* p = pointsFrame.at(x, y);
      covered += p[0] != background[0] || p[1] != background[1] || p[2] != background[2];
    }
  }
  EXPECT_GT(covered, 1000u) << "the discs of a points-only hybrid are drawn";

  // Points on a non-hybrid are refused by the scene.
  frontend::Representation wrong = full;
  wrong.points = hybrid.points;
  frontend::SceneBatch batch;
  frontend::SceneOperation op;
  op.id = 2;
  op.representation = wrong;
  batch.operations.push_back(op);
  EXPECT_EQ((*renderer)->submit(std::move(batch)).code(), ErrorCode::kInvalidArgument);
  (void)(*context)->makeCurrent();
  renderer->reset();
}

INSTANTIATE_TEST_SUITE_P(
    Styles, HybridRendering,
    ::testing::Values(render::DiscStyle::kInstancedQuads, render::DiscStyle::kPointSprites),
    [](const ::testing::TestParamInfo<render::DiscStyle>& info) {
      return std::string(info.param == render::DiscStyle::kPointSprites ? "sprites" : "quads");
    });

}  // namespace
}  // namespace thinlod
