#include "thinlod/simplifier/surface_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "test_meshes.h"

namespace thinlod::simplifier {
namespace {

using thinlod::testing::makeGrid;
using thinlod::testing::makeIcosphere;
using thinlod::testing::maxSagitta;

SurfaceErrorOptions fewSamples(std::size_t n = 20000) {
  SurfaceErrorOptions options;
  options.samplesPerMesh = n;
  return options;
}

TEST(SurfaceError, PlaneOffsetByHeightGivesMaxAndMeanEqualToHeight) {
  const float h = 0.25f;
  const IndexedMesh a = makeGrid(8, 4.0f, 0.0f);
  const IndexedMesh b = makeGrid(3, 4.0f, h);
  Result<SurfaceError> e = measureSurfaceError(a, b, fewSamples());
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_NEAR(e->maxForward, h, 1e-6);
  EXPECT_NEAR(e->maxBackward, h, 1e-6);
  EXPECT_NEAR(e->meanForward, h, 1e-6);
  EXPECT_NEAR(e->meanBackward, h, 1e-6);
  EXPECT_NEAR(e->relativeMax(), h / (4.0 * std::sqrt(2.0)), 1e-6);
}

TEST(SurfaceError, IdenticalMeshesGiveZero) {
  const IndexedMesh sphere = makeIcosphere(3, 1.0f);
  Result<SurfaceError> e = measureSurfaceError(sphere, sphere, fewSamples());
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_LE(e->max(), 1e-6);
  EXPECT_LE(e->mean(), 1e-7);
}

TEST(SurfaceError, SphereVersusTessellationMatchesSagitta) {
  const float radius = 2.0f;
  // The "sphere" is a fine tessellation whose own sagitta bounds how far it
  // is from the true sphere; the coarse one's sagitta is the analytic answer.
  const IndexedMesh fine = makeIcosphere(6, radius);  // 81920 triangles
  const IndexedMesh coarse = makeIcosphere(1, radius);
  const double expected = maxSagitta(coarse, radius);
  const double fineSagitta = maxSagitta(fine, radius);
  ASSERT_GT(expected, 50.0 * fineSagitta);
  Result<SurfaceError> e = measureSurfaceError(fine, coarse, fewSamples(100000));
  ASSERT_TRUE(e.ok()) << e.status().toString();
  // Sampling can only miss the worst point, so allow 1% below; the fine
  // mesh lies within fineSagitta of the sphere.
  EXPECT_NEAR(e->maxForward, expected, fineSagitta + 0.01 * expected);
  EXPECT_NEAR(e->maxBackward, expected, fineSagitta + 0.01 * expected);
  EXPECT_LE(e->max(), expected + fineSagitta);
  // Backward mean: the area average of (radius - |p|) over the coarse
  // surface, integrated independently on a dense barycentric grid.
  const int steps = 200;
  double weighted = 0.0;
  double area = 0.0;
  for (std::size_t t = 0; t < coarse.indices.size(); t += 3) {
    const glm::dvec3 a(coarse.positions[coarse.indices[t]]);
    const glm::dvec3 b(coarse.positions[coarse.indices[t + 1]]);
    const glm::dvec3 c(coarse.positions[coarse.indices[t + 2]]);
    const double faceArea = 0.5 * glm::length(glm::cross(b - a, c - a));
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < steps; ++i) {
      for (int j = 0; i + j < steps; ++j) {
        const double u = (i + 1.0 / 3.0) / steps, v = (j + 1.0 / 3.0) / steps;
        sum += radius - glm::length(a + u * (b - a) + v * (c - a));
        ++count;
      }
    }
    weighted += faceArea * sum / count;
    area += faceArea;
  }
  EXPECT_NEAR(e->meanBackward, weighted / area, fineSagitta + 0.01 * expected);
}

TEST(SurfaceError, RefinementFindsAnInteriorPeakFromFewSamples) {
  // The coarse sphere's farthest points from the sphere are its face
  // circumcentres (interior points). 400 samples (5 per face) miss them; the
  // local refinement of the worst samples must climb to them.
  const float radius = 2.0f;
  const IndexedMesh fine = makeIcosphere(5, radius);
  const IndexedMesh coarse = makeIcosphere(1, radius);
  const double expected = maxSagitta(coarse, radius);
  const double fineSagitta = maxSagitta(fine, radius);
  SurfaceErrorOptions options = fewSamples(400);
  options.includeVerticesAndEdges = false;
  Result<SurfaceError> e = measureSurfaceError(fine, coarse, options);
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_NEAR(e->maxBackward, expected, fineSagitta + 0.002 * expected);
}

TEST(SurfaceError, SwappingArgumentsSwapsDirections) {
  const IndexedMesh fine = makeIcosphere(3, 1.0f);
  const IndexedMesh coarse = makeIcosphere(1, 1.0f);
  Result<SurfaceError> ab = measureSurfaceError(fine, coarse, fewSamples());
  Result<SurfaceError> ba = measureSurfaceError(coarse, fine, fewSamples());
  ASSERT_TRUE(ab.ok() && ba.ok());
  EXPECT_EQ(ab->maxForward, ba->maxBackward);
  EXPECT_EQ(ab->maxBackward, ba->maxForward);
  EXPECT_EQ(ab->meanForward, ba->meanBackward);
  EXPECT_EQ(ab->meanBackward, ba->meanForward);
  EXPECT_EQ(ab->max(), ba->max());
}

TEST(SurfaceError, MissingPartShowsOnlyInForwardDirection) {
  // The simplified mesh covers half of the original: every simplified point
  // lies on the original (backward 0), the uncovered half is up to 2 away.
  const IndexedMesh full = makeGrid(8, 4.0f, 0.0f);
  IndexedMesh half = makeGrid(8, 4.0f, 0.0f);
  half.indices.resize(half.indices.size() / 2);  // rows y in [0, 2]
  Result<SurfaceError> e = measureSurfaceError(full, half, fewSamples());
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_NEAR(e->maxForward, 2.0, 1e-6);   // the far edge y = 4 is sampled
  EXPECT_NEAR(e->meanForward, 0.5, 0.02);  // half the area at mean distance 1
  EXPECT_LE(e->maxBackward, 1e-6);
}

TEST(SurfaceError, FeatureSamplesCatchASpikeRandomSamplesMiss) {
  // A single thin spike: its tip vertex is 1 away from the plane but the
  // spike's area is tiny, so random samples alone underestimate the max.
  IndexedMesh plane = makeGrid(4, 4.0f, 0.0f);
  IndexedMesh spiky = plane;
  spiky.positions.emplace_back(2.0f, 2.0f, 1.0f);
  spiky.positions.emplace_back(2.001f, 2.0f, 0.0f);
  const std::uint32_t tip = static_cast<std::uint32_t>(spiky.positions.size() - 2);
  spiky.indices.insert(spiky.indices.end(), {12, tip + 1, tip});
  SurfaceErrorOptions withFeatures = fewSamples(2000);
  SurfaceErrorOptions randomOnly = withFeatures;
  randomOnly.includeVerticesAndEdges = false;
  Result<SurfaceError> a = measureSurfaceError(plane, spiky, withFeatures);
  Result<SurfaceError> b = measureSurfaceError(plane, spiky, randomOnly);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NEAR(a->maxBackward, 1.0, 1e-6);
  EXPECT_LT(b->maxBackward, 0.99);
}

TEST(SurfaceError, DeterministicForASeedAndVariesWithIt) {
  const IndexedMesh fine = makeIcosphere(3, 1.0f);
  const IndexedMesh coarse = makeIcosphere(1, 1.0f);
  SurfaceErrorOptions o = fewSamples(5000);
  Result<SurfaceError> first = measureSurfaceError(fine, coarse, o);
  Result<SurfaceError> again = measureSurfaceError(fine, coarse, o);
  o.seed = 99;
  Result<SurfaceError> other = measureSurfaceError(fine, coarse, o);
  ASSERT_TRUE(first.ok() && again.ok() && other.ok());
  EXPECT_EQ(first->meanForward, again->meanForward);
  EXPECT_EQ(first->maxForward, again->maxForward);
  EXPECT_NE(first->meanForward, other->meanForward);
  EXPECT_NEAR(first->meanForward, other->meanForward, 0.02 * first->meanForward);
}

TEST(SurfaceError, EmptyMeshIsInvalidArgument) {
  const IndexedMesh sphere = makeIcosphere(1, 1.0f);
  const IndexedMesh empty;
  Result<SurfaceError> a = measureSurfaceError(empty, sphere);
  Result<SurfaceError> b = measureSurfaceError(sphere, empty);
  ASSERT_FALSE(a.ok());
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(a.status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(b.status().code(), ErrorCode::kInvalidArgument);
}

TEST(SurfaceError, OutOfRangeIndexIsInvalidArgument) {
  IndexedMesh bad = makeIcosphere(1, 1.0f);
  bad.indices[4] = 100000;
  Result<SurfaceError> e = measureSurfaceError(makeIcosphere(1, 1.0f), bad);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), ErrorCode::kInvalidArgument);
}

TEST(SurfaceError, NanPositionIsInvalidArgument) {
  IndexedMesh bad = makeIcosphere(1, 1.0f);
  bad.positions[3].y = std::numeric_limits<float>::quiet_NaN();
  Result<SurfaceError> e = measureSurfaceError(bad, makeIcosphere(1, 1.0f));
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), ErrorCode::kInvalidArgument);
}

TEST(SurfaceError, ZeroAreaMeshIsInvalidArgument) {
  IndexedMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.indices = {0, 1, 2};
  Result<SurfaceError> e = measureSurfaceError(makeIcosphere(1, 1.0f), flat);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), ErrorCode::kInvalidArgument);
}

TEST(SurfaceError, ZeroSamplesIsInvalidArgument) {
  const IndexedMesh sphere = makeIcosphere(1, 1.0f);
  Result<SurfaceError> e = measureSurfaceError(sphere, sphere, fewSamples(0));
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), ErrorCode::kInvalidArgument);
}

TEST(SurfaceError, DegenerateTrianglesAreMeasuredSafely) {
  // A sliver (collinear) triangle among valid ones: distances stay finite.
  IndexedMesh mesh = makeGrid(2, 1.0f, 0.0f);
  mesh.positions.emplace_back(0.0f, 0.0f, 0.5f);
  mesh.positions.emplace_back(0.5f, 0.0f, 0.5f);
  mesh.positions.emplace_back(1.0f, 0.0f, 0.5f);
  const std::uint32_t s = static_cast<std::uint32_t>(mesh.positions.size() - 3);
  mesh.indices.insert(mesh.indices.end(), {s, s + 1, s + 2});
  Result<SurfaceError> e = measureSurfaceError(makeGrid(2, 1.0f, 0.0f), mesh, fewSamples(1000));
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_TRUE(std::isfinite(e->maxBackward));
  EXPECT_NEAR(e->maxBackward, 0.5, 1e-6);  // the sliver's vertices are 0.5 above
}

// A grid with uv = (x, y) / size: object units per uv unit = size.
IndexedMesh texturedGrid(int cells, float size) {
  IndexedMesh m = makeGrid(cells, size, 0.0f);
  for (const glm::vec3& p : m.positions) m.uvs.emplace_back(p.x / size, p.y / size);
  return m;
}

TEST(UvError, IdenticalMeshesGiveZero) {
  const IndexedMesh m = texturedGrid(8, 2.0f);
  Result<UvError> e = measureUvError(m, m);
  ASSERT_TRUE(e.ok()) << e.status().toString();
  EXPECT_LT(e->maxUv, 1e-6);
  EXPECT_LT(e->maxDisplacement, 1e-6);
  EXPECT_EQ(e->samples, UvErrorOptions{}.samples);
  EXPECT_NEAR(uvArea(m), 1.0, 1e-6);
}

TEST(UvError, ShiftedUvsGiveTheShiftInUvAndTheTexelsDisplacement) {
  const IndexedMesh m = texturedGrid(8, 2.0f);  // 2 object units per uv unit
  IndexedMesh shifted = m;
  for (glm::vec2& uv : shifted.uvs) uv += glm::vec2(0.03f, -0.04f);  // |shift| = 0.05
  Result<UvError> e = measureUvError(m, shifted);
  ASSERT_TRUE(e.ok());
  // The surfaces coincide, so the uv at the closest point is the
  // sample's own: every sample is off by the shift.
  EXPECT_NEAR(e->meanUv, 0.05, 1e-5);
  EXPECT_NEAR(e->maxUv, 0.05, 1e-5);
  EXPECT_NEAR(e->p95Uv, 0.05, 1e-5);
  // Each texel is drawn 0.05 * 2 = 0.1 from its place, except where the
  // shifted uv leaves the texture's square (strips of width 0.03 and 0.04
  // along two sides): there the texel's nearest place is on the border.
  EXPECT_NEAR(e->maxDisplacement, 0.1, 1e-4);
  EXPECT_NEAR(e->p95Displacement, 0.1, 1e-4);
  EXPECT_GT(e->meanDisplacement, 0.09);
  EXPECT_LE(e->meanDisplacement, 0.1 + 1e-6);
}

TEST(UvError, ASeamIsNotChargedTheDistanceBetweenItsCharts) {
  // Two halves of a strip with their own uv charts (x < 0.5 -> u in [0, 0.25],
  // x >= 0.5 -> u in [0.75, 1]): the vertices at x = 0.5 are duplicated.
  IndexedMesh m;
  for (int side = 0; side < 2; ++side) {
    const auto first = static_cast<std::uint32_t>(m.positions.size());
    for (int j = 0; j <= 1; ++j) {
      for (int i = 0; i <= 4; ++i) {
        const float x = 0.5f * side + 0.125f * i;
        m.positions.emplace_back(x, static_cast<float>(j), 0.0f);
        m.uvs.emplace_back(side == 0 ? 0.5f * x : 0.75f + 0.5f * (x - 0.5f), static_cast<float>(j));
      }
    }
    for (std::uint32_t i = 0; i < 4; ++i) {
      const std::uint32_t v = first + i;
      m.indices.insert(m.indices.end(), {v, v + 1, v + 6, v, v + 6, v + 5});
    }
  }
  Result<UvError> self = measureUvError(m, m);
  ASSERT_TRUE(self.ok());
  EXPECT_LT(self->maxUv, 1e-6) << "a sample on the seam has two correct uvs";
  EXPECT_LT(self->maxDisplacement, 1e-6);
  // Welding the seam by position (the right half takes the left half's uvs
  // at x = 0.5) interpolates across the atlas in the first right column.
  IndexedMesh welded = m;
  for (std::uint32_t& v : welded.indices) {
    if (v == 10) v = 4;
    if (v == 15) v = 9;
  }
  Result<UvError> torn = measureUvError(m, welded);
  ASSERT_TRUE(torn.ok());
  // In that column (1/8 of the area) the error falls linearly from 0.5 at
  // the seam to 0 at x = 0.625: mean 0.25 there, 1/32 overall.
  EXPECT_GT(torn->maxUv, 0.45);
  EXPECT_NEAR(torn->meanUv, 1.0 / 32.0, 0.002);
  // The texels of that column come from between the charts or from the
  // left chart's edge, so none lands farther than the column's width from
  // where it is drawn.
  EXPECT_GT(torn->maxDisplacement, 0.05);
  EXPECT_LE(torn->maxDisplacement, 0.125 + 1e-6);
}

TEST(UvError, BadInputsAreErrors) {
  const IndexedMesh m = texturedGrid(2, 1.0f);
  IndexedMesh bare = m;
  bare.uvs.clear();
  EXPECT_EQ(measureUvError(m, bare).status().code(), ErrorCode::kInvalidArgument);
  EXPECT_EQ(measureUvError(bare, m).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh flatUv = m;
  for (glm::vec2& uv : flatUv.uvs) uv = glm::vec2(0.5f);
  EXPECT_EQ(measureUvError(flatUv, m).status().code(), ErrorCode::kInvalidArgument);
  UvErrorOptions none;
  none.samples = 0;
  EXPECT_EQ(measureUvError(m, m, none).status().code(), ErrorCode::kInvalidArgument);
  UvErrorOptions nan;
  nan.tieFactor = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(measureUvError(m, m, nan).status().code(), ErrorCode::kInvalidArgument);
  IndexedMesh broken = m;
  broken.uvs[0].x = std::numeric_limits<float>::infinity();
  EXPECT_EQ(measureUvError(m, broken).status().code(), ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::simplifier
