// TextureCodec: how a texture travels. One enum for the wire, the link codec
// frames and the daemons; its values are the wire's and the texture frame's
// codec byte (protocol/schema/thinlod_wire.fbs, codec/encoding.h).
#pragma once

#include <cstdint>

namespace thinlod {

enum class TextureCodec : std::uint8_t {
  kNone = 0,      // no texture (wire only)
  kRawRgba8 = 1,  // unframed RGBA8 bytes (wire only)
  kPng = 2,       // framed (codec/encoding.h)
  kJpeg = 3,      // framed, opaque images only
  kZstd = 4,      // framed, zstd of the RGBA8 bytes
};
// "none", "raw", "png", "jpeg", "zstd"; "invalid-codec" otherwise.
const char* textureCodecName(TextureCodec codec);
// True for the codecs that come in a codec frame (png, jpeg, zstd).
inline bool isFramedTextureCodec(TextureCodec codec) {
  return codec == TextureCodec::kPng || codec == TextureCodec::kJpeg ||
         codec == TextureCodec::kZstd;
}

}  // namespace thinlod
