// Test helpers for accuracy curves: invariant checks, brute-force references
// and random curve generators (fixed seeds are chosen by the tests).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "thinlod/common/core/accuracy_curve.h"

namespace thinlod::testing {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline double nextUp(double x) { return std::nextafter(x, kInf); }
inline double nextDown(double x) { return std::nextafter(x, -kInf); }

inline double evaluateSegment(const CurveSegment& s, double a) {
  return s.value + s.slope * (a - s.start);
}

// The invariants of accuracy_curve.h, checked exactly in floating point.
inline ::testing::AssertionResult satisfiesInvariants(const AccuracyCurve& curve) {
  const auto& segs = curve.segments();
  if (segs.empty()) return ::testing::AssertionSuccess();
  if (!std::isfinite(curve.maxAccuracy()) || curve.maxAccuracy() < segs.back().start) {
    return ::testing::AssertionFailure() << "bad maxAccuracy " << curve.maxAccuracy();
  }
  if (segs.front().value < 0.0) {
    return ::testing::AssertionFailure() << "negative value " << segs.front().value;
  }
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const CurveSegment& s = segs[i];
    if (!std::isfinite(s.start) || !std::isfinite(s.value) || !std::isfinite(s.slope)) {
      return ::testing::AssertionFailure() << "segment " << i << " not finite";
    }
    if (s.slope < 0.0) return ::testing::AssertionFailure() << "segment " << i << " slope < 0";
    if (i > 0) {
      if (!(s.start > segs[i - 1].start)) {
        return ::testing::AssertionFailure() << "segment " << i << " start not increasing";
      }
      const double end = evaluateSegment(segs[i - 1], s.start);
      if (s.value < end) {
        return ::testing::AssertionFailure()
               << "segment " << i << " decreases: " << s.value << " < " << end;
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// |got - want| <= rel * |want| (both infinite and equal also passes).
inline ::testing::AssertionResult closeRelative(double got, double want, double rel) {
  if (got == want) return ::testing::AssertionSuccess();
  if (std::fabs(got - want) <= rel * std::fabs(want)) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << got << " want " << want << " (rel "
                                       << std::fabs(got - want) / std::fabs(want) << ")";
}

// Like closeRelative, plus slack for a few ulps of error along the accuracy
// axis (slope bound times ulp(a)): what remains when accuracies themselves
// are rounded, e.g. knots scaled by a factor far from their spacing.
inline ::testing::AssertionResult closeWithAxisSlack(double got, double want, double rel,
                                                     double slopeBound, double a) {
  const double ulp = nextUp(std::fabs(a)) - std::fabs(a);
  const double allowed = rel * std::fabs(want) + 8.0 * slopeBound * ulp;
  if (got == want || std::fabs(got - want) <= allowed) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << got << " want " << want << " (diff "
                                       << std::fabs(got - want) << " allowed " << allowed << ")";
}

inline double maxSlope(const AccuracyCurve& curve) {
  double m = 0.0;
  for (const CurveSegment& s : curve.segments()) m = std::max(m, s.slope);
  return m;
}

// Draws a log-uniform magnitude 10^[lo, hi].
inline double logUniform(std::mt19937_64& rng, double lo, double hi) {
  return std::pow(10.0, std::uniform_real_distribution<double>(lo, hi)(rng));
}

struct CurveShape {
  int maxKnots = 6;
  double accuracyScale = 1.0;   // typical knot spacing
  double resourceScale = 1.0;   // typical value
  double accuracyOffset = 0.0;  // where the domain starts, roughly
};

// A random valid curve: random knot spacing, slopes (sometimes 0), jumps
// (sometimes 0), sometimes a zero-length last segment or a point curve.
inline AccuracyCurve randomCurve(std::mt19937_64& rng, const CurveShape& shape) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> knotCount(1, shape.maxKnots);
  const int n = knotCount(rng);
  std::vector<CurveSegment> segs;
  double a = shape.accuracyOffset + shape.accuracyScale * 10.0 * unit(rng);
  double value = unit(rng) < 0.1 ? 0.0 : shape.resourceScale * unit(rng);
  for (int i = 0; i < n; ++i) {
    CurveSegment s;
    s.start = a;
    if (i > 0) {
      const double end = evaluateSegment(segs.back(), a);
      const double jump = unit(rng) < 0.5 ? 0.0 : shape.resourceScale * unit(rng);
      value = end + jump;
    }
    s.value = value;
    s.slope = unit(rng) < 0.2 ? 0.0 : shape.resourceScale / shape.accuracyScale * 2.0 * unit(rng);
    segs.push_back(s);
    a = a + shape.accuracyScale * (0.01 + unit(rng));
  }
  double maxAccuracy = segs.back().start;
  if (unit(rng) < 0.85) maxAccuracy += shape.accuracyScale * (0.01 + unit(rng));
  auto curve = AccuracyCurve::fromSegments(segs, maxAccuracy);
  EXPECT_TRUE(curve.ok()) << curve.status().toString();
  return curve.ok() ? curve.value() : AccuracyCurve();
}

// A copy of `base` nudged by relative amounts of size `nudge`: knots, values
// and slopes, keeping the curve valid. Produces nearly coincident and nearly
// parallel segments when combined with `base`.
inline AccuracyCurve perturbedCurve(std::mt19937_64& rng, const AccuracyCurve& base, double nudge) {
  std::uniform_real_distribution<double> symmetric(-1.0, 1.0);
  std::vector<CurveSegment> segs = base.segments();
  const double span = std::max(base.maxAccuracy() - base.minAccuracy(), 1e-300);
  for (std::size_t i = 0; i < segs.size(); ++i) {
    segs[i].start += nudge * span * symmetric(rng) * 0.01;
    segs[i].slope *= 1.0 + nudge * symmetric(rng);
    segs[i].value *= 1.0 + nudge * symmetric(rng);
  }
  std::sort(segs.begin(), segs.end(),
            [](const CurveSegment& x, const CurveSegment& y) { return x.start < y.start; });
  std::vector<CurveSegment> fixed;
  for (CurveSegment s : segs) {
    if (!fixed.empty()) {
      if (!(s.start > fixed.back().start)) continue;
      s.value = std::max(s.value, evaluateSegment(fixed.back(), s.start));
    }
    s.value = std::max(s.value, 0.0);
    fixed.push_back(s);
  }
  const double maxAccuracy = std::max(fixed.back().start, base.maxAccuracy());
  auto curve = AccuracyCurve::fromSegments(fixed, maxAccuracy);
  EXPECT_TRUE(curve.ok()) << curve.status().toString();
  return curve.ok() ? curve.value() : AccuracyCurve();
}

// Sample accuracies that probe every knot of `curves` from both sides, plus
// uniform points across [lo, hi].
inline std::vector<double> probePoints(std::mt19937_64& rng,
                                       const std::vector<const AccuracyCurve*>& curves, double lo,
                                       double hi, int uniformCount) {
  std::vector<double> xs;
  for (const AccuracyCurve* c : curves) {
    if (c->empty()) continue;
    for (const CurveSegment& s : c->segments()) {
      xs.push_back(s.start);
      xs.push_back(nextUp(s.start));
      xs.push_back(nextDown(s.start));
    }
    xs.push_back(c->maxAccuracy());
    xs.push_back(nextUp(c->maxAccuracy()));
    xs.push_back(nextDown(c->maxAccuracy()));
  }
  std::uniform_real_distribution<double> inside(lo, hi);
  for (int i = 0; i < uniformCount; ++i) xs.push_back(inside(rng));
  xs.push_back(lo);
  xs.push_back(hi);
  std::sort(xs.begin(), xs.end());
  return xs;
}

}  // namespace thinlod::testing
