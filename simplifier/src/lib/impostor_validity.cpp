// Validity ranges of impostors (Pasman & Jansen 2002, section 3.5): the cone
// of viewer positions within which an impostor's angular error stays bounded.
//
// Derivation. Let E be the capture viewpoint, c the object centre, D = |E - c|,
// R the radius around c of everything the impostor draws (object and quad),
// and E' a new viewer with D' = |E' - c| > R. The impostor draws each surface
// point P at a point P' on the capture ray through E and P, |P - P'| <= t
// (depthDeviation). The error is the angle e at E' in triangle (E', P, P').
// Law of sines in that triangle: sin e = |P - P'| sin(psi) / |E' - P'|, where
// psi is the angle at P between the capture ray (direction P - E) and P - E'.
// Law of sines in triangle (E, P, E'): sin psi = |E - E'| sin(eps) / |E' - P|,
// eps the angle at E between E' - E and P - E. P - E lies within gamma =
// asin(R / D) of the axis c - E, so with beta the angle between the line EE'
// and the axis, sin(eps) <= sin(min(pi/2, beta + gamma)). Both |E' - P| and
// |E' - P'| are >= D' - R:
//
//     sin e <= t |E - E'| sin(min(pi/2, beta + gamma)) / (D' - R)^2.        (1)
//
// Moving sideways by a small angle theta at distance D (beta ~ pi/2) gives
// |E - E'| ~ D theta, so e ~ t theta / D for a small object: the familiar
// parallax "dz sin(theta) / D". Moving along the axis (beta = 0) only costs
// the factor R / D. A simple impostor's t is its depth extent along the rays
// (which also bounds what a nearer part can uncover behind it); a meshed
// impostor's t is only its depth-mesh error and the largest depth jump it
// splits, hence its much wider cone.
// A meshed impostor's rim is fixed on the surface: past a smooth silhouette
// of radius rho the true surface turns into view. For a sphere seen theta
// away from the capture direction the missing band is rho (1 - cos theta)
// deep, seen from D' - R at most; we add that as a second term (a model for
// smooth silhouettes, exact for the sphere):
//
//     e <= asin(min(1, (1))) + asin(min(1, rho (1 - cos theta) / (D' - R))).  (2)
//
// The cone (apex c, axis E - c) keeps (2) <= maxAngularError: alpha takes half
// the budget at the capture distance; the distance range is then the largest
// interval around D where (2), maximised over the angles up to alpha, stays
// within the whole budget.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <limits>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct BoundParameters {
  double captureDistance;  // D = |E - c|
  double reach;            // R
  double deviation;        // t
  double silhouette;       // rho
};

BoundParameters parameters(const ImpostorFraming& framing, const ImpostorErrorModel& model) {
  BoundParameters p;
  p.captureDistance = glm::length(glm::dvec3(framing.viewpoint) - glm::dvec3(framing.objectCenter));
  double reach = framing.objectRadius;
  const IndexedMesh quad = framing.quad.mesh();
  for (const glm::vec3& corner : quad.positions) {
    reach = std::max(reach, static_cast<double>(glm::length(corner - framing.objectCenter)));
  }
  p.reach = reach;
  p.deviation = std::max(0.0, model.depthDeviation);
  p.silhouette = std::max(0.0, model.silhouetteRadius);
  return p;
}

// The bound the cone keeps at distance d from c: maxAngularError, and with a
// length l > 0 also l / d (a relative accuracy's angle, which falls with the
// viewer's distance; d >= the distance to the object's surface, so l / d is
// at most what the credit allows there).
struct Limit {
  double angle;
  double length;
  double at(double d) const { return length > 0.0 ? std::min(angle, length / d) : angle; }
};

// Bound (2) for a viewer at distance d from c, at angle theta from the axis.
double boundAt(const BoundParameters& p, double d, double theta) {
  if (!(d > p.reach)) return kPi;
  const double D = p.captureDistance;
  // E' - E in (lateral, axial) coordinates of the plane through the axis.
  const double lateral = d * std::sin(theta);
  const double axial = d * std::cos(theta) - D;
  const double chord = std::hypot(lateral, axial);
  const double beta = std::atan2(std::fabs(lateral), std::fabs(axial));
  const double gamma = std::asin(std::min(1.0, p.reach / D));
  const double sinEps = std::sin(std::min(kPi / 2.0, beta + gamma));
  const double gap = d - p.reach;
  const double parallax = std::asin(std::min(1.0, p.deviation * chord * sinEps / (gap * gap)));
  const double rim = std::asin(std::min(1.0, p.silhouette * (1.0 - std::cos(theta)) / gap));
  return parallax + rim;
}

// (2) maximised over angles in [0, theta]: the bound need not grow with the
// angle everywhere (away from the object it first shrinks), so sample it.
double coneBoundAt(const BoundParameters& p, double d, double theta) {
  constexpr int kAngles = 16;
  double worst = 0.0;
  for (int i = 1; i <= kAngles; ++i) worst = std::max(worst, boundAt(p, d, theta * i / kAngles));
  return worst;
}

// Largest alpha in [0, pi] with coneBoundAt(d, alpha) <= limit.
double largestAngle(const BoundParameters& p, double d, double limit) {
  if (coneBoundAt(p, d, kPi) <= limit) return kPi;
  double good = 0.0;
  double bad = kPi;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (good + bad);
    (coneBoundAt(p, d, mid) <= limit ? good : bad) = mid;
  }
  return good;
}

// Walks from `from` towards `to` on a geometric grid; returns the last distance
// before the bound at angle `theta` first exceeds `limit`, refined by bisection.
double lastGoodDistance(const BoundParameters& p, double theta, const Limit& limit, double from,
                        double to) {
  constexpr int kSteps = 512;
  const double ratio = std::pow(to / from, 1.0 / kSteps);
  double good = from;
  for (int i = 1; i <= kSteps; ++i) {
    const double d = (i == kSteps) ? to : from * std::pow(ratio, i);
    if (coneBoundAt(p, d, theta) > limit.at(d)) {
      double bad = d;
      for (int j = 0; j < 60; ++j) {
        const double mid = 0.5 * (good + bad);
        (coneBoundAt(p, mid, theta) <= limit.at(mid) ? good : bad) = mid;
      }
      return good;
    }
    good = d;
  }
  return to;
}

}  // namespace

double impostorErrorBound(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                          const glm::vec3& eye) {
  const BoundParameters p = parameters(framing, model);
  // Double precision and atan2: a float dot product cannot resolve the tiny
  // angles of narrow cones (acos near 1 loses ~3e-4 rad).
  const glm::dvec3 axis = glm::dvec3(framing.viewpoint) - glm::dvec3(framing.objectCenter);
  const glm::dvec3 offset = glm::dvec3(eye) - glm::dvec3(framing.objectCenter);
  const double d = glm::length(offset);
  if (!(d > p.reach)) return kPi;
  const double theta = std::atan2(glm::length(glm::cross(axis, offset)), glm::dot(axis, offset));
  return boundAt(p, d, theta);
}

ConicRange impostorValidity(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                            double maxAngularError) {
  return impostorValidity(framing, model, maxAngularError, 0.0);
}

ConicRange impostorValidity(const ImpostorFraming& framing, const ImpostorErrorModel& model,
                            double maxAngularError, double maxErrorLength) {
  const BoundParameters p = parameters(framing, model);
  const glm::dvec3 center(framing.objectCenter);
  const double D = p.captureDistance;
  const Limit limit{maxAngularError,
                    std::isfinite(maxErrorLength) ? std::max(0.0, maxErrorLength) : 0.0};
  if (!(maxAngularError > 0.0) || !(D > p.reach)) {
    return ConicRange::ball(glm::dvec3(framing.viewpoint), 0.0);  // only the viewpoint itself
  }
  const double alpha = largestAngle(p, D, 0.5 * limit.at(D));
  if (!(alpha > 0.0)) return ConicRange::ball(glm::dvec3(framing.viewpoint), 0.0);

  // Beyond `far`, bound (1) <= t (D + d) / (d - R)^2 and the rim term
  // rho * 2 / (d - R) both decrease with d, so once they fit they fit forever
  // (against l / d too: d times either term decreases towards t and 2 rho).
  double far = 2.0 * D;
  auto farBound = [&](double d) {
    const double gap = d - p.reach;
    return std::asin(std::min(1.0, p.deviation * (D + d) / (gap * gap))) +
           std::asin(std::min(1.0, 2.0 * p.silhouette / gap));
  };
  while (farBound(far) > limit.at(far) && far < 1e9 * D) far *= 2.0;
  double maxDistance = lastGoodDistance(p, alpha, limit, D, far);
  if (maxDistance >= far && farBound(far) <= limit.at(far)) {
    maxDistance = std::numeric_limits<double>::infinity();
  }
  const double nearest = p.reach * (1.0 + 1e-6);
  const double minDistance = lastGoodDistance(p, alpha, limit, D, nearest);
  const glm::dvec3 direction = (glm::dvec3(framing.viewpoint) - center) / D;
  auto range = ConicRange::make(center, std::min(minDistance, D), std::max(maxDistance, D),
                                direction, std::min(alpha, kPi));
  // make() only rejects values this function cannot produce; stay safe anyway.
  return range.ok() ? range.value() : ConicRange::ball(glm::dvec3(framing.viewpoint), 0.0);
}

}  // namespace thinlod::simplifier
