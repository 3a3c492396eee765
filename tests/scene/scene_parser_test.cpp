#include "thinlod/common/scene/scene_parser.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace thinlod::scene {
namespace {

const std::string kHeader = "#VRML V2.0 utf8\n";

std::string readData(const std::string& file) {
  std::ifstream in(std::string(THINLOD_TEST_DATA_DIR) + "/scene/" + file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Result<Scene> parse(const std::string& text) { return parseScene(text, "t.wrl"); }

// The error is `code` and the message starts with "t.wrl:<line>:<col>:".
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

TEST(SceneParser, Figure10FragmentHasTheExpectedStructure) {
  Result<Scene> r = parseScene(readData("figure10.wrl"), "figure10.wrl");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  ASSERT_EQ(r->roots.size(), 1u);
  const LodNode* lod = r->roots[0]->as<LodNode>();
  ASSERT_NE(lod, nullptr);
  ASSERT_EQ(lod->children.size(), 3u);
  const ShapeNode* cylinder = lod->children[0]->as<ShapeNode>();
  ASSERT_NE(cylinder, nullptr);
  EXPECT_EQ(cylinder->defName, "MyCylinder");
  EXPECT_EQ(cylinder->geometry.kind, GeometryKind::kPrimitive);
  EXPECT_EQ(cylinder->geometry.primitive.kind, PrimitiveKind::kCylinder);
  EXPECT_FLOAT_EQ(cylinder->geometry.primitive.radius, 1.0f);  // VRML defaults
  EXPECT_FLOAT_EQ(cylinder->geometry.primitive.height, 2.0f);
  EXPECT_EQ(lod->children[1]->kind, NodeKind::kSimpleImposter);
  EXPECT_EQ(lod->children[2]->kind, NodeKind::kMeshedImposter);
  // USE shares the node: one Shape with three parents.
  ASSERT_EQ(lod->children[1]->children.size(), 1u);
  ASSERT_EQ(lod->children[2]->children.size(), 1u);
  EXPECT_EQ(lod->children[1]->children[0], lod->children[0]);
  EXPECT_EQ(lod->children[2]->children[0], lod->children[0]);
  EXPECT_EQ(r->defs.at("MyCylinder"), lod->children[0]);
  EXPECT_EQ(r->nodeCount, 4u);  // LOD, Shape, SimpleImposter, MeshedImposter
  ASSERT_EQ(lod->ranges.size(), 3u);
  EXPECT_TRUE(lod->ranges[0].isEverywhere());
  EXPECT_DOUBLE_EQ(lod->ranges[1].minDistance(), 10.0);
  EXPECT_DOUBLE_EQ(lod->ranges[1].maxDistance(), 1000.0);
  EXPECT_TRUE(lod->ranges[2].isEverywhere());
  const ImposterNode* simple = static_cast<const ImposterNode*>(lod->children[1].get());
  EXPECT_EQ(simple->size, glm::vec2(2.0f, 2.0f));  // Figure 9 defaults
  EXPECT_TRUE(simple->autosize);
  EXPECT_TRUE(simple->autocenter);
}

TEST(SceneParser, ImposterFieldsAreRead) {
  Result<Scene> r = parse(kHeader +
                          "SimplifiedPolygon { size 3 4 autosize FALSE center 1 2 3 autocenter "
                          "FALSE children [ Shape { geometry Sphere { radius 0.5 } } ] }");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const Node& n = *r->roots[0];
  ASSERT_EQ(n.kind, NodeKind::kSimplifiedPolygon);
  const ImposterNode& imp = static_cast<const ImposterNode&>(n);
  EXPECT_EQ(imp.size, glm::vec2(3.0f, 4.0f));
  EXPECT_FALSE(imp.autosize);
  EXPECT_EQ(imp.center, glm::vec3(1.0f, 2.0f, 3.0f));
  EXPECT_FALSE(imp.autocenter);
  EXPECT_EQ(imp.children.size(), 1u);
}

TEST(SceneParser, NodeIdsArePreOrderOfFirstAppearance) {
  Result<Scene> r = parse(kHeader +
                          "Group { children [ DEF S Shape { geometry Box {} } Transform { "
                          "children USE S } ] } Viewpoint {}");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const Node& group = *r->roots[0];
  EXPECT_EQ(group.id, 1u);
  EXPECT_EQ(group.children[0]->id, 2u);
  EXPECT_EQ(group.children[1]->id, 3u);
  EXPECT_EQ(group.children[1]->children[0]->id, 2u);
  EXPECT_EQ(r->roots[1]->id, 4u);
  EXPECT_EQ(r->nodeCount, 4u);
}

TEST(SceneParser, CommentsCommasAndStringEscapes) {
  Result<Scene> r = parse(kHeader +
                          "# a comment\nViewpoint { position 1, 2, 3 # trailing\n description "
                          "\"say \\\"hi\\\" \\\\ ok\" }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const ViewpointNode* vp = r->roots[0]->as<ViewpointNode>();
  ASSERT_NE(vp, nullptr);
  EXPECT_EQ(vp->position, glm::vec3(1, 2, 3));
  EXPECT_EQ(vp->description, "say \"hi\" \\ ok");
}

TEST(SceneParser, ThinlodHeaderWithKnownVersion) {
  Result<Scene> r = parse("#thinlod scene 1\nGroup {}\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  EXPECT_EQ(r->header, "thinlod 1");
}

TEST(SceneParser, ByteOrderMarkIsSkipped) {
  Result<Scene> r = parse("\xEF\xBB\xBF" + kHeader + "Group {}\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  EXPECT_EQ(r->roots.size(), 1u);
}

TEST(SceneParser, UnknownVersionsAreRejected) {
  expectError("#thinlod scene 2\nGroup {}\n", ErrorCode::kVersionMismatch, 1, 16, "version 2");
  expectError("#VRML V1.0 ascii\n", ErrorCode::kVersionMismatch, 1, 1, "V1.0");
  expectError("Group {}\n", ErrorCode::kParseError, 1, 1, "missing header");
}

TEST(SceneParser, UnknownNode) {
  expectError(kHeader + "Group {\n  children [\n    Foo { }\n  ]\n}\n", ErrorCode::kParseError, 4,
              5, "unknown node type 'Foo'");
}

TEST(SceneParser, UnknownField) {
  expectError(kHeader + "Transform {\n  translate 1 2 3\n}\n", ErrorCode::kParseError, 3, 3,
              "unknown field 'translate' in 'Transform'");
}

TEST(SceneParser, MissingOpeningBrace) {
  expectError(kHeader + "Shape geometry Sphere {} }\n", ErrorCode::kParseError, 2, 7,
              "expected '{' after 'Shape'");
}

TEST(SceneParser, MissingClosingBracket) {
  expectError(kHeader + "Group { children [ Group {} }\n", ErrorCode::kParseError, 2, 29,
              "expected a node or ']', found '}'");
}

TEST(SceneParser, BadNumber) {
  expectError(kHeader + "Transform {\n  translation 1 2 x3\n}\n", ErrorCode::kParseError, 3, 19,
              "bad number 'x3'");
}

TEST(SceneParser, NaNIsRejected) {
  expectError(kHeader + "Shape { geometry Sphere { radius nan } }\n", ErrorCode::kParseError, 2, 34,
              "'nan' is not finite");
  expectError(kHeader + "Viewpoint { position 1 inf 0 }\n", ErrorCode::kParseError, 2, 24,
              "not finite");
  expectError(kHeader + "Viewpoint { position 1 1e999 0 }\n", ErrorCode::kParseError, 2, 24,
              "not finite");
}

TEST(SceneParser, UseOfUndefinedName) {
  expectError(kHeader + "Group { children [\n  USE Nobody\n] }\n", ErrorCode::kParseError, 3, 7,
              "USE of undefined name 'Nobody'");
}

TEST(SceneParser, UseInsideItsOwnDefinitionIsUndefined) {
  expectError(kHeader + "DEF A Group { children [ USE A ] }\n", ErrorCode::kParseError, 2, 30,
              "undefined name 'A'");
}

TEST(SceneParser, UseOfTheWrongKind) {
  expectError(kHeader +
                  "Shape { appearance Appearance { material DEF M Material {} } }\nGroup { "
                  "children USE M }\n",
              ErrorCode::kParseError, 3, 22, "names a Material, expected a scene-graph node");
}

TEST(SceneParser, TooDeepNesting) {
  std::string text = kHeader;
  for (int i = 0; i < 70; ++i) text += "Group { children [\n";
  Result<Scene> r = parse(text);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::kResourceExhausted);
  // The 65th Group is on line 66 (header is line 1).
  EXPECT_EQ(r.status().message().rfind("t.wrl:66:1:", 0), 0u) << r.status().message();
  EXPECT_NE(r.status().message().find("deeper than 64"), std::string::npos);
}

TEST(SceneParser, TruncatedFile) {
  expectError(kHeader + "Group { children [\n  Shape { geometry Sphere { radius 1",
              ErrorCode::kParseError, 3, 37, "'Sphere' opened at 3:20 is not closed");
  expectError(kHeader + "Group {\n  children [ Shape {} ]\n", ErrorCode::kParseError, 4, 1,
              "'Group' opened at 2:1 is not closed");
  expectError(kHeader + "Viewpoint { description \"abc", ErrorCode::kParseError, 2, 25,
              "unterminated string");
}

TEST(SceneParser, UnsupportedVrmlFeatures) {
  expectError(kHeader + "PROTO Foo [] {}\n", ErrorCode::kParseError, 2, 1, "not supported");
  expectError(
      kHeader + "Shape { appearance Appearance { textureTransform TextureTransform {} } }\n",
      ErrorCode::kParseError, 2, 33, "'textureTransform' is not supported");
}

TEST(SceneParser, ValueLimits) {
  ParseLimits limits;
  limits.maxValuesPerField = 5;
  Result<Scene> r =
      parseScene(kHeader + "Shape { geometry IndexedFaceSet { coordIndex [ 0 1 2 -1 0 2 3 ] } }",
                 "t.wrl", limits);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_EQ(r.status().message().rfind("t.wrl:2:", 0), 0u) << r.status().message();
}

TEST(SceneParser, DefUseExplosionIsBounded) {
  std::string text = kHeader + "DEF L0 Group {}\n";
  for (int i = 1; i <= 30; ++i) {
    text += "DEF L" + std::to_string(i) + " Group { children [ USE L" + std::to_string(i - 1) +
            " USE L" + std::to_string(i - 1) + " ] }\n";
  }
  Result<Scene> r = parse(text);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("node instances"), std::string::npos);
}

TEST(SceneParser, IndexedFaceSetIsTriangulated) {
  Result<Scene> r = parse(kHeader +
                          "Shape { geometry IndexedFaceSet {\n"
                          "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0 ] }\n"
                          "  coordIndex [ 0 1 2 3 -1 ] } }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const ShapeNode* s = r->roots[0]->as<ShapeNode>();
  ASSERT_NE(s, nullptr);
  ASSERT_EQ(s->geometry.kind, GeometryKind::kIndexedFaceSet);
  ASSERT_TRUE(s->geometry.mesh);
  EXPECT_EQ(s->geometry.mesh->triangleCount(), 2u);
  EXPECT_EQ(s->geometry.mesh->indices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_TRUE(s->geometry.mesh->validate("ifs").ok());
  ASSERT_EQ(s->geometry.mesh->normals.size(), 4u);
  EXPECT_NEAR(s->geometry.mesh->normals[0].z, 1.0f, 1e-6f);
}

TEST(SceneParser, IndexedFaceSetClockwiseIsReversed) {
  Result<Scene> r = parse(kHeader +
                          "Shape { geometry IndexedFaceSet { ccw FALSE coord Coordinate { point "
                          "[ 0 0 0, 1 0 0, 1 1 0 ] } coordIndex [ 0 1 2 ] } }");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  EXPECT_EQ(r->roots[0]->as<ShapeNode>()->geometry.mesh->indices,
            (std::vector<std::uint32_t>{0, 2, 1}));
}

TEST(SceneParser, IndexedFaceSetIndexOutOfRange) {
  expectError(kHeader +
                  "Shape { geometry IndexedFaceSet {\n"
                  "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0 ] }\n"
                  "  coordIndex [ 0 1 7 ] } }\n",
              ErrorCode::kParseError, 4, 3, "coordIndex entry 2 is 7 but Coordinate has 3 points");
}

TEST(SceneParser, PlainVrmlRangesBecomeConicRanges) {
  Result<Scene> r = parse(kHeader +
                          "LOD { center 1 0 0 range [ 5 20 ] level [ Group {} Group {} Group {} "
                          "] }");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const LodNode* lod = r->roots[0]->as<LodNode>();
  ASSERT_EQ(lod->ranges.size(), 3u);
  EXPECT_DOUBLE_EQ(lod->ranges[0].minDistance(), 0.0);
  EXPECT_DOUBLE_EQ(lod->ranges[0].maxDistance(), 5.0);
  EXPECT_DOUBLE_EQ(lod->ranges[1].minDistance(), 5.0);
  EXPECT_DOUBLE_EQ(lod->ranges[1].maxDistance(), 20.0);
  EXPECT_DOUBLE_EQ(lod->ranges[2].minDistance(), 20.0);
  EXPECT_TRUE(std::isinf(lod->ranges[2].maxDistance()));
  EXPECT_EQ(lod->ranges[1].center(), glm::dvec3(1.0, 0.0, 0.0));
}

TEST(SceneParser, BadRangesAreRejected) {
  expectError(kHeader + "LOD { range [ 5 ] level [ Group {} ] }", ErrorCode::kParseError, 2, 7,
              "need 2 levels");
  expectError(kHeader + "LOD { range [ ConicRange { distance 10 5 } ] level [ Group {} ] }",
              ErrorCode::kParseError, 2, 15, "invalid ConicRange");
  expectError(kHeader + "LOD { range [ ConicRange { alpha 4 } ] level [ Group {} ] }",
              ErrorCode::kParseError, 2, 15, "invalid ConicRange");
}

TEST(SceneParser, LightsViewpointAndMaterial) {
  Result<Scene> r = parse(kHeader +
                          "DirectionalLight { direction 0 -2 0 intensity 0.5 color 1 0.5 0 }\n"
                          "PointLight { location 1 2 3 on FALSE }\n"
                          "Viewpoint { position 0 1.6 5 orientation 0 1 0 0.5 fieldOfView 1 }\n"
                          "Shape { appearance Appearance { material Material { diffuseColor 1 0 "
                          "0 transparency 0.5 } } geometry Cone { bottomRadius 0.5 height 1 } }\n");
  ASSERT_TRUE(r.ok()) << r.status().toString();
  const auto* dl = r->roots[0]->as<DirectionalLightNode>();
  ASSERT_NE(dl, nullptr);
  EXPECT_EQ(dl->direction, glm::vec3(0, -1, 0));
  EXPECT_FLOAT_EQ(dl->intensity, 0.5f);
  const auto* pl = r->roots[1]->as<PointLightNode>();
  ASSERT_NE(pl, nullptr);
  EXPECT_FALSE(pl->on);
  const auto* vp = r->roots[2]->as<ViewpointNode>();
  ASSERT_NE(vp, nullptr);
  EXPECT_FLOAT_EQ(vp->orientation.w, 0.5f);
  const auto* shape = r->roots[3]->as<ShapeNode>();
  ASSERT_NE(shape, nullptr);
  EXPECT_TRUE(shape->appearance.hasMaterial);
  EXPECT_EQ(shape->appearance.material.diffuseColor, glm::vec3(1, 0, 0));
  EXPECT_EQ(shape->geometry.primitive.kind, PrimitiveKind::kCone);
}

TEST(SceneParser, OutOfRangeValuesAreRejected) {
  expectError(kHeader + "Shape { geometry Sphere { radius -1 } }", ErrorCode::kParseError, 2, 34,
              "radius must be positive");
  expectError(kHeader +
                  "Shape { appearance Appearance { material Material { diffuseColor 2 0 0 "
                  "} } }",
              ErrorCode::kParseError, 2, 66, "colour components must be in [0, 1]");
  expectError(kHeader + "Transform { rotation 0 0 0 1 }", ErrorCode::kParseError, 2, 22,
              "rotation axis is zero");
  expectError(kHeader + "Inline { }", ErrorCode::kParseError, 2, 1, "Inline needs a url");
}

// Memory safety: every prefix and random corruptions of a valid file give a
// result, never a crash or hang.
TEST(SceneParser, TruncatedPrefixesAndCorruptionsNeverCrash) {
  const std::string good = readData("figure10.wrl") + readData("meshes.wrl").substr(17) +
                           "Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, "
                           "1 0 0, 1 1 0 ] } coordIndex [ 0 1 2 -1 ] } }\n";
  ASSERT_TRUE(parse(good).ok()) << parse(good).status().toString();
  for (std::size_t n = 0; n < good.size(); ++n) {
    Result<Scene> r = parse(good.substr(0, n));
    if (!r.ok()) {
      EXPECT_NE(r.status().message().find("t.wrl:"), std::string::npos);
    }
  }
  std::uint32_t state = 7u;  // fixed seed
  auto next = [&state]() {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  const char alphabet[] = "{}[]\"#,.-+0123456789eE DEFUSEnan\n\\";
  for (int trial = 0; trial < 2000; ++trial) {
    std::string text = good;
    const int edits = 1 + static_cast<int>(next() % 4);
    for (int k = 0; k < edits; ++k) {
      const std::size_t at = 16 + next() % (text.size() - 16);
      text[at] = alphabet[next() % (sizeof(alphabet) - 1)];
    }
    Result<Scene> r = parse(text);
    if (!r.ok()) {
      EXPECT_NE(r.status().message().find("t.wrl:"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace thinlod::scene
