// SimplifierService: hybrid (triangles + disc points) SimplifyRequests on the
// paper room's cow (no GL).
#include <gtest/gtest.h>

#include "service_test_util.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/protocol/codec.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

protocol::SimplifyRequest hybridAccuracy(std::uint64_t object, double accuracy, double kappa,
                                         std::uint16_t curvePoints) {
  protocol::SimplifyRequest request = triangles(object, 1, curvePoints);
  request.target = protocol::SimplifyRequest::Target::kAccuracy;
  request.targetAccuracy = accuracy;
  request.representation = protocol::RepresentationKind::kHybrid;
  request.kappa = kappa;
  return request;
}

HybridGeometry decodeGeometry(const protocol::Bytes& bytes) {
  Result<HybridGeometry> g = codec::decodeHybrid(bytes.data(), bytes.size());
  EXPECT_TRUE(g.ok()) << g.status().toString();
  return g.ok() ? std::move(g).value() : HybridGeometry();
}

TEST(SimplifierServiceHybrid, CowCutReachesTheAccuracyAndCarriesPoints) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult result = service.simplify(hybridAccuracy(kCow, 20.0, 10.0, 16));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.kind, protocol::RepresentationKind::kHybrid);
  EXPECT_EQ(result.kappa, 10.0);
  EXPECT_GE(result.accuracy, 20.0);
  const HybridGeometry g = decodeGeometry(result.mesh);
  EXPECT_EQ(g.triangles.triangleCount(), result.triangleCount);
  EXPECT_EQ(g.points.size(), result.pointCount);
  EXPECT_GT(result.pointCount, 0u) << "a coarse cow cut at kappa 10 keeps points";
  EXPECT_TRUE(protocol::validate(protocol::Message(result)).ok());
  // Curve: strictly increasing, resources in primitive units, and the
  // delivered cut lies on or above it (its units buy at least the curve's
  // accuracy at those units).
  ASSERT_GE(result.curve.size(), 2u);
  for (std::size_t i = 1; i < result.curve.size(); ++i) {
    EXPECT_GT(result.curve[i].accuracy, result.curve[i - 1].accuracy);
    EXPECT_GT(result.curve[i].resources, result.curve[i - 1].resources);
  }
  const double units = result.triangleCount + result.pointCount / result.kappa;
  EXPECT_LE(result.curve.front().resources, units + 1e-9);
}

TEST(SimplifierServiceHybrid, FinerAccuracyCostsMoreUnitsAndTheGraphIsReused) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult coarse = service.simplify(hybridAccuracy(kCow, 10.0, 3.0, 0));
  const protocol::SimplifyResult fine = service.simplify(hybridAccuracy(kCow, 200.0, 3.0, 0));
  ASSERT_TRUE(coarse.status.ok()) << coarse.status.toString();
  ASSERT_TRUE(fine.status.ok()) << fine.status.toString();
  EXPECT_GE(fine.accuracy, 200.0);
  EXPECT_LT(coarse.triangleCount + coarse.pointCount / 3.0,
            fine.triangleCount + fine.pointCount / 3.0);
  EXPECT_EQ(service.stats().hybridGraphBuilds, 1u);
  // Another kappa is another graph.
  ASSERT_TRUE(service.simplify(hybridAccuracy(kCow, 10.0, 8.0, 0)).status.ok());
  EXPECT_EQ(service.stats().hybridGraphBuilds, 2u);
}

TEST(SimplifierServiceHybrid, UnitTargetIsNotExceeded) {
  SimplifierService service(roomOptions());
  protocol::SimplifyRequest request = triangles(kCow, 400);
  request.representation = protocol::RepresentationKind::kHybrid;
  const protocol::SimplifyResult result = service.simplify(request);
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(result.kappa, service.options().hybridKappa);
  EXPECT_LE(result.triangleCount + result.pointCount / result.kappa, 400.0 + 1e-9);
}

TEST(SimplifierServiceHybrid, PrimitivesAndBadKappaAreRefused) {
  SimplifierService service(roomOptions());
  const protocol::SimplifyResult sphere =
      service.simplify(hybridAccuracy(kSphereLeft, 10.0, 3.0, 0));
  EXPECT_EQ(sphere.status.code(), ErrorCode::kUnsupported);
  const protocol::SimplifyResult badKappa = service.simplify(hybridAccuracy(kCow, 10.0, 0.5, 0));
  EXPECT_EQ(badKappa.status.code(), ErrorCode::kInvalidArgument);
  protocol::SimplifyRequest impostorKind = triangles(kCow, 100);
  impostorKind.representation = protocol::RepresentationKind::kSimpleImpostor;
  EXPECT_EQ(service.simplify(impostorKind).status.code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::simplifier
