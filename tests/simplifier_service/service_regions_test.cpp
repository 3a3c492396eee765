// SimplifierService and region objects (an Inline's `regions N`,
// docs/regions.md "In the running system"): with SimplifyRequest::keepBoundary
// every level of a region keeps every vertex on the region's open boundary
// (its borders with the other regions and the terrain's outer border), and
// the flag is part of every model and curve cache key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/mesh/mesh_regions.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

constexpr int kGrid = 33;  // vertices a side, on [0, 1]^2
constexpr float kSpacing = 1.0f / float(kGrid - 1);

IndexedMesh terrain() {
  IndexedMesh mesh;
  for (int j = 0; j < kGrid; ++j) {
    for (int i = 0; i < kGrid; ++i) {
      const float x = float(i) * kSpacing, y = float(j) * kSpacing;
      mesh.positions.emplace_back(
          x, y, 0.08f * std::sin(6.1f * x) * std::cos(4.3f * y) + 0.03f * std::sin(17 * x + 3 * y));
    }
  }
  for (int j = 0; j + 1 < kGrid; ++j) {
    for (int i = 0; i + 1 < kGrid; ++i) {
      const std::uint32_t a = std::uint32_t(j * kGrid + i), b = a + 1, c = a + kGrid, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return mesh;
}

// The scene (4 regions of the terrain) in this process's scratch directory.
std::string regionScene() {
  static const std::string path = [] {
    const std::string dir = scratchDir();
    EXPECT_TRUE(saveMeshFile(terrain(), dir + "/terrain.obj").ok());
    const std::string wrl = dir + "/terrain-regions.wrl";
    std::ofstream(wrl) << "#VRML V2.0 utf8\nInline { url \"terrain.obj\" regions 4 }\n";
    return wrl;
  }();
  return path;
}

ServiceOptions regionOptions(const std::string& curveDir = "") {
  ServiceOptions options;
  options.sceneRoot = scratchDir();
  options.curveCacheDir = curveDir;
  options.curve.error.samplesPerMesh = 4000;
  return options;
}

protocol::SimplifyRequest regionRequest(std::uint64_t object, std::uint32_t count, bool keep) {
  protocol::SimplifyRequest request;
  request.requestId = 500 + object;
  request.objectId = object;
  request.sourcePath = regionScene();
  request.targetTriangles = count;
  request.keepBoundary = keep;
  return request;
}

// The scene's region objects as every daemon numbers them.
std::vector<scene::SceneObject> regionObjects(scene::Scene& holder) {
  Result<scene::Scene> scene = scene::loadSceneFile(regionScene(), {});
  EXPECT_TRUE(scene.ok()) << scene.status().toString();
  holder = std::move(scene).value();
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(holder);
  EXPECT_TRUE(objects.ok()) << objects.status().toString();
  return objects.ok() ? std::move(objects).value() : std::vector<scene::SceneObject>();
}

// Open-boundary positions of `region` with no vertex of `level` within a
// quarter of the grid spacing (Draco moves a vertex by far less: 8 or more
// position bits over a region at most 1 m wide).
std::size_t missingBoundaryVertices(const IndexedMesh& region, const IndexedMesh& level) {
  const std::vector<bool> open = openBoundaryVertices(region);
  std::size_t missing = 0;
  for (std::size_t v = 0; v < region.vertexCount(); ++v) {
    if (!open[v]) continue;
    bool found = false;
    for (const glm::vec3& p : level.positions)
      found = found || glm::distance(p, region.positions[v]) < 0.25f * kSpacing;
    missing += found ? 0 : 1;
  }
  return missing;
}

IndexedMesh decode(const protocol::SimplifyResult& result) {
  Result<IndexedMesh> mesh = codec::decodeMesh(result.mesh.data(), result.mesh.size());
  EXPECT_TRUE(mesh.ok()) << mesh.status().toString();
  return mesh.ok() ? std::move(mesh).value() : IndexedMesh();
}

TEST(SimplifierServiceRegions, KeepBoundaryKeepsEveryBorderVertexAtEveryLevel) {
  scene::Scene holder;
  const std::vector<scene::SceneObject> objects = regionObjects(holder);
  ASSERT_EQ(objects.size(), 4u);
  SimplifierService service(regionOptions());
  for (const scene::SceneObject& object : objects) {
    const std::size_t full = object.fullMesh->triangleCount();
    for (std::uint32_t target : {1u, 20u, 120u, std::uint32_t(full)}) {
      const protocol::SimplifyResult result =
          service.simplify(regionRequest(object.id, target, true));
      ASSERT_TRUE(result.status.ok()) << result.status.toString();
      const IndexedMesh level = decode(result);
      EXPECT_EQ(missingBoundaryVertices(*object.fullMesh, level), 0u)
          << "region " << object.region << " at " << target << " triangles ("
          << result.triangleCount << " sent)";
    }
  }
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 4u) << "one border-keeping model per region";
}

TEST(SimplifierServiceRegions, WithoutTheFlagTheCoarsestLevelLosesBorderVertices) {
  scene::Scene holder;
  const std::vector<scene::SceneObject> objects = regionObjects(holder);
  ASSERT_EQ(objects.size(), 4u);
  SimplifierService service(regionOptions());
  const protocol::SimplifyResult kept = service.simplify(regionRequest(1, 1, true));
  const protocol::SimplifyResult free = service.simplify(regionRequest(1, 1, false));
  ASSERT_TRUE(kept.status.ok() && free.status.ok());
  EXPECT_GT(missingBoundaryVertices(*objects[0].fullMesh, decode(free)), 0u);
  EXPECT_EQ(missingBoundaryVertices(*objects[0].fullMesh, decode(kept)), 0u);
  EXPECT_GT(kept.triangleCount, free.triangleCount) << "the kept border costs triangles";
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 2u) << "the flag is part of the model key";
}

TEST(SimplifierServiceRegions, CurvesOfBothFlagsAreCachedApart) {
  const std::string curveDir = scratchDir() + "/region-curves";
  std::filesystem::remove_all(curveDir);
  auto curveRequest = [](bool keep) {
    protocol::SimplifyRequest request = regionRequest(2, 40, keep);
    request.curvePoints = 8;
    return request;
  };
  double keptCoarsest = 0.0;
  {
    SimplifierService service(regionOptions(curveDir));
    const protocol::SimplifyResult result = service.simplify(curveRequest(true));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    ASSERT_FALSE(result.curve.empty());
    keptCoarsest = result.curve.front().resources;
    EXPECT_EQ(service.stats().curvesMeasured, 1u);
  }
  {
    // The other flag finds no file of its own: measured, with a coarser floor.
    SimplifierService service(regionOptions(curveDir));
    const protocol::SimplifyResult result = service.simplify(curveRequest(false));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    EXPECT_EQ(service.stats().curvesFromDisk, 0u);
    EXPECT_EQ(service.stats().curvesMeasured, 1u);
    ASSERT_FALSE(result.curve.empty());
    EXPECT_LT(result.curve.front().resources, keptCoarsest);
  }
  {
    SimplifierService service(regionOptions(curveDir));
    const protocol::SimplifyResult result = service.simplify(curveRequest(true));
    ASSERT_TRUE(result.status.ok()) << result.status.toString();
    EXPECT_EQ(service.stats().curvesFromDisk, 1u);
    EXPECT_EQ(service.stats().curvesMeasured, 0u);
    ASSERT_FALSE(result.curve.empty());
    EXPECT_EQ(result.curve.front().resources, keptCoarsest);
  }
}

TEST(SimplifierServiceRegions, KeepBoundaryWorksOnSourceMeshesToo) {
  scene::Scene holder;
  const std::vector<scene::SceneObject> objects = regionObjects(holder);
  ASSERT_EQ(objects.size(), 4u);
  Result<std::vector<std::uint8_t>> bytes = codec::encodeMesh(*objects[3].fullMesh);
  ASSERT_TRUE(bytes.ok());
  // The source travels Draco-quantized: compare with what the service decodes.
  Result<IndexedMesh> source = codec::decodeMesh(bytes->data(), bytes->size());
  ASSERT_TRUE(source.ok());
  SimplifierService service(regionOptions());
  protocol::SimplifyRequest request = regionRequest(9, 1, true);
  request.sourcePath.clear();
  request.sourceMesh = *bytes;
  const protocol::SimplifyResult kept = service.simplify(request);
  ASSERT_TRUE(kept.status.ok()) << kept.status.toString();
  EXPECT_EQ(missingBoundaryVertices(*source, decode(kept)), 0u);
  request.keepBoundary = false;
  const protocol::SimplifyResult free = service.simplify(request);
  ASSERT_TRUE(free.status.ok());
  EXPECT_LT(free.triangleCount, kept.triangleCount) << "a separate model without the flag";
}

TEST(SimplifierServiceRegions, HybridWithKeepBoundaryIsRefused) {
  SimplifierService service(regionOptions());
  protocol::SimplifyRequest request = regionRequest(1, 50, true);
  request.representation = protocol::RepresentationKind::kHybrid;
  const protocol::SimplifyResult result = service.simplify(request);
  EXPECT_EQ(result.status.code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::simplifier
