// Randomized property tests of AccuracyCurve against brute-force sampling.
// Fixed seeds; magnitudes from 1e-9 to 1e12; nearly parallel and nearly
// coincident segments. More than 100,000 random curves in total.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "curve_test_util.h"
#include "thinlod/common/core/accuracy_curve.h"

namespace thinlod {
namespace {

using testing::closeRelative;
using testing::closeWithAxisSlack;
using testing::CurveShape;
using testing::kInf;
using testing::logUniform;
using testing::maxSlope;
using testing::nextDown;
using testing::nextUp;
using testing::perturbedCurve;
using testing::probePoints;
using testing::randomCurve;
using testing::satisfiesInvariants;

constexpr double kRelativeTolerance = 1e-9;

CurveShape randomShape(std::mt19937_64& rng, int maxKnots) {
  CurveShape shape;
  shape.maxKnots = maxKnots;
  shape.accuracyScale = logUniform(rng, -9, 11);
  shape.resourceScale = logUniform(rng, -9, 12);
  // Sometimes far from zero, so knots are close in relative terms.
  shape.accuracyOffset =
      std::uniform_real_distribution<double>(0, 1)(rng) < 0.3 ? shape.accuracyScale * 1e6 : 0.0;
  return shape;
}

// A family of children for one trial: independent curves, or perturbed
// copies of one base (nearly coincident / nearly parallel segments).
std::vector<AccuracyCurve> randomFamily(std::mt19937_64& rng, int maxChildren) {
  std::uniform_int_distribution<int> count(1, maxChildren);
  std::uniform_int_distribution<int> mode(0, 3);
  const int n = count(rng);
  const CurveShape shape = randomShape(rng, 7);
  std::vector<AccuracyCurve> curves;
  if (mode(rng) == 0) {
    const AccuracyCurve base = randomCurve(rng, shape);
    const double nudge = logUniform(rng, -15, -6);
    curves.push_back(base);
    for (int i = 1; i < n; ++i) curves.push_back(perturbedCurve(rng, base, nudge));
  } else {
    for (int i = 0; i < n; ++i) curves.push_back(randomCurve(rng, shape));
  }
  return curves;
}

std::vector<const AccuracyCurve*> pointersTo(const std::vector<AccuracyCurve>& curves) {
  std::vector<const AccuracyCurve*> out;
  for (const AccuracyCurve& c : curves) out.push_back(&c);
  return out;
}

::testing::AssertionResult monotoneAt(const AccuracyCurve& curve, const std::vector<double>& xs) {
  double previous = -kInf;
  for (double x : xs) {
    const double r = curve.resourcesFor(x);
    if (r < previous) {
      return ::testing::AssertionFailure()
             << "r decreases at a=" << x << ": " << r << " < " << previous;
    }
    previous = r;
  }
  return ::testing::AssertionSuccess();
}

TEST(AccuracyCurveProperty, SumMatchesBruteForce) {
  std::mt19937_64 rng(20020611);
  int curvesSeen = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::vector<AccuracyCurve> children = randomFamily(rng, 5);
    curvesSeen += static_cast<int>(children.size());
    const auto pointers = pointersTo(children);
    const AccuracyCurve sum = AccuracyCurve::sum(pointers);
    ASSERT_TRUE(satisfiesInvariants(sum)) << "trial " << trial;
    double lo = kInf, hi = -kInf;
    for (const AccuracyCurve& c : children) {
      lo = std::min(lo, c.minAccuracy());
      hi = std::max(hi, c.maxAccuracy());
    }
    ASSERT_EQ(sum.minAccuracy(), lo);
    ASSERT_EQ(sum.maxAccuracy(), hi);
    const std::vector<double> xs = probePoints(rng, pointers, lo, hi, 16);
    for (double x : xs) {
      if (x > hi) continue;
      double want = 0.0;
      for (const AccuracyCurve& c : children) want += c.resourcesForClamped(x);
      ASSERT_TRUE(closeRelative(sum.resourcesFor(x), want, kRelativeTolerance))
          << "trial " << trial << " a=" << x;
    }
    ASSERT_TRUE(monotoneAt(sum, xs)) << "trial " << trial;
  }
  EXPECT_GT(curvesSeen, 30000);
}

TEST(AccuracyCurveProperty, EnvelopeMatchesBruteForceAndOwners) {
  std::mt19937_64 rng(19660);
  int curvesSeen = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::vector<AccuracyCurve> children = randomFamily(rng, 6);
    curvesSeen += static_cast<int>(children.size());
    const auto pointers = pointersTo(children);
    std::vector<int> owner;
    const AccuracyCurve env = AccuracyCurve::lowerEnvelope(pointers, &owner);
    ASSERT_TRUE(satisfiesInvariants(env)) << "trial " << trial;
    ASSERT_EQ(owner.size(), env.segments().size());
    double lo = kInf, hi = -kInf;
    for (const AccuracyCurve& c : children) {
      lo = std::min(lo, c.minAccuracy());
      hi = std::max(hi, c.maxAccuracy());
    }
    ASSERT_EQ(env.minAccuracy(), lo);
    ASSERT_EQ(env.maxAccuracy(), hi);
    const std::vector<double> xs = probePoints(rng, pointers, lo, hi, 16);
    const auto& segs = env.segments();
    // Where lines cross within one ulp of accuracy the envelope may sit up to
    // slope * ulp(a) above the pointwise minimum (see lowerEnvelope).
    double slopeBound = 0.0;
    for (const AccuracyCurve& c : children) slopeBound = std::max(slopeBound, maxSlope(c));
    for (double x : xs) {
      double want = kInf;
      for (const AccuracyCurve& c : children) want = std::min(want, c.resourcesFor(x));
      const double got = env.resourcesFor(x);
      ASSERT_TRUE(closeWithAxisSlack(got, want, kRelativeTolerance, slopeBound, x))
          << "trial " << trial << " a=" << x;
      if (x < lo || x > hi) continue;
      // The reported owner really delivers (about) that cost here.
      const auto it = std::upper_bound(segs.begin(), segs.end(), x,
                                       [](double v, const CurveSegment& s) { return v < s.start; });
      const int o = owner[static_cast<std::size_t>(it - segs.begin()) - 1];
      ASSERT_TRUE(
          closeWithAxisSlack(children[o].resourcesFor(x), got, kRelativeTolerance, slopeBound, x))
          << "trial " << trial << " owner " << o << " a=" << x;
    }
    ASSERT_TRUE(monotoneAt(env, xs)) << "trial " << trial;
  }
  EXPECT_GT(curvesSeen, 30000);
}

TEST(AccuracyCurveProperty, EnvelopeOfManyChildren) {
  // Wider trees exercise the tournament beyond a couple of levels.
  std::mt19937_64 rng(77);
  for (int trial = 0; trial < 300; ++trial) {
    const CurveShape shape = randomShape(rng, 5);
    std::vector<AccuracyCurve> children;
    const int n = std::uniform_int_distribution<int>(10, 80)(rng);
    for (int i = 0; i < n; ++i) children.push_back(randomCurve(rng, shape));
    const auto pointers = pointersTo(children);
    const AccuracyCurve env = AccuracyCurve::lowerEnvelope(pointers);
    const AccuracyCurve sum = AccuracyCurve::sum(pointers);
    ASSERT_TRUE(satisfiesInvariants(env));
    ASSERT_TRUE(satisfiesInvariants(sum));
    const std::vector<double> xs =
        probePoints(rng, pointers, env.minAccuracy(), env.maxAccuracy(), 200);
    double slopeBound = 0.0;
    for (const AccuracyCurve& c : children) slopeBound = std::max(slopeBound, maxSlope(c));
    for (double x : xs) {
      double wantMin = kInf, wantSum = 0.0;
      for (const AccuracyCurve& c : children) {
        wantMin = std::min(wantMin, c.resourcesFor(x));
        wantSum += c.resourcesForClamped(x);
      }
      ASSERT_TRUE(
          closeWithAxisSlack(env.resourcesFor(x), wantMin, kRelativeTolerance, slopeBound, x));
      if (x <= sum.maxAccuracy()) {
        ASSERT_TRUE(closeRelative(sum.resourcesFor(x), wantSum, kRelativeTolerance));
      }
    }
  }
}

TEST(AccuracyCurveProperty, MaxAccuracyWithinInvertsResourcesFor) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 30000; ++trial) {
    const AccuracyCurve c = randomCurve(rng, randomShape(rng, 8));
    std::vector<double> budgets;
    for (const CurveSegment& s : c.segments()) {
      budgets.push_back(s.value);
      budgets.push_back(nextUp(s.value));
      budgets.push_back(nextDown(s.value));
    }
    const double top = c.resourcesFor(c.maxAccuracy());
    budgets.push_back(top);
    budgets.push_back(top * 2.0);
    for (int i = 0; i < 6; ++i) {
      const double a = c.minAccuracy() + unit(rng) * (c.maxAccuracy() - c.minAccuracy());
      budgets.push_back(c.resourcesFor(a));
      budgets.push_back(top * unit(rng));
    }
    for (double b : budgets) {
      const std::optional<double> a = c.maxAccuracyWithin(b);
      if (!a) {
        ASSERT_GT(c.resourcesFor(c.minAccuracy()), b) << "trial " << trial;
        continue;
      }
      ASSERT_GE(*a, c.minAccuracy());
      ASSERT_LE(*a, c.maxAccuracy());
      ASSERT_LE(c.resourcesFor(*a), b) << "trial " << trial << " budget " << b;
      const double up = nextUp(*a);
      ASSERT_TRUE(up > c.maxAccuracy() || c.resourcesFor(up) > b)
          << "trial " << trial << " budget " << b << " a=" << *a;
    }
  }
}

TEST(AccuracyCurveProperty, ScaledAccuracyMatchesDefinition) {
  std::mt19937_64 rng(31337);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 15000; ++trial) {
    const AccuracyCurve c = randomCurve(rng, randomShape(rng, 8));
    const double factor = logUniform(rng, -6, 6);
    const AccuracyCurve s = c.scaledAccuracy(factor);
    ASSERT_TRUE(satisfiesInvariants(s)) << "trial " << trial;
    ASSERT_TRUE(closeRelative(s.minAccuracy(), c.minAccuracy() * factor, 1e-15));
    ASSERT_TRUE(closeRelative(s.maxAccuracy(), c.maxAccuracy() * factor, 1e-15));
    const double width = c.maxAccuracy() - c.minAccuracy();
    for (int i = 0; i < 16; ++i) {
      const double y = c.minAccuracy() + unit(rng) * width;
      // Stay away from knots, where rounding of y * factor may pick the
      // neighbouring segment (a different value across a jump).
      bool nearKnot = false;
      for (const CurveSegment& seg : c.segments()) {
        nearKnot |= std::fabs(seg.start - y) <= 1e-12 * std::max(std::fabs(y), width);
      }
      if (nearKnot || y * factor > s.maxAccuracy()) continue;
      ASSERT_TRUE(closeWithAxisSlack(s.resourcesFor(y * factor), c.resourcesFor(y),
                                     kRelativeTolerance, maxSlope(c), y))
          << "trial " << trial << " factor " << factor;
    }
  }
}

TEST(AccuracyCurveProperty, ScaledAccuracyRoundTrips) {
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 5000; ++trial) {
    const AccuracyCurve c = randomCurve(rng, randomShape(rng, 6));
    const double factor = logUniform(rng, -3, 3);
    const AccuracyCurve back = c.scaledAccuracy(factor).scaledAccuracy(1.0 / factor);
    ASSERT_TRUE(closeRelative(back.maxAccuracy(), c.maxAccuracy(), 1e-14));
    ASSERT_TRUE(closeWithAxisSlack(back.resourcesFor(back.minAccuracy()),
                                   c.resourcesFor(c.minAccuracy()), kRelativeTolerance, maxSlope(c),
                                   c.minAccuracy()));
  }
}

// The measured staircase: the cheapest sample reaching at least a.
double staircase(const std::vector<AccuracySample>& samples, double a) {
  double best = kInf;
  for (const AccuracySample& s : samples) {
    if (s.accuracy >= a) best = std::min(best, s.resources);
  }
  return best;
}

void checkFit(const std::vector<AccuracySample>& samples, int maxSegments, std::mt19937_64& rng,
              int trial) {
  auto fit = AccuracyCurve::fitConservative(samples, maxSegments);
  ASSERT_TRUE(fit.ok()) << fit.status().toString();
  ASSERT_TRUE(satisfiesInvariants(*fit)) << "trial " << trial;
  ASSERT_LE(fit->segments().size(), static_cast<std::size_t>(maxSegments));
  double lo = kInf, hi = -kInf;
  for (const AccuracySample& s : samples) {
    lo = std::min(lo, s.accuracy);
    hi = std::max(hi, s.accuracy);
  }
  ASSERT_EQ(fit->minAccuracy(), lo);
  ASSERT_EQ(fit->maxAccuracy(), hi);
  std::vector<double> xs;
  for (const AccuracySample& s : samples) {
    xs.push_back(s.accuracy);
    xs.push_back(nextUp(s.accuracy));
    xs.push_back(nextDown(s.accuracy));
  }
  std::uniform_real_distribution<double> inside(lo, hi);
  for (int i = 0; i < 64; ++i) xs.push_back(inside(rng));
  for (double x : xs) {
    if (x < lo || x > hi) continue;
    ASSERT_GE(fit->resourcesFor(x), staircase(samples, x))
        << "trial " << trial << " a=" << x << " maxSegments " << maxSegments;
  }
}

TEST(AccuracyCurveProperty, FitIsNeverOptimistic) {
  std::mt19937_64 rng(1234567);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20000; ++trial) {
    const double accuracyScale = logUniform(rng, -9, 11);
    const double resourceScale = logUniform(rng, -9, 12);
    const int n = std::uniform_int_distribution<int>(1, 40)(rng);
    std::vector<AccuracySample> samples;
    for (int i = 0; i < n; ++i) {
      // Mostly a noisy increasing trend (like measured meshes), some outliers.
      const double a = accuracyScale * (1.0 + 100.0 * unit(rng));
      const double trend = resourceScale * (a / accuracyScale) * (0.5 + unit(rng));
      samples.push_back({a, unit(rng) < 0.1 ? resourceScale * 200 * unit(rng) : trend});
    }
    if (unit(rng) < 0.2) samples.push_back(samples.front());  // duplicate
    checkFit(samples, std::uniform_int_distribution<int>(1, 8)(rng), rng, trial);
  }
}

TEST(AccuracyCurveProperty, FitOfLargeSampleSetsThinsConservatively) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<AccuracySample> samples;
    const int n = std::uniform_int_distribution<int>(300, 2000)(rng);
    for (int i = 0; i < n; ++i) {
      const double a = 1.0 + 1000.0 * unit(rng);
      samples.push_back({a, a * a * (0.9 + 0.2 * unit(rng))});
    }
    checkFit(samples, std::uniform_int_distribution<int>(1, 12)(rng), rng, trial);
  }
}

// The fit minimises the worst ratio r(a) / staircase(a); that it never grows with more
// segments is CurveFitTightness.WorstRatioDoesNotGrowWithMoreSegments
// (curve_fit_tightness_test.cpp).

}  // namespace
}  // namespace thinlod
