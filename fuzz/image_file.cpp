// libFuzzer entry point for scene texture files (codec::decodeImageFile:
// PNG or JPEG by magic, structure checks, then OpenImageIO). Built as the
// fuzzer thinlod_fuzz_image_file under -DTHINLOD_FUZZ=ON; replayed over
// fuzz/corpus/image_file (fuzz.ImageFileFuzzer.*) under any compiler.
//
// Oracle: a decoded image is consistent, non-empty and within the limits.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "codec_frame.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace thinlod;
  const codec::DecodeLimits limits = fuzz::fuzzDecodeLimits();
  Result<RgbaImage> image = codec::decodeImageFile(data, size, limits);
  if (!image.ok()) return 0;
  if (image->empty() || !image->consistent() ||
      static_cast<std::uint32_t>(image->width) > limits.maxTextureDimension ||
      static_cast<std::uint32_t>(image->height) > limits.maxTextureDimension) {
    std::fprintf(stderr, "image file fuzz oracle: decoded %dx%d\n", image->width, image->height);
    std::abort();
  }
  return 0;
}
