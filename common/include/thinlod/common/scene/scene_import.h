// Scene import: glTF 2.0 (.gltf, .glb), Collada (.dae), FBX (.fbx) and
// OBJ+MTL (.obj) files read through Assimp as a Scene of their own
// (docs/scene-format.md, "Imported scenes").
//
// Contract:
// - The file and every file it pulls in (.bin buffers, .mtl libraries;
//   images are never read) are untrusted. Every failure is a Status whose
//   message starts with the file's path and names the problem; no exception
//   and no Assimp type crosses this interface, Assimp's own logging is never
//   switched on.
// - Sizes are bounded before anything large is allocated: each file Assimp
//   opens is checked against ImportLimits::maxFileBytes and all of them
//   together against maxTotalBytes before it is read; after parsing, the
//   triangles of every mesh instance (a mesh reached twice counts twice) are
//   summed against maxTriangles and the node tree against maxNodes/maxDepth
//   before any mesh is copied. glTF is pre-checked before Assimp runs: a
//   .glb header and chunks must fit the file, the JSON's declared triangles
//   must fit maxTriangles, and a file whose triangles Assimp silently drops
//   (out-of-range indices) is refused; JSON nesting deeper than 4096 and a
//   node graph with a cycle, deeper than maxDepth or expanding to more than
//   maxNodes instances are refused. Collada is pre-scanned too (element
//   nesting, truncation, accessors reading past their arrays, the node graph
//   with instance_node: src/scene/import_precheck.h): Assimp recursed over
//   cyclic and deep node graphs until the stack overflowed.
// - Result: node hierarchy -> TransformNode (identity transforms -> Group),
//   each Assimp mesh -> one ShapeNode with kMeshFile geometry (resolvedPath =
//   the file, urls = {file name}) holding an IndexedMesh with positions,
//   indices, and normals / uvs (first set) / vertex colours (first set, RGBA8)
//   where the file has them. A mesh used by several nodes is one shared
//   ShapeNode (DAG sharing, like DEF/USE). Points and lines are dropped.
// - Material: base colour (glTF pbr baseColorFactor, else diffuse colour) ->
//   Material::diffuseColor; emissive, specular, shininess, opacity where
//   present. The base-colour texture's path is recorded in
//   Appearance::textureUrl (as written in the file, "*N" for an embedded
//   image); loadSceneFile resolves it (resolveTextures). The link carries
//   resolved textures (docs/protocol.md, "Shared textures"); embedded ones
//   are not read.
// - Transforms must be translation * rotation * scale (glTF requires that);
//   a sheared node matrix is kUnsupported. Cameras, lights, animations and
//   skins are ignored here (skinned_import.h reads skins and clips).
// - An assertion inside Assimp (Debian builds it with them on) fails the
//   import with its message instead of aborting the process (the
//   executable's Assimp::aiAssertViolation throws: assimp_import.cpp).
// - Thread-safe: one Assimp::Importer per call, no shared state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "thinlod/common/core/status.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene.h"

namespace thinlod::scene {

struct ImportLimits {
  std::uint64_t maxFileBytes = std::uint64_t{256} << 20;   // any one file opened
  std::uint64_t maxTotalBytes = std::uint64_t{512} << 20;  // all files of one import
  std::uint64_t maxTriangles = 20'000'000;                 // summed over mesh instances
  std::uint64_t maxVertices = 20'000'000;                  // summed over distinct meshes
  std::size_t maxNodes = 1'000'000;                        // node instances in the tree
  int maxDepth = 256;  // skeletons nest deeply (a package Collada file: 65+)
};

// True for the extensions importScene() takes (case-insensitive):
// .gltf .glb .dae .fbx .obj.
bool isImportedSceneExtension(const std::string& path);

// Imports the file as a Scene. Scene::fingerprint is left 0 (loadSceneFile
// sets it); Scene::header names the format, e.g. "import glTF2".
Result<Scene> importScene(const std::string& path, const ImportLimits& limits = {});

// For `Inline { url "part.gltf" }` in a VRML scene: imports the file and
// flattens it into one mesh in the file's root frame (every mesh instance
// transformed, normals by the inverse transpose, winding flipped under a
// mirroring transform). uvs / colours are kept only when every part has
// them. The file's materials and textures are dropped (the VRML Shape's
// Appearance applies), which a warning says.
Result<LoadedMesh> importSceneAsMesh(const std::string& path, const ImportLimits& limits = {});

}  // namespace thinlod::scene
