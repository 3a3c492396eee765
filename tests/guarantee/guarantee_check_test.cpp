// Unit tests of the pure guarantee check: silhouette distance (against a
// brute-force reference on random masks), the check camera and the verdict.
#include "thinlod/simplifier/guarantee_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

CoverageMask blank(int w, int h) {
  CoverageMask m;
  m.width = w;
  m.height = h;
  m.covered.assign(static_cast<std::size_t>(w) * h, 0);
  return m;
}

void fillRect(CoverageMask& m, int x0, int y0, int x1, int y1, std::uint8_t value = 1) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) m.covered[static_cast<std::size_t>(y) * m.width + x] = value;
}

// max over pixels of `from` (not in `to`) of the distance to the nearest pixel of `to`.
double bruteDirected(const CoverageMask& from, const CoverageMask& to) {
  double worst = 0.0;
  for (int y = 0; y < from.height; ++y) {
    for (int x = 0; x < from.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * from.width + x;
      if (!from.covered[i] || to.covered[i]) continue;
      long long best = -1;  // squared; -1: no covered pixel in `to`
      for (int v = 0; v < to.height; ++v)
        for (int u = 0; u < to.width; ++u)
          if (to.covered[static_cast<std::size_t>(v) * to.width + u]) {
            const long long d2 = (long long)(u - x) * (u - x) + (long long)(v - y) * (v - y);
            if (best < 0 || d2 < best) best = d2;
          }
      worst = std::max(worst, best < 0 ? std::numeric_limits<double>::infinity()
                                       : std::sqrt(static_cast<double>(best)));
    }
  }
  return worst;
}

TEST(SilhouetteDistance, IdenticalMasksAreZero) {
  CoverageMask a = blank(20, 10);
  fillRect(a, 3, 2, 9, 8);
  auto d = silhouetteDistance(a, a);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d->pixels(), 0.0);
  EXPECT_EQ(d->missingCount, 0u);
  EXPECT_EQ(d->extraCount, 0u);
}

TEST(SilhouetteDistance, ShiftedSquareIsTheShift) {
  CoverageMask a = blank(32, 32);
  CoverageMask b = blank(32, 32);
  fillRect(a, 4, 4, 12, 12);
  fillRect(b, 7, 4, 15, 12);
  auto d = silhouetteDistance(a, b);
  ASSERT_TRUE(d.ok());
  EXPECT_DOUBLE_EQ(d->missingPixels, 3.0);
  EXPECT_DOUBLE_EQ(d->extraPixels, 3.0);
}

TEST(SilhouetteDistance, HoleCountsAsMissingFromItsMiddle) {
  CoverageMask full = blank(40, 40);
  fillRect(full, 5, 5, 35, 35);
  CoverageMask holed = full;
  fillRect(holed, 10, 10, 21, 21, 0);  // 11 x 11 hole: its centre is 6 px from the rim
  auto d = silhouetteDistance(full, holed);
  ASSERT_TRUE(d.ok());
  EXPECT_DOUBLE_EQ(d->missingPixels, 6.0);
  EXPECT_EQ(d->extraPixels, 0.0);
  EXPECT_EQ(d->missingCount, 121u);
}

TEST(SilhouetteDistance, EmptyShownIsInfinite) {
  CoverageMask a = blank(8, 8);
  fillRect(a, 1, 1, 3, 3);
  auto d = silhouetteDistance(a, blank(8, 8));
  ASSERT_TRUE(d.ok());
  EXPECT_TRUE(std::isinf(d->missingPixels));
  auto both = silhouetteDistance(blank(8, 8), blank(8, 8));
  ASSERT_TRUE(both.ok());
  EXPECT_EQ(both->pixels(), 0.0);
}

TEST(SilhouetteDistance, RejectsMismatchedOrMalformedMasks) {
  EXPECT_FALSE(silhouetteDistance(blank(8, 8), blank(8, 9)).ok());
  CoverageMask bad = blank(8, 8);
  bad.covered.pop_back();
  EXPECT_FALSE(silhouetteDistance(bad, blank(8, 8)).ok());
  EXPECT_FALSE(silhouetteDistance(CoverageMask{}, CoverageMask{}).ok());
}

TEST(SilhouetteDistance, MatchesBruteForceOnRandomMasks) {
  std::mt19937 rng(1302);
  for (int trial = 0; trial < 300; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 23);
    const int h = 1 + static_cast<int>(rng() % 17);
    const double density = (rng() % 100) / 100.0;
    CoverageMask a = blank(w, h);
    CoverageMask b = blank(w, h);
    std::bernoulli_distribution pa(density), pb(density * 0.5);
    for (auto& c : a.covered) c = pa(rng);
    for (auto& c : b.covered) c = pb(rng);
    auto d = silhouetteDistance(a, b);
    ASSERT_TRUE(d.ok());
    const double missing = bruteDirected(a, b);
    const double extra = bruteDirected(b, a);
    if (std::isinf(missing)) {
      EXPECT_TRUE(std::isinf(d->missingPixels)) << trial;
    } else {
      EXPECT_NEAR(d->missingPixels, missing, 1e-9) << trial;
    }
    if (std::isinf(extra)) {
      EXPECT_TRUE(std::isinf(d->extraPixels)) << trial;
    } else {
      EXPECT_NEAR(d->extraPixels, extra, 1e-9) << trial;
    }
  }
}

// The ring search, the transform, and the default (search, falling back to
// the transform past its budget; a tiny budget falls back mid-search) must
// give the same values, and the brute-force ones.
void expectAllPathsMatchBruteForce(const CoverageMask& a, const CoverageMask& b, int trial) {
  const double missing = bruteDirected(a, b);
  const double extra = bruteDirected(b, a);
  auto transformed = silhouetteDistance(a, b, 0.0);
  ASSERT_TRUE(transformed.ok());
  for (double visits : {1e-4, kSilhouetteSearchVisitsPerPixel,
                        std::numeric_limits<double>::infinity()}) {
    auto d = silhouetteDistance(a, b, visits);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(d->missingPixels, transformed->missingPixels) << trial << " visits " << visits;
    EXPECT_EQ(d->extraPixels, transformed->extraPixels) << trial << " visits " << visits;
    EXPECT_EQ(d->missingCount, transformed->missingCount) << trial;
    EXPECT_EQ(d->extraCount, transformed->extraCount) << trial;
  }
  if (std::isinf(missing)) {
    EXPECT_TRUE(std::isinf(transformed->missingPixels)) << trial;
  } else {
    EXPECT_NEAR(transformed->missingPixels, missing, 1e-9) << trial;
  }
  if (std::isinf(extra)) {
    EXPECT_TRUE(std::isinf(transformed->extraPixels)) << trial;
  } else {
    EXPECT_NEAR(transformed->extraPixels, extra, 1e-9) << trial;
  }
}

TEST(SilhouetteDistance, SearchAndTransformAgreeOnRandomMasks) {
  std::mt19937 rng(2011);
  for (int trial = 0; trial < 200; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 40);
    const int h = 1 + static_cast<int>(rng() % 30);
    const double density = (rng() % 100) / 100.0;
    CoverageMask a = blank(w, h);
    CoverageMask b = blank(w, h);
    std::bernoulli_distribution pa(density), pb(density * (rng() % 3) * 0.5);
    for (auto& c : a.covered) c = pa(rng);
    for (auto& c : b.covered) c = pb(rng);
    expectAllPathsMatchBruteForce(a, b, trial);
  }
}

// What the meshed check measures: a wide silhouette (an ellipse across the
// mask) and the same with a few pixels, bites and one distant island changed.
TEST(SilhouetteDistance, SparseDifferencesOnWideMasksMatchBruteForce) {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 16; ++trial) {
    const int w = 200 + static_cast<int>(rng() % 240);
    const int h = 24 + static_cast<int>(rng() % 48);
    CoverageMask reference = blank(w, h);
    const double cx = w * 0.5, cy = h * 0.5, rx = w * 0.4, ry = h * 0.4;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const double u = (x - cx) / rx, v = (y - cy) / ry;
        reference.covered[static_cast<std::size_t>(y) * w + x] = u * u + v * v <= 1.0;
      }
    CoverageMask shown = reference;
    const int flips = 1 + static_cast<int>(rng() % 40);
    for (int k = 0; k < flips; ++k) {  // single pixels anywhere
      const std::size_t i = rng() % shown.covered.size();
      shown.covered[i] = !shown.covered[i];
    }
    const int bites = static_cast<int>(rng() % 4);
    for (int k = 0; k < bites; ++k) {  // small rectangles off the rim (missing)
      const int x0 = static_cast<int>(cx + rx * 0.9) - static_cast<int>(rng() % 6);
      const int y0 = static_cast<int>(cy) - static_cast<int>(rng() % 6);
      fillRect(shown, std::max(0, x0), std::max(0, y0), std::min(w, x0 + 1 + int(rng() % 8)),
               std::min(h, y0 + 1 + int(rng() % 8)), 0);
    }
    if (trial % 3 == 0) fillRect(shown, 0, 0, 2, 2);  // an island far from the ellipse (extra)
    expectAllPathsMatchBruteForce(reference, shown, trial);
    expectAllPathsMatchBruteForce(shown, reference, 100 + trial);
  }
}

TEST(CheckCamera, ResolvesTheRequestedTangentAndHoldsTheBall) {
  auto camera = makeCheckCamera({0, 0, 5}, {0, 0, 0}, 1.0, 1e-3);
  ASSERT_TRUE(camera.ok());
  EXPECT_LE(camera->tangentPerPixel, 1e-3);
  // The ball's silhouette half-angle asin(1/5) fits in the half field of view.
  const double halfSpan = 0.5 * camera->tangentPerPixel * camera->pixels;
  EXPECT_GT(halfSpan, std::tan(std::asin(0.2)));
  // A tiny tangent clamps at maxPixels and says what it reached.
  auto coarse = makeCheckCamera({0, 0, 5}, {0, 0, 0}, 1.0, 1e-7, 256, 512);
  ASSERT_TRUE(coarse.ok());
  EXPECT_EQ(coarse->pixels, 512);
  EXPECT_GT(coarse->tangentPerPixel, 1e-7);
}

TEST(CheckCamera, RejectsEyeInsideAndBadInput) {
  EXPECT_FALSE(makeCheckCamera({0, 0, 1.005f}, {0, 0, 0}, 1.0, 1e-3).ok());
  EXPECT_FALSE(makeCheckCamera({0, 0, 5}, {0, 0, 0}, 0.0, 1e-3).ok());
  EXPECT_FALSE(makeCheckCamera({0, 0, 5}, {0, 0, 0}, 1.0, -1.0).ok());
  EXPECT_FALSE(makeCheckCamera({NAN, 0, 5}, {0, 0, 0}, 1.0, 1e-3).ok());
  EXPECT_FALSE(
      makeCheckCamera({0, 0, 5}, {0, 0, 0}, std::numeric_limits<double>::infinity(), 1e-3).ok());
}

TEST(GuaranteeVerdict, StatedErrorIsLOverAD) {
  auto camera = makeCheckCamera({0, 0, 5}, {0, 0, 0}, 1.0, 1e-3);
  ASSERT_TRUE(camera.ok());
  SilhouetteDistance measured;
  measured.missingPixels = 3.0;
  // L = 2, eye 5 from the centre: D = 4; a = 100 -> 2 / 400 = 5 mrad.
  GuaranteeVerdict v = judgeGuarantee(measured, *camera, {0, 0, 5}, {0, 0, 0}, 2.0, 100.0);
  EXPECT_DOUBLE_EQ(v.distance, 4.0);
  EXPECT_DOUBLE_EQ(v.statedRadians, 2.0 / 400.0);
  EXPECT_DOUBLE_EQ(v.measuredRadians, 3.0 * camera->tangentPerPixel);
  EXPECT_FALSE(v.exceeds);
  measured.missingPixels = 5e-3 / camera->tangentPerPixel + 2.0;  // two pixels over
  EXPECT_TRUE(judgeGuarantee(measured, *camera, {0, 0, 5}, {0, 0, 0}, 2.0, 100.0).exceeds);
  // The distance is clamped like the scheduler's (minimalDistance).
  EXPECT_DOUBLE_EQ(
      judgeGuarantee(measured, *camera, {0, 0, 1.02f}, {0, 0, 0}, 2.0, 100.0, 0.1).distance, 0.1);
  EXPECT_TRUE(
      std::isinf(judgeGuarantee(measured, *camera, {0, 0, 5}, {0, 0, 0}, 2.0, 0.0).statedRadians));
}

// impostorValidity with a length l: inside the cone the bound stays within
// min(maxAngularError, l / d), d the eye's distance from the centre (the angle
// a relative-accuracy credit allows there), over random objects, distances
// and magnitudes (fixed seed); a smaller l never widens the cone.
TEST(ImpostorValidityLength, BoundStaysWithinTheCreditedAngleInsideTheCone) {
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked = 0;
  int narrowed = 0;  // cones the length made narrower than the plain one
  for (int trial = 0; trial < 60; ++trial) {
    const double scale = std::pow(10.0, -3.0 + 6.0 * unit(rng));
    std::vector<glm::vec3> points;
    while (points.size() < 200) {
      const glm::dvec3 p(2 * unit(rng) - 1, 2 * unit(rng) - 1, 2 * unit(rng) - 1);
      if (glm::length(p) <= 1.0) points.push_back(glm::vec3(p * scale));
    }
    const double distance = scale * (3.0 + 40.0 * unit(rng));
    const glm::vec3 viewpoint =
        glm::normalize(glm::vec3(unit(rng) - 0.5, unit(rng) - 0.5, 1.0f)) * float(distance);
    auto framing = frameImpostor(points, viewpoint, ImpostorOptions());
    ASSERT_TRUE(framing.ok());
    ImpostorErrorModel model;
    model.depthDeviation = scale * (0.01 + 2.0 * unit(rng));
    model.silhouetteRadius = unit(rng) < 0.5 ? 0.0 : scale * unit(rng);
    const double maxError = 1e-3 + 2e-2 * unit(rng);
    const double length = maxError * distance * (0.05 + 2.0 * unit(rng));
    const ConicRange range = impostorValidity(*framing, model, maxError, length);
    const ConicRange plain = impostorValidity(*framing, model, maxError);
    const ConicRange tighter = impostorValidity(*framing, model, maxError, 0.5 * length);
    EXPECT_TRUE(range.containsPoint(glm::dvec3(viewpoint))) << trial;
    EXPECT_LE(range.alpha(), plain.alpha() + 1e-12) << trial;
    EXPECT_LE(tighter.alpha(), range.alpha() + 1e-12) << trial;
    EXPECT_EQ(plain, impostorValidity(*framing, model, maxError, 0.0)) << trial;
    narrowed += range.alpha() < plain.alpha();
    if (!(range.alpha() > 0.0)) continue;
    const glm::dvec3 axis = range.direction();
    const glm::dvec3 side = glm::normalize(glm::cross(axis, glm::dvec3(0.0, 1.0, 0.0)));
    const glm::dvec3 side2 = glm::cross(axis, side);
    const double farthest = std::min(range.maxDistance(), 50.0 * distance);
    for (int k = 0; k < 200; ++k) {
      const double theta = range.alpha() * std::sqrt(unit(rng));
      const double phi = 6.283185307179586 * unit(rng);
      const glm::dvec3 direction =
          axis * std::cos(theta) + (side * std::cos(phi) + side2 * std::sin(phi)) * std::sin(theta);
      const double d = range.minDistance() + (farthest - range.minDistance()) * unit(rng);
      const glm::dvec3 eye = range.center() + direction * d;
      if (!range.containsPoint(eye)) continue;
      const double bound = impostorErrorBound(*framing, model, glm::vec3(eye));
      ASSERT_LE(bound, std::min(maxError, length / d) * (1.0 + 1e-3))
          << "trial " << trial << " distance " << d << " angle " << theta;
      ++checked;
    }
  }
  EXPECT_GT(checked, 5000);
  EXPECT_GT(narrowed, 10);
}

}  // namespace
}  // namespace thinlod::simplifier
