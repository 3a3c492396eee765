// Skinned, animated models read through Assimp (glTF skins, Collada, FBX,
// DirectX .x, Valve .smd; no other format) into the pure skinning types of
// core/skinning.h (docs/animation.md).
//
// Contract:
// - The same front door as importScene (scene_import.h; one function in
//   assimp_import.cpp): every file opened is bounded by ImportLimits before
//   it is read, glTF, Collada and SMD are pre-checked, no
//   Assimp type or exception crosses this interface, failures are a Status
//   naming the file.
// - Skeleton: every node of the file is a bone, parents first (restLocal =
//   the node's transform, inverseBind = identity); each (mesh, bone) pair of
//   a skinned mesh adds a binding bone under that node with the file's
//   offset matrix as inverseBind. A mesh without bones is rigid on its node.
//   The skeleton is bounded by ImportLimits::maxNodes and maxDepth.
// - Skin: ASLOD's rule of one or two bones per vertex: the two largest
//   weights are kept and renormalised; `verticesOverTwoBones` and
//   `largestDroppedWeight` say what that cost. A vertex of a skinned mesh
//   with no weight is rigid on the mesh's node (counted in
//   `unweightedVertices`).
// - Mesh: every mesh instance's triangles concatenated (a skinned mesh once),
//   positions in mesh space (deform() maps them to the file's world frame);
//   normals and uvs when every part has them. Materials are not kept.
// - Clips: each animation, times converted from ticks (ticks per second 0 ->
//   25, Assimp's default); keys at repeated times keep the last, a channel
//   naming no node is skipped (`unmatchedChannels`); every clip passes
//   AnimationClip::validate. At most maxKeys keys in all.
// - Thread-safe: one Assimp::Importer per call.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"
#include "thinlod/common/core/skinning.h"
#include "thinlod/common/core/status.h"
#include "thinlod/common/scene/scene_import.h"

namespace thinlod::scene {

struct SkinnedModel {
  IndexedMesh mesh;
  anim::Skeleton skeleton;
  std::vector<anim::VertexSkin> skin;  // one per mesh vertex
  std::vector<anim::AnimationClip> clips;
  std::size_t skinnedMeshes = 0;
  std::size_t verticesOverTwoBones = 0;
  float largestDroppedWeight = 0.0f;
  std::size_t unweightedVertices = 0;
  std::size_t unmatchedChannels = 0;
};

struct SkinnedImportLimits {
  ImportLimits files;
  std::size_t maxKeys = 10'000'000;  // keys of all clips together
};

// True for the extensions importSkinnedModel takes (case-insensitive):
// .gltf .glb .dae .fbx .x .smd; any other is kUnsupported.
bool isSkinnedModelExtension(const std::string& path);

Result<SkinnedModel> importSkinnedModel(const std::string& path,
                                        const SkinnedImportLimits& limits = {});

}  // namespace thinlod::scene
