// SimplifierService cold start (ServiceOptions::answerBeforeCurve, the
// daemon's default): a mesh without a known curve is answered from its one
// measured level, a curve request still measures the whole curve, a stored
// curve is used without measuring, and long work reports progress.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "service_test_util.h"
#include "thinlod/simplifier/service.h"

namespace thinlod::simplifier {
namespace {

using namespace testing_util;

// A fresh cache directory per call: nothing measured yet.
ServiceOptions coldOptions(const std::string& name) {
  ServiceOptions options = roomOptions();
  options.curveCacheDir = scratchDir() + "/cold-" + name;
  std::filesystem::remove_all(options.curveCacheDir);
  options.curve.error.samplesPerMesh = 5000;  // only the counts matter here
  options.answerBeforeCurve = true;
  return options;
}

TEST(SimplifierServiceColdStart, FirstAnswerMeasuresOnlyItsOwnLevel) {
  std::vector<std::string> progress;
  ServiceOptions options = coldOptions("first");
  options.progress = [&](const std::string& line) { progress.push_back(line); };
  SimplifierService service(options);
  const protocol::SimplifyResult first = service.simplify(triangles(kCow, 500));
  ASSERT_TRUE(first.status.ok()) << first.status.toString();
  EXPECT_LE(first.triangleCount, 500u);
  EXPECT_GE(first.triangleCount, 499u);
  EXPECT_GT(first.accuracy, 1.0);
  EXPECT_TRUE(first.curve.empty());
  EXPECT_EQ(service.stats().levelsMeasuredAlone, 1u);
  EXPECT_EQ(service.stats().curvesMeasured, 0u);
  EXPECT_TRUE(progress.empty());  // no curve measured

  // The backbone's curve request: the whole ladder, one progress line per level.
  const protocol::SimplifyResult curve = service.simplify(triangles(kCow, 2000, 32));
  ASSERT_TRUE(curve.status.ok()) << curve.status.toString();
  EXPECT_GE(curve.curve.size(), 2u);
  EXPECT_EQ(service.stats().curvesMeasured, 1u);
  std::size_t levels = 0;
  for (const std::string& line : progress)
    levels += line.find("event=curve_progress mesh_triangles=5804 level=") == 0 ? 1 : 0;
  EXPECT_EQ(levels, 12u);  // options.curve.levels

  // From now on the ladder credits every answer (no single-level measurement).
  const protocol::SimplifyResult after = service.simplify(triangles(kCow, 500));
  ASSERT_TRUE(after.status.ok());
  EXPECT_EQ(service.stats().levelsMeasuredAlone, 1u);
  EXPECT_EQ(service.stats().progressiveMeshBuilds, 1u);
  EXPECT_GT(after.accuracy, 1.0);
}

TEST(SimplifierServiceColdStart, AStoredCurveIsUsedWithoutMeasuring) {
  ServiceOptions options = coldOptions("stored");
  {
    SimplifierService measuring(options);
    ASSERT_TRUE(measuring.simplify(triangles(kCow, 2000, 16)).status.ok());
    EXPECT_EQ(measuring.stats().curvesMeasured, 1u);
  }
  SimplifierService warm(options);
  const protocol::SimplifyResult result = warm.simplify(triangles(kCow, 300));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_EQ(warm.stats().curvesFromDisk, 1u);
  EXPECT_EQ(warm.stats().curvesMeasured, 0u);
  EXPECT_EQ(warm.stats().levelsMeasuredAlone, 0u);
}

TEST(SimplifierServiceColdStart, OffByDefaultTheCurveIsMeasuredFirst) {
  ServiceOptions options = coldOptions("off");
  options.answerBeforeCurve = false;
  SimplifierService service(options);
  ASSERT_TRUE(service.simplify(triangles(kCow, 500)).status.ok());
  EXPECT_EQ(service.stats().levelsMeasuredAlone, 0u);
  EXPECT_EQ(service.stats().curvesMeasured, 1u);
}

TEST(SimplifierServiceColdStart, AccuracyTargetsStillMeasureTheCurve) {
  SimplifierService service(coldOptions("accuracy"));
  const protocol::SimplifyResult result = service.simplify(accuracy(kCow, 20.0));
  ASSERT_TRUE(result.status.ok()) << result.status.toString();
  EXPECT_GE(result.accuracy, 20.0);
  EXPECT_EQ(service.stats().curvesMeasured, 1u);
  EXPECT_EQ(service.stats().levelsMeasuredAlone, 0u);
}

}  // namespace
}  // namespace thinlod::simplifier
