// Incremental impostor refreshes (Pasman & Jansen 2002, section 5, future
// work: "regular updates with small viewpoint displacements"): a refreshed
// RGBA8 texture encoded against the texture the client already holds (the
// reference), with zstd (Debian's libzstd), in a frame like encoding.h's.
//
// Frame (little-endian; the 32-byte header of encoding.h, then payload):
//   0 magic "TLTR"   4 u16 version (kFrameVersion)   6 u8 mode (1..4
//   below)   7 u8 flags (0)   8 u32 width   12 u32 height
//  16 u32 payload bytes  20 u32 colour step (odd, 1..255; 1 = lossless)
//  24 u64 FNV-1a 64 of the payload   32 payload: u64 FNV-1a 64 of the
//  reference's pixels, then exactly one zstd frame of width*height*4 bytes
//  in planar order (all R, all G, all B, all A; rows top-down):
//  - mode 1 (residual): per byte the code c of new against reference; alpha
//    and a step of 1: c = (new - ref) mod 256, exact; step s > 1 (colour
//    only): c = round((new - ref) / s) as int8, decoded clamp(ref + c s, 0,
//    255), so every colour channel is within (s - 1) / 2 of the new texture
//    and alpha (coverage) is exact;
//  - mode 2 (reference prefix): the new planes themselves, compressed with the
//    reference planes as zstd's prefix (long matches find content that moved
//    by a few texels); lossless only (step 1);
//  - mode 3 (residual, left-predicted): mode 1's codes, each plane row
//    replaced by its differences to the left neighbour (mod 256; the first
//    texel of a row as is): a sub-texel shift of smooth shading makes the
//    residual a smooth gradient, whose differences are near 0;
//  - mode 4 (intra, left-predicted): the new planes' left differences, no
//    reference content used (PNG's "sub" filter); lossless only. The
//    fallback when the view changed too much for the reference to help.
// Contract:
// - The reference and the refreshed texture have the same size (a new size
//   is sent as a full encodeTexture frame). The encoder returns the texture
//   the client will decode; a lossy sender keeps that one as its next
//   reference, so errors never accumulate over a chain of refreshes.
// - kAuto tries every mode (with a colour tolerance: modes 1 and 3) and keeps
//   the smallest frame.
// - decodeTextureDelta takes untrusted bytes: the header, sizes (against
//   DecodeLimits, before allocating), checksum, the reference's size and
//   fingerprint, the zstd frame's content size and extent are all checked
//   before zstd decodes. Errors: kParseError (malformed, wrong reference:
//   the client must ask for a full texture), kVersionMismatch,
//   kResourceExhausted, kUnsupported (unknown mode or step); never a crash.
// - Pure functions, no globals; safe to call concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/core/status.h"

namespace thinlod::codec {

enum class TextureDeltaMode : std::uint8_t {
  kAuto = 0,
  kResidual = 1,
  kReferencePrefix = 2,
  kResidualLeft = 3,
  kIntraLeft = 4,
};

struct TextureDeltaOptions {
  TextureDeltaMode mode = TextureDeltaMode::kAuto;
  int zstdLevel = 3;       // 1..19
  int colorTolerance = 0;  // 0..127: largest error per colour channel (modes 1 and 3)
};

struct EncodedTextureDelta {
  TextureDeltaMode mode = TextureDeltaMode::kResidual;  // the mode used
  std::vector<std::uint8_t> bytes;                      // the whole frame
  RgbaImage decoded;  // what decodeTextureDelta gives the client (== texture when lossless)
};

// Errors: kInvalidArgument for an invalid or empty image, different sizes,
// a side above 65500, options out of range (or a tolerance with mode 2 or 4).
Result<EncodedTextureDelta> encodeTextureDelta(const RgbaImage& reference, const RgbaImage& texture,
                                               const TextureDeltaOptions& options = {});

Result<RgbaImage> decodeTextureDelta(const RgbaImage& reference, const std::uint8_t* data,
                                     std::size_t size, const DecodeLimits& limits = {});

// The fingerprint a delta frame names its reference by (FNV-1a 64 of pixels).
std::uint64_t textureFingerprint(const RgbaImage& image);

}  // namespace thinlod::codec
