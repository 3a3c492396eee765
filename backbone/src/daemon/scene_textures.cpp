#include "scene_textures.h"

#include <map>
#include <utility>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::backbone_daemon {

SceneTextures loadSceneTextures(const std::vector<scene::SceneObject>& objects,
                                const SceneTextureOptions& options) {
  SceneTextures out;
  out.objectTexture.assign(objects.size(), 0);
  std::map<std::string, std::uint64_t> idOfPath;  // 0: the file failed
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const scene::SceneObject& object = objects[i];
    if (!scene::isTextured(object)) continue;
    const std::string& path = object.shape->appearance.texturePath;
    auto known = idOfPath.find(path);
    if (known == idOfPath.end()) {
      std::uint64_t id = 0;
      codec::DecodeLimits limits;
      limits.maxTextureDimension = protocol::kMaxTextureDimension;
      Result<RgbaImage> image = codec::readImageFile(path, limits);
      codec::TextureEncodeOptions encode;
      encode.policy = codec::TexturePolicy::kSmallestLossless;
      Result<codec::EncodedTexture> encoded =
          image.ok() ? codec::encodeTexture(*image, encode) : Result<codec::EncodedTexture>(image.status());
      if (!encoded.ok()) {
        out.warnings.push_back(encoded.status().message() + "; its objects are sent untextured");
      } else if (encoded->bytes.size() > options.maxEncodedBytes) {
        out.warnings.push_back(path + ": encoded texture of " +
                               std::to_string(encoded->bytes.size()) + " bytes is over the limit of " +
                               std::to_string(options.maxEncodedBytes) +
                               "; its objects are sent untextured");
      } else {
        protocol::SharedTexture shared;
        id = out.textures.size() + 1;
        shared.textureId = id;
        shared.texture.codec = encoded->codec;
        shared.texture.width = static_cast<std::uint32_t>(image->width);
        shared.texture.height = static_cast<std::uint32_t>(image->height);
        shared.texture.data = std::move(encoded->bytes);
        out.textures.push_back(std::move(shared));
      }
      known = idOfPath.emplace(path, id).first;
    }
    out.objectTexture[i] = known->second;
  }
  return out;
}

}  // namespace thinlod::backbone_daemon
