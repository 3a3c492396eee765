// Scene files: a VRML97 subset plus the paper's extension nodes
// (docs/scene-format.md). Parsing is pure (text in, Scene out); loading adds
// the file read and the mesh files named by Inline/url.
//
// Contract:
// - parseScene() does no I/O. The text is untrusted: every error is a
//   Status with code kParseError (syntax, unknown node/field, bad or
//   non-finite number, USE of an undefined name, truncated input),
//   kVersionMismatch (a header we do not speak) or kResourceExhausted (a
//   limit below), and a message "<sourceName>:<line>:<column>: <problem>".
// - Mesh geometry (Inline { url ... }) is left unloaded by parseScene();
//   resolveMeshes() loads it. A url is searched in `searchPaths` in order,
//   then in the scene file's directory; absolute urls, ".." components and
//   urls with a scheme ("http://") are rejected. Each file is loaded once
//   and shared by every Shape that names it.
// - Thread-safe (no shared state besides the mesh loader's own lock).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_import.h"

namespace thinlod::scene {

// The only thinlod-native header version; "#VRML V2.0 utf8" is also accepted.
inline constexpr int kSceneFormatVersion = 1;

struct ParseLimits {
  std::size_t maxBytes = std::size_t{64} << 20;
  int maxDepth = 64;                           // nested nodes
  std::size_t maxNodes = 1'000'000;            // all nodes incl. Appearance, Material, ...
  std::size_t maxValuesPerField = 16'000'000;  // numbers in one MF field
  std::size_t maxTotalValues = 64'000'000;     // numbers in the whole file
  std::size_t maxStringLength = 4096;          // also names
  // Node instances after DEF/USE expansion (what flattenInstances returns).
  std::uint64_t maxInstances = 1'000'000;
};

Result<Scene> parseScene(std::string_view text, const std::string& sourceName,
                         const ParseLimits& limits = {});

struct SceneLoadOptions {
  std::vector<std::string> meshSearchPaths;  // tried before the scene's directory
  ParseLimits limits;
  MeshLoadOptions meshOptions;
  ImportLimits importLimits;  // .gltf .glb .dae .fbx .obj scene files (scene_import.h)
};

// The url rules for mesh and texture urls: a relative file name (no scheme,
// not absolute, no ".."); kInvalidArgument / kUnsupported naming `where`.
Status checkUrl(const std::string& url, const std::string& where);

// Loads every mesh-file geometry in the scene (see the url rules above).
// Mesh warnings go to Geometry::loadWarnings and Scene::warnings.
Status resolveMeshes(Scene& scene, const std::string& sceneDirectory,
                     const SceneLoadOptions& options);

// Sets Appearance::texturePath of every shape whose textureUrl names an
// existing file (url rules as for meshes; relative to the imported mesh file
// that names it, else to `sceneDirectory`); the others get a Scene::warnings
// line and stay untextured. Reads no pixels: decoding is the renderer side's
// (codec::decodeImageFile).
void resolveTextures(Scene& scene, const std::string& sceneDirectory);

// Reads the file, parses it and resolves its meshes and textures. A path ending in
// .gltf .glb .dae .fbx or .obj is imported instead (importScene(), limits from
// options.importLimits); the fingerprint is then sceneFingerprint() of the
// file's bytes and the imported meshes.
Result<Scene> loadSceneFile(const std::string& path, const SceneLoadOptions& options = {});

}  // namespace thinlod::scene
