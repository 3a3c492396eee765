#include "scheduler_common.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <string>

namespace thinlod::backbone {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

Status validateBudget(const Budget& budget) {
  if (!budget.maxTriangles && !budget.maxLinkBytesPerSecond && !budget.fixedAccuracy &&
      !budget.maxFrameSeconds)
    return Status(ErrorCode::kInvalidArgument,
                  "Budget: set maxTriangles, maxLinkBytesPerSecond, fixedAccuracy and/or "
                  "maxFrameSeconds");
  if (budget.maxFrameSeconds &&
      !(std::isfinite(*budget.maxFrameSeconds) && *budget.maxFrameSeconds > 0))
    return Status(ErrorCode::kInvalidArgument, "Budget.maxFrameSeconds must be finite and > 0");
  if (budget.maxTriangles && !(std::isfinite(*budget.maxTriangles) && *budget.maxTriangles >= 0))
    return Status(ErrorCode::kInvalidArgument, "Budget.maxTriangles must be finite and >= 0");
  if (budget.maxLinkBytesPerSecond &&
      !(std::isfinite(*budget.maxLinkBytesPerSecond) && *budget.maxLinkBytesPerSecond >= 0))
    return Status(ErrorCode::kInvalidArgument,
                  "Budget.maxLinkBytesPerSecond must be finite and >= 0");
  if (budget.linkBurstBytes &&
      !(std::isfinite(*budget.linkBurstBytes) && *budget.linkBurstBytes >= 0))
    return Status(ErrorCode::kInvalidArgument, "Budget.linkBurstBytes must be finite and >= 0");
  if (budget.fixedAccuracy && !(std::isfinite(*budget.fixedAccuracy) && *budget.fixedAccuracy > 0))
    return Status(ErrorCode::kInvalidArgument, "Budget.fixedAccuracy must be finite and > 0");
  return Status::okStatus();
}

const char* objectActionName(ObjectAction action) {
  switch (action) {
    case ObjectAction::kKeep:
      return "keep";
    case ObjectAction::kSend:
      return "send";
    case ObjectAction::kRequest:
      return "request";
    case ObjectAction::kAwait:
      return "await";
    case ObjectAction::kRemove:
      return "remove";
  }
  return "unknown";
}

const char* modeName(const Budget& budget) {
  const int code = (budget.maxTriangles ? 1 : 0) | (budget.maxLinkBytesPerSecond ? 2 : 0) |
                   (budget.fixedAccuracy ? 4 : 0);
  static const char* const kNames[] = {
      "none",  "polygon",       "link",       "polygon+link",
      "fixed", "fixed+polygon", "fixed+link", "fixed+polygon+link"};
  return kNames[code];
}

double linkWindowSeconds(const Budget& budget, const SchedulerConfig& config) {
  const double lifetime = config.plannedLifetime;
  if (!budget.linkBurstBytes || !budget.maxLinkBytesPerSecond || !(*budget.maxLinkBytesPerSecond > 0))
    return lifetime;
  // At most an hour: a tiny rate would otherwise keep the link log forever
  // (a shorter window only allows rate x W < burst, so the bound still holds).
  constexpr double kLongestLinkWindowSeconds = 3600.0;
  const double window = *budget.linkBurstBytes / *budget.maxLinkBytesPerSecond;
  return std::max(lifetime, std::min(window, kLongestLinkWindowSeconds));
}

JointBudget hardBudget(const Budget& budget, const PlannerStateImpl& state,
                       const ViewerState& viewer, const SchedulerConfig& config) {
  JointBudget hard;
  if (budget.maxTriangles) {
    hard.useTriangles = true;
    hard.triangles = *budget.maxTriangles;
  }
  if (budget.maxLinkBytesPerSecond) {
    hard.useLink = true;
    const double window = linkWindowSeconds(budget, config);
    const double sent = recentLinkBytes(state, viewer.timeSeconds, window);
    hard.linkBytes = std::max(0.0, *budget.maxLinkBytesPerSecond * window - sent);
  }
  return hard;
}

JointBudget reserveShare(const JointBudget& budget, double share) {
  JointBudget soft = budget;
  if (soft.useTriangles) soft.triangles *= 1.0 - share;
  if (soft.useLink) soft.linkBytes *= 1.0 - share;
  return soft;
}

CandidateCost renderedCost(const std::vector<LeafSelection>& selections) {
  CandidateCost total;
  for (const LeafSelection& s : selections) {
    if (!s.rendered) continue;
    total.triangles += s.cost.triangles;
    total.linkBytes += s.cost.linkBytes;
  }
  return total;
}

bool withinBudget(const std::vector<LeafSelection>& selections, const JointBudget& budget) {
  const CandidateCost used = renderedCost(selections);
  return (!budget.useTriangles || used.triangles <= budget.triangles) &&
         (!budget.useLink || used.linkBytes <= budget.linkBytes);
}

void preferCurrentCopies(const SchedulingScene& scene, const SchedulerConfig& config,
                         const PredictedRegion& region, PlannerStateImpl& state,
                         const JointBudget& hard, bool trianglesFirst,
                         std::vector<LeafSelection>& selections, PlanStats& stats) {
  const CandidateCost used = renderedCost(selections);
  double triangles = used.triangles;
  double link = used.linkBytes;
  double roomTriangles = hard.useTriangles ? hard.triangles - triangles : kInf;
  double roomLink = hard.useLink ? hard.linkBytes - link : kInf;

  struct Wish {
    std::size_t selection;
    LeafCandidate copy;
    double extraTriangles;
    double extraLink;
    bool byDelay;
  };
  std::vector<Wish> wishes;
  std::vector<LeafCandidate> collected;
  const bool stored = config.reuseLeafWork && state.stepCandidates.valid &&
                      state.stepCandidates.begin.size() == selections.size() &&
                      state.stepCandidates.count.size() == selections.size();
  for (std::size_t i = 0; i < selections.size(); ++i) {
    LeafSelection& s = selections[i];
    if (!s.rendered || s.object >= state.switchCounters.size()) continue;
    std::uint16_t& counter = state.switchCounters[s.object];
    if (s.candidate.source == CandidateSource::kFrontendCopy ||
        s.candidate.source == CandidateSource::kPending) {
      counter = 0;
      continue;
    }
    // Cheap skip: nothing displayed or in flight for this object. A stored
    // frontend or in-flight candidate proves there is one without reading
    // the scene's options again (a cache miss per leaf).
    bool hasCopy = false;
    if (stored) {
      const std::uint32_t end = state.stepCandidates.begin[i] + state.stepCandidates.count[i];
      for (std::uint32_t c = state.stepCandidates.begin[i]; c < end && !hasCopy; ++c) {
        const CandidateSource source = state.stepCandidates.pool[c].source;
        hasCopy = source == CandidateSource::kFrontendCopy || source == CandidateSource::kPending;
      }
    }
    if (!hasCopy) {
      const SceneObject& object = scene.objects[s.object];
      hasCopy = pendingFor(state, s.object) != nullptr;
      for (std::uint32_t k = 0; k < object.optionCount && !hasCopy; ++k)
        hasCopy = scene.options[object.firstOption + k].atFrontend.present;
    }
    if (!hasCopy) continue;
    // The push-down's candidates for this leaf are the same ones (same
    // region, scene and in-flight requests): reuse them when stored.
    const LeafCandidate* candidates = nullptr;
    std::size_t candidateCount = 0;
    if (stored) {
      candidates = state.stepCandidates.pool.data() + state.stepCandidates.begin[i];
      candidateCount = state.stepCandidates.count[i];
    } else {
      const SceneNode& node = scene.nodes[s.node];
      collectLeafCandidates(scene, s.object, region, config, CandidateContext::kExact,
                            pendingFor(state, s.object), node.bounds, collected);
      candidates = collected.data();
      candidateCount = collected.size();
    }
    int best = -1;
    CandidateCost bestCost;
    for (std::size_t c = 0; c < candidateCount; ++c) {
      const LeafCandidate& k = candidates[c];
      if (k.source != CandidateSource::kFrontendCopy && k.source != CandidateSource::kPending)
        continue;
      if (!(k.maxRelativeAccuracy >= s.need * (1.0 - kAccuracyTolerance))) continue;
      const CandidateCost cost = candidateCost(k, s.need);
      const double p = trianglesFirst ? cost.triangles : cost.linkBytes;
      const double bp = trianglesFirst ? bestCost.triangles : bestCost.linkBytes;
      if (best < 0 || p < bp ||
          (p == bp && k.source == CandidateSource::kFrontendCopy &&
           candidates[best].source == CandidateSource::kPending)) {
        best = static_cast<int>(c);
        bestCost = cost;
      }
    }
    if (best < 0) {
      counter = 0;  // nothing valid to keep: the switch is forced
      continue;
    }
    const double keepPrimary = trianglesFirst ? bestCost.triangles : bestCost.linkBytes;
    const double pickPrimary = trianglesFirst ? s.cost.triangles : s.cost.linkBytes;
    const bool smallGain = keepPrimary <= pickPrimary * (1.0 + config.preferCurrentShare);
    const bool delayed = counter < config.switchDelaySteps;
    if (!smallGain && !delayed) {
      counter = 0;
      continue;
    }
    wishes.push_back({i, candidates[best], bestCost.triangles - s.cost.triangles,
                      bestCost.linkBytes - s.cost.linkBytes, !smallGain});
  }
  // Cheapest extras first, ties in wish order: a stable sort of small keys
  // (the same order as sorting the wishes themselves, fewer bytes moved).
  // When every wish fits together, with a margin far above the rounding of
  // the running room (n ulps), each one is kept whatever the order: then
  // the sort is skipped (reuseLeafWork) and the outcome is the same.
  struct WishKey {
    double extraTriangles;
    double extraLink;
    std::uint32_t wish;
  };
  auto allFit = [&](double room, double Wish::*extra) {
    if (!config.reuseLeafWork) return false;
    if (room == kInf) return true;
    double positive = 0.0;
    double negative = 0.0;
    for (const Wish& w : wishes) (w.*extra > 0.0 ? positive : negative) += std::fabs(w.*extra);
    const double margin = 1e-6 * (std::fabs(room) + positive + negative);
    return std::isfinite(positive + negative) && room >= 0.0 && positive <= room - margin;
  };
  const bool sortNeeded =
      !(allFit(roomTriangles, &Wish::extraTriangles) && allFit(roomLink, &Wish::extraLink));
  std::vector<WishKey> order;
  order.reserve(wishes.size());
  for (std::size_t w = 0; w < wishes.size(); ++w)
    order.push_back({wishes[w].extraTriangles, wishes[w].extraLink, static_cast<std::uint32_t>(w)});
  if (sortNeeded)
    std::stable_sort(order.begin(), order.end(), [](const WishKey& a, const WishKey& b) {
      if (a.extraTriangles != b.extraTriangles) return a.extraTriangles < b.extraTriangles;
      return a.extraLink < b.extraLink;
    });
  constexpr std::size_t kLookahead = 8;  // prefetch distance (random option reads)
  for (std::size_t at = 0; at < order.size(); ++at) {
    if (at + kLookahead < order.size()) {
      const Wish& ahead = wishes[order[at + kLookahead].wish];
      __builtin_prefetch(&ahead.copy.representation->atFrontend);
      __builtin_prefetch(&selections[ahead.selection]);
    }
    const WishKey& key = order[at];
    const Wish& w = wishes[key.wish];
    LeafSelection& s = selections[w.selection];
    std::uint16_t& counter = state.switchCounters[s.object];
    if (w.extraTriangles > roomTriangles || w.extraLink > roomLink) {
      counter = 0;  // no room: switch now
      continue;
    }
    roomTriangles -= w.extraTriangles;
    roomLink -= w.extraLink;
    s = makeSelection(s.node, s.object, w.copy, s.need, s.distance, s.diameter);
    counter = w.byDelay ? static_cast<std::uint16_t>(counter + 1) : 0;
    ++stats.hysteresisKeeps;
  }
  // The stored candidates stay valid (same region, scene and in-flight
  // requests) for the budget fill; the accuracy-curve method resets them.
}

ViewCone::ViewCone(const ViewerState& viewer)
    : position_(viewer.position),
      direction_(viewer.viewDirection),
      directionLength_(glm::length(viewer.viewDirection)),
      halfDiagonal_(std::atan(
          std::hypot(std::tan(0.5 * viewer.horizontalFov), std::tan(0.5 * viewer.verticalFov)))) {}

double ViewCone::onScreenWeight(const Sphere& bounds) const {
  const glm::dvec3 toObject = bounds.center - position_;
  const double distance = glm::length(toObject);
  if (!(distance > bounds.radius) || !(directionLength_ > 0.0)) return 1.0;  // viewer inside it
  const double cosAngle =
      std::clamp(glm::dot(toObject, direction_) / (distance * directionLength_), -1.0, 1.0);
  const double angle = std::acos(cosAngle);
  const double angularRadius = std::asin(std::min(1.0, bounds.radius / distance));
  return angle - angularRadius <= halfDiagonal_ ? 1.0 : kOffScreenWeight;
}

double ViewCone::keepPriority(const Sphere& bounds, double diameter, double distance) const {
  const double size = diameter / distance;
  const double withinClass = size / (1.0 + size);  // monotone, in [0, 1)
  return onScreenWeight(bounds) == 1.0 ? 1.0 + withinClass : withinClass;
}

}  // namespace thinlod::backbone
