// Conic ranges (Pasman & Jansen 2002, section 3.5, Figure 8): the part of
// space in which a representation or an absolute accuracy curve is valid.
//
// Contract:
// - A range is { p : minDistance <= |p - center| <= maxDistance and the angle
//   between p - center and direction is <= alpha }. Metres and radians.
//   maxDistance may be +infinity; alpha in (0, pi], pi = every direction.
//   The apex (p == center) counts as inside the cone when minDistance == 0.
// - The default range is "everywhere" (distance [0, inf), alpha = pi).
//   nowhere() is the empty range (the result of disjoint intersections).
// - containsSphere(c, r) is conservative: true only if every point of the
//   closed ball lies inside; a safety margin of ~1e-12 relative to the
//   coordinates absorbs rounding, so balls touching the boundary to within
//   that margin are reported as not contained.
// - intersect() returns a subset of the true intersection (never more):
//   exact when either range is everywhere/nowhere, when both are equal, when
//   one contains the bounding ball of the other, or when both share a centre
//   and one cone contains the other (or either is pi). Otherwise, as in the
//   paper, it falls back to a ball (a degenerate conic range) found by
//   probing candidate centres and verified with containsSphere() on both
//   ranges; nowhere() when no probe lies inside both. That ball can be much
//   smaller than the true intersection: callers must treat "outside" as
//   "re-plan", never as an error.
// - make() validates untrusted values (non-finite, negative or inverted
//   distances, zero direction, alpha outside (0, pi]; float pi, a hair
//   above pi, is clamped to pi); the direction is normalised. Pure value
//   type, no I/O, thread-safe.
#pragma once

#include <glm/vec3.hpp>
#include <limits>

#include "thinlod/common/core/status.h"

namespace thinlod {

struct Ball {
  glm::dvec3 center{0.0};
  double radius = 0.0;  // may be +infinity
};

class ConicRange {
 public:
  ConicRange() = default;  // everywhere

  static ConicRange everywhere() { return ConicRange(); }
  static ConicRange nowhere();
  // A ball: distance [0, radius], every direction. radius >= 0, finite centre.
  static ConicRange ball(const glm::dvec3& center, double radius);
  static Result<ConicRange> make(const glm::dvec3& center, double minDistance, double maxDistance,
                                 const glm::dvec3& direction, double alpha);

  const glm::dvec3& center() const { return center_; }
  double minDistance() const { return minDistance_; }
  double maxDistance() const { return maxDistance_; }
  const glm::dvec3& direction() const { return direction_; }
  double alpha() const { return alpha_; }

  bool isEmpty() const { return minDistance_ > maxDistance_; }
  bool isEverywhere() const;
  bool operator==(const ConicRange& other) const;
  bool operator!=(const ConicRange& other) const { return !(*this == other); }

  bool containsPoint(const glm::dvec3& p) const;
  // Every point of the closed ball (center, radius >= 0) lies inside.
  bool containsSphere(const glm::dvec3& center, double radius) const;
  // The radius of a ball around p that containsSphere() accepts, close to
  // the largest one (0 when p is outside or on the boundary).
  double clearance(const glm::dvec3& p) const;
  // A ball containing the whole range (radius +infinity when unbounded,
  // negative when the range is empty).
  Ball boundingBall() const;

  ConicRange intersect(const ConicRange& other) const;

 private:
  glm::dvec3 center_{0.0};
  double minDistance_ = 0.0;
  double maxDistance_ = std::numeric_limits<double>::infinity();
  glm::dvec3 direction_{0.0, 0.0, 1.0};
  double alpha_ = 3.14159265358979323846;
};

}  // namespace thinlod
