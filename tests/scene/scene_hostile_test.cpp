// Broken and hostile files through the scene front doors (importScene,
// loadSceneFile, and a VRML Inline for mesh formats): every one gives a clean
// Status naming the file (no crash, no exception, no kInternal) within bounded
// memory. One parametrized test over the files of the Debian package
// assimp-testmodels' invalid folders (a missing file FAILS, naming the
// package), and one test per class of hostile input written here: huge counts,
// NaN / infinite / overflowing coordinates, cyclic and very deep node graphs,
// deeply nested JSON, truncated files.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene_import.h"
#include "thinlod/common/scene/skinned_import.h"
#include "thinlod/common/scene/scene_parser.h"

namespace thinlod::scene {
namespace {

namespace fs = std::filesystem;

const std::string kModels = "/usr/share/assimp/models";

// Peak resident memory of this process; every hostile input must leave it
// below kMaxPeakBytes (the package's OutOfMemory.off asks for hundreds of GB).
constexpr long kMaxPeakBytes = 1L << 30;
long peakBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss * 1024L;  // kilobytes on Linux
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class HostileFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("thinlod_hostile_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  fs::path dir_;
};

// importScene (imported formats) or the mesh loader (mesh formats), and
// loadSceneFile (imported formats directly, mesh formats through a VRML
// Inline) all refuse `path` cleanly.
void expectRefusedEverywhere(const std::string& path, const fs::path& scratch) {
  SCOPED_TRACE(path);
  auto clean = [&](const Status& status, const char* door) {
    EXPECT_FALSE(status.ok()) << door << " accepted it";
    EXPECT_NE(status.message().find(fs::path(path).filename().string()), std::string::npos)
        << door << ": " << status.toString();
    EXPECT_NE(status.code(), ErrorCode::kInternal) << door << ": " << status.toString();
  };
  if (isImportedSceneExtension(path)) {
    clean(importScene(path).status(), "importScene");
    clean(loadSceneFile(path).status(), "loadSceneFile");
    clean(importSkinnedModel(path).status(), "importSkinnedModel");  // the same front door
  }
  if (isSupportedMeshExtension(path)) {
    clean(loadMeshFile(path).status(), "loadMeshFile");
    const fs::path wrl = scratch / "inline.wrl";
    std::ofstream(wrl) << "#VRML V2.0 utf8\nInline { url \"" << path << "\" }\n";
    clean(loadSceneFile(wrl.string()).status(), "VRML Inline");
  }
  if (!isImportedSceneExtension(path) && !isSupportedMeshExtension(path)) {
    // Not a format the project reads: refused by importScene up front, and
    // loadSceneFile reads it as (broken) VRML.
    clean(importScene(path).status(), "importScene");
    clean(loadSceneFile(path).status(), "loadSceneFile");
  }
  EXPECT_LT(peakBytes(), kMaxPeakBytes);
}

// ---- the package's invalid files ------------------------------------------

struct PackageCase {
  const char* file;  // under /usr/share/assimp/models
  bool loads;        // a valid scene after all (see the comment at the case)
};

class PackageInvalidFiles : public ::testing::TestWithParam<PackageCase> {};

TEST_P(PackageInvalidFiles, GiveACleanStatus) {
  const std::string path = kModels + "/" + GetParam().file;
  std::error_code ec;
  ASSERT_TRUE(fs::is_regular_file(path, ec))
      << path << " is missing: install the Debian package assimp-testmodels (deploy/setup does)";
  if (GetParam().loads) {
    // invalid/malformed2.obj only names a material that does not exist:
    // Assimp substitutes its default one, the geometry is valid.
    Result<Scene> r = importScene(path);
    ASSERT_TRUE(r.ok()) << r.status().toString();
    EXPECT_GT(r->nodeCount, 0u);
    EXPECT_LT(peakBytes(), kMaxPeakBytes);
    return;
  }
  expectRefusedEverywhere(path, fs::temp_directory_path());
}

// Every file of `dpkg -L assimp-testmodels | grep -i invalid`.
INSTANTIATE_TEST_SUITE_P(
    AssimpTestmodels, PackageInvalidFiles,
    ::testing::Values(
        PackageCase{"invalid/OutOfMemory.off", false}, PackageCase{"invalid/empty.3ds", false},
        PackageCase{"invalid/empty.ase", false}, PackageCase{"invalid/empty.lwo", false},
        PackageCase{"invalid/empty.md5mesh", false}, PackageCase{"invalid/empty.obj", false},
        PackageCase{"invalid/empty.off", false}, PackageCase{"invalid/empty.ply", false},
        PackageCase{"invalid/empty.raw", false}, PackageCase{"invalid/empty.smd", false},
        PackageCase{"invalid/empty.x", false}, PackageCase{"invalid/emptyIrrMesh.xml", false},
        PackageCase{"invalid/malformed.obj", false}, PackageCase{"invalid/malformed2.obj", false},
        PackageCase{"invalid/readme.txt", false}, PackageCase{"OFF/invalid.off", false}),
    [](const ::testing::TestParamInfo<PackageCase>& info) {
      std::string name = info.param.file;
      for (char& c : name) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      }
      return name;
    });

// ---- hostile files of our own, one class per test --------------------------

// A one-triangle Collada file; `positions` is the float_array's text and
// count, `library` and `scene` are spliced in as library_nodes and the
// visual scene's content.
std::string collada(const std::string& positions, const std::string& count,
                    const std::string& library, const std::string& scene) {
  return R"(<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<library_geometries><geometry id="g"><mesh>
<source id="p"><float_array id="pa" count=")" +
         count + R"(">)" + positions + R"(</float_array>
<technique_common><accessor source="#pa" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
</mesh></geometry></library_geometries>
<library_nodes>)" +
         library + R"(</library_nodes>
<library_visual_scenes><visual_scene id="s">)" +
         scene + R"(</visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)";
}

const std::string kTriangle = "0 0 0 1 0 0 0 1 0";
const std::string kGeometryNode = R"(<node id="root"><instance_geometry url="#g"/></node>)";

// A glTF with one triangle in a data: buffer (3 float positions, 3 uint16
// indices + 2 bytes padding), `positions` the 9 floats.
std::string gltfTriangle(const std::vector<float>& positions, const std::string& extra = "") {
  std::string bytes(36 + 8, '\0');
  std::memcpy(bytes.data(), positions.data(), 36);
  const std::uint16_t indices[3] = {0, 1, 2};
  std::memcpy(bytes.data() + 36, indices, 6);
  static const char* kBase64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t n =
        static_cast<std::uint8_t>(bytes[i]) << 16 |
        (i + 1 < bytes.size() ? static_cast<std::uint8_t>(bytes[i + 1]) << 8 : 0) |
        (i + 2 < bytes.size() ? static_cast<std::uint8_t>(bytes[i + 2]) : 0);
    b64 += kBase64[n >> 18 & 63];
    b64 += kBase64[n >> 12 & 63];
    b64 += i + 1 < bytes.size() ? kBase64[n >> 6 & 63] : '=';
    b64 += i + 2 < bytes.size() ? kBase64[n & 63] : '=';
  }
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
         R"("buffers":[{"byteLength":44,"uri":"data:application/octet-stream;base64,)" +
         b64 +
         R"("}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
         R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}])" +
         extra + "}";
}

TEST_F(HostileFiles, TheWellFormedTemplatesLoad) {
  // The templates below differ from these only in the hostile part.
  Result<Scene> dae = importScene(write("ok.dae", collada(kTriangle, "9", "", kGeometryNode)));
  EXPECT_TRUE(dae.ok()) << dae.status().toString();
  Result<Scene> gltf = importScene(write("ok.gltf", gltfTriangle({0, 0, 0, 1, 0, 0, 0, 1, 0})));
  EXPECT_TRUE(gltf.ok()) << gltf.status().toString();
  Result<Scene> obj = importScene(write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_TRUE(obj.ok()) << obj.status().toString();
}

TEST_F(HostileFiles, HugeDeclaredCountsAreRefused) {
  for (
      const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
          {"count.dae", collada(kTriangle, "2000000000", "", kGeometryNode)},
          {"accessor.dae",
           collada(kTriangle, "9", "", kGeometryNode)
               .replace(collada(kTriangle, "9", "", kGeometryNode).find("count=\"3\""), 9,
                        "count=\"1000000000\"")},
          {"vertices.off", "OFF\n2000000000 2000000000 0\n0 0 0\n"},
          {"faces.off", "OFF\n3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
          {"vertices.ply",
           "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
           "property float y\nproperty float z\nelement face 1\n"
           "property list uchar int vertex_indices\nend_header\n0 0 0\n"},
          {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n"},
          {"count.gltf",
           R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
           R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
           R"("buffers":[{"byteLength":36}],"bufferViews":[{"buffer":0,"byteLength":36}],)"
           R"("accessors":[{"bufferView":0,"componentType":5126,"count":4000000000,"type":"VEC3"}]})"},
      }) {
    expectRefusedEverywhere(write(name, bytes), dir_);
  }
}

TEST_F(HostileFiles, NanInfiniteAndOverflowingCoordinatesAreRefused) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
           {"nan.dae", collada("nan 0 0 1 0 0 0 1 0", "9", "", kGeometryNode)},
           {"inf.dae", collada("0 0 0 1e39 0 0 0 1 0", "9", "", kGeometryNode)},
           {"nan.gltf", gltfTriangle({nan, 0, 0, 1, 0, 0, 0, 1, 0})},
           {"inf.gltf", gltfTriangle({0, 0, 0, inf, 0, 0, 0, 1, 0})},
           {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
           {"overflow.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"},
           {"nan.off", "OFF\n3 1 0\nnan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
           {"inf.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\ninf 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
       }) {
    expectRefusedEverywhere(write(name, bytes), dir_);
  }
}

TEST_F(HostileFiles, CyclicNodeGraphsAreRefused) {
  // Collada: node a instantiates b, b instantiates a (and a itself).
  const std::string cycle = R"(<node id="a"><instance_node url="#b"/></node>)"
                            R"(<node id="b"><instance_node url="#a"/></node>)";
  const std::string self = R"(<node id="a"><instance_node url="#a"/></node>)";
  const std::string use =
      R"(<node id="root"><instance_node url="#a"/><instance_geometry url="#g"/></node>)";
  // glTF: a node that is its own child, and two nodes that are each other's.
  const std::string base = gltfTriangle({0, 0, 0, 1, 0, 0, 0, 1, 0});
  std::string selfChild = base;
  selfChild.replace(selfChild.find(R"("nodes":[{"mesh":0}])"), 20,
                    R"("nodes":[{"mesh":0,"children":[0]}])");
  std::string mutual = base;
  mutual.replace(mutual.find(R"("nodes":[{"mesh":0}])"), 20,
                 R"("nodes":[{"mesh":0,"children":[1]},{"children":[0]}])");
  for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
           {"cycle.dae", collada(kTriangle, "9", cycle, use)},
           {"self.dae", collada(kTriangle, "9", self, use)},
           {"self_child.gltf", selfChild},
           {"mutual.gltf", mutual},
       }) {
    expectRefusedEverywhere(write(name, bytes), dir_);
  }
}

TEST_F(HostileFiles, VeryDeepNestingIsRefused) {
  // 100 000 nested nodes / arrays: recursive parsers overflow the stack on
  // such input unless it is refused before they see it.
  constexpr int kDepth = 100000;
  std::string nodes;
  for (int i = 0; i < kDepth; ++i) nodes += "<node>";
  nodes += R"(<instance_geometry url="#g"/>)";
  for (int i = 0; i < kDepth; ++i) nodes += "</node>";
  std::string json =
      gltfTriangle({0, 0, 0, 1, 0, 0, 0, 1, 0},
                   R"(,"extras":)" + std::string(kDepth, '[') + std::string(kDepth, ']'));
  std::string gltfChain = gltfTriangle({0, 0, 0, 1, 0, 0, 0, 1, 0});
  {
    // 100 000 glTF nodes each the child of the previous.
    std::string list = R"("nodes":[)";
    for (int i = 0; i < kDepth; ++i) {
      list += i + 1 < kDepth ? R"({"children":[)" + std::to_string(i + 1) + "]}," : R"({"mesh":0})";
    }
    list += "]";
    gltfChain.replace(gltfChain.find(R"("nodes":[{"mesh":0}])"), 20, list);
  }
  for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
           {"deep.dae", collada(kTriangle, "9", "", nodes)},
           {"deep_json.gltf", json},
           {"deep_chain.gltf", gltfChain},
       }) {
    expectRefusedEverywhere(write(name, bytes), dir_);
  }
}

TEST_F(HostileFiles, TruncatedFilesAreRefused) {
  // Package files cut at 16 evenly spaced lengths: binary FBX, Collada,
  // OBJ (and the glb in scene_import_test.cpp).
  for (const char* file : {"FBX/box.fbx", "Collada/duck.dae", "OBJ/spider.obj"}) {
    const std::string path = kModels + "/" + file;
    ASSERT_TRUE(fs::is_regular_file(path))
        << path << " is missing: install the Debian package assimp-testmodels (deploy/setup does)";
    const std::string bytes = readAll(path);
    ASSERT_GT(bytes.size(), 1000u);
    const std::string name = "cut" + fs::path(path).extension().string();
    int refused = 0;
    for (int k = 0; k < 16; ++k) {
      const std::size_t length = bytes.size() * static_cast<std::size_t>(k) / 16;
      const std::string cut = write(name, bytes.substr(0, length));
      SCOPED_TRACE(std::string(file) + " cut at " + std::to_string(length));
      // A prefix of an OBJ is often a valid OBJ with fewer faces: it must
      // then load as a well-formed scene; every other outcome is a refusal
      // naming the file.
      Result<Scene> r = importScene(cut);
      if (r.ok()) {
        EXPECT_EQ(fs::path(path).extension(), ".obj") << "a cut binary or XML file loaded";
        continue;
      }
      ++refused;
      EXPECT_NE(r.status().message().find(name), std::string::npos) << r.status().toString();
      EXPECT_NE(r.status().code(), ErrorCode::kInternal) << r.status().toString();
    }
    EXPECT_GT(refused, 0) << file;
    EXPECT_LT(peakBytes(), kMaxPeakBytes);
  }
}

}  // namespace
}  // namespace thinlod::scene
