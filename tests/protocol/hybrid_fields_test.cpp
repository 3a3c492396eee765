// The hybrid (triangles + disc points) fields of the wire: round trip and
// the validator's rules (points only in Hybrid, kappa range, kinds a
// SimplifyRequest may ask for).
#include <gtest/gtest.h>

#include <limits>

#include "thinlod/protocol/codec.h"

namespace thinlod::protocol {
namespace {

SimplifyRequest hybridRequest(double kappa) {
  SimplifyRequest r;
  r.requestId = 3;
  r.objectId = 4;
  r.sourcePath = "scene.wrl";
  r.targetTriangles = 100;
  r.representation = RepresentationKind::kHybrid;
  r.kappa = kappa;
  return r;
}

SimplifyResult hybridResult() {
  SimplifyResult r;
  r.requestId = 3;
  r.objectId = 4;
  r.mesh = {1, 2, 3, 4};
  r.triangleCount = 10;
  r.pointCount = 30;
  r.kind = RepresentationKind::kHybrid;
  r.kappa = 3.0;
  r.accuracy = 12.0;
  return r;
}

TEST(HybridWireFields, RoundTrip) {
  for (const Message& message : {Message(hybridRequest(7.5)), Message(hybridResult())}) {
    Result<std::vector<std::uint8_t>> bytes = encode(message);
    ASSERT_TRUE(bytes.ok()) << bytes.status().toString();
    Result<Message> decoded = decode(bytes->data(), bytes->size());
    ASSERT_TRUE(decoded.ok()) << decoded.status().toString();
    EXPECT_TRUE(*decoded == message);
  }
}

TEST(HybridWireFields, RequestKappaIsZeroOrInRange) {
  EXPECT_TRUE(validate(Message(hybridRequest(0.0))).ok());
  EXPECT_TRUE(validate(Message(hybridRequest(1.0))).ok());
  EXPECT_TRUE(validate(Message(hybridRequest(kMaxKappa))).ok());
  for (double bad : {0.5, -3.0, kMaxKappa * 2.0, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(validate(Message(hybridRequest(bad))).code(), ErrorCode::kInvalidArgument) << bad;
  }
  SimplifyRequest mesh = hybridRequest(3.0);
  mesh.representation = RepresentationKind::kMesh;
  EXPECT_EQ(validate(Message(mesh)).code(), ErrorCode::kInvalidArgument) << "kappa without Hybrid";
  SimplifyRequest impostor = hybridRequest(0.0);
  impostor.representation = RepresentationKind::kMeshedImpostor;
  EXPECT_EQ(validate(Message(impostor)).code(), ErrorCode::kInvalidArgument);
}

TEST(HybridWireFields, PointsOnlyInHybridResultsAndRepresentations) {
  SimplifyResult mesh = hybridResult();
  mesh.kind = RepresentationKind::kMesh;
  mesh.kappa = 0.0;
  EXPECT_EQ(validate(Message(mesh)).code(), ErrorCode::kInvalidArgument);
  mesh.pointCount = 0;
  EXPECT_TRUE(validate(Message(mesh)).ok());
  SimplifyResult noKappa = hybridResult();
  noKappa.kappa = 0.0;
  EXPECT_EQ(validate(Message(noKappa)).code(), ErrorCode::kInvalidArgument);
  SimplifyResult tooMany = hybridResult();
  tooMany.pointCount = kMaxPointCount + 1;
  EXPECT_NE(validate(Message(tooMany)).code(), ErrorCode::kOk);
  SimplifyResult failed;
  failed.requestId = 3;
  failed.status = Status(ErrorCode::kUnsupported, "no");
  failed.pointCount = 2;
  EXPECT_EQ(validate(Message(failed)).code(), ErrorCode::kInvalidArgument);

  SceneUpdate update;
  update.plan = 1;
  SceneOperation op;
  op.objectId = 9;
  op.representation.kind = RepresentationKind::kHybrid;
  op.representation.mesh = {5, 6, 7};
  op.representation.pointCount = 12;
  update.operations.push_back(op);
  EXPECT_TRUE(validate(Message(update)).ok()) << validate(Message(update)).toString();
  update.operations[0].representation.kind = RepresentationKind::kMesh;
  EXPECT_EQ(validate(Message(update)).code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::protocol
