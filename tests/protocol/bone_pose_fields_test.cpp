// SceneUpdate.bonePoses (docs/protocol.md, "Bone poses"): round trip of the
// affine matrices through their three-row wire form, the validator's rules,
// hostile encodings built with the raw FlatBuffers builder, every truncated
// prefix, and the bytes a pose adds.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "thinlod/protocol/codec.h"
#include "thinlod_wire_generated.h"

namespace thinlod::protocol {
namespace {

namespace w = thinlod::wire;
namespace fb = flatbuffers;

glm::mat4 affine(float seed) {
  glm::mat4 m(1.0f);
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 3; ++r) m[c][r] = seed + 0.25f * float(c * 3 + r) - 1.5f;
  }
  return m;
}

SceneUpdate updateWithPoses(std::size_t objects, std::size_t bones) {
  SceneUpdate u;
  u.plan = 7;
  u.frame = 9;
  for (std::size_t o = 0; o < objects; ++o) {
    BonePose pose;
    pose.objectId = 1 + o;
    for (std::size_t b = 0; b < bones; ++b) pose.matrices.push_back(affine(float(o * 100 + b)));
    u.bonePoses.push_back(std::move(pose));
  }
  return u;
}

TEST(BonePoseWireFields, RoundTripIsExact) {
  const SceneUpdate update = updateWithPoses(3, 37);
  Result<Bytes> bytes = encode(Message(update));
  ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
  Result<Message> decoded = decode(bytes->data(), bytes->size());
  ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
  const auto* back = std::get_if<SceneUpdate>(&*decoded);
  ASSERT_NE(back, nullptr);
  EXPECT_TRUE(*back == update);
  ASSERT_EQ(back->bonePoses.size(), 3u);
  EXPECT_EQ(back->bonePoses[2].matrices[36], update.bonePoses[2].matrices[36]);
}

TEST(BonePoseWireFields, APoseCostsTwelveFloatsPerBone) {
  // The wire form of a pose: 48 bytes a matrix plus a small table per object.
  const Bytes none = *encode(Message(updateWithPoses(0, 0)));
  const Bytes one = *encode(Message(updateWithPoses(1, 37)));
  const Bytes two = *encode(Message(updateWithPoses(2, 37)));
  EXPECT_GE(one.size() - none.size(), 37u * 48u);
  EXPECT_LE(one.size() - none.size(), 37u * 48u + 64u);
  EXPECT_GE(two.size() - one.size(), 37u * 48u);
  EXPECT_LE(two.size() - one.size(), 37u * 48u + 32u);
}

TEST(BonePoseWireFields, ValidatorRefusesNonFiniteNonAffineDuplicateAndTooMany) {
  EXPECT_TRUE(validate(Message(updateWithPoses(2, 4))).ok());
  EXPECT_TRUE(validate(Message(updateWithPoses(1, 0))).ok()) << "a pose of no bones is empty";
  for (const float bad :
       {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    SceneUpdate u = updateWithPoses(1, 3);
    u.bonePoses[0].matrices[1][3][2] = bad;
    const Status status = validate(Message(u));
    EXPECT_EQ(status.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(status.message().find("bone_poses[0].matrices[1]"), std::string::npos)
        << status.toString();
  }
  SceneUpdate projective = updateWithPoses(1, 2);
  projective.bonePoses[0].matrices[0][2][3] = 0.5f;
  EXPECT_NE(validate(Message(projective)).message().find("not affine"), std::string::npos);
  SceneUpdate twice = updateWithPoses(2, 2);
  twice.bonePoses[1].objectId = twice.bonePoses[0].objectId;
  EXPECT_NE(validate(Message(twice)).message().find("two poses"), std::string::npos);
  const SceneUpdate tooMany = updateWithPoses(1, kMaxBonesPerPose + 1);
  EXPECT_EQ(validate(Message(tooMany)).code(), ErrorCode::kResourceExhausted);
  // encode() refuses what a peer would.
  EXPECT_FALSE(encode(Message(projective)).ok());
}

// A SceneUpdate whose pose holds `matrices` raw 12-float rows, as a peer could send.
Bytes rawUpdate(const std::vector<std::array<float, 12>>& matrices, std::size_t poses = 1) {
  fb::FlatBufferBuilder b;
  std::vector<w::BoneMatrix> rows;
  for (const auto& m : matrices) rows.emplace_back(fb::span<const float, 12>(m.data(), 12));
  std::vector<fb::Offset<w::BonePose>> list;
  for (std::size_t i = 0; i < poses; ++i)
    list.push_back(w::CreateBonePose(b, 1 + i, b.CreateVectorOfStructs(rows)));
  auto update = w::CreateSceneUpdate(b, 1, 1, 0.0, 0, 0, b.CreateVector(list));
  b.Finish(w::CreateEnvelope(b, kProtocolVersion, w::Body::SceneUpdate, update.Union()),
           w::EnvelopeIdentifier());
  return Bytes(b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize());
}

TEST(BonePoseWireFields, DecoderRefusesHostileEncodings) {
  std::array<float, 12> good{};
  good[0] = good[4] = good[8] = 1.0f;
  const Bytes fine = rawUpdate({good, good});
  EXPECT_TRUE(decode(fine.data(), fine.size()).ok());

  std::array<float, 12> nan = good;
  nan[10] = std::numeric_limits<float>::quiet_NaN();
  const Bytes withNan = rawUpdate({good, nan});
  Result<Message> decoded = decode(withNan.data(), withNan.size());
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kInvalidArgument);

  const Bytes tooMany = rawUpdate(std::vector<std::array<float, 12>>(kMaxBonesPerPose + 1, good));
  decoded = decode(tooMany.data(), tooMany.size());
  ASSERT_FALSE(decoded.ok());
  EXPECT_EQ(decoded.status().code(), ErrorCode::kResourceExhausted) << decoded.status().toString();

  // Two poses of object 1 (rawUpdate numbers them 1, 2: make a duplicate).
  fb::FlatBufferBuilder b;
  std::vector<fb::Offset<w::BonePose>> list{w::CreateBonePose(b, 5), w::CreateBonePose(b, 5)};
  auto update = w::CreateSceneUpdate(b, 1, 1, 0.0, 0, 0, b.CreateVector(list));
  b.Finish(w::CreateEnvelope(b, kProtocolVersion, w::Body::SceneUpdate, update.Union()),
           w::EnvelopeIdentifier());
  decoded = decode(b.GetBufferPointer(), b.GetSize());
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("two poses"), std::string::npos);
}

TEST(BonePoseWireFields, TruncationsAndCorruptionsNeverCrash) {
  const Bytes full = *encode(Message(updateWithPoses(2, 5)));
  std::size_t rejected = 0;
  for (std::size_t length = 0; length < full.size(); ++length) {
    const Bytes prefix(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(length));
    const Result<Message> decoded = decode(prefix.data(), prefix.size());
    if (!decoded.ok()) {
      ++rejected;
      EXPECT_FALSE(decoded.status().message().empty());
    }
  }
  EXPECT_GE(rejected + 8, full.size());  // only trailing padding may be cut
  std::mt19937 rng(20261204);
  std::size_t valid = 0;
  for (int i = 0; i < 500; ++i) {
    Bytes corrupt = full;
    for (int k = 0; k < 3; ++k) corrupt[rng() % corrupt.size()] = static_cast<std::uint8_t>(rng());
    const Result<Message> decoded = decode(corrupt.data(), corrupt.size());
    if (!decoded.ok()) continue;
    ++valid;
    // What decodes is valid: it re-encodes to itself.
    const Result<Bytes> again = encode(*decoded);
    ASSERT_TRUE(again.ok()) << again.status().toString();
    EXPECT_TRUE(*decode(again->data(), again->size()) == *decoded);
  }
  EXPECT_LT(valid, 500u);
}

}  // namespace
}  // namespace thinlod::protocol

namespace thinlod::protocol {
namespace {

// SimplifyResult.motion_included (a skinned object's accuracies measured
// under its clip): round trip, absent = false, Mesh results only, never on
// an error result.
TEST(MotionIncludedWireField, RoundTripAndRules) {
  SimplifyResult result;
  result.requestId = 5;
  result.objectId = 6;
  result.mesh = {1, 2, 3};
  result.triangleCount = 1;
  result.accuracy = 7.0;
  result.curve = {{2.0, 1.0}, {7.0, 10.0}};
  for (const bool included : {false, true}) {
    result.motionIncluded = included;
    ASSERT_TRUE(validate(Message(result)).ok());
    Result<std::vector<std::uint8_t>> bytes = encode(Message(result));
    ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
    Result<Message> decoded = decode(bytes->data(), bytes->size());
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_TRUE(*decoded == Message(result));
    EXPECT_EQ(std::get<SimplifyResult>(*decoded).motionIncluded, included);
  }
  SimplifyResult hybrid = result;
  hybrid.kind = RepresentationKind::kHybrid;
  hybrid.kappa = 3.0;
  hybrid.motionIncluded = true;
  EXPECT_EQ(validate(Message(hybrid)).code(), ErrorCode::kInvalidArgument);
  hybrid.motionIncluded = false;
  EXPECT_TRUE(validate(Message(hybrid)).ok());
  SimplifyResult failed;
  failed.requestId = 5;
  failed.status = Status(ErrorCode::kNotFound, "no");
  failed.motionIncluded = true;
  EXPECT_EQ(validate(Message(failed)).code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::protocol
