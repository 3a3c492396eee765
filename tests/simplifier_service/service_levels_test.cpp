// White-box tests of the service's level bookkeeping (service_internal.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "service_internal.h"
#include "thinlod/common/codec/encoding.h"

namespace thinlod::simplifier::service_detail {
namespace {

CurveLevel level(std::size_t triangles, double error) {
  CurveLevel l;
  l.requestedTriangles = triangles;
  l.triangles = triangles;
  l.relativeMaxError = error;
  return l;
}

TEST(ServiceLevels, CreditIsTheWorstErrorAtOrAboveTheRung) {
  // Non-monotone measurements: 400 triangles measured worse than 200.
  const std::vector<CurveLevel> levels = {level(100, 0.05), level(200, 0.01), level(400, 0.02),
                                          level(800, 0.005), level(1600, 0.0)};
  const std::vector<LevelCredit> ladder = creditLevels(levels, 1e-4);
  ASSERT_EQ(ladder.size(), 5u);
  EXPECT_DOUBLE_EQ(ladder[0].relativeError, 0.05);
  EXPECT_DOUBLE_EQ(ladder[1].relativeError, 0.02);  // lifted by the finer 400 rung
  EXPECT_DOUBLE_EQ(ladder[2].relativeError, 0.02);
  EXPECT_DOUBLE_EQ(ladder[3].relativeError, 0.005);
  EXPECT_DOUBLE_EQ(ladder[4].relativeError, 1e-4);  // the floor, not zero
}

TEST(ServiceLevels, CreditsNeverImproveWhenCoarsening) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> error(0.0, 0.1);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<CurveLevel> levels;
    for (std::size_t i = 0; i < 12; ++i) levels.push_back(level(10 << i, error(random)));
    const std::vector<LevelCredit> ladder = creditLevels(levels, 1e-4);
    for (std::size_t i = 0; i < ladder.size(); ++i) {
      EXPECT_GE(ladder[i].relativeError, std::max(levels[i].relativeMaxError, 1e-4));
      if (i > 0) {
        EXPECT_GE(ladder[i - 1].relativeError, ladder[i].relativeError);
      }
    }
  }
}

TEST(ServiceLevels, CreditForPicksTheFinestRungNotAboveTheCount) {
  const std::vector<LevelCredit> ladder = {{100, 100, 0.1}, {200, 199, 0.05}, {400, 400, 0.01}};
  EXPECT_EQ(creditFor(ladder, 100), 0u);
  EXPECT_EQ(creditFor(ladder, 198), 0u);
  EXPECT_EQ(creditFor(ladder, 199), 1u);
  EXPECT_EQ(creditFor(ladder, 100000), 2u);
  EXPECT_EQ(creditFor(ladder, 3), 0u);  // below every rung: the worst credit
}

TEST(ServiceLevels, DeliveredAccuracyIncludesQuantizationWithinTheBudget) {
  for (double d : {0.3, 0.05, 1e-2, 1e-3, 1e-4}) {
    const DeliveredLevel delivered = deliveredLevel(d);
    EXPECT_EQ(delivered.positionBits, codec::positionBitsForAccuracy(1.0 / d, kQuantizationBudget));
    EXPECT_LT(delivered.accuracy, 1.0 / d);
    EXPECT_GE(delivered.accuracy, 1.0 / (d * (1.0 + kQuantizationBudget)) * 0.999999) << d;
  }
}

TEST(ServiceLevels, QuantizationBoundMatchesTheEncoder) {
  // Our relative bound (step <= L, the reference sphere's diameter) is never
  // below the encoder's own.
  IndexedMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.indices = {0, 1, 2, 0, 2, 3};
  for (int bits : {8, 12, 16, 20}) {
    const double reference = referenceLength(referenceSphere(mesh));
    EXPECT_LE(codec::positionErrorBound(mesh, bits) / reference, quantizationError(bits) * 1.0001)
        << bits;
  }
}

TEST(ServiceLevels, CurveSamplesDropDominatedPointsAndSubsample) {
  std::vector<AccuracySample> points = {{10, 100}, {8, 150},  {20, 200},  {20, 300},
                                        {40, 400}, {80, 800}, {160, 1600}};
  const std::vector<AccuracySample> all = curveSamples(points, 100);
  ASSERT_EQ(all.size(), 5u);  // (8,150) and (20,300) are dominated
  EXPECT_EQ(all[1].resources, 200.0);
  const std::vector<AccuracySample> three = curveSamples(points, 3);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_EQ(three.front().resources, 100.0);
  EXPECT_EQ(three.back().resources, 1600.0);
  EXPECT_EQ(curveSamples(points, 1).size(), 1u);
  EXPECT_TRUE(curveSamples(points, 0).empty());
}

TEST(ServiceLevels, CurveSamplesSkipNonFiniteAccuracy) {
  const std::vector<AccuracySample> points = {{std::nan(""), 10}, {5, 20}, {INFINITY, 30}};
  const std::vector<AccuracySample> kept = curveSamples(points, 10);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].resources, 20.0);
}

}  // namespace
}  // namespace thinlod::simplifier::service_detail
