// The scene's base-colour textures as the link's shared textures
// (docs/protocol.md, "Shared textures"): each distinct texture file is read
// once, checked (codec::readImageFile: size bounded before decoding), encoded
// losslessly (PNG or zstd, the smaller: frames match the frontend's
// reference, which decodes the same file) and given an id 1, 2, ... in order
// of first use by the objects; an object gets the id of its Shape's texture.
//
// Contract:
// - Only objects whose mesh has uvs are textured (a texture needs them at the
//   frontend); a file that does not load is a warning naming it and its
//   objects stay untextured, as the frontend's reference draws them.
// - Sides above protocol::kMaxTextureDimension or encoded frames above
//   maxEncodedBytes are warnings too (never sent).
// - Reads files (the daemon's edge); no sockets, no logging.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/protocol/messages.h"

namespace thinlod::backbone_daemon {

struct SceneTextures {
  std::vector<protocol::SharedTexture> textures;  // textures[i].textureId == i + 1
  std::vector<std::uint64_t> objectTexture;       // per object (index), 0 = untextured
  std::vector<std::string> warnings;
};

struct SceneTextureOptions {
  std::size_t maxEncodedBytes = 16u << 20;  // one shared texture on the wire
};

SceneTextures loadSceneTextures(const std::vector<scene::SceneObject>& objects,
                                const SceneTextureOptions& options = {});

}  // namespace thinlod::backbone_daemon
