// Level choice and texture comparison of impostor_level.h (no GL).
#include "thinlod/simplifier/impostor_level.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace thinlod::simplifier {
namespace {

TEST(ImpostorLevel, PicksTheCoarsestLevelWithinTolerance) {
  const std::vector<double> credits = {0.1, 0.02, 0.005, 0.001, 1e-4};
  // diameter 2: world errors 0.2, 0.04, 0.01, 0.002, 2e-4.
  EXPECT_EQ(chooseImpostorLevel(credits, 2.0, 0.01),
            std::optional<std::size_t>(2));  // equal counts
  EXPECT_EQ(chooseImpostorLevel(credits, 2.0, 0.0099), std::optional<std::size_t>(3));
  EXPECT_EQ(chooseImpostorLevel(credits, 2.0, 1.0), std::optional<std::size_t>(0));
  EXPECT_EQ(chooseImpostorLevel(credits, 2.0, 1e-4), std::nullopt);  // none: full mesh
}

TEST(ImpostorLevel, BadInputsRenderTheFullMesh) {
  const std::vector<double> credits = {0.1, 0.01};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(chooseImpostorLevel({}, 1.0, 1.0), std::nullopt);
  for (double bad : {0.0, -1.0, nan, inf}) {
    EXPECT_EQ(chooseImpostorLevel(credits, bad, 1.0), std::nullopt) << bad;
    EXPECT_EQ(chooseImpostorLevel(credits, 1.0, bad), std::nullopt) << bad;
  }
  // NaN, negative and infinite credits never qualify; the next good one does.
  EXPECT_EQ(chooseImpostorLevel({nan, -1.0, inf, 0.01}, 1.0, 0.5), std::optional<std::size_t>(3));
}

// Property (fixed seed): the chosen level's world error is within the
// tolerance, no coarser level is, and a larger tolerance never picks a finer
// level; extreme magnitudes included.
TEST(ImpostorLevel, RandomLaddersKeepTheBoundAndAreMonotoneInTolerance) {
  std::mt19937 rng(20);
  std::uniform_real_distribution<double> logU(-12.0, 2.0);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<double> credits(1 + rng() % 14);
    for (double& c : credits) c = std::pow(10.0, logU(rng));
    // Ladders from creditedRelativeErrors are non-increasing; test that shape
    // half of the time and arbitrary orders otherwise.
    if (trial % 2 == 0) std::sort(credits.rbegin(), credits.rend());
    const double diameter = std::pow(10.0, logU(rng) * 3.0);
    double previousIndex = -1.0;  // index for the previous (smaller) tolerance
    double tolerance = diameter * std::pow(10.0, -14.0);
    for (int step = 0; step < 40; ++step, tolerance *= 3.0) {
      const auto level = chooseImpostorLevel(credits, diameter, tolerance);
      if (level) {
        ASSERT_LE(credits[*level] * diameter, tolerance);
        for (std::size_t i = 0; i < *level; ++i) ASSERT_GT(credits[i] * diameter, tolerance);
      } else {
        for (double c : credits) ASSERT_GT(c * diameter, tolerance);
      }
      const double index = level ? static_cast<double>(*level) : 1e9;  // full mesh = finest
      if (previousIndex >= 0.0) {
        ASSERT_LE(index, previousIndex);
      }
      previousIndex = index;
    }
  }
}

TEST(ImpostorLevel, CreditsAreTheWorstErrorAtOrFinerFloored) {
  std::vector<CurveLevel> levels(4);
  const double measured[] = {0.05, 0.002, 0.004, 0.0};  // rung 1 measured better than rung 2
  for (int i = 0; i < 4; ++i) levels[i].relativeMaxError = measured[i];
  const std::vector<double> credits = creditedRelativeErrors(levels, 1e-4);
  ASSERT_EQ(credits.size(), 4u);
  EXPECT_DOUBLE_EQ(credits[0], 0.05);
  EXPECT_DOUBLE_EQ(credits[1], 0.004);  // not better than a finer rung
  EXPECT_DOUBLE_EQ(credits[2], 0.004);
  EXPECT_DOUBLE_EQ(credits[3], 1e-4);  // full mesh: the floor
}

ImpostorFraming squareFraming(float quadSize, int texels, float nearDepth, float plane) {
  ImpostorFraming f;
  f.textureSize = texels;
  f.quad.width = quadSize;
  f.quad.height = quadSize * 1.5f;  // the smaller side counts
  f.nearDepth = nearDepth;
  f.planeDistance = plane;
  return f;
}

TEST(ImpostorLevel, ToleranceIsTheNearestTexel) {
  // 2.56 m quad over 256 texels: 1 cm at the plane; the nearest point at
  // 0.8 of the plane distance: 8 mm.
  const ImpostorFraming f = squareFraming(2.56f, 256, 8.0f, 10.0f);
  EXPECT_NEAR(impostorLevelTolerance(f), 0.008, 1e-7);
  EXPECT_NEAR(impostorLevelTolerance(f, 0.5), 0.004, 1e-7);
  EXPECT_EQ(impostorLevelTolerance(f, 0.0), 0.0);
  EXPECT_EQ(impostorLevelTolerance(f, std::nan("")), 0.0);
  EXPECT_EQ(impostorLevelTolerance(squareFraming(2.56f, 0, 8.0f, 10.0f)), 0.0);
  EXPECT_EQ(impostorLevelTolerance(squareFraming(2.56f, 256, 8.0f, 0.0f)), 0.0);
  EXPECT_EQ(impostorLevelTolerance(squareFraming(2.56f, 256, -1.0f, 10.0f)), 0.0);
  EXPECT_EQ(impostorLevelTolerance(squareFraming(NAN, 256, 8.0f, 10.0f)), 0.0);
}

TEST(ImpostorLevel, TextureDifferenceCountsChannelsAndCoverage) {
  RgbaImage a(2, 2);
  RgbaImage b(2, 2);
  a.pixels = {10, 20, 30, 255, 0, 0, 0, 0, 5, 5, 5, 255, 0, 0, 0, 0};
  b.pixels = {12, 20, 30, 255, 7, 7, 7, 0, 5, 5, 5, 0, 0, 0, 0, 0};
  auto diff = compareImpostorTextures(a, b);
  ASSERT_TRUE(diff.ok()) << diff.status().toString();
  EXPECT_EQ(diff->maxAbs, 255);
  EXPECT_NEAR(diff->meanAbs, (2.0 + 21.0 + 255.0) / 16.0, 1e-12);
  EXPECT_EQ(diff->coverageMismatch, 1u);
  EXPECT_EQ(diff->coveredEither, 2u);
  auto same = compareImpostorTextures(a, a);
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->maxAbs, 0);
  EXPECT_EQ(same->coverageMismatch, 0u);
  EXPECT_FALSE(compareImpostorTextures(a, RgbaImage(2, 3)).ok());
  RgbaImage broken(2, 2);
  broken.pixels.pop_back();
  EXPECT_FALSE(compareImpostorTextures(a, broken).ok());
}

}  // namespace
}  // namespace thinlod::simplifier
