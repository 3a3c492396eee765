// White-box tests of the closest-point query behind measureSurfaceError.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "surface_error_bvh.h"

namespace thinlod::simplifier::detail {
namespace {

// Independent reference: project onto the plane; inside -> plane distance,
// else the nearest of the three edges.
double referenceDistance(const dvec3& p, const Triangle& t) {
  const dvec3 n = glm::cross(t.b - t.a, t.c - t.a);
  const double n2 = glm::dot(n, n);
  if (n2 > 0.0) {
    const dvec3 q = p - n * (glm::dot(p - t.a, n) / n2);
    const double w0 = glm::dot(glm::cross(t.b - q, t.c - q), n);
    const double w1 = glm::dot(glm::cross(t.c - q, t.a - q), n);
    const double w2 = glm::dot(glm::cross(t.a - q, t.b - q), n);
    if (w0 >= 0 && w1 >= 0 && w2 >= 0) return glm::length(p - q);
  }
  return std::sqrt(
      std::min({squaredDistanceToSegment(p, t.a, t.b), squaredDistanceToSegment(p, t.b, t.c),
                squaredDistanceToSegment(p, t.c, t.a)}));
}

TEST(TriangleDistance, MatchesProjectionReferenceOnRandomCases) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 20000; ++i) {
    const Triangle t{{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
    const dvec3 p(u(rng), u(rng), u(rng));
    const double expected = referenceDistance(p, t);
    ASSERT_NEAR(std::sqrt(squaredDistanceToTriangle(p, t)), expected, 1e-9 * (1.0 + expected))
        << "case " << i;
  }
}

TEST(TriangleDistance, DegenerateTrianglesFallBackToEdges) {
  const Triangle line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  EXPECT_NEAR(std::sqrt(squaredDistanceToTriangle({1.5, 1.0, 0.0}, line)), 1.0, 1e-12);
  const Triangle point{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  EXPECT_NEAR(std::sqrt(squaredDistanceToTriangle({1, 1, 3}, point)), 2.0, 1e-12);
}

TEST(TriangleBvh, AgreesWithBruteForceOnRandomSoup) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  IndexedMesh soup;
  std::vector<Triangle> triangles;
  for (int t = 0; t < 3000; ++t) {
    const glm::vec3 c(u(rng) * 10, u(rng) * 10, u(rng) * 10);
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 v = c + glm::vec3(u(rng), u(rng), u(rng));
      soup.positions.push_back(v);
      soup.indices.push_back(static_cast<std::uint32_t>(soup.positions.size() - 1));
      (k == 0 ? tri.a : k == 1 ? tri.b : tri.c) = toDouble(v);
    }
    triangles.push_back(tri);
  }
  const TriangleBvh bvh(soup);
  std::uint32_t hint = 0;
  for (int i = 0; i < 2000; ++i) {
    const dvec3 p(u(rng) * 14, u(rng) * 14, u(rng) * 14);
    double brute = std::numeric_limits<double>::infinity();
    for (const Triangle& t : triangles) brute = std::min(brute, squaredDistanceToTriangle(p, t));
    ASSERT_EQ(bvh.squaredDistance(p, hint), brute) << "query " << i;
  }
}

// The least-value search (measureUvError's): the least distance from a
// target to a value interpolated inside each triangle within the radius is
// the brute force's over the same triangles, with values from a second,
// unrelated per-corner attribute (as uvs are to positions), including
// slivers, at scales 1e-6..1e6.
TEST(TriangleBvh, LeastValueSearchMatchesBruteForce) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> w(0.0, 1.0);
  for (const double scale : {1e-6, 1.0, 1e6}) {
    IndexedMesh soup;
    std::vector<Triangle> triangles;
    std::vector<std::array<dvec3, 3>> values;  // per input triangle
    for (int t = 0; t < 1500; ++t) {
      const dvec3 c(u(rng) * 10, u(rng) * 10, u(rng) * 10);
      Triangle tri;
      std::array<dvec3, 3> value;
      std::array<dvec3, 3> corner;
      for (int k = 0; k < 3; ++k) corner[k] = c + dvec3(u(rng), u(rng), u(rng));
      // Every 7th a sliver: the third corner a hair off the first edge's middle.
      if (t % 7 == 0) corner[2] = 0.5 * (corner[0] + corner[1]) + dvec3(1e-7 * u(rng), 0.0, 0.0);
      for (int k = 0; k < 3; ++k) {
        soup.positions.push_back(glm::vec3(corner[k] * scale));
        soup.indices.push_back(static_cast<std::uint32_t>(soup.positions.size() - 1));
        (k == 0 ? tri.a : k == 1 ? tri.b : tri.c) = toDouble(soup.positions.back());
        value[k] = dvec3(u(rng), u(rng), 0.0) * scale;
      }
      triangles.push_back(tri);
      values.push_back(value);
    }
    const TriangleBvh bvh(soup);
    const std::vector<Box> boxes =
        bvh.nodeBoxesOf([&](std::uint32_t i, int k) { return values[bvh.sourceTriangle(i)][k]; });
    // The value at triangle t's point nearest p: its corners' values
    // interpolated with a fixed pseudo-random convex weight per triangle.
    auto valueOf = [&](std::uint32_t t, const dvec3& target) {
      const double wb = w(rng) * 0.5, wc = 0.5 * w(rng);
      const std::array<dvec3, 3>& v = values[t];
      return glm::length(v[0] + wb * (v[1] - v[0]) + wc * (v[2] - v[0]) - target);
    };
    for (int i = 0; i < 300; ++i) {
      const dvec3 p = dvec3(u(rng) * 12, u(rng) * 12, u(rng) * 12) * scale;
      const dvec3 target = dvec3(u(rng), u(rng), 0.0) * scale;
      const double radius2 = std::pow(4.0 * w(rng) * scale, 2);
      // Weights drawn once per (query, triangle), shared by both searches.
      std::vector<double> value(triangles.size());
      for (std::uint32_t t = 0; t < triangles.size(); ++t) value[t] = valueOf(t, target);
      double brute = std::numeric_limits<double>::infinity();
      for (std::uint32_t t = 0; t < triangles.size(); ++t) {
        if (squaredDistanceToTriangle(p, triangles[t]) <= radius2) brute = std::min(brute, value[t]);
      }
      double best = std::numeric_limits<double>::infinity();
      bvh.forEachWithinWhileNearer(p, radius2, boxes, target, [&] { return best * best; },
                                   [&](std::uint32_t j, const Triangle&) {
                                     best = std::min(best, value[bvh.sourceTriangle(j)]);
                                   });
      ASSERT_EQ(best, brute) << "scale " << scale << " query " << i;
    }
  }
}

TEST(TriangleBvh, HandlesManyTrianglesWithIdenticalCentroids) {
  // All centroids coincide: the SAH cannot split; the build must still end.
  IndexedMesh fan;
  fan.positions.emplace_back(0.0f, 0.0f, 0.0f);
  for (int i = 0; i < 400; ++i) {
    const float a = 0.0157f * i;
    fan.positions.emplace_back(std::cos(a), std::sin(a), 0.0f);
    fan.positions.emplace_back(-std::cos(a), -std::sin(a), 0.0f);
    const std::uint32_t v = static_cast<std::uint32_t>(fan.positions.size() - 2);
    fan.indices.insert(fan.indices.end(), {0, v, v + 1});
  }
  const TriangleBvh bvh(fan);
  std::uint32_t hint = 0;
  EXPECT_NEAR(std::sqrt(bvh.squaredDistance({0.0, 0.0, 2.0}, hint)), 2.0, 1e-9);
}

}  // namespace
}  // namespace thinlod::simplifier::detail
