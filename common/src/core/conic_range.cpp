// Conic ranges: containment tests with a rounding margin, and intersection
// that is exact where a conic range can express it and otherwise falls back
// to a verified ball inside both (Pasman & Jansen 2002, section 3.5).
#include "thinlod/common/core/conic_range.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <glm/geometric.hpp>
#include <optional>
#include <string>
#include <vector>

#include "thinlod/common/core/finite.h"

namespace thinlod {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Relative to the coordinates involved: covers the rounding of |p - c|.
constexpr double kRelativeMargin = 1e-12;
// Radians: covers the rounding of atan2/asin.
constexpr double kAngleMargin = 1e-12;
// Accept float pi (3.14159274) as pi.
constexpr double kAlphaSlack = 1e-6;

// Angle between u (any length) and unit d; accurate near 0 and pi.
double angleTo(const glm::dvec3& u, const glm::dvec3& d) {
  return std::atan2(glm::length(glm::cross(u, d)), glm::dot(u, d));
}

// Points worth probing for a ball inside both ranges: along `range`'s axis
// and along the direction to the other range's centre, at distances spread
// over the range's shell.
void addProbes(const ConicRange& range, const ConicRange& other, double scale,
               std::vector<glm::dvec3>& probes) {
  std::vector<glm::dvec3> directions{range.direction()};
  const glm::dvec3 toOther = other.center() - range.center();
  if (glm::length(toOther) > 0.0) directions.push_back(glm::normalize(toOther));
  if (other.alpha() < kPi) directions.push_back(other.direction());
  probes.push_back(range.center());
  for (const glm::dvec3& d : directions) {
    if (std::isfinite(range.maxDistance())) {
      constexpr int kSteps = 8;
      for (int k = 0; k < kSteps; ++k) {
        const double t =
            range.minDistance() + (range.maxDistance() - range.minDistance()) * (k + 0.5) / kSteps;
        probes.push_back(range.center() + d * t);
      }
    } else {
      for (int k = -8; k <= 8; ++k) {
        probes.push_back(range.center() + d * (range.minDistance() + scale * std::ldexp(1.0, k)));
      }
    }
  }
}

// The paper's fallback: a ball inside both ranges, or nowhere.
ConicRange fallbackBall(const ConicRange& a, const ConicRange& b) {
  double scale = glm::length(a.center() - b.center());
  for (const ConicRange* r : {&a, &b}) {
    scale = std::max(scale, r->minDistance());
    if (std::isfinite(r->maxDistance())) scale = std::max(scale, r->maxDistance());
  }
  if (!(scale > 0.0)) scale = 1.0;

  std::vector<glm::dvec3> probes;
  addProbes(a, b, scale, probes);
  addProbes(b, a, scale, probes);
  constexpr int kSegmentSteps = 8;
  for (int k = 0; k <= kSegmentSteps; ++k) {
    probes.push_back(a.center() + (b.center() - a.center()) * (double(k) / kSegmentSteps));
  }

  auto score = [&](const glm::dvec3& p) { return std::min(a.clearance(p), b.clearance(p)); };
  glm::dvec3 best = probes.front();
  double bestScore = score(best);
  for (const glm::dvec3& p : probes) {
    const double s = score(p);
    if (s > bestScore) {
      bestScore = s;
      best = p;
    }
  }
  if (!(bestScore > 0.0)) return ConicRange::nowhere();

  // Pattern search: move the centre while the ball grows.
  const glm::dvec3 moves[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  // Stops once the step is a small fraction of the ball: the radius is then
  // within about that fraction of what this local search can reach.
  double step = std::max(bestScore, 0.05 * scale);
  for (int iteration = 0; iteration < 80 && step > 1e-3 * bestScore; ++iteration) {
    bool improved = false;
    for (const glm::dvec3& m : moves) {
      const glm::dvec3 q = best + m * step;
      const double s = score(q);
      if (s > bestScore) {
        bestScore = s;
        best = q;
        improved = true;
      }
    }
    if (!improved) step *= 0.5;
  }
  const ConicRange result = ConicRange::ball(best, bestScore);
  assert(a.containsSphere(best, bestScore) && b.containsSphere(best, bestScore) &&
         "ConicRange::intersect: fallback ball escaped a range");
  return result;
}

// Same centre: shells intersect to a shell; cones intersect to a cone when
// one contains the other. std::nullopt when the cones overlap partially.
std::optional<ConicRange> sameCentreIntersection(const ConicRange& a, const ConicRange& b) {
  const double lo = std::max(a.minDistance(), b.minDistance());
  const double hi = std::min(a.maxDistance(), b.maxDistance());
  if (lo > hi) return ConicRange::nowhere();
  glm::dvec3 direction = a.direction();
  double alpha = a.alpha();
  if (a.alpha() >= kPi) {
    direction = b.direction();
    alpha = b.alpha();
  } else if (b.alpha() < kPi) {
    const double gap = angleTo(a.direction(), b.direction());
    if (gap + a.alpha() + kAngleMargin <= b.alpha()) {
      // a's cone inside b's: keep a's.
    } else if (gap + b.alpha() + kAngleMargin <= a.alpha()) {
      direction = b.direction();
      alpha = b.alpha();
    } else if (gap >= a.alpha() + b.alpha()) {
      return ConicRange::nowhere();  // at most the apex in common
    } else {
      return std::nullopt;
    }
  }
  auto made = ConicRange::make(a.center(), lo, hi, direction, alpha);
  assert(made.ok() && "ConicRange::intersect: same-centre result invalid");
  return made.ok() ? std::optional<ConicRange>(made.value()) : std::nullopt;
}

}  // namespace

ConicRange ConicRange::nowhere() {
  ConicRange r;
  r.minDistance_ = kInfinity;
  r.maxDistance_ = 0.0;
  return r;
}

ConicRange ConicRange::ball(const glm::dvec3& center, double radius) {
  assert(allFinite(center) && radius >= 0.0 && "ConicRange::ball: bad centre or radius");
  ConicRange r;
  r.center_ = center;
  r.maxDistance_ = radius;
  return r;
}

Result<ConicRange> ConicRange::make(const glm::dvec3& center, double minDistance,
                                    double maxDistance, const glm::dvec3& direction, double alpha) {
  auto error = [](const std::string& what) {
    return Status(ErrorCode::kInvalidArgument, "conic range: " + what);
  };
  if (!allFinite(center)) return error("center is not finite");
  if (!std::isfinite(minDistance) || minDistance < 0.0) {
    return error("distance min " + std::to_string(minDistance) + " is not finite and >= 0");
  }
  if (std::isnan(maxDistance) || maxDistance < minDistance) {
    return error("distance max " + std::to_string(maxDistance) + " is below min " +
                 std::to_string(minDistance));
  }
  if (!allFinite(direction) || !(glm::length(direction) > 0.0)) {
    return error("direction is zero or not finite");
  }
  if (!(alpha > 0.0) || !(alpha <= kPi + kAlphaSlack)) {
    return error("alpha " + std::to_string(alpha) + " is outside (0, pi]");
  }
  ConicRange r;
  r.center_ = center;
  r.minDistance_ = minDistance;
  r.maxDistance_ = maxDistance;
  r.direction_ = glm::normalize(direction);
  r.alpha_ = std::min(alpha, kPi);
  return r;
}

bool ConicRange::isEverywhere() const {
  return minDistance_ == 0.0 && maxDistance_ == kInfinity && alpha_ >= kPi;
}

bool ConicRange::operator==(const ConicRange& other) const {
  return center_ == other.center_ && minDistance_ == other.minDistance_ &&
         maxDistance_ == other.maxDistance_ && direction_ == other.direction_ &&
         alpha_ == other.alpha_;
}

bool ConicRange::containsPoint(const glm::dvec3& p) const {
  if (isEmpty() || !allFinite(p)) return false;
  const glm::dvec3 v = p - center_;
  const double distance = glm::length(v);
  if (distance < minDistance_ || distance > maxDistance_) return false;
  if (alpha_ >= kPi || distance == 0.0) return true;
  return angleTo(v, direction_) <= alpha_;
}

bool ConicRange::containsSphere(const glm::dvec3& center, double radius) const {
  if (isEmpty() || !allFinite(center) || !std::isfinite(radius) || !(radius >= 0.0)) return false;
  const glm::dvec3 v = center - center_;
  const double distance = glm::length(v);
  const double tolerance =
      kRelativeMargin * (glm::length(center) + glm::length(center_) + radius + distance);
  if (distance + radius + tolerance > maxDistance_) return false;
  if (minDistance_ > 0.0 && distance - radius - tolerance < minDistance_) return false;
  if (alpha_ >= kPi) return true;
  // The ball must not reach the apex, and its angular radius seen from the
  // apex plus its centre's angle must stay within alpha.
  if (radius + tolerance >= distance) return false;
  const double angularRadius = std::asin((radius + tolerance) / distance);
  return angleTo(v, direction_) + angularRadius + kAngleMargin <= alpha_;
}

double ConicRange::clearance(const glm::dvec3& p) const {
  if (isEmpty() || !allFinite(p)) return 0.0;
  const glm::dvec3 v = p - center_;
  const double distance = glm::length(v);
  const double tolerance = kRelativeMargin * (glm::length(p) + glm::length(center_) + distance);
  double radius = kInfinity;
  if (std::isfinite(maxDistance_)) radius = std::min(radius, maxDistance_ - distance - tolerance);
  if (minDistance_ > 0.0) radius = std::min(radius, distance - minDistance_ - tolerance);
  if (alpha_ < kPi) {
    const double room = alpha_ - angleTo(v, direction_) - kAngleMargin;
    if (!(room > 0.0)) return 0.0;
    const double reach =
        room >= kPi / 2 ? distance * (1.0 - kRelativeMargin) : distance * std::sin(room);
    radius = std::min(radius, reach - tolerance);
  }
  if (radius == kInfinity) return kInfinity;
  radius /= 1.0 + kRelativeMargin;  // the margin grows with the radius too
  if (!(radius > 0.0)) return 0.0;
  // asin(sin(x)) may round up by an ulp or so: shrink until accepted.
  for (int attempt = 0; attempt < 8; ++attempt) {
    if (containsSphere(p, radius)) return radius;
    radius *= 1.0 - 1e-9;
  }
  return 0.0;
}

Ball ConicRange::boundingBall() const {
  if (isEmpty()) return Ball{center_, -1.0};
  if (!std::isfinite(maxDistance_)) return Ball{center_, kInfinity};
  const double slack = kRelativeMargin * (glm::length(center_) + maxDistance_);
  // A cone sector of half-angle < pi/2 is convex; its farthest points from
  // an axis point are the apex and the rim of the outer cap.
  if (alpha_ < kPi / 4) {
    const double t = maxDistance_ / (2.0 * std::cos(alpha_));
    return Ball{center_ + direction_ * t, t * (1.0 + kRelativeMargin) + slack};
  }
  if (alpha_ < kPi / 2) {
    return Ball{center_ + direction_ * (maxDistance_ * std::cos(alpha_)),
                maxDistance_ * std::sin(alpha_) * (1.0 + kRelativeMargin) + slack};
  }
  return Ball{center_, maxDistance_ * (1.0 + kRelativeMargin) + slack};
}

ConicRange ConicRange::intersect(const ConicRange& other) const {
  if (isEmpty() || other.isEmpty()) return nowhere();
  if (isEverywhere()) return other;
  if (other.isEverywhere() || *this == other) return *this;
  if (center_ == other.center_) {
    if (auto same = sameCentreIntersection(*this, other)) return *same;
  }
  const Ball mine = boundingBall();
  if (other.containsSphere(mine.center, mine.radius)) return *this;
  const Ball theirs = other.boundingBall();
  if (containsSphere(theirs.center, theirs.radius)) return other;
  return fallbackBall(*this, other);
}

}  // namespace thinlod
