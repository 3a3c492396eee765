#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

// A smooth, impostor-like image: a shaded disc on transparent black.
RgbaImage impostorLike(int size, bool opaque) {
  RgbaImage t(size, size);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5) / size - 0.5, v = (y + 0.5) / size - 0.5;
      const bool inside = u * u + v * v < 0.16;
      std::uint8_t* p = t.at(x, y);
      const double shade = inside ? 0.5 + 0.5 * std::cos(6 * u) * std::cos(5 * v) : 0.1;
      p[0] = static_cast<std::uint8_t>(255 * shade);
      p[1] = static_cast<std::uint8_t>(200 * shade);
      p[2] = static_cast<std::uint8_t>(120 * shade + 40);
      p[3] = opaque || inside ? 255 : 0;
    }
  }
  return t;
}

RgbaImage noise(int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  RgbaImage t(w, h);
  for (std::uint8_t& b : t.pixels) b = static_cast<std::uint8_t>(rng());
  return t;
}

double psnr(const RgbaImage& a, const RgbaImage& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = double(a.pixels[i]) - b.pixels[i];
    sum += d * d;
  }
  const double mse = sum / a.pixels.size();
  return mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : INFINITY;
}

RgbaImage roundTrip(const RgbaImage& t, TextureCodec codec) {
  Result<std::vector<std::uint8_t>> frame = encodeTextureWith(t, codec);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  if (!frame.ok()) return {};
  Result<RgbaImage> decoded = decodeTexture(frame->data(), frame->size());
  EXPECT_TRUE(decoded.ok()) << decoded.status().toString();
  return decoded.ok() ? *decoded : RgbaImage{};
}

TEST(TextureEncoding, ZstdRoundTripIsExact) {
  const RgbaImage t = noise(37, 21, 3);  // odd sizes, every alpha value
  const RgbaImage back = roundTrip(t, TextureCodec::kZstd);
  EXPECT_EQ(back.width, t.width);
  EXPECT_EQ(back.height, t.height);
  EXPECT_EQ(back.pixels, t.pixels);
}

TEST(TextureEncoding, PngRoundTripIsExactIncludingAlpha) {
  // Random alpha with colour under transparent pixels: premultiplication
  // anywhere in the pipeline would change these bytes.
  const RgbaImage t = noise(37, 21, 4);
  const RgbaImage back = roundTrip(t, TextureCodec::kPng);
  EXPECT_EQ(back.width, t.width);
  EXPECT_EQ(back.pixels, t.pixels);
}

TEST(TextureEncoding, JpegRoundTripIsWithinTolerance) {
  const RgbaImage t = impostorLike(256, true);
  const RgbaImage back = roundTrip(t, TextureCodec::kJpeg);
  ASSERT_EQ(back.pixels.size(), t.pixels.size());
  EXPECT_GT(psnr(t, back), 35.0);
  for (std::size_t i = 3; i < back.pixels.size(); i += 4) ASSERT_EQ(back.pixels[i], 255);
}

TEST(TextureEncoding, JpegRefusesTransparentImages) {
  Result<std::vector<std::uint8_t>> frame =
      encodeTextureWith(impostorLike(64, false), TextureCodec::kJpeg);
  EXPECT_EQ(frame.status().code(), ErrorCode::kInvalidArgument);
}

TEST(TextureEncoding, FastestPolicyUsesZstd) {
  TextureEncodeOptions options;
  options.policy = TexturePolicy::kFastest;
  Result<EncodedTexture> e = encodeTexture(impostorLike(128, true), options);
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_EQ(e->codec, TextureCodec::kZstd);
}

TEST(TextureEncoding, SmallestLosslessPicksTheSmallerLosslessCodec) {
  TextureEncodeOptions options;
  options.policy = TexturePolicy::kSmallestLossless;
  const RgbaImage t = impostorLike(128, false);
  Result<EncodedTexture> e = encodeTexture(t, options);
  ASSERT_TRUE(e.ok()) << e.status().toString();
  const std::size_t png = encodeTextureWith(t, TextureCodec::kPng)->size();
  const std::size_t zstd = encodeTextureWith(t, TextureCodec::kZstd)->size();
  EXPECT_EQ(e->bytes.size(), std::min(png, zstd));
  Result<RgbaImage> back = decodeTexture(e->bytes.data(), e->bytes.size());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->pixels, t.pixels);
}

TEST(TextureEncoding, SmallestPolicyUsesJpegOnlyForOpaqueImages) {
  Result<EncodedTexture> opaque = encodeTexture(impostorLike(256, true));
  Result<EncodedTexture> transparent = encodeTexture(impostorLike(256, false));
  ASSERT_TRUE(opaque.ok() && transparent.ok());
  EXPECT_EQ(opaque->codec, TextureCodec::kJpeg);
  EXPECT_NE(transparent->codec, TextureCodec::kJpeg);
}

TEST(TextureEncoding, SmallestPolicyRejectsJpegBelowThePsnrFloor) {
  // Noise compresses badly and loses a lot in JPEG: PSNR falls under 60 dB.
  RgbaImage t = noise(64, 64, 5);
  for (std::size_t i = 3; i < t.pixels.size(); i += 4) t.pixels[i] = 255;
  TextureEncodeOptions options;
  options.jpegMinPsnr = 60.0;
  Result<EncodedTexture> e = encodeTexture(t, options);
  ASSERT_TRUE(e.ok());
  EXPECT_NE(e->codec, TextureCodec::kJpeg);
}

TEST(TextureEncoding, InvalidImagesAreRejected) {
  RgbaImage wrongSize(4, 4);
  wrongSize.pixels.resize(10);
  EXPECT_EQ(encodeTextureWith(wrongSize, TextureCodec::kZstd).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(encodeTexture(RgbaImage{}).status().code(), ErrorCode::kInvalidArgument);
}

TEST(TextureEncoding, NegativeSizesAreRejected) {
  RgbaImage negative;
  negative.width = -2;
  negative.height = 4;
  Result<std::vector<std::uint8_t>> frame = encodeTextureWith(negative, TextureCodec::kZstd);
  EXPECT_EQ(frame.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(frame.status().message().find("negative size -2x4"), std::string::npos)
      << frame.status().message();
}

TEST(TextureEncoding, SidesLongerThan65500AreRejected) {
  const RgbaImage wide(65501, 1);
  Result<std::vector<std::uint8_t>> frame = encodeTextureWith(wide, TextureCodec::kZstd);
  EXPECT_EQ(frame.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(frame.status().message().find("65501x1"), std::string::npos)
      << frame.status().message();
}

TEST(TextureEncoding, DimensionsBeyondTheLimitAreRejectedBeforeDecoding) {
  const RgbaImage t = noise(300, 10, 6);
  Result<std::vector<std::uint8_t>> frame = encodeTextureWith(t, TextureCodec::kZstd);
  ASSERT_TRUE(frame.ok());
  DecodeLimits limits;
  limits.maxTextureDimension = 256;
  Result<RgbaImage> decoded = decodeTexture(frame->data(), frame->size(), limits);
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted);
}

}  // namespace
}  // namespace thinlod::codec
