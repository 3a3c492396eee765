// VRML ImageTexture / TextureCoordinate / texCoordIndex (docs/scene-format.md,
// "Textures"): parsed into Appearance::textureUrl and IndexedMesh uvs, with
// clear errors for bad urls and indices.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

namespace fs = std::filesystem;
const std::string kHeader = "#VRML V2.0 utf8\n";

Result<Scene> parse(const std::string& text) { return parseScene(text, "t.wrl"); }

void expectError(const std::string& text, ErrorCode code, int line, int column,
                 const std::string& part) {
  Result<Scene> r = parse(text);
  ASSERT_FALSE(r.ok()) << "parsed: " << text;
  EXPECT_EQ(r.status().code(), code) << r.status().toString();
  const std::string prefix = "t.wrl:" + std::to_string(line) + ":" + std::to_string(column) + ":";
  EXPECT_EQ(r.status().message().rfind(prefix, 0), 0u)
      << "want " << prefix << " got " << r.status().message();
  EXPECT_NE(r.status().message().find(part), std::string::npos) << r.status().message();
}

const ShapeNode& firstShape(const Scene& scene) {
  const ShapeNode* shape = scene.roots.at(0)->as<ShapeNode>();
  EXPECT_NE(shape, nullptr);
  return *shape;
}

TEST(SceneTexture, ImageTextureUrlsGoToTheAppearanceAndDefUseCopiesThem) {
  Result<Scene> r = parse(kHeader +
                          "Shape { appearance Appearance { texture DEF T ImageTexture {\n"
                          "  url [ \"a.png\" \"textures/b.jpg\" ] repeatS FALSE repeatT TRUE } }\n"
                          "  geometry Box {} }\n"
                          "Shape { appearance Appearance { texture USE T } geometry Sphere {} }\n"
                          "Shape { appearance Appearance { texture NULL } geometry Sphere {} }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  ASSERT_EQ(r->roots.size(), 3u);
  const Appearance& a = r->roots[0]->as<ShapeNode>()->appearance;
  EXPECT_EQ(a.textureUrl, "a.png");
  EXPECT_EQ(a.textureAlternatives, std::vector<std::string>{"textures/b.jpg"});
  const Appearance& used = r->roots[1]->as<ShapeNode>()->appearance;
  EXPECT_EQ(used.textureUrl, "a.png");
  EXPECT_EQ(used.textureAlternatives, a.textureAlternatives);
  EXPECT_TRUE(r->roots[2]->as<ShapeNode>()->appearance.textureUrl.empty());
}

TEST(SceneTexture, BadUrlsAreErrorsAtTheUrl) {
  expectError(kHeader + "Shape { appearance Appearance { texture ImageTexture {} } }\n",
              ErrorCode::kParseError, 2, 41, "ImageTexture has no url");
  expectError(kHeader + "Shape { appearance Appearance { texture ImageTexture { url [] } } }\n",
              ErrorCode::kParseError, 2, 56, "ImageTexture has no url");
  expectError(kHeader + "Shape { appearance Appearance { texture ImageTexture { url \"\" } } }\n",
              ErrorCode::kInvalidArgument, 2, 56, "empty url");
  expectError(kHeader +
                  "Shape { appearance Appearance { texture ImageTexture { url "
                  "\"http://example.invalid/t.png\" } } }\n",
              ErrorCode::kUnsupported, 2, 56, "has a scheme");
  expectError(kHeader +
                  "Shape { appearance Appearance { texture ImageTexture { url "
                  "[ \"ok.png\" \"../up.png\" ] } } }\n",
              ErrorCode::kInvalidArgument, 2, 56, "contains '..'");
  expectError(kHeader +
                  "Shape { appearance Appearance { texture ImageTexture { url \"/etc/t.png\" } } }\n",
              ErrorCode::kInvalidArgument, 2, 56, "is absolute");
  expectError(kHeader + "Shape { appearance Appearance { texture PixelTexture {} } }\n",
              ErrorCode::kParseError, 2, 41, "only ImageTexture");
  expectError(kHeader + "Shape { appearance Appearance { texture USE Nope } }\n",
              ErrorCode::kParseError, 2, 45, "Nope");
}

TEST(SceneTexture, TexCoordIndexSplitsVerticesAtUvSeams) {
  // A quad of two triangles whose shared edge has other uvs in each face.
  Result<Scene> r = parse(kHeader +
                          "Shape { geometry IndexedFaceSet {\n"
                          "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0 ] }\n"
                          "  coordIndex [ 0 1 2 -1 0 2 3 -1 ]\n"
                          "  texCoord TextureCoordinate { point [ 0 0, 1 0, 1 1, 0 1, 0.5 0.5 ] }\n"
                          "  texCoordIndex [ 0 1 2 -1 4 2 3 -1 ] } }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const IndexedMesh& mesh = *firstShape(*r).geometry.mesh;
  EXPECT_EQ(mesh.triangleCount(), 2u);
  // (0,0) (1,1) (2,2) (0,4) (3,3): vertex 0 is two vertices, vertex 2 one.
  ASSERT_EQ(mesh.positions.size(), 5u);
  ASSERT_EQ(mesh.uvs.size(), 5u);
  EXPECT_TRUE(mesh.validate("mesh").ok());
  const std::uint32_t secondFirst = mesh.indices[3];
  EXPECT_EQ(mesh.positions[secondFirst], glm::vec3(0.0f));
  EXPECT_EQ(mesh.uvs[secondFirst], glm::vec2(0.5f));
  EXPECT_EQ(mesh.uvs[mesh.indices[0]], glm::vec2(0.0f));
  EXPECT_EQ(mesh.indices[2], mesh.indices[4]);  // (2,2) is shared
}

TEST(SceneTexture, WithoutTexCoordIndexTheCoordIndexIndexesTheUvs) {
  Result<Scene> r = parse(kHeader +
                          "Shape { geometry IndexedFaceSet {\n"
                          "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0 ] }\n"
                          "  texCoord DEF UV TextureCoordinate { point [ 0 0, 1 0, 1 1 ] }\n"
                          "  coordIndex [ 0 1 2 ] } }\n"
                          "Shape { geometry IndexedFaceSet {\n"
                          "  coord Coordinate { point [ 0 0 1, 1 0 1, 1 1 1 ] }\n"
                          "  texCoord USE UV coordIndex [ 2 1 0 ] } }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const IndexedMesh& mesh = *firstShape(*r).geometry.mesh;
  ASSERT_EQ(mesh.uvs.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(mesh.uvs[mesh.indices[i]], glm::vec2(mesh.positions[mesh.indices[i]]));
  }
  const IndexedMesh& used = *r->roots[1]->as<ShapeNode>()->geometry.mesh;
  ASSERT_EQ(used.uvs.size(), 3u);
  EXPECT_EQ(used.uvs[used.indices[0]], glm::vec2(1.0f, 1.0f));
}

TEST(SceneTexture, OutOfRangeOrMismatchedTexCoordIndicesAreErrors) {
  const std::string coords = "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0 ] }\n";
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 ]\n"
                  "  texCoord TextureCoordinate { point [ 0 0, 1 0 ] }\n"
                  "  texCoordIndex [ 0 1 5 ] } }\n",
              ErrorCode::kParseError, 6, 3,
              "texCoordIndex entry 2 is 5 but TextureCoordinate has 2 points");
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 ]\n"
                  "  texCoord TextureCoordinate { point [ 0 0, 1 0 ] } } }\n",
              ErrorCode::kParseError, 4, 3,
              "coordIndex entry 2 is 2 but TextureCoordinate has 2 points");
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 -1 ]\n"
                  "  texCoord TextureCoordinate { point [ 0 0, 1 0, 1 1 ] }\n"
                  "  texCoordIndex [ 0 1 2 ] } }\n",
              ErrorCode::kParseError, 6, 3, "texCoordIndex has 3 entries, coordIndex 4");
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 -1 ]\n"
                  "  texCoord TextureCoordinate { point [ 0 0, 1 0, 1 1 ] }\n"
                  "  texCoordIndex [ 0 1 2 0 ] } }\n",
              ErrorCode::kParseError, 6, 3, "where coordIndex ends a face");
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 ]\n"
                  "  texCoordIndex [ 0 1 2 ] } }\n",
              ErrorCode::kParseError, 5, 3, "texCoordIndex without a TextureCoordinate");
  expectError(kHeader + "Shape { geometry IndexedFaceSet {\n" + coords +
                  "  coordIndex [ 0 1 2 ]\n"
                  "  texCoord TextureCoordinate { point [ 0 nan ] } } }\n",
              ErrorCode::kParseError, 5, 42, "nan");
}

TEST(SceneTexture, LoaderResolvesTheFirstExistingUrlAndWarnsWhenNoneExists) {
  const fs::path dir = fs::temp_directory_path() / "thinlod-scene-texture-test";
  fs::remove_all(dir);
  fs::create_directories(dir / "tex");
  std::ofstream(dir / "tex" / "b.png") << "x";  // existence is all the loader checks
  std::ofstream(dir / "scene.wrl")
      << kHeader
      << "Shape { appearance Appearance { texture ImageTexture { url [ \"a.png\" \"tex/b.png\" ] } }"
         " geometry Box {} }\n"
         "Shape { appearance Appearance { texture ImageTexture { url \"gone.png\" } }"
         " geometry Box {} }\n";
  Result<Scene> r = loadSceneFile((dir / "scene.wrl").string());
  ASSERT_TRUE(r.ok()) << r.status().toString();
  ASSERT_EQ(r->roots.size(), 2u);
  EXPECT_EQ(fs::path(r->roots[0]->as<ShapeNode>()->appearance.texturePath), dir / "tex" / "b.png");
  EXPECT_TRUE(r->roots[1]->as<ShapeNode>()->appearance.texturePath.empty());
  bool warned = false;
  for (const std::string& w : r->warnings) warned |= w.find("gone.png") != std::string::npos;
  EXPECT_TRUE(warned);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace thinlod::scene
