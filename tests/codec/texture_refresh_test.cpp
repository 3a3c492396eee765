// Incremental texture refreshes (codec/texture_refresh.h): round trips of
// every mode, the lossy mode's per-channel bound, wrong references, bad
// options and the decoder's safety (every truncated prefix, resealed
// corruptions). The libFuzzer entry point is fuzz/codec_texture_refresh.cpp.
#include "thinlod/common/codec/texture_refresh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr TextureDeltaMode kLosslessModes[] = {
    TextureDeltaMode::kResidual, TextureDeltaMode::kReferencePrefix,
    TextureDeltaMode::kResidualLeft, TextureDeltaMode::kIntraLeft};

// A shaded disc on transparent black centred at (cx, cy) (texels), as an
// impostor of a sphere captured from a slightly moved viewpoint.
RgbaImage disc(int size, double cx, double cy, double light) {
  RgbaImage t(size, size);
  const double r = 0.35 * size;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double u = (x + 0.5 - cx) / r, v = (y + 0.5 - cy) / r;
      std::uint8_t* p = t.at(x, y);
      if (u * u + v * v >= 1.0) continue;  // transparent black
      const double z = std::sqrt(1.0 - u * u - v * v);
      const double shade = std::clamp(0.2 + 0.8 * (light * z - 0.3 * u), 0.0, 1.0);
      p[0] = static_cast<std::uint8_t>(230 * shade);
      p[1] = static_cast<std::uint8_t>(90 * shade + 20);
      p[2] = static_cast<std::uint8_t>(60 * shade);
      p[3] = 255;
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

Bytes encodeFrame(const RgbaImage& ref, const RgbaImage& next, TextureDeltaOptions options = {}) {
  Result<EncodedTextureDelta> e = encodeTextureDelta(ref, next, options);
  EXPECT_TRUE(e.ok()) << e.status().toString();
  return e.ok() ? e->bytes : Bytes{};
}

void reseal(Bytes& frame) {
  const std::uint32_t payload = static_cast<std::uint32_t>(frame.size() - kFrameHeaderBytes);
  for (int i = 0; i < 4; ++i) frame[16 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint64_t sum = frameChecksum(frame.data() + kFrameHeaderBytes, payload);
  for (int i = 0; i < 8; ++i) frame[24 + i] = static_cast<std::uint8_t>(sum >> (8 * i));
}

TEST(TextureRefresh, EveryLosslessModeRoundTripsExactly) {
  const RgbaImage ref = disc(64, 31.0, 33.0, 1.0);
  const RgbaImage next = disc(64, 32.5, 33.0, 0.95);
  for (TextureDeltaMode mode : kLosslessModes) {
    TextureDeltaOptions options;
    options.mode = mode;
    Result<EncodedTextureDelta> e = encodeTextureDelta(ref, next, options);
    ASSERT_TRUE(e.ok()) << e.status().toString();
    EXPECT_EQ(e->mode, mode);
    EXPECT_EQ(e->decoded.pixels, next.pixels);
    Result<RgbaImage> back = decodeTextureDelta(ref, e->bytes.data(), e->bytes.size());
    ASSERT_TRUE(back.ok()) << back.status().toString();
    EXPECT_EQ(back->width, 64);
    EXPECT_EQ(back->height, 64);
    EXPECT_EQ(back->pixels, next.pixels);
  }
}

TEST(TextureRefresh, NoiseRoundTripsExactlyInEveryMode) {
  // Every byte value, including residuals that wrap around 256.
  const RgbaImage ref = noise(19, 7, 1);
  const RgbaImage next = noise(19, 7, 2);
  for (TextureDeltaMode mode : kLosslessModes) {
    TextureDeltaOptions options;
    options.mode = mode;
    const Bytes frame = encodeFrame(ref, next, options);
    Result<RgbaImage> back = decodeTextureDelta(ref, frame.data(), frame.size());
    ASSERT_TRUE(back.ok()) << back.status().toString();
    EXPECT_EQ(back->pixels, next.pixels);
  }
}

TEST(TextureRefresh, AutoKeepsTheSmallestMode) {
  const RgbaImage ref = disc(96, 40.0, 50.0, 1.0);
  const RgbaImage next = disc(96, 43.0, 50.0, 1.0);
  std::size_t smallest = SIZE_MAX;
  TextureDeltaMode best = TextureDeltaMode::kAuto;
  for (TextureDeltaMode mode : kLosslessModes) {
    TextureDeltaOptions options;
    options.mode = mode;
    const std::size_t size = encodeFrame(ref, next, options).size();
    if (size < smallest) {
      smallest = size;
      best = mode;
    }
  }
  Result<EncodedTextureDelta> chosen = encodeTextureDelta(ref, next);
  ASSERT_TRUE(chosen.ok());
  EXPECT_EQ(chosen->bytes.size(), smallest);
  EXPECT_EQ(chosen->mode, best);
}

TEST(TextureRefresh, SmallDisplacementCostsLessThanAFullTexture) {
  const RgbaImage ref = disc(128, 63.0, 64.0, 1.0);
  const RgbaImage next = disc(128, 64.0, 64.5, 1.0);
  Result<Bytes> full = encodeTextureWith(next, TextureCodec::kZstd);
  ASSERT_TRUE(full.ok());
  EXPECT_LT(encodeFrame(ref, next).size(), full->size());
}

TEST(TextureRefresh, UnchangedTextureIsAFewDozenBytes) {
  const RgbaImage ref = disc(128, 63.0, 64.0, 1.0);
  const Bytes frame = encodeFrame(ref, ref);
  EXPECT_LT(frame.size(), 100u);
  Result<RgbaImage> back = decodeTextureDelta(ref, frame.data(), frame.size());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->pixels, ref.pixels);
}

TEST(TextureRefresh, ColourToleranceBoundsEveryChannelAndKeepsAlphaExact) {
  const RgbaImage ref = noise(33, 17, 5);
  const RgbaImage next = noise(33, 17, 6);
  for (int tolerance : {1, 3, 10, 127}) {
    for (TextureDeltaMode mode :
         {TextureDeltaMode::kResidual, TextureDeltaMode::kResidualLeft, TextureDeltaMode::kAuto}) {
      TextureDeltaOptions options;
      options.colorTolerance = tolerance;
      options.mode = mode;
      Result<EncodedTextureDelta> e = encodeTextureDelta(ref, next, options);
      ASSERT_TRUE(e.ok()) << e.status().toString();
      EXPECT_TRUE(e->mode == TextureDeltaMode::kResidual ||
                  e->mode == TextureDeltaMode::kResidualLeft);
      if (mode != TextureDeltaMode::kAuto) {
        EXPECT_EQ(e->mode, mode);
      }
      Result<RgbaImage> back = decodeTextureDelta(ref, e->bytes.data(), e->bytes.size());
      ASSERT_TRUE(back.ok());
      EXPECT_EQ(back->pixels, e->decoded.pixels);  // the sender knows what the client holds
      int worst = 0;
      for (std::size_t i = 0; i < next.pixels.size(); ++i) {
        const int d = std::abs(int{back->pixels[i]} - int{next.pixels[i]});
        if (i % 4 == 3) {
          EXPECT_EQ(d, 0) << "alpha at " << i;
        } else {
          worst = std::max(worst, d);
        }
      }
      EXPECT_LE(worst, tolerance);
      EXPECT_GT(worst, 0) << "noise must need the tolerance";
    }
  }
}

TEST(TextureRefresh, LossyChainDoesNotAccumulateError) {
  // Each refresh is encoded against what the client decoded last time.
  TextureDeltaOptions options;
  options.colorTolerance = 2;
  RgbaImage held = disc(64, 30.0, 32.0, 1.0);
  for (int k = 1; k <= 12; ++k) {
    const RgbaImage next = disc(64, 30.0 + 0.4 * k, 32.0, 1.0 - 0.02 * k);
    Result<EncodedTextureDelta> e = encodeTextureDelta(held, next, options);
    ASSERT_TRUE(e.ok());
    Result<RgbaImage> back = decodeTextureDelta(held, e->bytes.data(), e->bytes.size());
    ASSERT_TRUE(back.ok());
    ASSERT_EQ(back->pixels, e->decoded.pixels);
    for (std::size_t i = 0; i < next.pixels.size(); ++i) {
      ASSERT_LE(std::abs(int{back->pixels[i]} - int{next.pixels[i]}), i % 4 == 3 ? 0 : 2);
    }
    held = *back;
  }
}

TEST(TextureRefresh, AnotherReferenceIsRejected) {
  const RgbaImage ref = disc(32, 15.0, 16.0, 1.0);
  const RgbaImage next = disc(32, 16.0, 16.0, 1.0);
  const Bytes frame = encodeFrame(ref, next);
  RgbaImage other = ref;
  other.pixels[4 * 100] ^= 1;
  Result<RgbaImage> back = decodeTextureDelta(other, frame.data(), frame.size());
  ASSERT_FALSE(back.ok());
  EXPECT_EQ(back.status().code(), ErrorCode::kParseError);
  const RgbaImage bigger = disc(33, 15.0, 16.0, 1.0);
  back = decodeTextureDelta(bigger, frame.data(), frame.size());
  ASSERT_FALSE(back.ok());
  EXPECT_EQ(back.status().code(), ErrorCode::kParseError);
  RgbaImage broken = ref;
  broken.pixels.pop_back();  // inconsistent
  EXPECT_FALSE(decodeTextureDelta(broken, frame.data(), frame.size()).ok());
}

TEST(TextureRefresh, EncoderRejectsBadInput) {
  const RgbaImage a = disc(16, 8.0, 8.0, 1.0);
  const RgbaImage b = disc(17, 8.0, 8.0, 1.0);
  EXPECT_EQ(encodeTextureDelta(a, b).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(encodeTextureDelta(RgbaImage(), RgbaImage()).status().code(),
            ErrorCode::kInvalidArgument);
  RgbaImage broken = a;
  broken.pixels.resize(3);
  EXPECT_EQ(encodeTextureDelta(a, broken).status().code(), ErrorCode::kInvalidArgument);
  TextureDeltaOptions options;
  options.zstdLevel = 0;
  EXPECT_EQ(encodeTextureDelta(a, a, options).status().code(), ErrorCode::kInvalidArgument);
  options = {};
  options.colorTolerance = 128;
  EXPECT_EQ(encodeTextureDelta(a, a, options).status().code(), ErrorCode::kInvalidArgument);
  for (TextureDeltaMode lossless :
       {TextureDeltaMode::kReferencePrefix, TextureDeltaMode::kIntraLeft}) {
    options = {};
    options.colorTolerance = 2;
    options.mode = lossless;
    EXPECT_EQ(encodeTextureDelta(a, a, options).status().code(), ErrorCode::kInvalidArgument);
  }
  options = {};
  options.mode = static_cast<TextureDeltaMode>(5);
  EXPECT_EQ(encodeTextureDelta(a, a, options).status().code(), ErrorCode::kInvalidArgument);
}

TEST(TextureRefresh, UnknownModeOrStepIsUnsupported) {
  const RgbaImage ref = disc(16, 8.0, 8.0, 1.0);
  TextureDeltaOptions prefix;
  prefix.mode = TextureDeltaMode::kReferencePrefix;
  TextureDeltaOptions intra;
  intra.mode = TextureDeltaMode::kIntraLeft;
  struct Case {
    std::size_t offset;
    std::uint8_t value;
    const TextureDeltaOptions* options;
  };
  const TextureDeltaOptions residual;
  // Offset 6 is the mode, 20..23 the colour step (odd, 1..255; 1 for modes 2 and 4).
  for (const Case& c : {Case{6, 0, &residual}, Case{6, 5, &residual}, Case{20, 0, &residual},
                        Case{20, 4, &residual}, Case{21, 1, &residual}, Case{20, 3, &prefix},
                        Case{20, 3, &intra}}) {
    Bytes frame = encodeFrame(ref, ref, *c.options);
    frame[c.offset] = c.value;
    Result<RgbaImage> back = decodeTextureDelta(ref, frame.data(), frame.size());
    ASSERT_FALSE(back.ok()) << c.offset << "=" << int(c.value);
    EXPECT_EQ(back.status().code(), ErrorCode::kUnsupported) << back.status().toString();
  }
}

TEST(TextureRefresh, DimensionsOverTheLimitsAreRejectedBeforeDecoding) {
  const RgbaImage ref = disc(64, 30.0, 32.0, 1.0);
  const Bytes frame = encodeFrame(ref, ref);
  DecodeLimits limits;
  limits.maxTextureDimension = 32;
  Result<RgbaImage> back = decodeTextureDelta(ref, frame.data(), frame.size(), limits);
  ASSERT_FALSE(back.ok());
  EXPECT_EQ(back.status().code(), ErrorCode::kResourceExhausted);
  limits = {};
  limits.maxPayloadBytes = 8;
  EXPECT_EQ(decodeTextureDelta(ref, frame.data(), frame.size(), limits).status().code(),
            ErrorCode::kResourceExhausted);
}

TEST(TextureRefresh, EveryTruncatedPrefixIsAnError) {
  const RgbaImage ref = disc(24, 11.0, 12.0, 1.0);
  const RgbaImage next = disc(24, 12.0, 12.0, 0.9);
  for (TextureDeltaMode mode : kLosslessModes) {
    TextureDeltaOptions options;
    options.mode = mode;
    const Bytes frame = encodeFrame(ref, next, options);
    ASSERT_GT(frame.size(), kFrameHeaderBytes + 8);
    for (std::size_t n = 0; n < frame.size(); ++n) {
      const Bytes prefix(frame.begin(), frame.begin() + static_cast<std::ptrdiff_t>(n));
      EXPECT_FALSE(decodeTextureDelta(ref, prefix.empty() ? nullptr : prefix.data(), n).ok()) << n;
      // Resealed, so the checks behind the frame checksum see the short payload too.
      if (n > kFrameHeaderBytes) {
        Bytes resealed = prefix;
        reseal(resealed);
        EXPECT_FALSE(decodeTextureDelta(ref, resealed.data(), resealed.size()).ok()) << n;
      }
    }
  }
}

TEST(TextureRefresh, ResealedCorruptionsDecodeToAnErrorOrAnImageOfTheReferenceSize) {
  const RgbaImage ref = disc(24, 11.0, 12.0, 1.0);
  const RgbaImage next = disc(24, 12.5, 12.0, 0.9);
  std::mt19937 rng(7);

  for (TextureDeltaMode mode : kLosslessModes) {
    TextureDeltaOptions options;
    options.mode = mode;
    const Bytes frame = encodeFrame(ref, next, options);
    for (int trial = 0; trial < 400; ++trial) {
      Bytes bad = frame;
      // Payload bytes after the fingerprint: zstd sees the damage.
      const std::size_t first = kFrameHeaderBytes + 8;
      const int flips = 1 + static_cast<int>(rng() % 4);
      for (int f = 0; f < flips; ++f) {
        bad[first + rng() % (bad.size() - first)] = static_cast<std::uint8_t>(rng());
      }
      reseal(bad);
      Result<RgbaImage> back = decodeTextureDelta(ref, bad.data(), bad.size());
      if (!back.ok()) continue;

      EXPECT_EQ(back->width, 24);
      EXPECT_EQ(back->height, 24);
      EXPECT_TRUE(back->consistent());
    }
  }
}

TEST(TextureRefresh, TextureFrameIsNotARefreshFrame) {
  const RgbaImage ref = disc(16, 8.0, 8.0, 1.0);
  Result<Bytes> full = encodeTextureWith(ref, TextureCodec::kZstd);
  ASSERT_TRUE(full.ok());
  EXPECT_EQ(decodeTextureDelta(ref, full->data(), full->size()).status().code(),
            ErrorCode::kParseError);
}

}  // namespace
}  // namespace thinlod::codec
