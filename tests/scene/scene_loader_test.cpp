#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

std::string dataPath(const std::string& file) {
  return std::string(THINLOD_TEST_DATA_DIR) + "/scene/" + file;
}

SceneLoadOptions withModels() {
  SceneLoadOptions options;
  options.meshSearchPaths.push_back(std::string(THINLOD_SHARED_DIR) + "/models");
  return options;
}

TEST(SceneLoader, MeshesResolveThroughSearchPathAndSceneDirectory) {
  Result<Scene> r = loadSceneFile(dataPath("meshes.wrl"), withModels());
  ASSERT_TRUE(r.ok()) << r.status().toString();
  ASSERT_EQ(r->roots.size(), 3u);
  const ShapeNode* cowA = r->roots[0]->children[0]->as<ShapeNode>();
  const ShapeNode* cowB = r->roots[1]->children[0]->as<ShapeNode>();
  const ShapeNode* tetra = r->roots[2]->as<ShapeNode>();
  ASSERT_TRUE(cowA && cowB && tetra);
  ASSERT_TRUE(cowA->geometry.mesh);
  EXPECT_EQ(cowA->geometry.mesh->triangleCount(), 5804u);
  EXPECT_EQ(cowA->geometry.mesh, cowB->geometry.mesh);  // loaded once
  EXPECT_EQ(cowB->geometry.resolvedPath.substr(cowB->geometry.resolvedPath.size() - 7), "cow.obj");
  ASSERT_TRUE(tetra->geometry.mesh);
  EXPECT_EQ(tetra->geometry.mesh->triangleCount(), 4u);
  EXPECT_EQ(tetra->appearance.material.diffuseColor, glm::vec3(0.2f, 0.4f, 0.6f));
  // The cow's non-manifold triangles are reported once, not per Shape.
  ASSERT_EQ(r->warnings.size(), 1u);
  EXPECT_NE(r->warnings[0].find("non-manifold"), std::string::npos);
  // Inline Shapes get a lit default material.
  EXPECT_TRUE(cowA->appearance.hasMaterial);
  Result<NodeCurve> curve = relativeCurve(*r->roots[0]);
  ASSERT_TRUE(curve.ok()) << curve.status().toString();
  EXPECT_DOUBLE_EQ(curve->curve.resourcesFor(10.0), 5804.0);
}

TEST(SceneLoader, MissingMeshNamesTheSceneLineAndTheTriedPaths) {
  Result<Scene> r = loadSceneFile(dataPath("missing_mesh.wrl"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::kNotFound);
  EXPECT_NE(r.status().message().find("missing_mesh.wrl:2:1"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find("no_such_mesh.obj"), std::string::npos);
}

TEST(SceneLoader, MissingSceneFile) {
  Result<Scene> r = loadSceneFile(dataPath("nope.wrl"));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::kNotFound);
}

TEST(SceneLoader, UnsafeUrlsAreRejected) {
  for (const char* url : {"../mesh/good_tetra.obj", "/etc/passwd.obj", "http://x/cow.obj"}) {
    Result<Scene> s =
        parseScene(std::string("#VRML V2.0 utf8\nInline { url \"") + url + "\" }", "u.wrl");
    ASSERT_TRUE(s.ok()) << s.status().toString();
    const Status st = resolveMeshes(*s, std::string(THINLOD_TEST_DATA_DIR) + "/scene", {});
    EXPECT_FALSE(st.ok()) << url;
    EXPECT_NE(st.message().find("u.wrl:2:1"), std::string::npos) << st.message();
  }
}

TEST(SceneLoader, NonMeshUrlIsUnsupported) {
  Result<Scene> s = parseScene("#VRML V2.0 utf8\nInline { url \"other.wrl\" }", "u.wrl");
  ASSERT_TRUE(s.ok());
  const Status st = resolveMeshes(*s, std::string(THINLOD_TEST_DATA_DIR) + "/scene", {});
  EXPECT_EQ(st.code(), ErrorCode::kUnsupported) << st.toString();
}

}  // namespace
}  // namespace thinlod::scene

namespace thinlod::scene {
namespace {

// The fingerprint the daemons compare at the handshake: equal for the same
// text and meshes wherever they were found, different when either changes.
class SceneFingerprint : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("thinlod-fingerprint-" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
            std::to_string(reinterpret_cast<std::uintptr_t>(this)));
    std::filesystem::create_directories(dir_);
    std::filesystem::copy_file(dataPath("meshes.wrl"), dir_ / "meshes.wrl");
    std::filesystem::copy_file(dataPath("tetra.off"), dir_ / "tetra.off");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::uint64_t fingerprint() {
    Result<Scene> r = loadSceneFile((dir_ / "meshes.wrl").string(), withModels());
    EXPECT_TRUE(r.ok()) << r.status().toString();
    return r.ok() ? r->fingerprint : 0;
  }
  void write(const char* file, const std::string& text) {
    std::ofstream out(dir_ / file, std::ios::trunc);
    out << text;
  }
  std::filesystem::path dir_;
};

TEST_F(SceneFingerprint, SameTextAndMeshesGiveTheSameNonZeroFingerprintWhereverTheyLie) {
  const std::uint64_t copied = fingerprint();
  Result<Scene> original = loadSceneFile(dataPath("meshes.wrl"), withModels());
  ASSERT_TRUE(original.ok());
  EXPECT_NE(copied, 0u);
  EXPECT_EQ(copied, original->fingerprint);
  EXPECT_EQ(copied, fingerprint());
}

TEST_F(SceneFingerprint, ChangedSceneTextChangesIt) {
  const std::uint64_t before = fingerprint();
  std::ifstream in(dir_ / "meshes.wrl");
  std::stringstream text;
  text << in.rdbuf();
  write("meshes.wrl", text.str() + "# one more comment\n");
  EXPECT_NE(fingerprint(), before);
}

TEST_F(SceneFingerprint, ChangedMeshGeometryChangesIt) {
  const std::uint64_t before = fingerprint();
  // The same tetrahedron with one vertex moved.
  write("tetra.off",
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1.5\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  EXPECT_NE(fingerprint(), before);
}

TEST(SceneFingerprintOfText, ParsedWithoutLoadingIsZero) {
  Result<Scene> parsed =
      parseScene("#thinlod scene 1\nShape { geometry Sphere { radius 1 } }\n", "inline.wrl");
  ASSERT_TRUE(parsed.ok()) << parsed.status().toString();
  EXPECT_EQ(parsed->fingerprint, 0u);
  EXPECT_NE(sceneFingerprint("#thinlod scene 1\n", *parsed), 0u);
}

}  // namespace
}  // namespace thinlod::scene
