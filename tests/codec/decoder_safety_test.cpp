// Memory-safety tests of the untrusted-input decoders (STYLE.md item 8):
// every truncated prefix and random corruptions of valid frames decode to an
// error or a valid result, never a crash. Corruptions are applied both to
// whole frames (caught by the checksum) and to payloads with the checksum
// recomputed, so the third-party decoders (Draco, zstd, libpng, libjpeg)
// see the damaged bytes themselves. The libFuzzer targets for both decoders
// are fuzz/codec_mesh_frame.cpp and fuzz/codec_texture_frame.cpp.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes meshFrame() {
  IndexedMesh sphere = thinlod::testing::makeIcosphere(2, 1.0f);
  sphere.computeNormals();
  for (const glm::vec3& p : sphere.positions) {
    sphere.uvs.emplace_back(p.x, p.y);
    sphere.colors.push_back({10, 20, 30, 255});
  }
  Result<Bytes> frame = encodeMesh(sphere);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  return frame.ok() ? *frame : Bytes{};
}

Bytes textureFrame(TextureCodec codec) {
  RgbaImage t(24, 16);
  for (std::size_t i = 0; i < t.pixels.size(); ++i) {
    t.pixels[i] = static_cast<std::uint8_t>(i % 4 == 3 ? 255 : (i * 7) % 251);
  }
  Result<Bytes> frame = encodeTextureWith(t, codec);
  EXPECT_TRUE(frame.ok()) << frame.status().toString();
  return frame.ok() ? *frame : Bytes{};
}

// Rewrites the header's payload size and checksum to match the payload.
void resealFrame(Bytes& frame) {
  const std::uint32_t payload = static_cast<std::uint32_t>(frame.size() - kFrameHeaderBytes);
  for (int i = 0; i < 4; ++i) frame[16 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint64_t sum = frameChecksum(frame.data() + kFrameHeaderBytes, payload);
  for (int i = 0; i < 8; ++i) frame[24 + i] = static_cast<std::uint8_t>(sum >> (8 * i));
}

// Decodes with the decoder matching the frame; returns whether it succeeded
// and checks that any success is a valid value.
bool decodeChecked(const Bytes& frame, bool isMesh) {
  if (isMesh) {
    Result<IndexedMesh> mesh = decodeMesh(frame.data(), frame.size());
    if (mesh.ok()) {
      EXPECT_TRUE(mesh->validate("decoded").ok());
    }
    return mesh.ok();
  }
  Result<RgbaImage> texture = decodeTexture(frame.data(), frame.size());
  if (texture.ok()) {
    EXPECT_FALSE(texture->empty());
    EXPECT_TRUE(texture->consistent());
  }
  return texture.ok();
}

struct NamedFrame {
  std::string name;
  Bytes bytes;
  bool isMesh;
};

std::vector<NamedFrame> validFrames() {
  return {{"draco", meshFrame(), true},
          {"zstd", textureFrame(TextureCodec::kZstd), false},
          {"png", textureFrame(TextureCodec::kPng), false},
          {"jpeg", textureFrame(TextureCodec::kJpeg), false}};
}

TEST(DecoderSafety, ValidFramesDecode) {
  for (const NamedFrame& f : validFrames()) EXPECT_TRUE(decodeChecked(f.bytes, f.isMesh)) << f.name;
}

TEST(DecoderSafety, EveryTruncatedFrameIsAnError) {
  for (const NamedFrame& f : validFrames()) {
    for (std::size_t n = 0; n < f.bytes.size(); ++n) {
      const Bytes prefix(f.bytes.begin(), f.bytes.begin() + n);
      ASSERT_FALSE(decodeChecked(prefix, f.isMesh)) << f.name << " prefix " << n;
    }
  }
}

TEST(DecoderSafety, EveryTruncatedPayloadWithResealedHeaderIsSafe) {
  for (const NamedFrame& f : validFrames()) {
    for (std::size_t n = kFrameHeaderBytes; n < f.bytes.size(); ++n) {
      Bytes prefix(f.bytes.begin(), f.bytes.begin() + n);
      resealFrame(prefix);
      decodeChecked(prefix, f.isMesh);  // error or valid; must not crash
    }
  }
}

TEST(DecoderSafety, RandomFrameCorruptionsAreRejectedOrValid) {
  std::mt19937 rng(1234);
  for (const NamedFrame& f : validFrames()) {
    int accepted = 0;
    for (int iteration = 0; iteration < 500; ++iteration) {
      Bytes corrupt = f.bytes;
      const int flips = 1 + static_cast<int>(rng() % 8);
      for (int k = 0; k < flips; ++k) corrupt[rng() % corrupt.size()] ^= 1u << (rng() % 8);
      accepted += decodeChecked(corrupt, f.isMesh);
    }
    // Bit flips anywhere in header or payload are caught (checksum, fields).
    EXPECT_EQ(accepted, 0) << f.name;
  }
}

TEST(DecoderSafety, RandomPayloadCorruptionsReachTheCodecSafely) {
  std::mt19937 rng(4321);
  for (const NamedFrame& f : validFrames()) {
    const std::size_t payload = f.bytes.size() - kFrameHeaderBytes;
    for (int iteration = 0; iteration < 1000; ++iteration) {
      Bytes corrupt = f.bytes;
      const int changes = 1 + static_cast<int>(rng() % 16);
      for (int k = 0; k < changes; ++k) {
        const std::size_t at = kFrameHeaderBytes + rng() % payload;
        corrupt[at] = (rng() % 2) ? static_cast<std::uint8_t>(rng()) : corrupt[at] ^ 0x80;
      }
      resealFrame(corrupt);
      decodeChecked(corrupt, f.isMesh);  // error or valid; must not crash
    }
  }
}

TEST(DecoderSafety, TruncatedPngPayloadIsRejectedBeforeTheImageLibrary) {
  Bytes frame = textureFrame(TextureCodec::kPng);
  frame.resize(frame.size() - 5);  // cuts into the IEND chunk
  resealFrame(frame);
  Result<RgbaImage> decoded = decodeTexture(frame.data(), frame.size());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kParseError);
  EXPECT_NE(decoded.status().message().find("truncated"), std::string::npos)
      << decoded.status().message();
}

TEST(DecoderSafety, UnknownVersionIsVersionMismatch) {
  Bytes frame = meshFrame();
  frame[4] = static_cast<std::uint8_t>(kFrameVersion + 1);
  EXPECT_EQ(decodeMesh(frame.data(), frame.size()).status().code(), ErrorCode::kVersionMismatch);
}

TEST(DecoderSafety, UnframedCodecInATextureFrameIsUnsupported) {
  for (TextureCodec unframed : {TextureCodec::kNone, TextureCodec::kRawRgba8}) {
    Bytes frame = textureFrame(TextureCodec::kZstd);
    frame[6] = static_cast<std::uint8_t>(unframed);
    EXPECT_EQ(decodeTexture(frame.data(), frame.size()).status().code(), ErrorCode::kUnsupported);
    RgbaImage image(4, 4);
    EXPECT_EQ(encodeTextureWith(image, unframed).status().code(), ErrorCode::kInvalidArgument);
  }
}

TEST(DecoderSafety, WrongMagicIsParseError) {
  Bytes frame = textureFrame(TextureCodec::kZstd);
  EXPECT_EQ(decodeMesh(frame.data(), frame.size()).status().code(), ErrorCode::kParseError);
}

TEST(DecoderSafety, UnknownCodecIsUnsupported) {
  Bytes frame = textureFrame(TextureCodec::kZstd);
  frame[6] = 9;
  EXPECT_EQ(decodeTexture(frame.data(), frame.size()).status().code(), ErrorCode::kUnsupported);
}

TEST(DecoderSafety, DeclaredCountsBeyondLimitsAreRejectedBeforeDecoding) {
  const Bytes frame = meshFrame();
  DecodeLimits limits;
  limits.maxVertices = 10;
  EXPECT_EQ(decodeMesh(frame.data(), frame.size(), limits).status().code(),
            ErrorCode::kResourceExhausted);
  limits = DecodeLimits{};
  limits.maxPayloadBytes = 100;
  EXPECT_EQ(decodeMesh(frame.data(), frame.size(), limits).status().code(),
            ErrorCode::kResourceExhausted);
}

TEST(DecoderSafety, HeaderCountsMustMatchTheDecodedMesh) {
  Bytes frame = meshFrame();
  frame[12] ^= 1;  // triangle count: still within limits, now wrong
  EXPECT_EQ(decodeMesh(frame.data(), frame.size()).status().code(), ErrorCode::kParseError);
}

TEST(DecoderSafety, TextureSidesBeyondIntAreRejectedWhateverTheLimit) {
  Bytes frame = textureFrame(TextureCodec::kZstd);
  for (int i = 8; i < 16; ++i) frame[i] = 0xff;  // width and height 2^32 - 1
  DecodeLimits limits;
  limits.maxTextureDimension = 0xffffffffu;  // admits any u32 side
  Result<RgbaImage> decoded = decodeTexture(frame.data(), frame.size(), limits);
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_NE(decoded.status().message().find("outside [1, 2147483647]"), std::string::npos)
      << decoded.status().message();
}

// Fuzz finding (fuzz/corpus/codec_mesh/crash-draco-bool-131.bin, a valid
// checksum over a mutated Draco payload): libdraco stores an attribute's
// "normalized" flag from the bitstream unchecked, and reading it through
// GeometryAttribute::ConvertValue was a load of bool 131 (UB). The decoder
// now copies attribute bytes itself; the frame decodes or fails cleanly.
TEST(DecoderSafety, DracoAttributeWithACorruptNormalizedFlagIsHandled) {
  std::ifstream in(
      std::string(THINLOD_SOURCE_DIR) + "/fuzz/corpus/codec_mesh/crash-draco-bool-131.bin",
      std::ios::binary);
  const Bytes frame((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(frame.size(), kFrameHeaderBytes);
  decodeChecked(frame, /*isMesh=*/true);  // checks any success is a valid mesh
}

// Fuzz finding (fuzz/corpus/codec_texture/crash-jpeg-app1-without-nul.bin):
// OpenImageIO's JPEG reader strcmp()s APP1 data, reading past a segment
// without a NUL (heap over-read). Such payloads, and JPEG headers whose
// segments run past the payload, are rejected before OpenImageIO sees them.
TEST(DecoderSafety, JpegWithAnUnterminatedApp1SegmentIsRejected) {
  std::ifstream in(std::string(THINLOD_SOURCE_DIR) +
                       "/fuzz/corpus/codec_texture/crash-jpeg-app1-without-nul.bin",
                   std::ios::binary);
  Bytes frame((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(frame.size(), kFrameHeaderBytes);
  resealFrame(frame);
  const Result<RgbaImage> decoded = decodeTexture(frame.data(), frame.size());
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kParseError);
  EXPECT_NE(decoded.status().message().find("JPEG payload has a malformed header"),
            std::string::npos)
      << decoded.status().message();
  // A segment length running past the payload is rejected the same way.
  Bytes valid = textureFrame(TextureCodec::kJpeg);
  valid[kFrameHeaderBytes + 4] = 0xFF;  // APP0 length high byte
  resealFrame(valid);
  EXPECT_EQ(decodeTexture(valid.data(), valid.size()).status().code(), ErrorCode::kParseError);
}

TEST(DecoderSafety, NullInputIsAnError) {
  EXPECT_FALSE(decodeMesh(nullptr, 0).ok());
  EXPECT_FALSE(decodeTexture(nullptr, 0).ok());
}

}  // namespace
}  // namespace thinlod::codec
