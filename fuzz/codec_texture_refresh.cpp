// libFuzzer entry point for incremental texture refreshes
// (codec/texture_refresh.h: decodeTextureDelta against a held reference).
// Built as thinlod_fuzz_codec_texture_refresh under -DTHINLOD_FUZZ=ON;
// replayed over fuzz/corpus/codec_texture_refresh
// (fuzz.CodecTextureRefreshFuzzer) under any compiler.
//
// Input: u8 width-1, u8 height-1 (each taken mod 64, so 1..64), then
// width * height * 4 bytes of the reference texture (missing bytes are 0),
// then the refresh frame. The frame's payload size, checksum and reference
// fingerprint are recomputed first, so mutations reach zstd itself.
//
// Oracle: a decoded texture has the reference's size, is consistent, and a
// lossless residual frame of zero codes gives back the reference (checked by
// the unit tests; here: size and consistency).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "codec_frame.h"
#include "thinlod/common/codec/texture_refresh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  if (size < 2) return 0;
  const int width = data[0] % 64 + 1;
  const int height = data[1] % 64 + 1;
  RgbaImage reference(width, height);
  const std::size_t referenceBytes = reference.pixels.size();
  std::size_t at = 2;
  for (std::size_t i = 0; i < referenceBytes && at < size; ++i, ++at) {
    reference.pixels[i] = data[at];
  }
  std::vector<std::uint8_t> frame(data + at, data + size);
  if (frame.size() >= codec::kFrameHeaderBytes + 8) {
    const std::uint64_t fingerprint = codec::textureFingerprint(reference);
    for (int i = 0; i < 8; ++i) {
      frame[codec::kFrameHeaderBytes + i] = static_cast<std::uint8_t>(fingerprint >> (8 * i));
    }
  }
  frame = fuzz::resealedFrame(frame.data(), frame.size());
  Result<RgbaImage> decoded =
      codec::decodeTextureDelta(reference, frame.data(), frame.size(), fuzz::fuzzDecodeLimits());
  if (!decoded.ok()) return 0;
  if (decoded->width != width || decoded->height != height || !decoded->consistent()) {
    std::fprintf(stderr, "texture refresh fuzz oracle: decoded %dx%d, reference %dx%d\n",
                 decoded->width, decoded->height, width, height);
    std::abort();
  }
  return 0;
}
