// Spheres and validity ranges for the scheduler (Pasman & Jansen 2002, 3.5).
//
// Contract:
// - Units: metres and radians, world space, double precision.
// - A validity range is common's ConicRange (see conic_range.h): distance
//   band around a centre, optionally limited to a cone; the default value is
//   all of space. Its invariants hold by construction (ConicRange::make
//   validates untrusted values), so the scheduler never re-checks them.
// - "The range contains the whole predicted region" is containsBall(range,
//   region), conservative: a ball touching the boundary counts as outside.
// - Plain value types, no I/O; safe to use from any thread.
#pragma once

#include <glm/vec3.hpp>

#include "thinlod/common/core/conic_range.h"

namespace thinlod::backbone {

using ValidityRange = thinlod::ConicRange;

struct Sphere {
  glm::dvec3 center{0.0};
  double radius = 0.0;
};

inline bool containsBall(const ValidityRange& range, const Sphere& ball) {
  // Most ranges are unrestricted: skip the geometry (regions are finite).
  return range.isEverywhere() || range.containsSphere(ball.center, ball.radius);
}

}  // namespace thinlod::backbone
