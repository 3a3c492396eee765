// Point replacement sampling and point merging (Cohen-Aliaga-Zhang 5.3-5.4):
// coverage, centres inside, counts, the sample-distance search, merged balls.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <random>

#include "thinlod/simplifier/hybrid_graph.h"

namespace thinlod::simplifier {
namespace {

using glm::dvec3;

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

struct Tri {
  dvec3 a, b, c;
};

// Random triangles of all shapes: near-equilateral, right, obtuse, slivers,
// at scales from 1e-3 to 1e4 and arbitrary orientation.
std::vector<Tri> randomTriangles(std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::vector<Tri> out;
  for (int i = 0; i < count; ++i) {
    const double scale = std::pow(10.0, uniform(rng, -3.0, 4.0));
    const dvec3 offset(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    Tri t;
    t.a = offset * scale +
          scale * dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    t.b = offset * scale +
          scale * dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    if (i % 4 == 0) {
      // Sliver: c close to segment ab.
      t.c = 0.3 * t.a + 0.7 * t.b +
            1e-3 * scale * dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 1.0);
    } else {
      t.c = offset * scale +
            scale * dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
    }
    out.push_back(t);
  }
  return out;
}

double longestEdge(const Tri& t) {
  return std::max({glm::length(t.b - t.a), glm::length(t.c - t.b), glm::length(t.a - t.c)});
}

TEST(HybridSampling, SamplesCoverTheTriangleWithCentresInside) {
  std::mt19937_64 rng(11);
  for (const Tri& t : randomTriangles(1, 200)) {
    const double d = longestEdge(t) * uniform(rng, 0.04, 1.5);
    const std::vector<TriangleSample> samples = sampleTriangle(t.a, t.b, t.c, d);
    ASSERT_EQ(samples.size(), countTriangleSamples(t.a, t.b, t.c, d));
    ASSERT_FALSE(samples.empty());
    const double area = 0.5 * glm::length(glm::cross(t.b - t.a, t.c - t.a));
    double cellArea = 0.0;
    for (const TriangleSample& s : samples) {
      EXPECT_GE(s.barycentric.x, 0.0);
      EXPECT_GE(s.barycentric.y, 0.0);
      EXPECT_GE(s.barycentric.z, 0.0);
      EXPECT_NEAR(s.barycentric.x + s.barycentric.y + s.barycentric.z, 1.0, 1e-12);
      const dvec3 fromBary = s.barycentric.x * t.a + s.barycentric.y * t.b + s.barycentric.z * t.c;
      EXPECT_LE(glm::length(fromBary - s.centre), 1e-9 * longestEdge(t));
      cellArea += s.cellArea;
    }
    // The cells partition the triangle (squares of a row only overlap where
    // the last one is shifted back).
    EXPECT_GE(cellArea, area * (1.0 - 1e-9));
    // Every point of the triangle is within d / sqrt(2) of a centre.
    const double radius = d / std::sqrt(2.0);
    for (int k = 0; k < 400; ++k) {
      double u = uniform(rng, 0, 1), v = uniform(rng, 0, 1);
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      const dvec3 p = t.a + u * (t.b - t.a) + v * (t.c - t.a);
      double nearest = std::numeric_limits<double>::infinity();
      for (const TriangleSample& s : samples)
        nearest = std::min(nearest, glm::length(p - s.centre));
      ASSERT_LE(nearest, radius * (1.0 + 1e-9)) << "uncovered point, d = " << d;
    }
  }
}

TEST(HybridSampling, CornersAreCovered) {
  for (const Tri& t : randomTriangles(2, 100)) {
    for (double f : {0.07, 0.3, 1.0}) {
      const double d = f * longestEdge(t);
      const auto samples = sampleTriangle(t.a, t.b, t.c, d);
      for (const dvec3& corner : {t.a, t.b, t.c}) {
        double nearest = std::numeric_limits<double>::infinity();
        for (const auto& s : samples) nearest = std::min(nearest, glm::length(corner - s.centre));
        EXPECT_LE(nearest, d / std::sqrt(2.0) * (1.0 + 1e-9));
      }
    }
  }
}

TEST(HybridSampling, DegenerateTriangleHasNoSamples) {
  const dvec3 a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  EXPECT_TRUE(sampleTriangle(a, b, c, 0.1).empty());
  EXPECT_EQ(countTriangleSamples(a, b, c, 0.1), 0u);
  EXPECT_EQ(countTriangleSamples(a, b, dvec3(0, 1, 0), 0.0), 0u);
}

TEST(HybridSampling, OneSampleNeedsTheLongestEdge) {
  const dvec3 a(0, 0, 0), b(2, 0, 0), c(0.5, 1, 0);
  const double d = smallestSampleDistance(a, b, c, 1, 1e-6);
  EXPECT_NEAR(d, 2.0, 2e-6 * 2.0);
  EXPECT_EQ(countTriangleSamples(a, b, c, d), 1u);
}

TEST(HybridSampling, SmallestSampleDistanceIsFeasibleAndBounded) {
  const double tolerance = 1e-4;
  for (const Tri& t : randomTriangles(3, 120)) {
    const double area = 0.5 * glm::length(glm::cross(t.b - t.a, t.c - t.a));
    for (std::size_t s : {1u, 2u, 3u, 5u, 9u}) {
      const double d = smallestSampleDistance(t.a, t.b, t.c, s, tolerance);
      EXPECT_LE(countTriangleSamples(t.a, t.b, t.c, d), s);
      // s squares of side d must at least hold the area.
      EXPECT_GE(s * d * d, area * (1.0 - 1e-9));
      // One square of side = longest edge covers the triangle, so the search
      // (doubling, then bisection) never ends beyond twice that.
      EXPECT_LE(d, 2.0 * longestEdge(t));
    }
  }
}

TEST(HybridMerge, ParentBallContainsChildrenAndErrorFollowsTheDerivation) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 7);
    std::vector<HybridPoint> children(n);
    std::vector<double> errors(n);
    for (int i = 0; i < n; ++i) {
      children[i].centre = dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      children[i].normal = glm::normalize(dvec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 1.0));
      children[i].radius = uniform(rng, 0.01, 0.3);
      children[i].area = uniform(rng, 0.0, 2.0);
      children[i].color = {static_cast<std::uint8_t>(rng() & 255), 0, 255, 255};
      errors[i] = children[i].radius + uniform(rng, 0.0, 0.2);
    }
    const MergedPoint m = mergePoints(children, errors);
    double maxTrianglePart = 0.0;
    double centreBound = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      const double dist = glm::length(m.point.centre - children[i].centre);
      EXPECT_LE(dist + children[i].radius, m.point.radius);
      EXPECT_GE(m.error, errors[i]);  // monotone towards the root
      maxTrianglePart = std::max(maxTrianglePart, errors[i] - children[i].radius);
      centreBound = std::min(centreBound, dist + errors[i] - children[i].radius);
    }
    EXPECT_NEAR(m.error, m.point.radius + std::max(maxTrianglePart, centreBound), 1e-12);
    EXPECT_NEAR(glm::length(m.point.normal), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(m.point.normal, m.point.tangent), 0.0, 1e-12);
  }
}

TEST(HybridMerge, ColourIsTheAreaWeightedMean) {
  std::vector<HybridPoint> children(2);
  children[0].area = 3.0;
  children[0].color = {200, 0, 100, 255};
  children[1].centre = dvec3(1, 0, 0);
  children[1].area = 1.0;
  children[1].color = {0, 100, 100, 255};
  const MergedPoint m = mergePoints(children, {0.0, 0.0});
  EXPECT_EQ(m.point.color[0], 150);
  EXPECT_EQ(m.point.color[1], 25);
  EXPECT_EQ(m.point.color[2], 100);
  EXPECT_NEAR(m.point.centre.x, 0.25, 1e-12);
  EXPECT_DOUBLE_EQ(m.point.area, 4.0);
}

}  // namespace
}  // namespace thinlod::simplifier
