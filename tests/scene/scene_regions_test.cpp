// An Inline's `regions N` (docs/scene-format.md, docs/regions.md "In the
// running system"): the field is parsed and refused like the other fields,
// splitMeshIntoRegions gives every input triangle to exactly one region, and
// collectSceneObjects makes one object per region.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>
#include <tuple>

#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/mesh/mesh_regions.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

const std::string kHeader = "#VRML V2.0 utf8\n";

// n x n vertices on [0, 1]^2 (z a gentle bump), two triangles per square.
IndexedMesh grid(int n) {
  IndexedMesh mesh;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float x = float(i) / float(n - 1), y = float(j) / float(n - 1);
      mesh.positions.emplace_back(x, y, 0.1f * x * (1.0f - x) * y);
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const std::uint32_t a = std::uint32_t(j * n + i), b = a + 1, c = a + std::uint32_t(n),
                          d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return mesh;
}

// A triangle by its corner positions, rotated so the smallest comes first
// (orientation kept).
using Corner = std::tuple<float, float, float>;
using Triangle = std::tuple<Corner, Corner, Corner>;
Triangle triangleOf(const IndexedMesh& mesh, std::size_t t) {
  Corner c[3];
  for (int k = 0; k < 3; ++k) {
    const glm::vec3& p = mesh.positions[mesh.indices[3 * t + k]];
    c[k] = Corner(p.x, p.y, p.z);
  }
  const int first = int(std::min_element(c, c + 3) - c);
  return Triangle(c[first], c[(first + 1) % 3], c[(first + 2) % 3]);
}

Result<Scene> parse(const std::string& body) { return parseScene(kHeader + body, "t.wrl"); }

void expectRefused(const std::string& body, int line, int column, const std::string& part) {
  Result<Scene> r = parse(body);
  ASSERT_FALSE(r.ok()) << body;
  EXPECT_EQ(r.status().code(), ErrorCode::kParseError) << r.status().toString();
  const std::string prefix = "t.wrl:" + std::to_string(line) + ":" + std::to_string(column) + ":";
  EXPECT_EQ(r.status().message().rfind(prefix, 0), 0u) << r.status().message();
  EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message();
}

TEST(SceneRegions, InlineRegionsFieldIsParsed) {
  Result<Scene> r = parse("Inline { url \"t.obj\" regions 4 }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const ShapeNode* shape = r->roots[0]->as<ShapeNode>();
  ASSERT_NE(shape, nullptr);
  EXPECT_EQ(shape->geometry.regionCount, 4u);
  Result<Scene> plain = parse("Inline { url \"t.obj\" }\n");
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->roots[0]->as<ShapeNode>()->geometry.regionCount, 0u);
  EXPECT_TRUE(parse("Inline { url \"t.obj\" regions 2 }\n").ok());
  EXPECT_TRUE(parse("Inline { url \"t.obj\" regions 1024 }\n").ok());
}

TEST(SceneRegions, OutOfRangeRegionsAreRefusedAtTheField) {
  expectRefused("Inline { url \"t.obj\" regions 1 }\n", 2, 22, "must be in [2, 1024]");
  expectRefused("Inline { url \"t.obj\" regions 0 }\n", 2, 22, "must be in [2, 1024]");
  expectRefused("Inline { url \"t.obj\" regions -3 }\n", 2, 22, "must be in [2, 1024]");
  expectRefused("Inline { url \"t.obj\" regions 1025 }\n", 2, 22, "must be in [2, 1024]");
}

TEST(SceneRegions, NonIntegerRegionsAreRefused) {
  expectRefused("Inline { url \"t.obj\" regions 2.5 }\n", 2, 30, "bad integer");
  expectRefused("Inline { url \"t.obj\" regions \"4\" }\n", 2, 30, "integer");
}

TEST(SceneRegions, RegionsAndAnimationAreRefusedTogether) {
  expectRefused("Inline { url \"a.x\" regions 4 animation \"Run\" }\n", 2, 20,
                "cannot be combined with animation");
  expectRefused("Inline { url \"a.x\" animation \"Run\" regions 4 }\n", 2, 36,
                "cannot be combined with animation");
}

TEST(SceneRegions, SplitGivesEveryTriangleToExactlyOneRegion) {
  const IndexedMesh mesh = grid(17);
  for (std::size_t k : {2u, 3u, 4u, 7u, 16u}) {
    Result<std::vector<MeshRegion>> split = splitMeshIntoRegions(mesh, k);
    ASSERT_TRUE(split.ok()) << split.status().toString();
    ASSERT_EQ(split->size(), k);
    std::multiset<Triangle> input, output;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) input.insert(triangleOf(mesh, t));
    std::size_t total = 0;
    for (const MeshRegion& region : *split) {
      ASSERT_TRUE(region.mesh.validate("region").ok());
      EXPECT_GT(region.mesh.triangleCount(), 0u);
      ASSERT_EQ(region.sourceVertex.size(), region.mesh.vertexCount());
      for (std::size_t v = 0; v < region.mesh.vertexCount(); ++v)
        EXPECT_EQ(region.mesh.positions[v], mesh.positions[region.sourceVertex[v]]);
      // No unreferenced vertex in a region.
      std::vector<bool> used(region.mesh.vertexCount(), false);
      for (std::uint32_t i : region.mesh.indices) used[i] = true;
      EXPECT_EQ(std::count(used.begin(), used.end(), false), 0);
      for (std::size_t t = 0; t < region.mesh.triangleCount(); ++t)
        output.insert(triangleOf(region.mesh, t));
      total += region.mesh.triangleCount();
    }
    EXPECT_EQ(total, mesh.triangleCount()) << k << " regions";
    EXPECT_EQ(output, input) << k << " regions: the union is not the input";
  }
}

TEST(SceneRegions, SplitOwnershipFollowsTheVertexPartition) {
  const IndexedMesh mesh = grid(9);
  Result<std::vector<std::uint32_t>> labels = partitionVertices(mesh.positions, 4);
  ASSERT_TRUE(labels.ok());
  Result<std::vector<MeshRegion>> split = splitMeshIntoRegions(mesh, 4);
  ASSERT_TRUE(split.ok());
  for (std::size_t r = 0; r < split->size(); ++r) {
    const MeshRegion& region = (*split)[r];
    for (std::size_t t = 0; t < region.mesh.triangleCount(); ++t) {
      std::uint32_t l[3];
      for (int k = 0; k < 3; ++k)
        l[k] = (*labels)[region.sourceVertex[region.mesh.indices[3 * t + k]]];
      EXPECT_EQ(triangleRegion(l[0], l[1], l[2]), r);
    }
  }
}

TEST(SceneRegions, SplitRefusesTooManyRegionsAndBadMeshes) {
  const IndexedMesh mesh = grid(3);  // 9 vertices, 8 triangles
  EXPECT_EQ(splitMeshIntoRegions(mesh, 0).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(splitMeshIntoRegions(mesh, 10).status().code(), ErrorCode::kInvalidArgument);
  // 9 regions of 9 vertices: some region cannot own a triangle.
  Result<std::vector<MeshRegion>> nine = splitMeshIntoRegions(mesh, 9);
  ASSERT_FALSE(nine.ok());
  EXPECT_NE(nine.status().message().find("owns no triangle"), std::string::npos)
      << nine.status().message();
  IndexedMesh bad = mesh;
  bad.indices[0] = 99;
  EXPECT_EQ(splitMeshIntoRegions(bad, 2).status().code(), ErrorCode::kInvalidArgument);
}

TEST(SceneRegions, SeamCopiesStayInOneRegion) {
  // The grid with its middle column of vertices duplicated (a uv seam):
  // copies share a label, so the split matches the welded grid's.
  IndexedMesh mesh = grid(5);
  const std::size_t before = mesh.positions.size();
  std::map<std::uint32_t, std::uint32_t> copyOf;
  for (std::uint32_t v = 0; v < before; ++v) {
    if (v % 5 == 2) {
      copyOf[v] = std::uint32_t(mesh.positions.size());
      mesh.positions.push_back(mesh.positions[v]);
    }
  }
  // Triangles right of the seam use the copies.
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    bool right = false;
    for (int k = 0; k < 3; ++k) right = right || mesh.indices[3 * t + k] % 5 > 2;
    if (!right) continue;
    for (int k = 0; k < 3; ++k) {
      auto found = copyOf.find(mesh.indices[3 * t + k]);
      if (found != copyOf.end()) mesh.indices[3 * t + k] = found->second;
    }
  }
  Result<std::vector<MeshRegion>> seam = splitMeshIntoRegions(mesh, 3);
  Result<std::vector<MeshRegion>> plain = splitMeshIntoRegions(grid(5), 3);
  ASSERT_TRUE(seam.ok() && plain.ok());
  for (std::size_t r = 0; r < 3; ++r)
    EXPECT_EQ((*seam)[r].mesh.triangleCount(), (*plain)[r].mesh.triangleCount()) << r;
  // The seam is no boundary: only the grid's outer ring is open.
  const std::vector<bool> open = openBoundaryVertices(mesh);
  for (std::uint32_t v = 0; v < before; ++v) {
    const std::uint32_t i = v % 5, j = v / 5;
    EXPECT_EQ(open[v], i == 0 || i == 4 || j == 0 || j == 4) << v;
  }
}

TEST(SceneRegions, OpenBoundaryOfARegionIsItsBordersAndTheOuterRing) {
  const IndexedMesh mesh = grid(9);
  Result<std::vector<MeshRegion>> split = splitMeshIntoRegions(mesh, 2);
  ASSERT_TRUE(split.ok());
  // Vertices of both regions (the shared border) and the outer ring are all
  // open in each region; nothing else is.
  std::map<std::uint32_t, int> regionsOf;
  for (const MeshRegion& region : *split)
    for (std::uint32_t s : region.sourceVertex) ++regionsOf[s];
  for (const MeshRegion& region : *split) {
    const std::vector<bool> open = openBoundaryVertices(region.mesh);
    for (std::size_t v = 0; v < region.mesh.vertexCount(); ++v) {
      const std::uint32_t s = region.sourceVertex[v];
      const std::uint32_t i = s % 9, j = s / 9;
      const bool outer = i == 0 || i == 8 || j == 0 || j == 8;
      EXPECT_EQ(open[v], outer || regionsOf[s] > 1) << "vertex " << s;
    }
  }
}

std::string scratchDir() {
  static const std::string dir = [] {
    const std::filesystem::path path = std::filesystem::path(THINLOD_BINARY_DIR) / "test-tmp" /
                                       ("scene-regions-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

TEST(SceneRegions, EachRegionIsASceneObject) {
  const std::string dir = scratchDir();
  ASSERT_TRUE(saveMeshFile(grid(17), dir + "/grid.obj").ok());
  std::ofstream(dir + "/regions.wrl")
      << kHeader
      << "Shape { geometry Box { size 1 1 1 } }\n"
         "Transform { translation 5 0 0 scale 2 2 2 children [\n"
         "  Shape { appearance Appearance { material Material { diffuseColor 1 0 0 } }\n"
         "          geometry Inline { url \"grid.obj\" regions 4 } }\n"
         "] }\n";
  Result<Scene> scene = loadSceneFile(dir + "/regions.wrl", {});
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  Result<std::vector<SceneObject>> objects = collectSceneObjects(*scene);
  ASSERT_TRUE(objects.ok()) << objects.status().toString();
  ASSERT_EQ(objects->size(), 5u);  // the box, then 4 regions
  EXPECT_EQ((*objects)[0].regionCount, 0u);
  std::size_t triangles = 0;
  for (std::size_t r = 0; r < 4; ++r) {
    const SceneObject& o = (*objects)[1 + r];
    EXPECT_EQ(o.id, 2 + r);
    EXPECT_EQ(o.region, r);
    EXPECT_EQ(o.regionCount, 4u);
    EXPECT_EQ(o.shape, (*objects)[1].shape);  // one Shape, one appearance
    EXPECT_EQ(o.instance, (*objects)[1].instance);
    EXPECT_EQ(o.objectToWorld, (*objects)[1].objectToWorld);
    EXPECT_LT(o.fullMesh->triangleCount(), 512u);
    triangles += o.fullMesh->triangleCount();
    // Its own sphere: smaller than the whole grid's (diagonal sqrt 2, scale 2).
    EXPECT_LT(o.worldSphere.radius, 0.8f * std::sqrt(2.0f));
  }
  EXPECT_EQ(triangles, 512u);  // 16 x 16 squares, two triangles each
  // The same scene loaded again numbers the regions the same way.
  Result<Scene> again = loadSceneFile(dir + "/regions.wrl", {});
  ASSERT_TRUE(again.ok());
  Result<std::vector<SceneObject>> objectsAgain = collectSceneObjects(*again);
  ASSERT_TRUE(objectsAgain.ok());
  for (std::size_t k = 0; k < 5; ++k)
    EXPECT_EQ((*objectsAgain)[k].fullMesh->positions, (*objects)[k].fullMesh->positions);
}

TEST(SceneRegions, ASplitThatCannotBeMadeNamesTheInline) {
  const std::string dir = scratchDir();
  ASSERT_TRUE(saveMeshFile(grid(3), dir + "/tiny.obj").ok());
  std::ofstream(dir + "/tiny.wrl") << kHeader << "\n  Inline { url \"tiny.obj\" regions 9 }\n";
  Result<Scene> scene = loadSceneFile(dir + "/tiny.wrl", {});
  ASSERT_TRUE(scene.ok()) << scene.status().toString();
  Result<std::vector<SceneObject>> objects = collectSceneObjects(*scene);
  ASSERT_FALSE(objects.ok());
  EXPECT_EQ(objects.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(objects.status().message().find("tiny.wrl:3:3: Inline regions 9"), std::string::npos)
      << objects.status().message();
}

}  // namespace
}  // namespace thinlod::scene
