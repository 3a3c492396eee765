// codec::decodeImageFile: scene texture files (PNG / JPEG without a frame).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

RgbaImage noise(int w, int h, std::uint32_t seed, bool opaque) {
  std::mt19937 rng(seed);
  RgbaImage t(w, h);
  for (std::size_t i = 0; i < t.pixels.size(); ++i) {
    t.pixels[i] = (opaque && i % 4 == 3) ? 255 : static_cast<std::uint8_t>(rng());
  }
  return t;
}

// The image file inside a link frame: the frame's payload.
std::vector<std::uint8_t> fileBytes(const RgbaImage& image, TextureCodec codec) {
  Result<std::vector<std::uint8_t>> frame = encodeTextureWith(image, codec);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  if (!frame.ok()) return {};
  return std::vector<std::uint8_t>(frame->begin() + kFrameHeaderBytes, frame->end());
}

TEST(ImageFile, PngDecodesToTheSameRgbaPixels) {
  const RgbaImage image = noise(37, 21, 7, false);
  const std::vector<std::uint8_t> png = fileBytes(image, TextureCodec::kPng);
  Result<RgbaImage> decoded = decodeImageFile(png.data(), png.size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_EQ(decoded->width, 37);
  EXPECT_EQ(decoded->height, 21);
  EXPECT_EQ(decoded->pixels, image.pixels);
}

TEST(ImageFile, JpegDecodesOpaqueAtItsOwnSize) {
  const RgbaImage image = noise(40, 24, 8, true);
  const std::vector<std::uint8_t> jpeg = fileBytes(image, TextureCodec::kJpeg);
  Result<RgbaImage> decoded = decodeImageFile(jpeg.data(), jpeg.size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_EQ(decoded->width, 40);
  EXPECT_EQ(decoded->height, 24);
  for (std::size_t i = 3; i < decoded->pixels.size(); i += 4) ASSERT_EQ(decoded->pixels[i], 255);
}

TEST(ImageFile, OtherFormatsAreUnsupported) {
  const std::vector<std::uint8_t> gif = {'G', 'I', 'F', '8', '9', 'a', 1, 0, 1, 0, 0, 0, 0};
  Result<RgbaImage> decoded = decodeImageFile(gif.data(), gif.size());
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kUnsupported);
  EXPECT_EQ(decodeImageFile(nullptr, 0).status().code(), ErrorCode::kParseError);
}

// TGA (Collada's duck uses one): an 18-byte header, then the pixels (BGR, bottom row first
// unless bit 5 of the descriptor says top-down).
std::vector<std::uint8_t> tgaHeader(std::uint8_t type, int width, int height, std::uint8_t bits,
                                    std::uint8_t colourMap = 0) {
  return {0, colourMap, type, 0, 0, 0, 0, 0, 0, 0, 0, 0,
          static_cast<std::uint8_t>(width & 255), static_cast<std::uint8_t>(width >> 8),
          static_cast<std::uint8_t>(height & 255), static_cast<std::uint8_t>(height >> 8), bits,
          0x20};  // top-down
}

TEST(ImageFile, TgaDecodesToRgba) {
  std::vector<std::uint8_t> tga = tgaHeader(2, 2, 1, 24);
  tga.insert(tga.end(), {10, 20, 30, 40, 50, 60});  // BGR BGR
  Result<RgbaImage> decoded = decodeImageFile(tga.data(), tga.size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  ASSERT_EQ(decoded->width, 2);
  ASSERT_EQ(decoded->height, 1);
  EXPECT_EQ(decoded->pixels, (std::vector<std::uint8_t>{30, 20, 10, 255, 60, 50, 40, 255}));
}

TEST(ImageFile, HostileTgaHeadersAreRefusedBeforeDecoding) {
  // Raw pixels missing, a colour map, a colour-mapped type, zero sides, odd bit depths.
  for (const std::vector<std::uint8_t>& bad :
       {tgaHeader(2, 1, 1, 24), tgaHeader(2, 1, 1, 24, 1), tgaHeader(1, 1, 1, 8),
        tgaHeader(2, 0, 1, 24), tgaHeader(2, 1, 1, 7), std::vector<std::uint8_t>(10, 0)}) {
    std::vector<std::uint8_t> bytes = bad;
    bytes.resize(std::max<std::size_t>(bytes.size(), 18) + (bytes.size() >= 18 ? 1 : 0), 0);
    Result<RgbaImage> decoded = decodeImageFile(bytes.data(), bytes.size());
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), ErrorCode::kUnsupported) << decoded.status().toString();
  }
  // Sides over the limits: refused from the header, before any pixel.
  std::vector<std::uint8_t> wide = tgaHeader(10, 60000, 2, 32);  // RLE: no size check up front
  wide.resize(64, 0);
  DecodeLimits limits;
  limits.maxTextureDimension = 4096;
  Result<RgbaImage> decoded = decodeImageFile(wide.data(), wide.size(), limits);
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted) << decoded.status().toString();
}

TEST(ImageFile, TheColladaDucksTgaDecodes) {
  const std::string path = "/usr/share/assimp/models/Collada/duckCM.tga";
  Result<RgbaImage> decoded = readImageFile(path);
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString()
                            << " (install assimp-testmodels: deploy/setup does)";
  EXPECT_GT(decoded->width, 0);
  EXPECT_TRUE(decoded->consistent());
  Result<RgbaImage> missing = readImageFile("/nonexistent/texture.png");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().message().rfind("/nonexistent/texture.png", 0), 0u)
      << missing.status().message();
}

TEST(ImageFile, TruncatedFilesAreParseErrors) {
  const RgbaImage image = noise(16, 16, 9, true);
  for (TextureCodec codec : {TextureCodec::kPng, TextureCodec::kJpeg}) {
    const std::vector<std::uint8_t> bytes = fileBytes(image, codec);
    for (std::size_t keep : {std::size_t{3}, std::size_t{20}, bytes.size() / 2}) {
      Result<RgbaImage> decoded = decodeImageFile(bytes.data(), keep);
      EXPECT_FALSE(decoded.ok()) << "kept " << keep << " bytes";
    }
  }
}

TEST(ImageFile, ImagesOverTheLimitsAreRefusedBeforeDecoding) {
  const std::vector<std::uint8_t> png = fileBytes(noise(64, 8, 10, false), TextureCodec::kPng);
  DecodeLimits limits;
  limits.maxTextureDimension = 32;
  Result<RgbaImage> decoded = decodeImageFile(png.data(), png.size(), limits);
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted);
  // Both edges of the side check: a side equal to the limit decodes, one
  // past it is refused (the image file fuzzer relies on this being the only
  // place the limit matters).
  limits.maxTextureDimension = 64;
  ASSERT_TRUE(decodeImageFile(png.data(), png.size(), limits).ok());
  limits.maxTextureDimension = 63;
  EXPECT_EQ(decodeImageFile(png.data(), png.size(), limits).status().code(),
            ErrorCode::kResourceExhausted);
  limits = DecodeLimits{};
  limits.maxPayloadBytes = png.size() - 1;
  EXPECT_EQ(decodeImageFile(png.data(), png.size(), limits).status().code(),
            ErrorCode::kResourceExhausted);
}

std::vector<std::uint8_t> seedFile(const std::string& name) {
  std::ifstream in(std::string(THINLOD_SOURCE_DIR) + "/fuzz/corpus/image_file/" + name,
                   std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// grey_4x3.png / grey_alpha_3x5.png (written by hand: value = (40x + 17y + 60c) mod 256).
TEST(ImageFile, GreyAndGreyAlphaBecomeRgba) {
  const std::vector<std::uint8_t> grey = seedFile("grey_4x3.png");
  ASSERT_FALSE(grey.empty());
  Result<RgbaImage> g = decodeImageFile(grey.data(), grey.size());
  ASSERT_TRUE(g.ok()) << g.status().toString();
  ASSERT_EQ(g->width, 4);
  ASSERT_EQ(g->height, 3);
  const std::uint8_t* p = g->at(2, 1);
  EXPECT_EQ(p[0], 40 * 2 + 17);
  EXPECT_EQ(p[1], p[0]);
  EXPECT_EQ(p[2], p[0]);
  EXPECT_EQ(p[3], 255);
  const std::vector<std::uint8_t> greyAlpha = seedFile("grey_alpha_3x5.png");
  Result<RgbaImage> ga = decodeImageFile(greyAlpha.data(), greyAlpha.size());
  ASSERT_TRUE(ga.ok()) << ga.status().toString();
  const std::uint8_t* q = ga->at(1, 4);
  EXPECT_EQ(q[0], 40 + 17 * 4);
  EXPECT_EQ(q[2], q[0]);
  EXPECT_EQ(q[3], 40 + 17 * 4 + 60);
}

// rgb16_5x3.png (written by hand, 16 bits per channel): channel c of pixel
// (x, y) holds 257 k + 10 (k = (40x + 17y + 60c) mod 256; 65535 for k = 255),
// so its 8-bit value is k. Read in the file's own type and converted by
// readAsRgba8 (not by ImageInput::read_image's 64 MB conversion buffer).
TEST(ImageFile, SixteenBitPngBecomesEightBitRgba) {
  const std::vector<std::uint8_t> bytes = seedFile("rgb16_5x3.png");
  ASSERT_FALSE(bytes.empty());
  Result<RgbaImage> image = decodeImageFile(bytes.data(), bytes.size());
  ASSERT_TRUE(image.ok()) << image.status().toString();
  ASSERT_EQ(image->width, 5);
  ASSERT_EQ(image->height, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      const std::uint8_t* p = image->at(x, y);
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(p[c], (40 * x + 17 * y + 60 * c) % 256) << x << "," << y << " channel " << c;
      }
      EXPECT_EQ(p[3], 255);
    }
  }
}

}  // namespace
}  // namespace thinlod::codec
