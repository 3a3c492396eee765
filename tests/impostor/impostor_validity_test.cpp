// Framing and validity math of impostors (no GL).
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <random>
#include <vector>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

std::vector<glm::vec3> randomBall(std::mt19937& rng, int count, float radius) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<glm::vec3> points;
  while (static_cast<int>(points.size()) < count) {
    const glm::vec3 p(u(rng), u(rng), u(rng));
    if (glm::length(p) <= 1.0f) points.push_back(p * radius);
  }
  return points;
}

// Where the simple impostor draws p: on the quad plane, along the capture ray.
glm::vec3 drawnAt(const ImpostorFraming& f, const glm::vec3& p) {
  const glm::vec3 ray = p - f.viewpoint;
  return f.viewpoint + ray * (f.planeDistance / glm::dot(ray, f.forward));
}

// In double, with atan2: acos of a float dot product cannot resolve angles below ~5e-4.
double angleBetween(const glm::vec3& a, const glm::vec3& b) {
  const glm::dvec3 x(a);
  const glm::dvec3 y(b);
  return std::atan2(glm::length(glm::cross(x, y)), glm::dot(x, y));
}

TEST(ImpostorFraming, QuadPlaneHoldsEveryProjectedPoint) {
  std::mt19937 rng(7);
  const auto points = randomBall(rng, 500, 1.0f);
  auto framing = frameImpostor(points, glm::vec3(1.0f, 2.0f, 8.0f), ImpostorOptions());
  ASSERT_TRUE(framing.ok()) << framing.status().toString();
  const ImpostorQuad& q = framing->quad;
  for (const glm::vec3& p : points) {
    const glm::vec3 local = drawnAt(*framing, p) - q.center;
    EXPECT_LE(std::fabs(glm::dot(local, q.right)), 0.5f * q.width + 1e-4f);
    EXPECT_LE(std::fabs(glm::dot(local, q.up)), 0.5f * q.height + 1e-4f);
    EXPECT_NEAR(glm::dot(local, q.normal), 0.0f, 1e-4f);
  }
  EXPECT_NEAR(glm::length(q.normal + framing->forward), 0.0f, 1e-5f);
}

TEST(ImpostorFraming, RejectsViewpointInsideAndBadInput) {
  const std::vector<glm::vec3> cube = {{-1, -1, -1}, {1, 1, 1}};
  EXPECT_EQ(frameImpostor(cube, glm::vec3(0.5f, 0, 0), {}).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(frameImpostor({}, glm::vec3(0, 0, 10), {}).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(frameImpostor({{0, 0, std::nanf("")}}, glm::vec3(0, 0, 10), {}).status().code(),
            ErrorCode::kInvalidArgument);
  ImpostorOptions hugePadding;
  hugePadding.paddingPixels = 100.0f;
  EXPECT_EQ(frameImpostor(cube, glm::vec3(0, 0, 10), hugePadding).status().code(),
            ErrorCode::kInvalidArgument);
}

// Paper Figure 9, autocenter FALSE: the quad is centred where the fixed
// centre projects and still covers every point (it grows, symmetric).
TEST(ImpostorFraming, AFixedCentreCentresTheQuadAndStillCoversThePoints) {
  std::mt19937 rng(11);
  const auto points = randomBall(rng, 300, 1.0f);
  const glm::vec3 eye(0.0f, 0.0f, 10.0f);
  auto automatic = frameImpostor(points, eye, ImpostorOptions());
  ImpostorOptions fixed;
  fixed.fixedCenter = glm::vec3(0.6f, -0.3f, 0.0f);
  auto framing = frameImpostor(points, eye, fixed);
  ASSERT_TRUE(automatic.ok() && framing.ok()) << framing.status().toString();
  const ImpostorQuad& q = framing->quad;
  // The quad centre lies on the ray from the eye through the fixed centre.
  const glm::vec3 ray = glm::normalize(*fixed.fixedCenter - eye);
  EXPECT_NEAR(glm::length(glm::cross(glm::normalize(q.center - eye), ray)), 0.0f, 1e-5f);
  EXPECT_GT(q.width, automatic->quad.width);
  EXPECT_EQ(framing->clippedExtent, 0.0f);
  for (const glm::vec3& p : points) {
    const glm::vec3 local = drawnAt(*framing, p) - q.center;
    EXPECT_LE(std::fabs(glm::dot(local, q.right)), 0.5f * q.width + 1e-4f);
    EXPECT_LE(std::fabs(glm::dot(local, q.up)), 0.5f * q.height + 1e-4f);
  }
}

// autosize FALSE: the quad has the fixed size; what does not fit is reported
// (a quad larger than the objects clips nothing).
TEST(ImpostorFraming, AFixedSizeIsTheQuadsSizeAndReportsWhatItCutsOff) {
  std::mt19937 rng(12);
  const auto points = randomBall(rng, 300, 1.0f);
  const glm::vec3 eye(0.0f, 0.0f, 10.0f);
  auto automatic = frameImpostor(points, eye, ImpostorOptions());
  ASSERT_TRUE(automatic.ok());
  ImpostorOptions small;
  small.fixedSize = glm::vec2(1.0f, 0.5f);
  auto framing = frameImpostor(points, eye, small);
  ASSERT_TRUE(framing.ok()) << framing.status().toString();
  // Padding grows the quad by one texel each side of 256.
  const float grow = 256.0f / 254.0f;
  EXPECT_NEAR(framing->quad.width, 1.0f * grow, 1e-4f);
  EXPECT_NEAR(framing->quad.height, 0.5f * grow, 1e-4f);
  // The ball's half extent on the plane is about 1 m: 0.75 m cut off vertically.
  const float halfHeight = 0.5f * automatic->quad.height / grow;
  EXPECT_NEAR(framing->clippedExtent, halfHeight - 0.25f, 1e-4f);
  ImpostorOptions large;
  large.fixedSize = glm::vec2(5.0f, 5.0f);
  auto roomy = frameImpostor(points, eye, large);
  ASSERT_TRUE(roomy.ok());
  EXPECT_EQ(roomy->clippedExtent, 0.0f);
  EXPECT_NEAR(roomy->quad.width, 5.0f * grow, 1e-3f);
  ImpostorOptions bad;
  bad.fixedSize = glm::vec2(std::nanf(""), 1.0f);
  EXPECT_EQ(frameImpostor(points, eye, bad).status().code(), ErrorCode::kInvalidArgument);
  ImpostorOptions behind;
  behind.fixedCenter = glm::vec3(0.0f, 0.0f, 20.0f);
  EXPECT_EQ(frameImpostor(points, eye, behind).status().code(), ErrorCode::kInvalidArgument);
}

TEST(ImpostorFraming, LookingAlongUpStillFrames) {
  const std::vector<glm::vec3> cube = {{-1, -1, -1}, {1, 1, 1}};
  auto framing = frameImpostor(cube, glm::vec3(0, 20, 0), {});
  ASSERT_TRUE(framing.ok());
  EXPECT_NEAR(std::fabs(glm::dot(framing->quad.up, framing->forward)), 0.0f, 1e-5f);
  EXPECT_GT(framing->quad.width, 0.0f);
}

// The derivation in impostor_validity.cpp, checked numerically: inside the
// cone, no surface point appears farther than maxAngularError from where the
// impostor draws it.
TEST(ImpostorValidity, MeasuredParallaxStaysWithinBoundInsideTheCone) {
  std::mt19937 rng(2024);
  const auto points = randomBall(rng, 400, 1.0f);
  for (double distance : {4.0, 10.0, 40.0}) {
    const glm::vec3 viewpoint = glm::normalize(glm::vec3(0.3f, 0.4f, 1.0f)) * float(distance);
    auto framing = frameImpostor(points, viewpoint, ImpostorOptions());
    ASSERT_TRUE(framing.ok());
    ImpostorErrorModel model;
    for (const glm::vec3& p : points) {
      model.depthDeviation =
          std::max(model.depthDeviation, double(glm::length(p - drawnAt(*framing, p))));
    }
    const double maxError = 2e-3;
    const ConicRange range = impostorValidity(*framing, model, maxError);
    ASSERT_GT(range.alpha(), 0.0);
    const float farthest =
        static_cast<float>(std::min(range.maxDistance(), range.minDistance() * 20.0));
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    double worst = 0.0;
    for (int trial = 0; trial < 300; ++trial) {
      // A random eye in the cone: angle <= alpha around the axis, distance in range.
      const glm::vec3 axis(range.direction());
      const glm::vec3 side = glm::normalize(glm::cross(axis, glm::vec3(0.0f, 1.0f, 0.0f)));
      const glm::vec3 side2 = glm::cross(axis, side);
      const float theta = static_cast<float>(range.alpha()) * std::sqrt(unit(rng));
      const float phi = 6.2831853f * unit(rng);
      const glm::vec3 direction =
          axis * std::cos(theta) + (side * std::cos(phi) + side2 * std::sin(phi)) * std::sin(theta);
      const float nearest = static_cast<float>(range.minDistance());
      const float d = nearest + (farthest - nearest) * unit(rng);
      const glm::vec3 eye = glm::vec3(range.center()) + direction * d;
      const double bound = impostorErrorBound(*framing, model, eye);
      ASSERT_LE(bound, maxError * (1.0 + 1e-4)) << "distance " << d << " angle " << theta;
      for (int k = 0; k < 40; ++k) {
        const glm::vec3& p = points[(trial * 40 + k) % points.size()];
        const double measured = angleBetween(p - eye, drawnAt(*framing, p) - eye);
        worst = std::max(worst, measured);
        ASSERT_LE(measured, bound + 1e-6) << "point parallax exceeds the bound";
      }
    }
    EXPECT_GT(worst, 0.0);
  }
}

TEST(ImpostorValidity, CaptureViewpointIsInsideAndErrorFree) {
  std::mt19937 rng(3);
  const auto points = randomBall(rng, 200, 1.0f);
  const glm::vec3 viewpoint(0, 0, 10);
  auto framing = frameImpostor(points, viewpoint, {});
  ASSERT_TRUE(framing.ok());
  ImpostorErrorModel model;
  model.depthDeviation = 2.0;
  EXPECT_EQ(impostorErrorBound(*framing, model, viewpoint), 0.0);
  const ConicRange range = impostorValidity(*framing, model, 1e-3);
  EXPECT_TRUE(range.containsPoint(glm::dvec3(viewpoint)));
  const float d = glm::length(viewpoint - glm::vec3(range.center()));
  EXPECT_LE(range.minDistance(), d);
  EXPECT_GE(range.maxDistance(), d);
  EXPECT_GT(range.alpha(), 0.0);
  // Alpha spends half the budget at the capture distance.
  const glm::vec3 axis(range.direction());
  const glm::vec3 across = glm::normalize(glm::cross(axis, glm::vec3(0, 1, 0)));
  const float alpha = static_cast<float>(range.alpha());
  const glm::vec3 side =
      glm::vec3(range.center()) + (axis * std::cos(alpha) + across * std::sin(alpha)) * d;
  EXPECT_NEAR(impostorErrorBound(*framing, model, side), 0.5e-3, 2e-5);
}

TEST(ImpostorValidity, BoundGrowsWithAngleAndShrinksWithDepthDeviation) {
  std::mt19937 rng(5);
  const auto points = randomBall(rng, 200, 1.0f);
  auto framing = frameImpostor(points, glm::vec3(0, 0, 10), {});
  ASSERT_TRUE(framing.ok());
  ImpostorErrorModel deep{2.0, 0.0};
  ImpostorErrorModel shallow{0.02, 0.0};
  double previous = 0.0;
  for (double theta = 0.01; theta < 1.5; theta += 0.1) {
    const glm::vec3 eye(10.0 * std::sin(theta), 0.0, 10.0 * std::cos(theta));
    const double bound = impostorErrorBound(*framing, deep, eye);
    EXPECT_GT(bound, previous);
    previous = bound;
    EXPECT_LT(impostorErrorBound(*framing, shallow, eye), bound);
  }
  const ConicRange wide = impostorValidity(*framing, shallow, 1e-3);
  const ConicRange narrow = impostorValidity(*framing, deep, 1e-3);
  EXPECT_GT(wide.alpha(), 10.0 * narrow.alpha());
}

TEST(ImpostorValidity, SilhouetteTermLimitsMeshedCones) {
  std::mt19937 rng(9);
  const auto points = randomBall(rng, 200, 1.0f);
  auto framing = frameImpostor(points, glm::vec3(0, 0, 10), {});
  ASSERT_TRUE(framing.ok());
  const ConicRange exact = impostorValidity(*framing, ImpostorErrorModel{0.0, 0.0}, 1e-3);
  EXPECT_GT(exact.alpha(), 3.1);  // nothing can go wrong: every direction is fine
  EXPECT_TRUE(std::isinf(exact.maxDistance()));
  const ConicRange rim = impostorValidity(*framing, ImpostorErrorModel{0.0, 1.0}, 1e-3);
  EXPECT_LT(rim.alpha(), 0.2);
  EXPECT_GT(rim.alpha(), 0.05);
}

TEST(ImpostorValidity, FarViewersAreValidWhenParallaxShrinks) {
  std::mt19937 rng(11);
  const auto points = randomBall(rng, 200, 1.0f);
  auto framing = frameImpostor(points, glm::vec3(0, 0, 50), {});
  ASSERT_TRUE(framing.ok());
  const ConicRange range = impostorValidity(*framing, ImpostorErrorModel{2.0, 0.0}, 1e-2);
  EXPECT_TRUE(std::isinf(range.maxDistance()));
  EXPECT_GT(range.minDistance(), 1.0);
  EXPECT_LT(range.minDistance(), 50.0);
}

}  // namespace
}  // namespace thinlod::simplifier
