#include "thinlod/backbone/pipeline.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <string>

namespace thinlod::backbone {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool finite3(const glm::dvec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

Status invalidField(const char* owner, const char* field, const char* rule) {
  return Status(ErrorCode::kInvalidArgument, std::string(owner) + "." + field + " " + rule);
}

double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  const double la = glm::length(a);
  const double lb = glm::length(b);
  if (la == 0.0 || lb == 0.0) return kPi;
  return std::acos(std::clamp(glm::dot(a, b) / (la * lb), -1.0, 1.0));
}

}  // namespace

SchedulerConfig withoutApproximations(SchedulerConfig c) {
  c.mergeDistanceFactor = std::numeric_limits<double>::infinity();
  c.cacheDistanceMargin = 0.0;
  c.cacheAngleMargin = 0.0;
  c.curveTolerance = 0.0;
  c.maxParetoPasses = 100000;
  c.budgetReserveShare = 0.0;
  c.preferCurrentShare = 0.0;
  c.switchDelaySteps = 0;
  c.targetHysteresis = 0.0;
  c.rangeHysteresis = 0.0;
  c.fillBudget = false;
  return c;
}

Status validateConfig(const SchedulerConfig& c) {
  const char* o = "SchedulerConfig";
  if (c.fillRounds < 1 || c.fillRounds > 16)
    return invalidField(o, "fillRounds", "must be in 1..16");
  if (!(c.fillShadingWeight >= 0.0) || !std::isfinite(c.fillShadingWeight))
    return invalidField(o, "fillShadingWeight", "must be finite and >= 0");
  auto nonNegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!nonNegative(c.maxSpeed)) return invalidField(o, "maxSpeed", "must be finite and >= 0");
  if (!nonNegative(c.maxAngularSpeed))
    return invalidField(o, "maxAngularSpeed", "must be finite and >= 0");
  if (!std::isfinite(c.plannedLifetime) || c.plannedLifetime <= 0.0)
    return invalidField(o, "plannedLifetime", "must be finite and > 0");
  if (!nonNegative(c.linkDelay)) return invalidField(o, "linkDelay", "must be finite and >= 0");
  if (!(c.viewConeHorizon > 0.0))
    return invalidField(o, "viewConeHorizon", "must be > 0 (infinity: the reach horizon)");
  if (!nonNegative(c.generationDelay))
    return invalidField(o, "generationDelay", "must be finite and >= 0");
  if (!nonNegative(c.keepSlack)) return invalidField(o, "keepSlack", "must be finite and >= 0");
  if (!std::isfinite(c.minimalDistance) || c.minimalDistance <= 0.0)
    return invalidField(o, "minimalDistance", "must be finite and > 0");
  if (std::isnan(c.maxViewDistance) || c.maxViewDistance <= 0.0)
    return invalidField(o, "maxViewDistance", "must be > 0");
  if (std::isnan(c.mergeDistanceFactor) || c.mergeDistanceFactor <= 0.0)
    return invalidField(o, "mergeDistanceFactor", "must be > 0 (infinity disables merging)");
  if (!nonNegative(c.cacheDistanceMargin))
    return invalidField(o, "cacheDistanceMargin", "must be finite and >= 0");
  if (!nonNegative(c.cacheAngleMargin))
    return invalidField(o, "cacheAngleMargin", "must be finite and >= 0");
  if (!nonNegative(c.curveTolerance) || c.curveTolerance > 1.0)
    return invalidField(o, "curveTolerance", "must be in [0, 1]");
  if (!nonNegative(c.budgetReserveShare) || c.budgetReserveShare >= 1.0)
    return invalidField(o, "budgetReserveShare", "must be in [0, 1)");
  if (!nonNegative(c.preferCurrentShare))
    return invalidField(o, "preferCurrentShare", "must be finite and >= 0");
  if (c.switchDelaySteps < 0 || c.switchDelaySteps > 1000)
    return invalidField(o, "switchDelaySteps", "must be in [0, 1000]");
  if (!nonNegative(c.targetHysteresis))
    return invalidField(o, "targetHysteresis", "must be finite and >= 0");
  if (!nonNegative(c.rangeHysteresis))
    return invalidField(o, "rangeHysteresis", "must be finite and >= 0");
  if (c.paretoCap < 2 || c.paretoCap > 100000)
    return invalidField(o, "paretoCap", "must be in [2, 100000]");
  if (c.maxParetoPasses < 0 || c.maxParetoPasses > 100000)
    return invalidField(o, "maxParetoPasses", "must be in [0, 100000]");
  return Status::okStatus();
}

Status validateViewer(const ViewerState& v) {
  const char* o = "ViewerState";
  if (!std::isfinite(v.timeSeconds)) return invalidField(o, "timeSeconds", "must be finite");
  if (!finite3(v.position)) return invalidField(o, "position", "must be finite");
  if (!finite3(v.viewDirection) || glm::length(v.viewDirection) == 0.0)
    return invalidField(o, "viewDirection", "must be finite and non-zero");
  if (!std::isfinite(v.horizontalFov) || v.horizontalFov <= 0.0 || v.horizontalFov >= kPi)
    return invalidField(o, "horizontalFov", "must be in (0, pi) rad");
  if (!std::isfinite(v.verticalFov) || v.verticalFov <= 0.0 || v.verticalFov >= kPi)
    return invalidField(o, "verticalFov", "must be in (0, pi) rad");
  return Status::okStatus();
}

PredictedRegion predictRegion(const ViewerState& viewer, const SchedulerConfig& config) {
  PredictedRegion region;
  region.center = viewer.position;
  const double horizon = config.plannedLifetime + config.linkDelay + config.generationDelay;
  region.reachRadius = config.maxSpeed * horizon;
  region.keepRadius =
      config.maxSpeed * (config.linkDelay + config.generationDelay + config.keepSlack);
  region.viewDirection = glm::normalize(viewer.viewDirection);
  // Half-angle of the cone around the rectangular frustum (its corner ray).
  const double th = std::tan(viewer.horizontalFov / 2);
  const double tv = std::tan(viewer.verticalFov / 2);
  const double frustumHalf = std::atan(std::sqrt(th * th + tv * tv));
  region.viewHalfAngle =
      std::min(kPi, frustumHalf + config.maxAngularSpeed * std::min(horizon, config.viewConeHorizon));
  region.maxViewDistance = config.maxViewDistance;
  return region;
}

PredictedRegion growRegion(const PredictedRegion& region, double distance, double angle) {
  PredictedRegion grown = region;
  grown.reachRadius += distance;
  grown.keepRadius += distance;
  grown.viewHalfAngle = std::min(kPi, region.viewHalfAngle + angle);
  return grown;
}

bool regionContains(const PredictedRegion& outer, const PredictedRegion& inner) {
  const double shift = glm::length(outer.center - inner.center);
  if (!(shift + inner.reachRadius <= outer.reachRadius)) return false;
  if (!(shift + inner.keepRadius <= outer.keepRadius)) return false;
  if (!(outer.maxViewDistance >= inner.maxViewDistance)) return false;
  if (outer.viewHalfAngle >= kPi) return true;
  return angleBetween(outer.viewDirection, inner.viewDirection) + inner.viewHalfAngle <=
         outer.viewHalfAngle;
}

Visibility classifySphere(const PredictedRegion& region, const Sphere& bounds) {
  // Seen from a point of the ball (c, R) <=> seen from c after growing the
  // sphere by R (Minkowski difference of two balls is a ball).
  const double grown = bounds.radius + region.reachRadius;
  const glm::dvec3 offset = bounds.center - region.center;
  const double dist = glm::length(offset);
  if (dist - grown > region.maxViewDistance) return Visibility::kCulled;
  const bool allNear = dist + grown <= region.maxViewDistance;
  if (region.viewHalfAngle >= kPi) return allNear ? Visibility::kInside : Visibility::kPartial;
  if (dist <= grown) return Visibility::kPartial;
  const double phi = angleBetween(offset, region.viewDirection);
  const double spread = std::asin(std::min(1.0, grown / dist));
  if (phi - spread > region.viewHalfAngle) return Visibility::kCulled;
  if (phi + spread <= region.viewHalfAngle && allNear) return Visibility::kInside;
  return Visibility::kPartial;
}

double conversionDistance(const glm::dvec3& center, double radius, const Sphere& bounds,
                          double minimalDistance) {
  const double gap = glm::length(bounds.center - center) - bounds.radius - radius;
  return std::max(minimalDistance, gap);
}

const char* candidateSourceName(CandidateSource source) {
  switch (source) {
    case CandidateSource::kNew:
      return "new";
    case CandidateSource::kFrontendCopy:
      return "frontend";
    case CandidateSource::kBackboneCopy:
      return "backbone";
    case CandidateSource::kPending:
      return "pending";
  }
  return "unknown";
}

CandidateCost candidateCost(const LeafCandidate& candidate, double relativeAccuracy) {
  if (candidate.source != CandidateSource::kNew)
    return {candidate.fixedTriangles, candidate.fixedLinkBytes};
  const double a = std::min(relativeAccuracy, candidate.maxRelativeAccuracy);
  return {candidate.representation->relativeTriangles.resourcesFor(a),
          candidate.representation->relativeLinkBytes.resourcesFor(a)};
}

void collectLeafCandidates(const SchedulingScene& scene, std::uint32_t object,
                           const PredictedRegion& region, const SchedulerConfig& config,
                           CandidateContext context, const std::vector<PendingCopy>* pending,
                           const Sphere& bounds, std::vector<LeafCandidate>& out) {
  out.clear();
  const SceneObject& obj = scene.objects[object];
  const Sphere reach = region.reachBall();
  const Sphere keep = region.keepBall();
  const Sphere reachForNewKinds{region.center, region.reachRadius + config.rangeHysteresis};
  const bool exact = context == CandidateContext::kExact;
  // A displayed copy is judged over the keep ball: credit it, in the leaf's
  // frame (a_abs = a_rel * D_reach / diameter), with D_keep / D_reach >= 1.
  // Computed only when some copy needs it (most leaves have none).
  double keepCredit = -1.0;
  auto credit = [&]() {
    if (keepCredit < 0.0) {
      keepCredit = 1.0;
      if (exact) {
        const double dReach =
            conversionDistance(region.center, region.reachRadius, bounds, config.minimalDistance);
        const double dKeep =
            conversionDistance(region.center, region.keepRadius, bounds, config.minimalDistance);
        keepCredit = dKeep / dReach;
      }
    }
    return keepCredit;
  };
  for (std::uint32_t k = 0; k < obj.optionCount; ++k) {
    const std::uint32_t index = obj.firstOption + k;
    const RepresentationOption& option = scene.options[index];
    bool pendingHere = false;
    if (exact && pending) {
      for (const PendingCopy& p : *pending) pendingHere |= p.option == index;
    }
    // Schmitt trigger: a kind not on display must fit a larger region.
    const bool current = option.atFrontend.present || pendingHere;
    const Sphere& needed = current ? reach : reachForNewKinds;
    const bool kindUsable = containsBall(option.validity, needed);
    if (kindUsable) {
      LeafCandidate c;
      c.option = index;
      c.source = CandidateSource::kNew;
      c.representation = &option;
      c.maxRelativeAccuracy =
          std::min(option.relativeTriangles.maxAccuracy(), option.relativeLinkBytes.maxAccuracy());
      out.push_back(c);
    }
    const RepresentationCopy& front = option.atFrontend;
    if (front.present && containsBall(option.validity, keep) &&
        containsBall(front.validity, keep)) {
      LeafCandidate c;
      c.option = index;
      c.source = CandidateSource::kFrontendCopy;
      c.representation = &option;
      c.maxRelativeAccuracy = front.relativeAccuracy * credit();
      c.fixedTriangles = front.triangles;
      c.fixedLinkBytes = 0.0;
      c.copyId = front.id;
      out.push_back(c);
    }
    const RepresentationCopy& back = option.atBackbone;
    if (back.present && kindUsable && containsBall(back.validity, reach)) {
      LeafCandidate c;
      c.option = index;
      c.source = CandidateSource::kBackboneCopy;
      c.representation = &option;
      c.maxRelativeAccuracy = back.relativeAccuracy;
      c.fixedTriangles = back.triangles;
      c.fixedLinkBytes = back.encodedBytes;
      c.copyId = back.id;
      out.push_back(c);
    }
    if (pendingHere && containsBall(option.validity, keep)) {
      for (const PendingCopy& p : *pending) {
        if (p.option != index) continue;
        const double shift = glm::length(p.servesRegion.center - region.center);
        if (!(shift + region.keepRadius <= p.servesRegion.radius)) continue;
        LeafCandidate c;
        c.option = index;
        c.source = CandidateSource::kPending;
        c.representation = &option;
        c.maxRelativeAccuracy = p.relativeAccuracy * credit();
        c.fixedTriangles = p.triangles;
        c.fixedLinkBytes = 0.0;
        c.copyId = p.requestId;
        out.push_back(c);
      }
    }
  }
}

}  // namespace thinlod::backbone
