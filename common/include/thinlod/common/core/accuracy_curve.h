// Accuracy curves (Pasman & Jansen 2002, sections 3.1-3.4): the minimal
// resources r needed to reach accuracy a, piecewise linear and monotone.
//
// Contract:
// - Accuracy a = 1/d, d = distortion. Relative curves measure d as a fraction
//   of the object's diameter; absolute curves as an angle in radians, so an
//   absolute accuracy is in rad^-1. Resources are non-negative (triangles,
//   bytes, bytes/s: the caller decides the unit; one unit per curve).
// - A curve has a closed domain [minAccuracy, maxAccuracy]. Segment i covers
//   [A_i, A_{i+1}) (the last one [A_n, maxAccuracy]) with r = R_i + K_i a.
//   Invariants, checked by fromTriples and kept by every operation:
//   A strictly increasing, all values finite, K_i >= 0, r >= 0 on the domain,
//   r non-decreasing (vertical jumps up at a knot are allowed).
// - Internally a segment stores its value at its start (V_i = r(A_i)) instead
//   of the intercept R_i: R_i = V_i - K_i A_i cancels catastrophically when A
//   is large, V_i does not. triples() converts back to the paper's (A, R, K).
// - The empty curve (no segments) is "nothing to render": it costs 0 at every
//   accuracy; sum() ignores it and lowerEnvelope() ignores it.
// - Pure value type: no I/O, no globals; safe to use from any thread.
#pragma once

#include <optional>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod {

// One piece in the paper's notation: r = R + K a from A on.
struct CurveTriple {
  double A = 0.0;
  double R = 0.0;
  double K = 0.0;
};

// One piece as stored: r = value + slope (a - start).
struct CurveSegment {
  double start = 0.0;  // A_i
  double value = 0.0;  // r(A_i)
  double slope = 0.0;  // K_i >= 0
};

// One measured operating point: `resources` reach accuracy `accuracy`.
struct AccuracySample {
  double accuracy = 0.0;
  double resources = 0.0;
};

class AccuracyCurve {
 public:
  AccuracyCurve() = default;

  // Validates the invariants above; the error (kInvalidArgument) names the
  // offending triple/segment. Decreases or negative values within a few ulps
  // of the caller's own rounding (R + K A) are repaired, not rejected.
  // An empty list gives the empty curve.
  static Result<AccuracyCurve> fromTriples(const std::vector<CurveTriple>& triples,
                                           double maxAccuracy);
  static Result<AccuracyCurve> fromSegments(std::vector<CurveSegment> segments, double maxAccuracy);
  // A single representation: accuracy `accuracy` for `resources` (a point curve,
  // domain [accuracy, accuracy]).
  static AccuracyCurve point(double accuracy, double resources);

  bool empty() const { return segments_.empty(); }
  const std::vector<CurveSegment>& segments() const { return segments_; }
  std::vector<CurveTriple> triples() const;
  double minAccuracy() const;  // precondition: !empty()
  double maxAccuracy() const { return maxAccuracy_; }

  // r(a) on the domain. Left of the domain: r(minAccuracy) (a better
  // representation is acceptable). Right of it: +infinity (unreachable).
  // This is "the fewest resources that reach at least accuracy a".
  // Empty curve: 0 everywhere. NaN a: +infinity. Exactly non-decreasing in
  // floating point (every operation keeps that), O(log segments).
  double resourcesFor(double a) const;
  // Like resourcesFor, but right of the domain r(maxAccuracy): the Group
  // rule "render at your best when more is asked".
  double resourcesForClamped(double a) const;

  // The largest accuracy a in the domain with resourcesFor(a) <= budget
  // (exactly: a double for which resourcesFor(a) <= budget holds and the next
  // larger double either leaves the domain or exceeds the budget).
  // std::nullopt when even minAccuracy costs more than budget (or budget is
  // NaN). At a vertical jump the answer is the last double below the jump.
  // Empty curve: +infinity for budget >= 0 (everything is free).
  std::optional<double> maxAccuracyWithin(double budget) const;

  // Scales the accuracy axis by factor > 0: new r(a) = old r(a / factor).
  // Relative -> absolute: factor = closestDistance / diameter. Relative
  // rescaling of a child into its group: factor = groupDiameter / childDiameter.
  AccuracyCurve scaledAccuracy(double factor) const;

  // Maps the resource axis: new r(a) = offset + scale * r(a) on the same
  // accuracy domain (triangles -> link bytes: offset = a frame's overhead,
  // scale = bytes per triangle). offset finite, scale finite and >= 0 (the
  // curve stays monotone). A result that overflows a double is refused by
  // fromSegments; then the curve is returned unchanged.
  AccuracyCurve affineResources(double offset, double scale) const;

  // Group node: r(a) = sum of children's resourcesForClamped(a), on the union
  // of the children's domains (horizontal extension both sides).
  // O(total knots * log children); values carry O(log children) roundings.
  static AccuracyCurve sum(const std::vector<const AccuracyCurve*>& children);
  // LOD node: r(a) = min of children's resourcesFor(a) (left extension only),
  // crossings computed exactly, monotone, no cracks. Also reports which child
  // is cheapest on each resulting segment (index into `children`).
  // A child stays available up to and including its maxAccuracy, so where
  // the cheapest child runs out the envelope jumps at the next double above
  // that maxAccuracy. Where two lines cross within one ulp of a knot the
  // result may exceed the pointwise minimum by at most slope * ulp(a), the
  // price of staying monotone. O(total knots and crossings * log children).
  static AccuracyCurve lowerEnvelope(const std::vector<const AccuracyCurve*>& children,
                                     std::vector<int>* segmentOwner = nullptr);

  // Fits a curve with at most maxSegments segments to measured samples,
  // conservatively: for every a, the fitted r(a) >= the measured staircase
  // min{ r_j : a_j >= a }, so the curve never promises more accuracy than was
  // measured for a given resource. Samples need not be sorted or monotone
  // (dominated samples are dropped). Errors on no samples, non-finite data,
  // negative resources or maxSegments < 1. Domain [lowest, highest sample
  // accuracy]. With enough segments the result is the staircase itself;
  // otherwise the pieces minimise the worst ratio r(a) / staircase(a) over the
  // domain (knots at measured steps, vertical jumps allowed).
  static Result<AccuracyCurve> fitConservative(std::vector<AccuracySample> samples,
                                               int maxSegments);

 private:
  std::vector<CurveSegment> segments_;
  double maxAccuracy_ = 0.0;
};

}  // namespace thinlod
