// SimplifierService cold start, impostors (ServiceOptions::answerBeforeCurve):
// a mesh without a known curve is rendered at full resolution, without
// building its progressive mesh or measuring its curve; once the curve is
// known the coarser level is used again.
#include <gtest/gtest.h>

#include <filesystem>

#include "service_test_util.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

TEST(SimplifierServiceColdImpostor, FullMeshUntilTheCurveIsKnown) {
  ServiceOptions options = roomOptions();
  options.defaultScenePath = roomScene();
  options.curveCacheDir = scratchDir() + "/cold-impostor";
  std::filesystem::remove_all(options.curveCacheDir);
  options.curve.error.samplesPerMesh = 5000;
  options.answerBeforeCurve = true;
  SimplifierService service(options);
  protocol::ImpostorRequest request;
  request.requestId = 9004;
  request.objectIds = {kCow};
  request.eye = glm::vec3(2.0f, 1.1f, 3.5f);
  request.textureWidth = 256;
  request.textureHeight = 256;
  request.kind = protocol::RepresentationKind::kSimpleImpostor;
  request.accuracyBound = 2e-3;
  request.textureCodec = protocol::TextureCodec::kRawRgba8;
  const protocol::ImpostorResult cold = service.renderImpostor(request);
  ASSERT_TRUE(cold.status.ok()) << cold.status.toString();
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 0u);
  EXPECT_EQ(service.stats().curvesMeasured, 0u);
  EXPECT_EQ(service.stats().impostorLevelsExtracted, 0u);

  // The curve request measures the curve; the next impostor uses a level.
  protocol::SimplifyResult curve = service.simplify(triangles(kCow, 2000, 16));
  ASSERT_TRUE(curve.status.ok()) << curve.status.toString();
  const protocol::ImpostorResult warm = service.renderImpostor(request);
  ASSERT_TRUE(warm.status.ok()) << warm.status.toString();
  EXPECT_EQ(service.stats().impostorLevelsExtracted, 1u);
  // The full mesh has no level error: at least the level's accuracy.
  EXPECT_GE(cold.representation.accuracy, warm.representation.accuracy);
}

}  // namespace
}  // namespace thinlod::simplifier
