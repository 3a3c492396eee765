// AccuracyCurve::fitConservative: tight in relative terms, never optimistic.
// The fit's quality is the ratio r_fit(a) / S(a) to the measured staircase
// S(a) = min{ r_j : a_j >= a }. Since r_fit is non-decreasing and S is
// constant on (a_{j-1}, a_j], the worst ratio on a step is at its right end,
// so the exact worst ratio is max_j r_fit(a_j) / r_j over the frontier.
// Ladders: every tessellation of a primitive up to 16384 triangles (as
// primitiveAccuracyCurve enumerates them), and synthetic r = K a^p.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "curve_test_util.h"
#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/mesh/primitives.h"

namespace thinlod {
namespace {

using testing::kInf;
using testing::logUniform;
using testing::nextDown;
using testing::nextUp;
using testing::satisfiesInvariants;

constexpr int kLadderMaxTriangles = 16384;

// The Pareto frontier (accuracy and resources strictly increasing).
std::vector<AccuracySample> frontierOf(std::vector<AccuracySample> samples) {
  std::sort(samples.begin(), samples.end(), [](const AccuracySample& x, const AccuracySample& y) {
    return x.accuracy != y.accuracy ? x.accuracy < y.accuracy : x.resources < y.resources;
  });
  std::vector<AccuracySample> frontier;
  double cheapestAbove = kInf;
  for (std::size_t i = samples.size(); i-- > 0;) {
    if (samples[i].resources < cheapestAbove) {
      if (!frontier.empty() && frontier.back().accuracy == samples[i].accuracy) {
        frontier.back() = samples[i];
      } else {
        frontier.push_back(samples[i]);
      }
      cheapestAbove = samples[i].resources;
    }
  }
  std::reverse(frontier.begin(), frontier.end());
  return frontier;
}

// S(a) from a frontier sorted by accuracy.
double staircaseOf(const std::vector<AccuracySample>& frontier, double a) {
  const auto it =
      std::lower_bound(frontier.begin(), frontier.end(), a,
                       [](const AccuracySample& s, double value) { return s.accuracy < value; });
  return it == frontier.end() ? kInf : it->resources;
}

// max over the domain of r_fit / S (exact, see the top comment).
double worstRatioOf(const AccuracyCurve& fit, const std::vector<AccuracySample>& samples) {
  double worst = 0.0;
  for (const AccuracySample& s : frontierOf(samples)) {
    worst = std::max(worst, fit.resourcesFor(s.accuracy) / s.resources);
  }
  return worst;
}

struct Tightness {
  double worst = 0.0;    // max over the domain of r_fit / S
  double logMean = 0.0;  // mean of r_fit / S over log(a), domain [lowest, highest]
};

// Frontier resources must be > 0 (ratios).
Tightness tightnessOf(const AccuracyCurve& fit, const std::vector<AccuracySample>& samples) {
  const std::vector<AccuracySample> frontier = frontierOf(samples);
  Tightness t;
  t.worst = worstRatioOf(fit, samples);
  const double lo = fit.minAccuracy();
  const double hi = fit.maxAccuracy();
  constexpr int kGrid = 20000;
  double sum = 0.0;
  for (int i = 0; i < kGrid; ++i) {
    const double a = std::min(hi, lo * std::pow(hi / lo, (i + 0.5) / kGrid));
    sum += fit.resourcesFor(a) / staircaseOf(frontier, a);
  }
  t.logMean = sum / kGrid;
  return t;
}

std::vector<AccuracySample> sphereLadder(const PrimitiveShape& shape) {
  std::vector<AccuracySample> ladder;
  for (int rings = 2; 2 * std::max(3, rings) * (rings - 1) <= kLadderMaxTriangles; ++rings) {
    const int hi = std::min(4 * rings, kLadderMaxTriangles / (2 * (rings - 1)));
    for (int segments = std::max(3, rings); segments <= hi; ++segments) {
      const TessellationParams p{segments, rings};
      ladder.push_back(
          {tessellationAccuracy(shape, p), static_cast<double>(tessellationTriangles(shape, p))});
    }
  }
  return ladder;
}

std::vector<AccuracySample> roundLadder(const PrimitiveShape& shape) {
  std::vector<AccuracySample> ladder;
  for (int n = 3; tessellationTriangles(shape, TessellationParams{n, 2}) <= kLadderMaxTriangles;
       ++n) {
    const TessellationParams p{n, 2};
    ladder.push_back(
        {tessellationAccuracy(shape, p), static_cast<double>(tessellationTriangles(shape, p))});
  }
  return ladder;
}

// Every double near every sample and a dense uniform and geometric grid.
::testing::AssertionResult neverOptimistic(const AccuracyCurve& fit,
                                           const std::vector<AccuracySample>& samples,
                                           std::mt19937_64& rng) {
  const std::vector<AccuracySample> frontier = frontierOf(samples);
  double lo = kInf, hi = -kInf;
  std::vector<double> xs;
  for (const AccuracySample& s : samples) {
    lo = std::min(lo, s.accuracy);
    hi = std::max(hi, s.accuracy);
    xs.insert(xs.end(), {s.accuracy, nextUp(s.accuracy), nextDown(s.accuracy)});
  }
  for (const CurveSegment& s : fit.segments()) {
    xs.insert(xs.end(), {s.start, nextUp(s.start), nextDown(s.start)});
  }
  std::uniform_real_distribution<double> inside(lo, hi);
  for (int i = 0; i < 256; ++i) xs.push_back(inside(rng));
  if (lo > 0.0) {
    for (int i = 0; i <= 256; ++i) xs.push_back(lo * std::pow(hi / lo, i / 256.0));
  }
  for (double x : xs) {
    if (!(x >= lo && x <= hi)) continue;
    const double need = staircaseOf(frontier, x);
    if (!(fit.resourcesFor(x) >= need)) {
      return ::testing::AssertionFailure() << "optimistic at a=" << x << ": fit "
                                           << fit.resourcesFor(x) << " < staircase " << need;
    }
  }
  return ::testing::AssertionSuccess();
}

// The best fit by at most maxSegments flat pieces (a coarser staircase),
// minimising the worst ratio: brute force over the frontier. Flat pieces
// are among the lines fitConservative may use, so it is never worse.
double bestFlatWorstRatio(const std::vector<AccuracySample>& samples, int maxSegments) {
  const std::vector<AccuracySample> f = frontierOf(samples);
  const std::size_t m = f.size();
  // worst[j][q]: best worst ratio covering frontier 0..q-1 with j flat pieces.
  std::vector<std::vector<double>> worst(maxSegments + 1, std::vector<double>(m + 1, kInf));
  worst[0][0] = 1.0;
  for (int j = 1; j <= maxSegments; ++j) {
    for (std::size_t q = 1; q <= m; ++q) {
      for (std::size_t p = 0; p < q; ++p) {
        // A flat piece at f[q-1] over points p..q-1: worst at point p.
        const double piece = f[q - 1].resources / f[p].resources;
        worst[j][q] = std::min(worst[j][q], std::max(worst[j - 1][p], piece));
      }
    }
  }
  double best = kInf;
  for (int j = 1; j <= maxSegments; ++j) best = std::min(best, worst[j][m]);
  return best;
}

void report(const char* name, int segments, const AccuracyCurve& fit, const Tightness& t) {
  std::printf("[ tightness ] %s: %d segments allowed, %zu used, worst ratio %.4f, log-mean %.4f\n",
              name, segments, fit.segments().size(), t.worst, t.logMean);
  ::testing::Test::RecordProperty(std::string(name) + "_worst", std::to_string(t.worst));
  ::testing::Test::RecordProperty(std::string(name) + "_log_mean", std::to_string(t.logMean));
}

TEST(CurveFitTightness, SphereLadderWithin1_5At16Segments) {
  const std::vector<AccuracySample> ladder = sphereLadder(PrimitiveShape::sphere(0.3f));
  auto fit = AccuracyCurve::fitConservative(ladder, 16);
  ASSERT_TRUE(fit.ok()) << fit.status().toString();
  ASSERT_LE(fit->segments().size(), 16u);
  std::mt19937_64 rng(11);
  ASSERT_TRUE(neverOptimistic(*fit, ladder, rng));
  const Tightness t = tightnessOf(*fit, ladder);
  report("sphere(0.3)", 16, *fit, t);
  EXPECT_LE(t.worst, 1.5);
}

TEST(CurveFitTightness, CylinderLadderWithin1_5At16Segments) {
  const std::vector<AccuracySample> ladder = roundLadder(PrimitiveShape::cylinder(0.2f, 1.0f));
  auto fit = AccuracyCurve::fitConservative(ladder, 16);
  ASSERT_TRUE(fit.ok()) << fit.status().toString();
  ASSERT_LE(fit->segments().size(), 16u);
  std::mt19937_64 rng(12);
  ASSERT_TRUE(neverOptimistic(*fit, ladder, rng));
  const Tightness t = tightnessOf(*fit, ladder);
  report("cylinder(0.2,1)", 16, *fit, t);
  EXPECT_LE(t.worst, 1.5);
}

TEST(CurveFitTightness, PowerLawsOverThreeDecadesWithin1_5At16Segments) {
  // r = K a^p, p in [1, 2], 200 geometric samples over 3 decades of a.
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worstSeen = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    const double p = 1.0 + unit(rng);
    const double k = logUniform(rng, -3, 3);
    const double a0 = logUniform(rng, -2, 2);
    std::vector<AccuracySample> samples;
    for (int i = 0; i < 200; ++i) {
      const double a = a0 * std::pow(1000.0, i / 199.0);
      samples.push_back({a, k * std::pow(a, p)});
    }
    auto fit = AccuracyCurve::fitConservative(samples, 16);
    ASSERT_TRUE(fit.ok()) << fit.status().toString();
    ASSERT_LE(fit->segments().size(), 16u);
    ASSERT_TRUE(neverOptimistic(*fit, samples, rng)) << "trial " << trial;
    const Tightness t = tightnessOf(*fit, samples);
    worstSeen = std::max(worstSeen, t.worst);
    EXPECT_LE(t.worst, 1.5) << "trial " << trial << " p=" << p;
  }
  std::printf("[ tightness ] r = K a^p, p in [1,2], 3 decades: worst ratio over 40 trials %.4f\n",
              worstSeen);
}

TEST(CurveFitTightness, NeverWorseThanTheBestFlatStaircase) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<AccuracySample> samples;
    const int n = std::uniform_int_distribution<int>(2, 40)(rng);
    const double p = 0.5 + 2.0 * unit(rng);
    for (int i = 0; i < n; ++i) {
      const double a = logUniform(rng, 0, 3);
      samples.push_back({a, std::pow(a, p) * (0.5 + unit(rng))});
    }
    const int segments = std::uniform_int_distribution<int>(1, 8)(rng);
    auto fit = AccuracyCurve::fitConservative(samples, segments);
    ASSERT_TRUE(fit.ok());
    const double flat = bestFlatWorstRatio(samples, segments);
    ASSERT_LE(worstRatioOf(*fit, samples), flat * (1.0 + 1e-9))
        << "trial " << trial << " segments " << segments;
  }
}

TEST(CurveFitTightness, WorstRatioDoesNotGrowWithMoreSegments) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<AccuracySample> samples;
    for (int i = 0; i < 60; ++i) {
      const double a = logUniform(rng, 0, 3);
      samples.push_back({a, a * (0.8 + 0.4 * unit(rng))});
    }
    double previous = kInf;
    for (int segments = 1; segments <= 12; ++segments) {
      auto fit = AccuracyCurve::fitConservative(samples, segments);
      ASSERT_TRUE(fit.ok());
      const double worst = worstRatioOf(*fit, samples);
      ASSERT_LE(worst, previous * (1.0 + 1e-9)) << "trial " << trial << " segments " << segments;
      previous = worst;
    }
  }
}

TEST(CurveFitTightness, LargeNoisySampleSetsAreThinnedConservativelyAndStayTight) {
  // 10^5 measurements of r ~ a^1.5 (as bench_curves fits): the frontier is
  // thinned before fitting, which must stay conservative and tight.
  std::mt19937_64 rng(5150);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<AccuracySample> samples(100000);
  for (AccuracySample& s : samples) {
    s.accuracy = 1.0 + 999.0 * unit(rng);
    s.resources = std::pow(s.accuracy, 1.5) * (0.9 + 0.2 * unit(rng));
  }
  for (int segments : {8, 16}) {
    auto fit = AccuracyCurve::fitConservative(samples, segments);
    ASSERT_TRUE(fit.ok()) << fit.status().toString();
    ASSERT_TRUE(satisfiesInvariants(*fit));
    ASSERT_LE(fit->segments().size(), static_cast<std::size_t>(segments));
    ASSERT_TRUE(neverOptimistic(*fit, samples, rng));
    const Tightness t = tightnessOf(*fit, samples);
    report(segments == 8 ? "1e5 noisy a^1.5, 8" : "1e5 noisy a^1.5, 16", segments, *fit, t);
    EXPECT_LE(t.worst, 1.5);
  }
}

TEST(CurveFitTightness, NeverOptimisticAtExtremeMagnitudes) {
  // Samples spread over several decades at scales 1e-9..1e11 (accuracy) and
  // 1e-9..1e12 (resources); noise, outliers, duplicates and zero resources.
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 3000; ++trial) {
    const double accuracyScale = logUniform(rng, -9, 9);
    const double resourceScale = logUniform(rng, -9, 9);
    const double decades = 4.0 * unit(rng);
    const double p = 0.3 + 2.0 * unit(rng);
    const int n = std::uniform_int_distribution<int>(1, 300)(rng);
    std::vector<AccuracySample> samples;
    for (int i = 0; i < n; ++i) {
      const double x = std::pow(10.0, decades * unit(rng));
      double r = resourceScale * std::pow(x, p) * (0.7 + 0.6 * unit(rng));
      if (unit(rng) < 0.05) r = resourceScale * 1e3 * unit(rng);  // outlier
      if (unit(rng) < 0.02) r = 0.0;
      samples.push_back({accuracyScale * x, r});
    }
    if (unit(rng) < 0.2) samples.push_back(samples.front());
    const int segments = std::uniform_int_distribution<int>(1, 20)(rng);
    auto fit = AccuracyCurve::fitConservative(samples, segments);
    ASSERT_TRUE(fit.ok()) << fit.status().toString();
    ASSERT_TRUE(satisfiesInvariants(*fit)) << "trial " << trial;
    ASSERT_LE(fit->segments().size(), static_cast<std::size_t>(segments)) << "trial " << trial;
    ASSERT_TRUE(neverOptimistic(*fit, samples, rng)) << "trial " << trial;
  }
}

TEST(CurveFitTightness, NeverOptimisticWhenAccuraciesAreUlpsApart) {
  // Frontier points one ulp apart, and a domain starting at accuracy 0.
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    std::vector<AccuracySample> samples;
    double a = trial % 2 == 0 ? 0.0 : logUniform(rng, -6, 6);
    double r = unit(rng) < 0.3 ? 0.0 : logUniform(rng, -6, 6);
    const int n = std::uniform_int_distribution<int>(2, 50)(rng);
    for (int i = 0; i < n; ++i) {
      samples.push_back({a, r});
      a = unit(rng) < 0.5 ? nextUp(a) : a + std::fabs(a) * unit(rng) + 1e-3 * unit(rng);
      r += r * 2.0 * unit(rng) + 1e-3 * unit(rng);
    }
    const int segments = std::uniform_int_distribution<int>(1, 6)(rng);
    auto fit = AccuracyCurve::fitConservative(samples, segments);
    ASSERT_TRUE(fit.ok()) << fit.status().toString();
    ASSERT_TRUE(satisfiesInvariants(*fit)) << "trial " << trial;
    ASSERT_LE(fit->segments().size(), static_cast<std::size_t>(segments));
    ASSERT_TRUE(neverOptimistic(*fit, samples, rng)) << "trial " << trial;
  }
}

}  // namespace
}  // namespace thinlod
