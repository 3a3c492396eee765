#include "thinlod/common/mesh/primitives.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <thread>
#include <vector>

namespace thinlod {
namespace {

constexpr double kPi = 3.14159265358979323846;
using dvec2 = glm::dvec2;
using dvec3 = glm::dvec3;

// ---- independent geometry for measuring (not the library's code path)

double pointSegment2(const dvec2& p, const dvec2& a, const dvec2& b) {
  const dvec2 ab = b - a;
  const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

double pointSegment3(const dvec3& p, const dvec3& a, const dvec3& b) {
  const dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

// Projection onto the plane when it falls inside, else the nearest edge.
double pointTriangle(const dvec3& p, const dvec3& a, const dvec3& b, const dvec3& c) {
  const dvec3 n = glm::cross(b - a, c - a);
  const double n2 = glm::dot(n, n);
  if (n2 > 0) {
    const dvec3 q = p - n * (glm::dot(p - a, n) / n2);
    const double wa = glm::dot(glm::cross(b - q, c - q), n);
    const double wb = glm::dot(glm::cross(c - q, a - q), n);
    const double wc = glm::dot(glm::cross(a - q, b - q), n);
    if (wa >= 0 && wb >= 0 && wc >= 0) return glm::length(p - q);
  }
  return std::min({pointSegment3(p, a, b), pointSegment3(p, b, c), pointSegment3(p, c, a)});
}

// Distance to the true closed surface through its meridian profile: a
// surface of revolution about y, so the nearest point lies in p's meridian.
double distanceToSurface(const PrimitiveShape& s, const dvec3& p) {
  const dvec2 q(std::sqrt(p.x * p.x + p.z * p.z), p.y);
  const double R = s.radius;
  const double h2 = 0.5 * s.height;
  switch (s.kind) {
    case PrimitiveKind::kSphere:
      return std::abs(glm::length(p) - R);
    case PrimitiveKind::kCylinder:
      return std::min({pointSegment2(q, {0, h2}, {R, h2}), pointSegment2(q, {R, h2}, {R, -h2}),
                       pointSegment2(q, {R, -h2}, {0, -h2})});
    case PrimitiveKind::kCone:
      return std::min(pointSegment2(q, {0, h2}, {R, -h2}), pointSegment2(q, {R, -h2}, {0, -h2}));
    default:
      return 0.0;
  }
}

dvec3 vertex(const IndexedMesh& m, std::uint32_t i) { return dvec3(m.positions[i]); }

// Max over a barycentric grid (vertices, edge midpoints, centroids included)
// of the distance from the tessellation to the true surface.
double meshToSurface(const PrimitiveShape& s, const IndexedMesh& m) {
  const int K = 12;
  double worst = 0.0;
  for (std::size_t t = 0; t < m.triangleCount(); ++t) {
    const dvec3 a = vertex(m, m.indices[3 * t]), b = vertex(m, m.indices[3 * t + 1]),
                c = vertex(m, m.indices[3 * t + 2]);
    for (int i = 0; i <= K; ++i) {
      for (int j = 0; i + j <= K; ++j) {
        const dvec3 p = (a * double(i) + b * double(j) + c * double(K - i - j)) / double(K);
        worst = std::max(worst, distanceToSurface(s, p));
      }
    }
  }
  return worst;
}

double distanceToMesh(const IndexedMesh& m, const dvec3& p) {
  double best = 1e300;
  for (std::size_t t = 0; t < m.triangleCount(); ++t) {
    best = std::min(best,
                    pointTriangle(p, vertex(m, m.indices[3 * t]), vertex(m, m.indices[3 * t + 1]),
                                  vertex(m, m.indices[3 * t + 2])));
  }
  return best;
}

// Samples of the true surface on a grid that contains the rim points half
// way between tessellation vertices.
double surfaceToMesh(const PrimitiveShape& s, const IndexedMesh& m, int segments) {
  const int angles = 4 * segments;
  const double R = s.radius;
  const double h2 = 0.5 * s.height;
  std::vector<dvec2> profile;  // (r, y) samples of the meridian
  const int steps = 24;
  for (int k = 0; k <= steps; ++k) {
    const double t = double(k) / steps;
    if (s.kind == PrimitiveKind::kSphere) {
      profile.push_back({R * std::sin(kPi * t), R * std::cos(kPi * t)});
    } else if (s.kind == PrimitiveKind::kCylinder) {
      profile.push_back({R, h2 - 2 * h2 * t});
      profile.push_back({R * t, h2});
      profile.push_back({R * t, -h2});
    } else {
      profile.push_back({R * t, h2 - 2 * h2 * t});
      profile.push_back({R * t, -h2});
    }
  }
  double worst = 0.0;
  for (int a = 0; a < angles; ++a) {
    const double phi = 2 * kPi * a / angles;
    for (const dvec2& rp : profile) {
      worst = std::max(worst,
                       distanceToMesh(m, dvec3(rp.x * std::sin(phi), rp.y, rp.x * std::cos(phi))));
    }
  }
  return worst;
}

// ---- tests

struct ErrorCase {
  PrimitiveShape shape;
  TessellationParams params;
  const char* label;
};

std::vector<ErrorCase> errorCases() {
  return {
      {PrimitiveShape::sphere(1.0f), {6, 3}, "sphere 6x3"},
      {PrimitiveShape::sphere(1.0f), {16, 8}, "sphere 16x8"},
      {PrimitiveShape::sphere(2.5f), {24, 9}, "sphere 24x9"},
      {PrimitiveShape::sphere(1.0f), {3, 2}, "sphere 3x2"},
      {PrimitiveShape::cylinder(0.3f, 1.2f), {5, 2}, "cylinder n5"},
      {PrimitiveShape::cylinder(1.0f, 2.0f), {24, 2}, "cylinder n24"},
      {PrimitiveShape::cone(0.5f, 1.0f), {6, 2}, "cone n6"},
      {PrimitiveShape::cone(1.0f, 0.4f), {20, 2}, "flat cone n20"},
  };
}

TEST(Primitives, MeasuredHausdorffMatchesAnalyticError) {
  for (const ErrorCase& c : errorCases()) {
    const IndexedMesh m = tessellate(c.shape, c.params);
    const double analytic = tessellationError(c.shape, c.params);
    const double forward = meshToSurface(c.shape, m);
    const double backward = surfaceToMesh(c.shape, m, c.params.segments);
    const double measured = std::max(forward, backward);
    // Float positions: allow 1e-6 of the size on top.
    EXPECT_LE(forward, analytic * (1 + 1e-5) + 1e-6 * c.shape.radius) << c.label;
    EXPECT_LE(backward, analytic * (1 + 1e-5) + 1e-6 * c.shape.radius) << c.label;
    EXPECT_GE(measured, analytic * 0.98) << c.label << " forward " << forward << " backward "
                                         << backward << " analytic " << analytic;
  }
}

TEST(Primitives, CylinderErrorIsTheRimSagitta) {
  const PrimitiveShape s = PrimitiveShape::cylinder(2.0f, 1.0f);
  for (int n : {3, 4, 10, 100}) {
    EXPECT_DOUBLE_EQ(tessellationError(s, {n, 2}), 2.0 * (1.0 - std::cos(kPi / n))) << n;
  }
}

TEST(Primitives, BoxIsExactWithTwelveTriangles) {
  const PrimitiveShape s = PrimitiveShape::box({1.0f, 2.0f, 3.0f});
  const IndexedMesh m = tessellate(s, {});
  EXPECT_EQ(m.triangleCount(), 12u);
  EXPECT_EQ(tessellationError(s, {}), 0.0);
  EXPECT_EQ(tessellationAccuracy(s, {}), kExactRelativeAccuracy);
  // The reference sphere's diameter: the box diagonal, padded by 1e-6.
  EXPECT_NEAR(primitiveDiameter(s), std::sqrt(14.0), 1e-5);
  EXPECT_GE(primitiveDiameter(s), std::sqrt(14.0));
  for (const glm::vec3& p : m.positions) {
    EXPECT_FLOAT_EQ(std::abs(p.x), 0.5f);
    EXPECT_FLOAT_EQ(std::abs(p.y), 1.0f);
    EXPECT_FLOAT_EQ(std::abs(p.z), 1.5f);
  }
}

TEST(Primitives, TriangleCountFormulaMatchesMesh) {
  PrimitiveShape openTube = PrimitiveShape::cylinder(1.0f, 1.0f);
  openTube.top = openTube.bottom = false;
  PrimitiveShape capOnlyCone = PrimitiveShape::cone(1.0f, 1.0f);
  capOnlyCone.side = false;
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(1.0f), PrimitiveShape::cylinder(1.0f, 1.0f),
        PrimitiveShape::cone(1.0f, 2.0f), openTube, capOnlyCone}) {
    for (int n = 3; n < 40; n += 5) {
      for (int rings = 2; rings < 12; rings += 3) {
        const TessellationParams p{n, rings};
        const IndexedMesh m = tessellate(s, p);
        EXPECT_EQ(m.triangleCount(), static_cast<std::size_t>(tessellationTriangles(s, p)))
            << primitiveKindName(s.kind) << " " << n << "x" << rings;
        EXPECT_TRUE(m.validate("primitive").ok());
      }
    }
  }
}

TEST(Primitives, NormalsUnitUvsInRangeTrianglesFaceOutward) {
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(0.7f), PrimitiveShape::cylinder(0.5f, 2.0f),
        PrimitiveShape::cone(1.0f, 1.5f), PrimitiveShape::box({1.0f, 0.5f, 2.0f})}) {
    const IndexedMesh m = tessellate(s, {12, 6});
    ASSERT_EQ(m.normals.size(), m.vertexCount());
    ASSERT_EQ(m.uvs.size(), m.vertexCount());
    for (std::size_t i = 0; i < m.vertexCount(); ++i) {
      EXPECT_NEAR(glm::length(m.normals[i]), 1.0f, 1e-5f);
      EXPECT_GE(m.uvs[i].x, 0.0f);
      EXPECT_LE(m.uvs[i].x, 1.0f);
      EXPECT_GE(m.uvs[i].y, 0.0f);
      EXPECT_LE(m.uvs[i].y, 1.0f);
    }
    // Convex shapes around the origin: each face normal points away from it.
    for (std::size_t t = 0; t < m.triangleCount(); ++t) {
      const glm::vec3 a = m.positions[m.indices[3 * t]];
      const glm::vec3 b = m.positions[m.indices[3 * t + 1]];
      const glm::vec3 c = m.positions[m.indices[3 * t + 2]];
      const glm::vec3 n = glm::cross(b - a, c - a);
      EXPECT_GT(glm::dot(n, (a + b + c) / 3.0f), 0.0f) << primitiveKindName(s.kind) << " " << t;
    }
  }
}

TEST(Primitives, ChooseTessellationHitsBudgetWithinGranularity) {
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(1.0f), PrimitiveShape::cylinder(1.0f, 3.0f),
        PrimitiveShape::cone(1.0f, 1.0f)}) {
    for (int budget : {20, 50, 100, 200, 350, 1000, 5000}) {
      const TessellationParams p = chooseTessellation(s, budget);
      const int got = tessellationTriangles(s, p);
      EXPECT_LE(got, budget) << primitiveKindName(s.kind);
      // Granularity: 4 (cylinder), 2 (cone); the sphere grid steps by
      // 2 (rings - 1) per segment and trades count for shape, within 10%.
      const int granularity = s.kind == PrimitiveKind::kSphere
                                  ? std::max(2 * (p.rings - 1), budget / 10)
                                  : (s.kind == PrimitiveKind::kCylinder ? 4 : 2);
      EXPECT_GT(got, budget - granularity) << primitiveKindName(s.kind) << " budget " << budget;
    }
  }
}

TEST(Primitives, HugeBudgetsAreCapped) {
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(1.0f), PrimitiveShape::cylinder(1.0f, 1.0f)}) {
    const TessellationParams p = chooseTessellation(s, std::numeric_limits<int>::max());
    EXPECT_LE(tessellationTriangles(s, p), kMaxPrimitiveTriangles);
    EXPECT_GT(tessellationTriangles(s, p), kMaxPrimitiveTriangles / 2);
  }
}

TEST(Primitives, ChooseTessellationBelowMinimumGivesCoarsest) {
  EXPECT_EQ(tessellationTriangles(PrimitiveShape::sphere(1),
                                  chooseTessellation(PrimitiveShape::sphere(1), 1)),
            6);
  EXPECT_EQ(tessellationTriangles(PrimitiveShape::cylinder(1, 1),
                                  chooseTessellation(PrimitiveShape::cylinder(1, 1), 0)),
            8);
}

TEST(Primitives, SphereChoiceIsBestErrorWithinBudget) {
  const PrimitiveShape s = PrimitiveShape::sphere(1.0f);
  const int budget = 300;
  const double chosen = tessellationError(s, chooseTessellation(s, budget));
  for (int rings = 2; rings < 40; ++rings) {
    for (int n = std::max(3, rings); n <= 4 * rings; ++n) {
      if (2 * n * (rings - 1) > budget) continue;
      EXPECT_LE(chosen, tessellationError(s, {n, rings}) * (1 + 1e-12)) << n << "x" << rings;
    }
  }
}

TEST(Primitives, TessellationForAccuracyIsCheapestThatReaches) {
  for (const PrimitiveShape& s : {PrimitiveShape::cylinder(0.5f, 1.0f),
                                  PrimitiveShape::cone(1.0f, 2.0f), PrimitiveShape::sphere(1.0f)}) {
    for (double a : {5.0, 20.0, 100.0, 1000.0}) {
      Result<TessellationParams> p = tessellationForAccuracy(s, a, 1 << 20);
      ASSERT_TRUE(p.ok()) << p.status().toString();
      EXPECT_GE(tessellationAccuracy(s, *p), a);
      const int triangles = tessellationTriangles(s, *p);
      // Nothing cheaper in the searched family reaches a.
      const TessellationParams cheaper = chooseTessellation(s, triangles - 1);
      if (tessellationTriangles(s, cheaper) < triangles) {
        EXPECT_LT(tessellationAccuracy(s, cheaper), a) << primitiveKindName(s.kind) << " " << a;
      }
    }
  }
}

TEST(Primitives, TessellationForAccuracyRefusesBeyondBudget) {
  Result<TessellationParams> p = tessellationForAccuracy(PrimitiveShape::sphere(1.0f), 1e5, 1000);
  ASSERT_FALSE(p.ok());
  EXPECT_EQ(p.status().code(), ErrorCode::kResourceExhausted);
}

TEST(Primitives, RelativeAccuracyIsScaleInvariant) {
  for (int n : {5, 17}) {
    EXPECT_NEAR(tessellationAccuracy(PrimitiveShape::sphere(0.01f), {n, 4}),
                tessellationAccuracy(PrimitiveShape::sphere(100.0f), {n, 4}), 1e-3);
  }
}

TEST(Primitives, ValidateRejectsBadShapes) {
  EXPECT_FALSE(validatePrimitive(PrimitiveShape::sphere(std::nanf(""))).ok());
  EXPECT_FALSE(validatePrimitive(PrimitiveShape::sphere(-1.0f)).ok());
  EXPECT_FALSE(validatePrimitive(PrimitiveShape::cylinder(1.0f, INFINITY)).ok());
  EXPECT_FALSE(validatePrimitive(PrimitiveShape::box({1.0f, 0.0f, 1.0f})).ok());
  PrimitiveShape nothing = PrimitiveShape::cylinder(1.0f, 1.0f);
  nothing.side = nothing.top = nothing.bottom = false;
  EXPECT_EQ(validatePrimitive(nothing).code(), ErrorCode::kInvalidArgument);
  EXPECT_TRUE(validatePrimitive(PrimitiveShape::cone(1.0f, 1.0f)).ok());
}

// ---- curves

TEST(PrimitiveCurves, BoxIsAPointAtTwelve) {
  Result<AccuracyCurve> c = primitiveAccuracyCurve(PrimitiveShape::box({1, 1, 1}));
  ASSERT_TRUE(c.ok()) << c.status().toString();
  EXPECT_DOUBLE_EQ(c->resourcesFor(10.0), 12.0);
  EXPECT_DOUBLE_EQ(c->maxAccuracy(), kExactRelativeAccuracy);
}

TEST(PrimitiveCurves, NeverPromiseMoreThanATessellationDelivers) {
  std::mt19937 rng(20020224u);  // fixed seed
  PrimitiveCurveOptions options;
  options.maxTriangles = 4096;
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(1.0f), PrimitiveShape::cylinder(0.25f, 2.0f),
        PrimitiveShape::cylinder(1.0f, 0.1f), PrimitiveShape::cone(0.5f, 1.0f)}) {
    Result<AccuracyCurve> curve = primitiveAccuracyCurve(s, options);
    ASSERT_TRUE(curve.ok()) << curve.status().toString();
    ASSERT_FALSE(curve->empty());
    const double lo = curve->minAccuracy();
    const double hi = curve->maxAccuracy();
    EXPECT_GT(hi, lo);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 300; ++trial) {
      // Log-uniform over the domain.
      const double a = lo * std::pow(hi / lo, u(rng));
      const double budget = curve->resourcesFor(a);
      ASSERT_TRUE(std::isfinite(budget));
      const TessellationParams p = chooseTessellation(s, static_cast<int>(std::floor(budget)));
      EXPECT_LE(tessellationTriangles(s, p), budget);
      EXPECT_GE(tessellationAccuracy(s, p), a * (1 - 1e-12))
          << primitiveKindName(s.kind) << " a=" << a << " budget=" << budget;
    }
  }
}

// The fit is tight: never more than 10% above the cheapest tessellation that
// reaches an accuracy (measured 1.06-1.08 with the default 24 segments).
TEST(PrimitiveCurves, OverestimateIsAtMostTenPercent) {
  PrimitiveCurveOptions options;
  options.maxTriangles = 4096;
  for (const PrimitiveShape& s :
       {PrimitiveShape::sphere(1.0f), PrimitiveShape::cylinder(0.25f, 2.0f),
        PrimitiveShape::cone(0.5f, 1.0f)}) {
    Result<AccuracyCurve> curve = primitiveAccuracyCurve(s, options);
    ASSERT_TRUE(curve.ok()) << curve.status().toString();
    EXPECT_LE(curve->segments().size(), static_cast<std::size_t>(options.maxSegments));
    const double lo = curve->minAccuracy();
    const double hi = curve->maxAccuracy();
    double worst = 0.0;
    for (int k = 0; k <= 400; ++k) {
      // Clamped: pow may round the last point one ulp past the domain.
      const double a = std::min(hi, lo * std::pow(hi / lo, k / 400.0));
      Result<TessellationParams> cheapest = tessellationForAccuracy(s, a, options.maxTriangles);
      ASSERT_TRUE(cheapest.ok()) << a;
      worst = std::max(worst, curve->resourcesFor(a) / tessellationTriangles(s, *cheapest));
    }
    std::printf("[ overestimate ] %s: worst %.4f\n", primitiveKindName(s.kind), worst);
    EXPECT_LE(worst, 1.10) << primitiveKindName(s.kind);
  }
}

TEST(PrimitiveCurves, ZeroSegmentsIsRejected) {
  PrimitiveCurveOptions options;
  options.maxSegments = 0;
  EXPECT_EQ(primitiveAccuracyCurve(PrimitiveShape::sphere(1.0f), options).status().code(),
            ErrorCode::kInvalidArgument);
}

TEST(PrimitiveCurves, CoarsestTessellationStartsTheCurve) {
  Result<AccuracyCurve> curve = primitiveAccuracyCurve(PrimitiveShape::cylinder(1.0f, 2.0f));
  ASSERT_TRUE(curve.ok());
  const TessellationParams coarsest{3, 2};
  EXPECT_NEAR(curve->minAccuracy(),
              tessellationAccuracy(PrimitiveShape::cylinder(1.0f, 2.0f), coarsest), 1e-9);
  EXPECT_DOUBLE_EQ(curve->resourcesFor(curve->minAccuracy()), 8.0);
}

TEST(PrimitiveCurves, InvalidShapeIsAnError) {
  EXPECT_FALSE(primitiveAccuracyCurve(PrimitiveShape::sphere(0.0f)).ok());
}

void expectSameSegments(const AccuracyCurve& a, const AccuracyCurve& b) {
  ASSERT_EQ(a.segments().size(), b.segments().size());
  for (std::size_t i = 0; i < a.segments().size(); ++i) {
    EXPECT_EQ(a.segments()[i].start, b.segments()[i].start) << "segment " << i;
    EXPECT_EQ(a.segments()[i].value, b.segments()[i].value) << "segment " << i;
    EXPECT_EQ(a.segments()[i].slope, b.segments()[i].slope) << "segment " << i;
  }
}

// primitiveAccuracyCurve remembers the curves it fitted (by their exact
// inputs): a repeated call gives the same curve bit for bit, and inputs that
// differ in any field, even by one ulp or in the options, are not confused.
TEST(PrimitiveCurves, RepeatedCallsGiveTheSameCurveAndNeighboursTheirOwn) {
  PrimitiveCurveOptions options;
  options.maxTriangles = 2048;
  const PrimitiveShape cone = PrimitiveShape::cone(0.377f, 1.913f);
  Result<AccuracyCurve> first = primitiveAccuracyCurve(cone, options);
  Result<AccuracyCurve> again = primitiveAccuracyCurve(cone, options);
  ASSERT_TRUE(first.ok() && again.ok());
  expectSameSegments(*first, *again);

  // A cone one ulp taller and the same cone with a part left out: their own
  // curves, each the same as a second call of its own.
  PrimitiveShape taller = cone;
  taller.height = std::nextafter(cone.height, 10.0f);
  PrimitiveShape open = cone;
  open.bottom = false;
  for (const PrimitiveShape& other : {taller, open}) {
    Result<AccuracyCurve> c = primitiveAccuracyCurve(other, options);
    Result<AccuracyCurve> c2 = primitiveAccuracyCurve(other, options);
    ASSERT_TRUE(c.ok() && c2.ok());
    expectSameSegments(*c, *c2);
  }
  Result<AccuracyCurve> openCurve = primitiveAccuracyCurve(open, options);
  ASSERT_TRUE(openCurve.ok());
  EXPECT_LT(openCurve->resourcesFor(openCurve->minAccuracy()),
            first->resourcesFor(first->minAccuracy()))
      << "no bottom disc: fewer triangles than the closed cone's curve";
  // Other options: a shorter ladder ends at a lower top accuracy.
  PrimitiveCurveOptions shortLadder = options;
  shortLadder.maxTriangles = 64;
  Result<AccuracyCurve> shortCurve = primitiveAccuracyCurve(cone, shortLadder);
  ASSERT_TRUE(shortCurve.ok());
  EXPECT_LT(shortCurve->maxAccuracy(), first->maxAccuracy());
}

// Threads asking for curves at once (the memo is shared) get what one
// thread alone gets.
TEST(PrimitiveCurves, ConcurrentCallsGiveTheSequentialCurves) {
  PrimitiveCurveOptions options;
  options.maxTriangles = 512;
  std::vector<PrimitiveShape> shapes;
  for (int i = 0; i < 24; ++i) {
    const float r = 0.5f + 0.0371f * float(i % 6);
    shapes.push_back(i % 3 == 0   ? PrimitiveShape::sphere(r)
                     : i % 3 == 1 ? PrimitiveShape::cylinder(r, 1.0f + 0.1f * float(i))
                                  : PrimitiveShape::cone(r, 1.0f + 0.1f * float(i)));
  }
  std::vector<AccuracyCurve> sequential;
  for (const PrimitiveShape& s : shapes) {
    Result<AccuracyCurve> c = primitiveAccuracyCurve(s, options);
    ASSERT_TRUE(c.ok());
    sequential.push_back(*c);
  }
  std::vector<std::vector<AccuracyCurve>> perThread(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t i = 0; i < shapes.size(); ++i) {
        const PrimitiveShape& s = shapes[(i + 5 * std::size_t(t)) % shapes.size()];
        Result<AccuracyCurve> c = primitiveAccuracyCurve(s, options);
        perThread[t].push_back(c.ok() ? *c : AccuracyCurve());
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < 4; ++t) {
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      expectSameSegments(perThread[t][i], sequential[(i + 5 * std::size_t(t)) % shapes.size()]);
    }
  }
}

}  // namespace
}  // namespace thinlod
