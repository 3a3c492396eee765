// Shared textures on the wire (docs/protocol.md, "Shared textures"): sent
// once in a SceneUpdate, held by the frontend and named by every mesh that
// uses them.
#include <gtest/gtest.h>

#include "daemon_test_util.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {
namespace {

using protocol::TextureCodec;
using testing::addOp;
using testing::gradientTexture;
using testing::meshRepresentation;
using testing::quadMesh;
using testing::sphereMesh;
using testing::wireTexture;

protocol::SharedTexture sharedTexture(std::uint64_t id, int w, int h,
                                      TextureCodec codec = TextureCodec::kPng) {
  protocol::SharedTexture t;
  t.textureId = id;
  t.texture = wireTexture(gradientTexture(w, h), codec);
  return t;
}

protocol::Representation texturedQuad(std::uint64_t textureId) {
  protocol::Representation rep = meshRepresentation(quadMesh());
  rep.textureId = textureId;
  return rep;
}

TEST(SharedTextureWire, OneTextureServesEveryMeshNamingItAndLaterUpdates) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  protocol::SceneUpdate first;
  first.plan = 1;
  first.textures.push_back(sharedTexture(5, 16, 8));
  first.operations.push_back(addOp(1, texturedQuad(5)));
  first.operations.push_back(addOp(2, texturedQuad(5)));
  auto batch = convertUpdate(first, options);
  ASSERT_TRUE(batch.ok()) << batch.status().toString();
  ASSERT_EQ(batch->operations.size(), 2u);
  const auto& a = batch->operations[0].representation.texture;
  const auto& b = batch->operations[1].representation.texture;
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a.get(), b.get());  // one decoded image, shared
  EXPECT_EQ(a->width, 16);
  EXPECT_EQ(a->height, 8);
  EXPECT_EQ(a->pixels, gradientTexture(16, 8).pixels);  // PNG is lossless
  EXPECT_EQ(cache.textures.size(), 1u);
  EXPECT_EQ(cache.decodedBytes, 16u * 8u * 4u);

  // A later update names it without carrying it.
  protocol::SceneUpdate second;
  second.plan = 2;
  second.operations.push_back(addOp(3, texturedQuad(5)));
  auto later = convertUpdate(second, options);
  ASSERT_TRUE(later.ok()) << later.status().toString();
  EXPECT_EQ(later->operations[0].representation.texture.get(), a.get());
  EXPECT_EQ(payloadBytes(first),
            first.textures[0].texture.data.size() + first.operations[0].representation.mesh.size() +
                first.operations[1].representation.mesh.size());
}

TEST(SharedTextureWire, UnknownTextureIdRefusesTheUpdateNamingTheId) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  protocol::SceneUpdate update;
  update.plan = 4;
  update.operations.push_back(addOp(9, texturedQuad(77)));
  auto batch = convertUpdate(update, options);
  ASSERT_FALSE(batch.ok());
  EXPECT_EQ(batch.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(batch.status().message().find("shared texture 77"), std::string::npos)
      << batch.status().message();
  EXPECT_NE(batch.status().message().find("object 9"), std::string::npos);
}

TEST(SharedTextureWire, TexturesOfAnUpdateWhoseOperationFailsAreStillHeld) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  protocol::SceneUpdate update;
  update.textures.push_back(sharedTexture(1, 4, 4));
  protocol::Representation broken = texturedQuad(1);
  broken.triangleCount = 99;  // announces the wrong count
  update.operations.push_back(addOp(1, broken));
  ASSERT_FALSE(convertUpdate(update, options).ok());
  EXPECT_EQ(cache.textures.count(1), 1u);  // the backbone need not send it again
}

TEST(SharedTextureWire, BadTextureRefusesTheUpdateAndAddsNothing) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  protocol::SceneUpdate update;
  update.textures.push_back(sharedTexture(1, 4, 4));
  protocol::SharedTexture lying = sharedTexture(2, 8, 8);
  lying.texture.width = 9;  // decoded size differs from the announced one
  update.textures.push_back(lying);
  auto batch = convertUpdate(update, options);
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("shared texture 1 (id 2)"), std::string::npos)
      << batch.status().message();
  EXPECT_TRUE(cache.textures.empty());

  protocol::SceneUpdate zero;
  zero.textures.push_back(sharedTexture(0, 4, 4));
  EXPECT_FALSE(convertUpdate(zero, options).ok());
  protocol::SceneUpdate twice;
  twice.textures.push_back(sharedTexture(3, 4, 4));
  twice.textures.push_back(sharedTexture(3, 4, 4));
  auto duplicate = convertUpdate(twice, options);
  ASSERT_FALSE(duplicate.ok());
  EXPECT_NE(duplicate.status().message().find("listed twice"), std::string::npos);
}

TEST(SharedTextureWire, OversizedSidesAreRefusedBeforeDecoding) {
  ConversionOptions options;
  options.limits.maxTextureDimension = 64;
  protocol::SceneUpdate update;
  protocol::SharedTexture big = sharedTexture(1, 4, 4);
  big.texture.width = 100000;  // checked against the limit before the frame is decoded
  update.textures.push_back(big);
  auto batch = convertUpdate(update, options);
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("outside 1..64"), std::string::npos)
      << batch.status().message();
}

TEST(SharedTextureWire, CacheLimitsRefuseTheUpdateWithResourceExhausted) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  options.maxSharedTextures = 1;
  protocol::SceneUpdate update;
  update.textures.push_back(sharedTexture(1, 4, 4));
  update.textures.push_back(sharedTexture(2, 4, 4));
  auto batch = convertUpdate(update, options);
  ASSERT_FALSE(batch.ok());
  EXPECT_EQ(batch.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_TRUE(cache.textures.empty());

  options.maxSharedTextures = 8;
  options.maxSharedTextureBytes = 100;  // one 4x4 texture is 64 bytes
  auto bytes = convertUpdate(update, options);
  ASSERT_FALSE(bytes.ok());
  EXPECT_EQ(bytes.status().code(), ErrorCode::kResourceExhausted);
  // Re-sending a held id replaces it without growing the count.
  protocol::SceneUpdate one;
  one.textures.push_back(sharedTexture(1, 4, 4));
  ASSERT_TRUE(convertUpdate(one, options).ok());
  ASSERT_TRUE(convertUpdate(one, options).ok());
  EXPECT_EQ(cache.textures.size(), 1u);
  EXPECT_EQ(cache.decodedBytes, 64u);
}

TEST(SharedTextureWire, TextureIdNeedsUvsAndAMeshKind) {
  SharedTextureCache cache;
  ConversionOptions options;
  options.sharedTextures = &cache;
  protocol::SceneUpdate update;
  update.textures.push_back(sharedTexture(1, 4, 4));
  IndexedMesh plain = sphereMesh(1.0f, 8, 4);
  plain.uvs.clear();
  protocol::Representation noUvs = meshRepresentation(plain);
  noUvs.textureId = 1;
  update.operations.push_back(addOp(1, noUvs));
  auto batch = convertUpdate(update, options);
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("no uvs"), std::string::npos)
      << batch.status().message();

  protocol::Representation impostor = testing::impostorRepresentation(TextureCodec::kPng);
  impostor.textureId = 1;
  auto rep = convertRepresentation(impostor, 1, options, "op");
  ASSERT_FALSE(rep.ok());
  EXPECT_NE(rep.status().message().find("names shared texture"), std::string::npos);
}

}  // namespace
}  // namespace thinlod::frontend::daemon
