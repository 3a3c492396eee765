// libFuzzer entry point for the imported formats' front door: files read
// through Assimp (importScene: glTF, glb, Collada, FBX, OBJ; and the skinned
// import, importSkinnedModel, which also takes DirectX .x and Valve .smd),
// behind our byte limits and the glTF / Collada pre-checks
// (common/src/scene/import_precheck.h). Built as the fuzzer
// thinlod_fuzz_imported_scene under -DTHINLOD_FUZZ=ON; replayed over its
// seeds (fuzz.ImportedSceneFuzzer.*) under any compiler.
//
// Assimp picks a reader by the file's extension, so the input is written to
// a file first. Its extension: a first byte 0x01-0x07 names it (gltf, glb,
// dae, fbx, obj, x, smd) and is dropped, so mutations can hand any bytes to
// any reader; otherwise it is guessed from the content as a user's file
// would be named, so real files are seeds as they are.
//
// Oracle beyond "no crash, no UB, no leak": an imported scene's meshes pass
// IndexedMesh::validate; a skinned model's skeleton, skin and clips pass
// their own validation; errors name the file.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_import.h"
#include "thinlod/common/scene/skinned_import.h"

namespace {

const char* const kExtensions[] = {"gltf", "glb", "dae", "fbx", "obj", "x", "smd"};

// The extension a user's file with these bytes would carry.
const char* guessExtension(std::string_view bytes) {
  const std::string_view head = bytes.substr(0, 512);
  if (bytes.substr(0, 4) == "glTF") return "glb";
  if (head.find("<COLLADA") != std::string_view::npos) return "dae";
  if (bytes.substr(0, 18) == "Kaydara FBX Binary" || head.find("FBXHeaderExtension") !=
                                                         std::string_view::npos) {
    return "fbx";
  }
  if (bytes.substr(0, 4) == "xof ") return "x";
  if (bytes.substr(0, 7) == "version") return "smd";
  const std::size_t first = bytes.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && bytes[first] == '{') return "gltf";
  return "obj";
}

// One file per process (libFuzzer runs inputs one at a time), in memory
// where the machine has /dev/shm.
std::string scratchPath(const char* extension) {
  static const std::string directory =
      std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
  return directory + "/thinlod-fuzz-import-" + std::to_string(::getpid()) + "." + extension;
}

bool errorNamesTheFile(const thinlod::Status& status, const std::string& path) {
  return status.message().find(path) != std::string::npos;
}

void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "imported scene fuzz oracle: %s: %s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const char* extension = nullptr;
  if (!bytes.empty() && bytes[0] >= 1 && bytes[0] <= 7) {
    extension = kExtensions[bytes[0] - 1];
    bytes.remove_prefix(1);
  } else {
    extension = guessExtension(bytes);
  }
  const std::string path = scratchPath(extension);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) return 0;
  }
  // Small limits keep one input cheap; the checks are the same at any size.
  scene::ImportLimits limits;
  limits.maxFileBytes = 1u << 20;
  limits.maxTotalBytes = 2u << 20;
  limits.maxTriangles = 200'000;
  limits.maxVertices = 200'000;
  limits.maxNodes = 20'000;
  limits.maxDepth = 64;

  const std::string ext(extension);
  if (ext != "x" && ext != "smd") {
    Result<scene::Scene> imported = scene::importScene(path, limits);
    if (imported.ok()) {
      for (const scene::NodeInstance& instance : scene::flattenInstances(*imported)) {
        const scene::ShapeNode* shape =
            instance.node != nullptr ? instance.node->as<scene::ShapeNode>() : nullptr;
        if (shape == nullptr || !shape->geometry.mesh) continue;
        const Status valid = shape->geometry.mesh->validate(path);
        if (!valid.ok()) fail("an imported mesh is invalid", valid.toString());
      }
    } else if (!errorNamesTheFile(imported.status(), path)) {
      fail("importScene's error does not name the file", imported.status().toString());
    }
  }

  scene::SkinnedImportLimits skinnedLimits;
  skinnedLimits.files = limits;
  skinnedLimits.maxKeys = 100'000;
  Result<scene::SkinnedModel> skinned = scene::importSkinnedModel(path, skinnedLimits);
  if (skinned.ok()) {
    Status valid = skinned->mesh.validate(path);
    if (valid.ok()) valid = skinned->skeleton.validate(path);
    if (valid.ok()) {
      valid = anim::validateSkin(skinned->skin, skinned->mesh.vertexCount(),
                                 skinned->skeleton.bones.size(), path);
    }
    for (const anim::AnimationClip& clip : skinned->clips) {
      if (valid.ok()) valid = clip.validate(skinned->skeleton, path);
    }
    if (!valid.ok()) fail("a skinned import is invalid", valid.toString());
  } else if (!errorNamesTheFile(skinned.status(), path)) {
    fail("importSkinnedModel's error does not name the file", skinned.status().toString());
  }
  std::remove(path.c_str());
  return 0;
}
