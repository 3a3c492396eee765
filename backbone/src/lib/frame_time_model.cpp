#include "frame_time_model.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <glm/geometric.hpp>

namespace thinlod::backbone {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDegreesPerRadian = 180.0 / kPi;

double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  // atan2 of |a x b| and a.b: accurate for small and near-pi angles alike.
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// v rotated by the minimal rotation taking unit `from` to unit `to`
// (Rodrigues' formula; any perpendicular axis for opposite directions).
glm::dvec3 rotateLike(const glm::dvec3& v, const glm::dvec3& from, const glm::dvec3& to) {
  glm::dvec3 axis = glm::cross(from, to);
  const double sine = glm::length(axis);
  const double cosine = glm::dot(from, to);
  if (sine < 1e-300) {
    if (cosine > 0.0) return v;
    axis = glm::cross(from, std::abs(from.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
    axis = glm::normalize(axis);
    return -v + 2.0 * axis * glm::dot(axis, v);  // half turn about `axis`
  }
  axis /= sine;
  return v * cosine + glm::cross(axis, v) * sine + axis * glm::dot(axis, v) * (1.0 - cosine);
}
}  // namespace

double objectRenderSeconds(const FrameCostConstants& c, const ObjectFrameLoad& load,
                           double resolution) {
  const double triangles = resolution * load.maxTriangles * c.triangleSeconds;
  const double pixels = load.coveredPixels * c.pixelSeconds;
  return c.setupSeconds + (c.additive ? triangles + pixels : std::max(triangles, pixels));
}

double fillBoundResolution(const FrameCostConstants& c, const ObjectFrameLoad& load) {
  if (c.additive) return 0.0;  // every triangle costs time: no floor
  const double perResolution = load.maxTriangles * c.triangleSeconds;
  const double fill = load.coveredPixels * c.pixelSeconds;
  if (!(perResolution > 0.0)) return 1.0;
  return std::clamp(fill / perResolution, 0.0, 1.0);
}

double fixedFrameSeconds(const FrameCostConstants& c, std::size_t objectCount,
                         double reserveSeconds) {
  return c.initSeconds + c.finalSeconds + reserveSeconds +
         static_cast<double>(objectCount) * c.setupSeconds;
}

double projectedSpherePixels(double centerDistance, double radius, const ScreenProjection& s) {
  assert(radius > 0.0 && s.widthPixels > 0.0 && s.heightPixels > 0.0 && s.verticalFov > 0.0);
  const double screen = s.widthPixels * s.heightPixels;
  if (!(centerDistance > radius)) return screen;
  const double focal = 0.5 * s.heightPixels / std::tan(0.5 * s.verticalFov);
  // tan(asin(R / d)) = R / sqrt(d^2 - R^2), written to avoid cancellation.
  const double tangent = radius / std::sqrt((centerDistance - radius) * (centerDistance + radius));
  const double discRadius = focal * tangent;
  return std::min(screen, kPi * discRadius * discRadius);
}

double pixelsPerDegree(double resolutionX, double resolutionY, double widthMetres,
                       double heightMetres, double viewingDistanceMetres) {
  const double density = std::min(resolutionX / widthMetres, resolutionY / heightMetres);
  return viewingDistanceMetres * std::tan(1.0 / kDegreesPerRadian) * density;
}

double eccentricityDegrees(const glm::dvec3& eye, const glm::dvec3& focusDirection,
                           const glm::dvec3& center, double radius) {
  const glm::dvec3 toCenter = center - eye;
  const double d = glm::length(toCenter);
  if (!(d > radius)) return 0.0;
  const double angularRadius = std::asin(radius / d);
  return std::max(0.0, angleBetween(focusDirection, toCenter) - angularRadius) * kDegreesPerRadian;
}

double apparentSpeedDegreesPerSecond(const glm::dvec3& eyeBefore, const glm::dvec3& viewBefore,
                                     const glm::dvec3& eyeNow, const glm::dvec3& viewNow,
                                     const glm::dvec3& point, double seconds) {
  if (!(seconds > 0.0)) return 0.0;
  const glm::dvec3 before = point - eyeBefore;
  const glm::dvec3 now = point - eyeNow;
  if (glm::length(before) == 0.0 || glm::length(now) == 0.0) return 0.0;
  // Express the old direction in the new view frame: rotate it with the view.
  const glm::dvec3 carried =
      rotateLike(glm::normalize(before), glm::normalize(viewBefore), glm::normalize(viewNow));
  return angleBetween(carried, glm::normalize(now)) * kDegreesPerRadian / seconds;
}

// Reddy, "The development and evaluation of a model of visual acuity for
// computer-generated imagery" (1997), as used by Reddy et al. 1998: the
// highest spatial frequency (cycles/degree) perceivable at angular velocity
// v (deg/s) is G(v) = 60 up to 0.825 deg/s, 57.69 - 27.78 log10(v) up to
// 118.3 deg/s, 0.1 beyond (continuous at both joints); at eccentricity e
// (deg) it is scaled by M(e) = 1 up to 5.79 deg, 7.49 / (0.3 e + 1)^2 beyond
// (continuous at 5.79). The paper's w_v "log ..." is this velocity model.
double reddyVelocityFactor(double v) {
  double g = 60.0;
  if (v > 118.3) {
    g = 0.1;
  } else if (v > 0.825) {
    g = 57.69 - 27.78 * std::log10(v);
  }
  return std::clamp(g / 60.0, 0.1 / 60.0, 1.0);
}

double reddyEccentricityFactor(double e) {
  if (!(e > 5.79)) return 1.0;
  const double s = 0.3 * e + 1.0;
  return std::min(1.0, 7.49 / (s * s));
}

double reddyAcuity(double degreesPerSecond, double eccentricity) {
  return reddyVelocityFactor(degreesPerSecond) * reddyEccentricityFactor(eccentricity);
}

}  // namespace thinlod::backbone
