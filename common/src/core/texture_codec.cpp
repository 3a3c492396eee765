#include "thinlod/common/core/texture_codec.h"

namespace thinlod {

const char* textureCodecName(TextureCodec codec) {
  switch (codec) {
    case TextureCodec::kNone:
      return "none";
    case TextureCodec::kRawRgba8:
      return "raw";
    case TextureCodec::kPng:
      return "png";
    case TextureCodec::kJpeg:
      return "jpeg";
    case TextureCodec::kZstd:
      return "zstd";
  }
  return "invalid-codec";
}

}  // namespace thinlod
