// libFuzzer entry point for link texture frames (decodeTexture: frame
// header, then zstd, PNG or JPEG through OpenImageIO). Built as the fuzzer
// thinlod_fuzz_codec_texture under -DTHINLOD_FUZZ=ON; replayed over
// fuzz/corpus/codec_texture (fuzz.FuzzReplay.codec_texture) under any
// compiler. The checksum and payload size are recomputed first, so the
// fuzzer's mutations reach the image decoders.
//
// Oracle: a decoded image is consistent, has the header's size and is
// within the limits.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "codec_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  const std::vector<std::uint8_t> frame = fuzz::resealedFrame(data, size);
  const codec::DecodeLimits limits = fuzz::fuzzDecodeLimits();
  Result<RgbaImage> image = codec::decodeTexture(frame.data(), frame.size(), limits);
  if (!image.ok()) return 0;
  const std::uint32_t width = std::uint32_t{frame[8]} | std::uint32_t{frame[9]} << 8 |
                              std::uint32_t{frame[10]} << 16 | std::uint32_t{frame[11]} << 24;
  const std::uint32_t height = std::uint32_t{frame[12]} | std::uint32_t{frame[13]} << 8 |
                               std::uint32_t{frame[14]} << 16 | std::uint32_t{frame[15]} << 24;
  if (image->empty() || !image->consistent() || static_cast<std::uint32_t>(image->width) != width ||
      static_cast<std::uint32_t>(image->height) != height || width > limits.maxTextureDimension ||
      height > limits.maxTextureDimension) {
    std::fprintf(stderr, "codec texture fuzz oracle: decoded %dx%d, header %ux%u\n", image->width,
                 image->height, width, height);
    std::abort();
  }
  return 0;
}
