// Codec: round trips, limits, versions and semantic checks (codec.h).
#include "thinlod/protocol/codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <ostream>

#include "seed_messages.h"
#include "thinlod_wire_generated.h"

namespace thinlod::protocol::seeds {
// A parameter prints as its name: gtest (and so ctest's test list) would
// otherwise show the struct's raw bytes.
void PrintTo(const NamedMessage& seed, std::ostream* os) { *os << seed.name; }
}  // namespace thinlod::protocol::seeds

namespace thinlod::protocol {
namespace {

namespace fb = flatbuffers;
namespace w = thinlod::wire;

Bytes finish(fb::FlatBufferBuilder& b, std::uint16_t version, w::Body type, fb::Offset<void> body) {
  b.Finish(w::CreateEnvelope(b, version, type, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

Bytes wireHeartbeat(std::uint16_t version) {
  fb::FlatBufferBuilder b;
  auto body = w::CreateHeartbeat(b, 5, 6).Union();
  return finish(b, version, w::Body::Heartbeat, body);
}

Bytes wirePose(w::Vec3 position, w::Quat orientation, float fov) {
  fb::FlatBufferBuilder b;
  auto body = w::CreateViewerPose(b, 1, 2, &position, &orientation, fov, 640, 480).Union();
  return finish(b, kProtocolVersion, w::Body::ViewerPose, body);
}

ViewerPose validPose() { return std::get<ViewerPose>(seeds::seedMessages()[3].message); }

class SeedRoundTrip : public ::testing::TestWithParam<seeds::NamedMessage> {};

TEST_P(SeedRoundTrip, DecodesToTheSameMessage) {
  const Message& original = GetParam().message;
  Result<Bytes> bytes = encode(original);
  ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
  Result<Message> decoded = decode(*bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_EQ(decoded->index(), original.index());
  EXPECT_TRUE(*decoded == original) << GetParam().name;
}

TEST_P(SeedRoundTrip, EncodingIsDeterministicAndMatchesEncoder) {
  const Message& original = GetParam().message;
  Result<Bytes> first = encode(original);
  Result<Bytes> second = encode(original);
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(*first, *second);
  Encoder encoder;
  auto view = encoder.encode(original);
  ASSERT_TRUE(view.ok());
  EXPECT_EQ(Bytes(view->data, view->data + view->size), *first);
}

TEST_P(SeedRoundTrip, DecodesFromAMisalignedBuffer) {
  Result<Bytes> bytes = encode(GetParam().message);
  ASSERT_TRUE(bytes.ok());
  Bytes shifted(bytes->size() + 1);
  std::copy(bytes->begin(), bytes->end(), shifted.begin() + 1);
  Result<Message> decoded = decode(shifted.data() + 1, bytes->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  EXPECT_TRUE(*decoded == GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(AllMessages, SeedRoundTrip, ::testing::ValuesIn(seeds::seedMessages()),
                         [](const auto& info) { return info.param.name; });

TEST(Codec, SeedsCoverEveryMessageType) {
  std::vector<bool> seen(std::variant_size_v<Message>, false);
  for (const auto& seed : seeds::seedMessages()) seen[seed.message.index()] = true;
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_TRUE(seen[i]) << "message index " << i;
}

TEST(Codec, LargeSceneUpdateRoundTrips) {
  const SceneUpdate update = seeds::sceneUpdateOfSize(256 * 1024, 3);
  auto bytes = encode(update);
  ASSERT_TRUE(bytes.ok());
  EXPECT_GT(bytes->size(), 256u * 1024u);
  auto decoded = decode(*bytes);
  ASSERT_TRUE(decoded.ok());
  EXPECT_TRUE(std::get<SceneUpdate>(*decoded) == update);
}

TEST(Codec, EveryErrorCodeMapsOneToOne) {
  for (int code = 0; code <= static_cast<int>(ErrorCode::kInternal); ++code) {
    const auto value = static_cast<ErrorCode>(code);
    auto back = errorCodeFromWire(errorCodeToWire(value));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(*back, value);
    if (value == ErrorCode::kOk) continue;
    SimplifyResult failed;
    failed.requestId = 1;
    failed.status = Status(value, std::string("because ") + errorCodeName(value));
    auto decoded = decode(*encode(failed));
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_EQ(std::get<SimplifyResult>(*decoded).status.code(), value);
    EXPECT_EQ(std::get<SimplifyResult>(*decoded).status.message(), failed.status.message());
  }
  EXPECT_FALSE(errorCodeFromWire(static_cast<std::uint8_t>(ErrorCode::kInternal) + 1).ok());
}

TEST(Codec, WrongVersionIsVersionMismatch) {
  for (std::uint16_t version :
       {std::uint16_t(0), std::uint16_t(kProtocolVersion + 1), std::uint16_t(0xffff)}) {
    auto decoded = decode(wireHeartbeat(version));
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), ErrorCode::kVersionMismatch) << decoded.status().toString();
    EXPECT_NE(decoded.status().message().find(std::to_string(version)), std::string::npos);
  }
  EXPECT_TRUE(decode(wireHeartbeat(kProtocolVersion)).ok());
}

TEST(Codec, PeekVersionReadsOnlyTheHeader) {
  auto version =
      peekVersion(wireHeartbeat(kProtocolVersion).data(), wireHeartbeat(kProtocolVersion).size());
  ASSERT_TRUE(version.ok());
  EXPECT_EQ(*version, kProtocolVersion);
}

TEST(Codec, OversizedInputIsResourceExhausted) {
  Bytes huge(kMaxMessageBytes + 1, 0);
  auto decoded = decode(huge);
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted);
}

TEST(Codec, OversizedMessageIsNotEncoded) {
  SceneUpdate update = seeds::sceneUpdateOfSize(kMaxMessageBytes, 1);
  auto bytes = encode(update);
  ASSERT_FALSE(bytes.ok());
  EXPECT_EQ(bytes.status().code(), ErrorCode::kResourceExhausted);
}

TEST(Codec, ShortOrForeignInputIsInvalid) {
  EXPECT_EQ(decode(nullptr, 0).status().code(), ErrorCode::kInvalidArgument);
  Bytes bytes = wireHeartbeat(kProtocolVersion);
  EXPECT_EQ(decode(bytes.data(), 7).status().code(), ErrorCode::kInvalidArgument);
  bytes[4] = 'X';  // file identifier
  auto decoded = decode(bytes);
  EXPECT_EQ(decoded.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(decoded.status().message().find("identifier"), std::string::npos);
}

TEST(Codec, EnvelopeWithoutBodyIsInvalid) {
  fb::FlatBufferBuilder b;
  auto bytes = finish(b, kProtocolVersion, w::Body::NONE, 0);
  EXPECT_EQ(decode(bytes).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, UnknownMessageTypeIsUnsupported) {
  fb::FlatBufferBuilder b;
  auto body = w::CreateHeartbeat(b, 1, 2).Union();
  auto bytes = finish(b, kProtocolVersion, static_cast<w::Body>(200), body);
  auto decoded = decode(bytes);
  EXPECT_EQ(decoded.status().code(), ErrorCode::kUnsupported) << decoded.status().toString();
}

TEST(Codec, NanPositionIsRejectedWithItsFieldName) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto decoded = decode(wirePose(w::Vec3(0, nan, 0), w::Quat(0, 0, 0, 1), 1.0f));
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_NE(decoded.status().message().find("ViewerPose.position.y"), std::string::npos)
      << decoded.status().message();
}

TEST(Codec, NonUnitQuaternionIsRejected) {
  auto decoded = decode(wirePose(w::Vec3(0, 0, 0), w::Quat(0, 0, 0, 2), 1.0f));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("orientation"), std::string::npos);
  EXPECT_TRUE(decode(wirePose(w::Vec3(0, 0, 0), w::Quat(0, 0, 0, 1.0001f), 1.0f)).ok());
}

TEST(Codec, InfiniteFovIsRejected) {
  auto decoded = decode(
      wirePose(w::Vec3(0, 0, 0), w::Quat(0, 0, 0, 1), std::numeric_limits<float>::infinity()));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("fov_y"), std::string::npos);
}

TEST(Codec, MissingRequiredStructIsRejected) {
  fb::FlatBufferBuilder b;
  const w::Quat q(0, 0, 0, 1);
  auto body = w::CreateViewerPose(b, 1, 2, nullptr, &q, 1.0f).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::ViewerPose, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("position: is missing"), std::string::npos);
}

TEST(Codec, EncodeRejectsWhatDecodeRejects) {
  ViewerPose pose = validPose();
  pose.position.x = std::numeric_limits<float>::infinity();
  EXPECT_EQ(encode(pose).status().code(), ErrorCode::kInvalidArgument);
  pose = validPose();
  pose.orientation = glm::quat(0.5f, 0.0f, 0.0f, 0.0f);
  EXPECT_EQ(encode(pose).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, TextureLargerThanTheLimitIsResourceExhausted) {
  SceneUpdate update;
  SceneOperation op;
  op.objectId = 1;
  op.representation = seeds::sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 16);
  op.representation.texture.width = kMaxTextureDimension + 1;
  update.operations.push_back(op);
  auto encoded = encode(update);
  ASSERT_FALSE(encoded.ok());
  EXPECT_EQ(encoded.status().code(), ErrorCode::kResourceExhausted);

  // The same on the wire.
  fb::FlatBufferBuilder b;
  auto data = b.CreateVector(std::vector<std::uint8_t>(64, 1));
  auto texture = w::CreateTexture(b, w::TextureCodec::Png, kMaxTextureDimension + 1, 4, data);
  const w::Mat4 transform;
  const w::ConicRange validity(w::Vec3(0, 0, 0), 0.0f, 10.0f, w::Vec3(0, 0, 1), 3.0f);
  auto rep = w::CreateRepresentation(b, 1, 1, w::RepresentationKind::SimpleImpostor, 0, texture,
                                     &transform, &validity, 1.0, 2);
  auto ops = b.CreateVector(std::vector<fb::Offset<w::SceneOp>>{
      w::CreateSceneOp(b, w::SceneOpType::AddOrReplace, 1, rep)});
  auto body = w::CreateSceneUpdate(b, 1, 1, 1.0, ops).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::SceneUpdate, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted) << decoded.status().toString();
  EXPECT_NE(decoded.status().message().find("operations[0].representation.texture"),
            std::string::npos)
      << decoded.status().message();
}

// Shared textures (docs/protocol.md, "Shared textures").
SharedTexture pngShared(std::uint64_t id) {
  SharedTexture t;
  t.textureId = id;
  t.texture = seeds::sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 8).texture;
  return t;
}

TEST(Codec, SharedTexturesAndTextureIdsRoundTrip) {
  SceneUpdate update = seeds::sceneUpdateOfSize(512, 4);
  update.operations[0].representation.textureId = 7;
  update.textures = {pngShared(7), pngShared(9)};
  auto encoded = encode(update);
  ASSERT_TRUE(encoded.ok()) << encoded.status().toString();
  auto decoded = decode(*encoded);
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  const SceneUpdate& back = std::get<SceneUpdate>(*decoded);
  EXPECT_TRUE(back == update);
  ASSERT_EQ(back.textures.size(), 2u);
  EXPECT_EQ(back.textures[1].textureId, 9u);
  EXPECT_EQ(back.operations[0].representation.textureId, 7u);
}

TEST(Codec, SharedTextureRulesAreCheckedOnBothSides) {
  SceneUpdate zero;
  zero.textures = {pngShared(0)};
  auto encoded = encode(zero);
  ASSERT_FALSE(encoded.ok());
  EXPECT_NE(encoded.status().message().find("textures[0].texture_id"), std::string::npos)
      << encoded.status().message();

  SceneUpdate twice;
  twice.textures = {pngShared(3), pngShared(3)};
  encoded = encode(twice);
  ASSERT_FALSE(encoded.ok());
  EXPECT_NE(encoded.status().message().find("texture id 3 twice"), std::string::npos);

  SceneUpdate oversized;
  oversized.textures = {pngShared(1)};
  oversized.textures[0].texture.width = kMaxTextureDimension + 1;
  EXPECT_EQ(encode(oversized).status().code(), ErrorCode::kResourceExhausted);

  // An impostor carries its own texture: a texture id there is refused.
  SceneUpdate impostor;
  SceneOperation op;
  op.objectId = 1;
  op.representation = seeds::sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 4);
  op.representation.textureId = 2;
  impostor.operations.push_back(op);
  encoded = encode(impostor);
  ASSERT_FALSE(encoded.ok());
  EXPECT_NE(encoded.status().message().find("texture_id"), std::string::npos);

  // Decode refuses the same from the wire: a SharedTexture without its texture.
  fb::FlatBufferBuilder b;
  auto shared = b.CreateVector(std::vector<fb::Offset<w::SharedTexture>>{
      w::CreateSharedTexture(b, 1, 0)});
  auto body = w::CreateSceneUpdate(b, 1, 1, 1.0, 0, shared).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::SceneUpdate, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("textures[0].texture"), std::string::npos)
      << decoded.status().message();
}

TEST(Codec, TooManySharedTexturesIsResourceExhausted) {
  fb::FlatBufferBuilder b;
  std::vector<fb::Offset<w::SharedTexture>> textures;
  for (std::size_t i = 0; i <= kMaxSharedTextures; ++i)
    textures.push_back(w::CreateSharedTexture(b, i + 1, 0));
  auto vector = b.CreateVector(textures);
  auto body = w::CreateSceneUpdate(b, 1, 1, 1.0, 0, vector).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::SceneUpdate, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted) << decoded.status().toString();
}

TEST(Codec, TooManyOperationsIsResourceExhausted) {
  fb::FlatBufferBuilder b;
  std::vector<fb::Offset<w::SceneOp>> ops;
  for (std::size_t i = 0; i <= kMaxSceneOperations; ++i) {
    ops.push_back(w::CreateSceneOp(b, w::SceneOpType::Remove, i, 0));
  }
  auto vector = b.CreateVector(ops);
  auto body = w::CreateSceneUpdate(b, 1, 1, 1.0, vector).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::SceneUpdate, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted) << decoded.status().toString();
}

TEST(Codec, LongStringIsResourceExhausted) {
  Shutdown shutdown{std::string(kMaxTextBytes + 1, 'x')};
  EXPECT_EQ(encode(shutdown).status().code(), ErrorCode::kResourceExhausted);
  fb::FlatBufferBuilder b;
  auto reason = b.CreateString(std::string(kMaxTextBytes + 1, 'x'));
  auto body = w::CreateShutdown(b, reason).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::Shutdown, body));
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted);
}

TEST(Codec, RawTextureSizeMustMatchItsDimensions) {
  SceneUpdate update;
  SceneOperation op;
  op.objectId = 1;
  op.representation = seeds::sampleRepresentation(RepresentationKind::kSimpleImpostor, 0, 4);
  op.representation.texture.codec = TextureCodec::kRawRgba8;
  op.representation.texture.data.assign(4 * 4 * 4 - 1, 0);
  update.operations.push_back(op);
  auto encoded = encode(update);
  ASSERT_FALSE(encoded.ok());
  EXPECT_NE(encoded.status().message().find("expected 64"), std::string::npos)
      << encoded.status().message();
}

TEST(Codec, DuplicateObjectInOneBatchIsRejected) {
  SceneUpdate update;
  SceneOperation remove;
  remove.type = SceneOperation::Type::kRemove;
  remove.objectId = 9;
  update.operations = {remove, remove};
  auto encoded = encode(update);
  ASSERT_FALSE(encoded.ok());
  EXPECT_NE(encoded.status().message().find("object 9 appears twice"), std::string::npos);
}

TEST(Codec, MeshRepresentationNeedsMeshBytes) {
  SceneUpdate update;
  SceneOperation op;
  op.objectId = 1;
  op.representation = seeds::sampleRepresentation(RepresentationKind::kMesh, 10, 0);
  op.representation.mesh.clear();
  update.operations.push_back(op);
  EXPECT_EQ(encode(update).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, ConicRangeMayBeUnboundedButNotNan) {
  SceneUpdate update;
  SceneOperation op;
  op.objectId = 1;
  op.representation = seeds::sampleRepresentation(RepresentationKind::kMesh, 10, 0);
  op.representation.validity.distanceMax = std::numeric_limits<float>::infinity();
  update.operations.push_back(op);
  EXPECT_TRUE(encode(update).ok());
  update.operations[0].representation.validity.distanceMax =
      std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(encode(update).status().code(), ErrorCode::kInvalidArgument);
  update.operations[0].representation.validity.distanceMax = 1.0f;  // below distance_min 2
  EXPECT_EQ(encode(update).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, SimplifyRequestNeedsExactlyOneSource) {
  SimplifyRequest request;
  request.requestId = 1;
  request.targetTriangles = 10;
  EXPECT_EQ(encode(request).status().code(), ErrorCode::kInvalidArgument);
  request.sourcePath = "a.obj";
  EXPECT_TRUE(encode(request).ok());
  request.sourceMesh = {1, 2, 3};
  EXPECT_EQ(encode(request).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, RequestIdZeroIsReserved) {
  SimplifyRequest request;
  request.sourcePath = "a.obj";
  request.targetTriangles = 10;
  EXPECT_EQ(encode(request).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, ErrorResultCarriesNoPayload) {
  SimplifyResult result;
  result.requestId = 1;
  result.status = Status(ErrorCode::kIoError, "disk");
  result.mesh = {1};
  EXPECT_EQ(encode(result).status().code(), ErrorCode::kInvalidArgument);
}

TEST(Codec, ErrorTableWithOkCodeIsRejected) {
  fb::FlatBufferBuilder b;
  auto error = w::CreateError(b, w::ErrorCode::Ok, b.CreateString("fine"));
  auto body = w::CreateSimplifyResult(b, 1, 1, error).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::SimplifyResult, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("error.code"), std::string::npos);
}

TEST(Codec, OutOfRangeEnumIsRejected) {
  fb::FlatBufferBuilder b;
  auto name = b.CreateString("x");
  auto body = w::CreateHello(b, 1, 1, static_cast<w::Role>(77), name).Union();
  auto decoded = decode(finish(b, kProtocolVersion, w::Body::Hello, body));
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("Hello.role"), std::string::npos);
}

TEST(Codec, PeerNamesThatCouldForgeALogLineAreRejected) {
  for (const std::string& bad : {std::string("w\nevent=ready"), std::string("a\"b"),
                                std::string("a\\b"), std::string("\x7f"), std::string("caf\xc3\xa9")}) {
    Hello hello;
    hello.role = Role::kSimplifier;
    hello.name = bad;
    const Result<Bytes> bytes = encode(Message(hello));
    ASSERT_FALSE(bytes.ok()) << bad;
    EXPECT_NE(bytes.status().message().find("Hello.name"), std::string::npos)
        << bytes.status().message();
  }
  Hello hello;
  hello.role = Role::kSimplifier;
  hello.name = "simplifier@host-1#42 (farm)";
  EXPECT_TRUE(encode(Message(hello)).ok());
}

TEST(Codec, NegotiatesTheHighestCommonVersion) {
  Hello hello;
  hello.minVersion = 1;
  hello.maxVersion = 9;
  auto version = negotiateVersion(hello);
  ASSERT_TRUE(version.ok());
  EXPECT_EQ(*version, kProtocolVersion);
  hello.minVersion = kProtocolVersion + 1;
  EXPECT_EQ(negotiateVersion(hello).status().code(), ErrorCode::kVersionMismatch);
}

}  // namespace
}  // namespace thinlod::protocol

namespace thinlod::protocol {
namespace {

TEST(SceneIdentity, EqualOrUnclaimedFingerprintsPass) {
  EXPECT_TRUE(checkSameScene("backbone", 7, "a.wrl", "frontend", 7, "b.wrl").ok());
  EXPECT_TRUE(checkSameScene("backbone", 7, "a.wrl", "frontend", 0, "").ok());
  EXPECT_TRUE(checkSameScene("backbone", 0, "a.wrl", "frontend", 9, "b.wrl").ok());
}

TEST(SceneIdentity, DifferentFingerprintsAreRefusedNamingBothSides) {
  const Status s =
      checkSameScene("backbone", 0xabcull, "/srv/room.wrl", "frontend", 0xdefull, "/tmp/hall.wrl");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), ErrorCode::kInvalidArgument);
  for (const char* part : {"scene mismatch", "backbone", "/srv/room.wrl", "0000000000000abc",
                           "frontend", "/tmp/hall.wrl", "0000000000000def"})
    EXPECT_NE(s.message().find(part), std::string::npos) << part << " in " << s.message();
}

TEST(SceneIdentity, FingerprintsAndRejectedPlansSurviveTheWire) {
  Hello hello;
  hello.role = Role::kFrontend;
  hello.name = "f";
  hello.sceneFingerprint = 0xfeedfacecafebeefull;
  hello.sceneFile = "deploy/data/paper-room.wrl";
  FrameStats stats;
  stats.rejectedPlans = {3, 4, 9};
  for (const Message& m : {Message(hello), Message(stats)}) {
    Result<Bytes> bytes = encode(m);
    ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
    Result<Message> back = decode(*bytes);
    ASSERT_TRUE(back.ok()) << back.status().toString();
    EXPECT_TRUE(*back == m);
  }
  stats.rejectedPlans.assign(kMaxRejectedPlans + 1, 1);
  EXPECT_FALSE(encode(Message(stats)).ok());
}

}  // namespace
}  // namespace thinlod::protocol

namespace thinlod::protocol {
namespace {

namespace fb = flatbuffers;
namespace w = thinlod::wire;

FrameCostConstants someFrameCost() {
  FrameCostConstants c;
  c.initSeconds = 4.0e-4;
  c.finalSeconds = 6.0e-4;
  c.setupSeconds = 3.0e-5;
  c.triangleSeconds = 1.5e-7;
  c.pixelSeconds = 6.8e-8;
  c.additive = true;
  return c;
}

Hello frontendHello() {
  Hello hello;
  hello.role = Role::kFrontend;
  hello.name = "frontend@test";
  return hello;
}

// A Hello whose FrameCost table holds what the sender wrote, bypassing the
// encoder's checks (a hostile or broken peer).
Bytes wireHelloWithFrameCost(const FrameCostConstants& c) {
  fb::FlatBufferBuilder b;
  auto name = b.CreateString("frontend@hostile");
  auto cost = w::CreateFrameCost(b, c.initSeconds, c.finalSeconds, c.setupSeconds,
                                 c.triangleSeconds, c.pixelSeconds, c.additive);
  auto body = w::CreateHello(b, 1, 1, w::Role::Frontend, name, 7, 0, 0, 0, 0, cost).Union();
  b.Finish(w::CreateEnvelope(b, kProtocolVersion, w::Body::Hello, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

// A frontend's Hello with only the fields of the first protocol revision.
Bytes olderFrontendHello() {
  fb::FlatBufferBuilder b;
  auto name = b.CreateString("frontend@old");
  auto body = w::CreateHello(b, 1, 1, w::Role::Frontend, name).Union();
  b.Finish(w::CreateEnvelope(b, kProtocolVersion, w::Body::Hello, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

TEST(HelloFrameCost, ConstantsSurviveTheWireBitForBit) {
  Hello hello = frontendHello();
  hello.frameCost = someFrameCost();
  Result<Bytes> bytes = encode(Message(hello));
  ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
  Result<Message> back = decode(*bytes);
  ASSERT_TRUE(back.ok()) << back.status().toString();
  const Hello& got = std::get<Hello>(*back);
  ASSERT_TRUE(got.frameCost.has_value());
  EXPECT_EQ(got.frameCost->initSeconds, 4.0e-4);
  EXPECT_EQ(got.frameCost->finalSeconds, 6.0e-4);
  EXPECT_EQ(got.frameCost->setupSeconds, 3.0e-5);
  EXPECT_EQ(got.frameCost->triangleSeconds, 1.5e-7);
  EXPECT_EQ(got.frameCost->pixelSeconds, 6.8e-8);
  EXPECT_TRUE(got.frameCost->additive);
  EXPECT_TRUE(got == hello);
}

TEST(HelloFrameCost, AbsentConstantsStayAbsentAndOlderHellosDecode) {
  Result<Bytes> bytes = encode(Message(frontendHello()));
  ASSERT_TRUE(bytes.ok());
  Result<Message> back = decode(*bytes);
  ASSERT_TRUE(back.ok());
  EXPECT_FALSE(std::get<Hello>(*back).frameCost.has_value());
  // A Hello built without the new field at all (an older frontend's).
  Result<Message> old = decode(olderFrontendHello());
  ASSERT_TRUE(old.ok()) << old.status().toString();
  EXPECT_FALSE(std::get<Hello>(*old).frameCost.has_value());
}

TEST(HelloFrameCost, NonFiniteNegativeAndImplausibleConstantsAreRefusedNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    double FrameCostConstants::*field;
    double value;
    const char* expected;
  };
  const Case cases[] = {
      {"NaN t_tri", &FrameCostConstants::triangleSeconds, nan, "triangleSeconds"},
      {"Inf t_pix", &FrameCostConstants::pixelSeconds, inf, "pixelSeconds"},
      {"-Inf t_init", &FrameCostConstants::initSeconds, -inf, "initSeconds"},
      {"negative t_setup", &FrameCostConstants::setupSeconds, -1e-6, "setupSeconds"},
      {"negative t_final", &FrameCostConstants::finalSeconds, -0.5, "finalSeconds"},
      {"1 s per triangle", &FrameCostConstants::triangleSeconds, 1.0, "exceeds the limit"},
      {"1 s per pixel", &FrameCostConstants::pixelSeconds, 1.0, "exceeds the limit"},
      {"1 s setup", &FrameCostConstants::setupSeconds, 1.0, "exceeds the limit"},
      {"a minute to clear", &FrameCostConstants::initSeconds, 60.0, "exceeds the limit"},
      {"free triangles", &FrameCostConstants::triangleSeconds, 0.0, "must be > 0"},
      {"negative zero t_tri", &FrameCostConstants::triangleSeconds, -0.0, "must be > 0"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    FrameCostConstants bad = someFrameCost();
    bad.*c.field = c.value;
    Result<Message> decoded = decode(wireHelloWithFrameCost(bad));
    ASSERT_FALSE(decoded.ok());
    EXPECT_EQ(decoded.status().code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(decoded.status().message().find("Hello.frame_cost"), std::string::npos)
        << decoded.status().toString();
    EXPECT_NE(decoded.status().message().find(c.expected), std::string::npos)
        << decoded.status().toString();
    // We never send what a peer would refuse either.
    Hello hello = frontendHello();
    hello.frameCost = bad;
    EXPECT_FALSE(encode(Message(hello)).ok());
  }
  // The limits themselves are accepted.
  FrameCostConstants edge;
  edge.initSeconds = kMaxFrameFixedSeconds;
  edge.finalSeconds = kMaxFrameFixedSeconds;
  edge.setupSeconds = kMaxObjectSetupSeconds;
  edge.triangleSeconds = kMaxTriangleSeconds;
  edge.pixelSeconds = kMaxPixelSeconds;
  EXPECT_TRUE(decode(wireHelloWithFrameCost(edge)).ok());
}

}  // namespace
}  // namespace thinlod::protocol

// ---- Hello.held: a frontend's holdings for a new backbone session ----
namespace thinlod::protocol {
namespace {

namespace fb = flatbuffers;
namespace w = thinlod::wire;

HeldRepresentation held(std::uint64_t object, RepresentationKind kind, std::uint32_t triangles,
                        std::uint32_t points = 0) {
  HeldRepresentation h;
  h.objectId = object;
  h.representationId = 1000 + object;
  h.kind = kind;
  h.triangleCount = triangles;
  h.pointCount = points;
  return h;
}

Hello helloHolding(std::vector<HeldRepresentation> items) {
  Hello hello;
  hello.role = Role::kFrontend;
  hello.name = "frontend@test";
  hello.held = std::move(items);
  return hello;
}

// A Hello whose held list is what the sender wrote (a hostile or broken peer).
Bytes wireHelloHolding(const std::vector<HeldRepresentation>& items) {
  fb::FlatBufferBuilder b;
  auto name = b.CreateString("frontend@hostile");
  std::vector<fb::Offset<w::HeldRepresentation>> offsets;
  for (const HeldRepresentation& h : items)
    offsets.push_back(w::CreateHeldRepresentation(b, h.objectId, h.representationId,
                                                  static_cast<w::RepresentationKind>(h.kind),
                                                  h.triangleCount, h.pointCount));
  auto vec = b.CreateVector(offsets);
  auto body =
      w::CreateHello(b, 1, 1, w::Role::Frontend, name, 7, 0, 0, 0, 0, 0, vec).Union();
  b.Finish(w::CreateEnvelope(b, kProtocolVersion, w::Body::Hello, body), "TLOD");
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

TEST(HelloHeld, HoldingsSurviveTheWireAndOlderHellosHaveNone) {
  const Hello hello =
      helloHolding({held(1, RepresentationKind::kMesh, 120),
                    held(3, RepresentationKind::kMeshedImpostor, 32),
                    held(9, RepresentationKind::kHybrid, 40, 300),
                    held(12, RepresentationKind::kSimpleImpostor, 2)});
  Result<Bytes> bytes = encode(Message(hello));
  ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
  Result<Message> back = decode(*bytes);
  ASSERT_TRUE(back.ok()) << back.status().toString();
  const Hello& got = std::get<Hello>(*back);
  ASSERT_EQ(got.held.size(), 4u);
  EXPECT_EQ(got.held[2].objectId, 9u);
  EXPECT_EQ(got.held[2].representationId, 1009u);
  EXPECT_EQ(got.held[2].kind, RepresentationKind::kHybrid);
  EXPECT_EQ(got.held[2].triangleCount, 40u);
  EXPECT_EQ(got.held[2].pointCount, 300u);
  EXPECT_TRUE(got == hello);
  Hello other = hello;
  other.held[0].triangleCount = 121;
  EXPECT_FALSE(other == hello);

  // The frontend of an earlier protocol revision sends no list.
  Result<Message> old = decode(olderFrontendHello());
  ASSERT_TRUE(old.ok()) << old.status().toString();
  EXPECT_TRUE(std::get<Hello>(*old).held.empty());
}

TEST(HelloHeld, MalformedHoldingsAreRefusedNamingTheEntry) {
  struct Case {
    const char* what;
    std::vector<HeldRepresentation> items;
    const char* expected;
  };
  const Case cases[] = {
      {"object 0", {held(0, RepresentationKind::kMesh, 10)}, "Hello.held[0].object_id"},
      {"descending ids",
       {held(5, RepresentationKind::kMesh, 10), held(4, RepresentationKind::kMesh, 10)},
       "Hello.held[1].object_id"},
      {"an object twice",
       {held(5, RepresentationKind::kMesh, 10), held(5, RepresentationKind::kMesh, 12)},
       "unique and ascending"},
      {"unknown kind", {held(2, static_cast<RepresentationKind>(9), 10)}, "Hello.held[0].kind"},
      {"too many triangles",
       {held(2, RepresentationKind::kMesh, kMaxTriangleCount + 1)},
       "Hello.held[0].triangle_count"},
      {"points on a mesh", {held(2, RepresentationKind::kMesh, 10, 5)}, "Hello.held[0].point_count"},
      {"too many points",
       {held(2, RepresentationKind::kHybrid, 10, kMaxPointCount + 1)},
       "Hello.held[0].point_count"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    Result<Message> decoded = decode(wireHelloHolding(c.items));
    ASSERT_FALSE(decoded.ok());
    EXPECT_NE(decoded.status().message().find(c.expected), std::string::npos)
        << decoded.status().toString();
    // We never send what a peer would refuse either.
    EXPECT_FALSE(encode(Message(helloHolding(c.items))).ok());
  }
  // Holdings belong to frontends.
  Hello worker = helloHolding({held(1, RepresentationKind::kMesh, 10)});
  worker.role = Role::kSimplifier;
  Result<Bytes> workerBytes = encode(Message(worker));
  ASSERT_FALSE(workerBytes.ok());
  EXPECT_NE(workerBytes.status().message().find("frontends only"), std::string::npos);
}

TEST(HelloHeld, TheListIsBoundedByKMaxHeldRepresentations) {
  std::vector<HeldRepresentation> items;
  for (std::uint64_t id = 1; id <= kMaxHeldRepresentations; ++id)
    items.push_back(held(id, RepresentationKind::kMesh, 2));
  Result<Bytes> full = encode(Message(helloHolding(items)));
  ASSERT_TRUE(full.ok()) << full.status().toString();
  ASSERT_TRUE(decode(*full).ok());
  items.push_back(held(kMaxHeldRepresentations + 1, RepresentationKind::kMesh, 2));
  EXPECT_FALSE(encode(Message(helloHolding(items))).ok());
  Result<Message> over = decode(wireHelloHolding(items));
  ASSERT_FALSE(over.ok());
  EXPECT_NE(over.status().message().find("Hello.held"), std::string::npos)
      << over.status().toString();
}

}  // namespace
}  // namespace thinlod::protocol
