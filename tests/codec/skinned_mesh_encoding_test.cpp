// Skinned mesh frames (encoding.h, encodeSkinnedMesh / decodeSkinnedMesh):
// the two-bone skin travels with its vertex through Draco's reordering
// (bones exact, weights to 1/65535), plain decodeMesh reads the frame, the encoder refuses bad
// skins, and the decoder survives every prefix and resealed corruptions
// (whatever decodes is a valid skin).
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <random>

#include "articulated_figure.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::codec {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Figure {
  IndexedMesh mesh;
  std::vector<anim::VertexSkin> skin;
};

Figure figure() {
  anim::testing::FigureShape shape;
  shape.ringsPerUnit = 6;
  shape.around = 10;
  anim::testing::ArticulatedFigure f = anim::testing::makeArticulatedFigure(shape);
  return {std::move(f.mesh), std::move(f.skin)};
}

// The input vertex nearest to `p` (brute force: the figure is small).
std::size_t nearest(const IndexedMesh& mesh, const glm::vec3& p) {
  std::size_t best = 0;
  for (std::size_t v = 1; v < mesh.vertexCount(); ++v) {
    if (glm::distance(mesh.positions[v], p) < glm::distance(mesh.positions[best], p)) best = v;
  }
  return best;
}

void resealFrame(Bytes& frame) {
  const auto payload = static_cast<std::uint32_t>(frame.size() - kFrameHeaderBytes);
  for (int i = 0; i < 4; ++i) frame[16 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint64_t sum = frameChecksum(frame.data() + kFrameHeaderBytes, payload);
  for (int i = 0; i < 8; ++i) frame[24 + i] = static_cast<std::uint8_t>(sum >> (8 * i));
}

void expectValidSkin(const SkinnedMeshFrame& frame) {
  ASSERT_EQ(frame.skin.size(), frame.mesh.vertexCount());
  EXPECT_TRUE(
      anim::validateSkin(frame.skin, frame.mesh.vertexCount(), kMaxSkinBones, "decoded").ok());
}

TEST(SkinnedMeshEncoding, SkinTravelsWithItsVertex) {
  const Figure f = figure();
  MeshEncodeOptions options;
  options.positionBits = 16;
  Result<Bytes> bytes = encodeSkinnedMesh(f.mesh, f.skin, options);
  ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
  Result<SkinnedMeshFrame> decoded = decodeSkinnedMesh(bytes->data(), bytes->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  expectValidSkin(*decoded);
  EXPECT_EQ(decoded->mesh.triangleCount(), f.mesh.triangleCount());
  const double bound = positionErrorBound(f.mesh, options.positionBits);
  std::size_t twoBone = 0;
  for (std::size_t v = 0; v < decoded->mesh.vertexCount(); ++v) {
    const std::size_t source = nearest(f.mesh, decoded->mesh.positions[v]);
    ASSERT_LE(glm::distance(f.mesh.positions[source], decoded->mesh.positions[v]), bound * 1.01);
    const anim::VertexSkin& want = f.skin[source];
    const anim::VertexSkin& got = decoded->skin[v];
    EXPECT_EQ(got.boneA, want.boneA) << v;
    if (want.rigid()) {
      EXPECT_TRUE(got.rigid()) << v;
    } else {
      ++twoBone;
      EXPECT_EQ(got.boneB, want.boneB) << v;
      EXPECT_NEAR(got.weightB, want.weightB, 0.5f / 65535.0f + 1e-7f) << v;
    }
  }
  EXPECT_GT(twoBone, 0u) << "the figure has deformable joints";

  // decodeMesh reads the same frame (without the skin).
  Result<IndexedMesh> plain = decodeMesh(bytes->data(), bytes->size());
  ASSERT_TRUE(plain.ok()) << plain.status().toString();
  EXPECT_EQ(plain->positions, decoded->mesh.positions);
  EXPECT_EQ(plain->indices, decoded->mesh.indices);
  // A frame without a skin decodes with an empty one.
  Result<Bytes> unskinned = encodeMesh(f.mesh, options);
  ASSERT_TRUE(unskinned.ok());
  Result<SkinnedMeshFrame> none = decodeSkinnedMesh(unskinned->data(), unskinned->size());
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->skin.empty());
}

TEST(SkinnedMeshEncoding, EncoderRefusesSkinsThatDoNotFit) {
  const Figure f = figure();
  std::vector<anim::VertexSkin> shorter(f.skin.begin(), f.skin.end() - 1);
  EXPECT_EQ(encodeSkinnedMesh(f.mesh, shorter).status().code(), ErrorCode::kInvalidArgument);
  std::vector<anim::VertexSkin> heavy = f.skin;
  heavy[3] = {0, 1, 1.5f};
  EXPECT_EQ(encodeSkinnedMesh(f.mesh, heavy).status().code(), ErrorCode::kInvalidArgument);
  std::vector<anim::VertexSkin> nan = f.skin;
  nan[3] = {0, 1, std::nanf("")};
  EXPECT_EQ(encodeSkinnedMesh(f.mesh, nan).status().code(), ErrorCode::kInvalidArgument);
  std::vector<anim::VertexSkin> farBone = f.skin;
  farBone[3] = {kMaxSkinBones, kMaxSkinBones, 0.0f};
  EXPECT_EQ(encodeSkinnedMesh(f.mesh, farBone).status().code(), ErrorCode::kInvalidArgument);
}

TEST(SkinnedMeshEncoding, SkinBitWithoutTheAttributeIsAParseError) {
  const Figure f = figure();
  Result<Bytes> bytes = encodeMesh(f.mesh);
  ASSERT_TRUE(bytes.ok());
  Bytes claimed = *bytes;
  claimed[20] |= 8;  // the attribute bits (not under the payload checksum)
  Result<SkinnedMeshFrame> decoded = decodeSkinnedMesh(claimed.data(), claimed.size());
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kParseError) << decoded.status().toString();
}

TEST(SkinnedMeshEncoding, PrefixesAndResealedCorruptionsNeverCrash) {
  const Figure f = figure();
  Result<Bytes> bytes = encodeSkinnedMesh(f.mesh, f.skin);
  ASSERT_TRUE(bytes.ok());
  for (std::size_t length = 0; length < bytes->size(); ++length) {
    const Bytes prefix(bytes->begin(), bytes->begin() + static_cast<std::ptrdiff_t>(length));
    EXPECT_FALSE(decodeSkinnedMesh(prefix.data(), prefix.size()).ok()) << length;
  }
  std::mt19937 rng(20261204);
  std::size_t accepted = 0;
  for (int i = 0; i < 400; ++i) {
    Bytes corrupt = *bytes;
    for (int k = 0; k < 4; ++k) {
      const std::size_t at = kFrameHeaderBytes + rng() % (corrupt.size() - kFrameHeaderBytes);
      corrupt[at] = static_cast<std::uint8_t>(rng());
    }
    resealFrame(corrupt);
    Result<SkinnedMeshFrame> decoded = decodeSkinnedMesh(corrupt.data(), corrupt.size());
    if (!decoded.ok()) continue;
    ++accepted;
    EXPECT_TRUE(decoded->mesh.validate("corrupt").ok());
    expectValidSkin(*decoded);
  }
  EXPECT_LT(accepted, 400u);
}

}  // namespace
}  // namespace thinlod::codec
