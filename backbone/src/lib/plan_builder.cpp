#include <algorithm>
#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>

#include "scheduler_common.h"
#include "selection.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNever = 1e30;  // "does not expire", finite so it sorts and prints

std::uint64_t fingerprint(const SchedulerConfig& c) {
  // Bitwise hash of the plain-double config (no padding-sensitive memcmp).
  const double fields[] = {c.maxSpeed,
                           c.maxAngularSpeed,
                           c.plannedLifetime,
                           c.linkDelay,
                           c.generationDelay,
                           c.keepSlack,
                           c.minimalDistance,
                           c.maxViewDistance,
                           c.mergeDistanceFactor,
                           c.cacheDistanceMargin,
                           c.cacheAngleMargin,
                           c.rangeHysteresis,
                           c.curveTolerance};
  std::uint64_t h = 1469598103934665603ULL;
  for (double f : fields) {
    std::uint64_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    h = (h ^ bits) * 1099511628211ULL;
  }
  return h;
}

struct CurrentCopy {
  bool anyPresent = false;
  bool usable = false;
  double absoluteAccuracy = 0.0;
  double secondsToExpiry = 0.0;
};

// The best displayed copy of an object over the keep ball, for request urgency.
CurrentCopy currentCopy(const PlanContext& ctx, std::uint32_t object, const Sphere& bounds) {
  CurrentCopy result;
  const SceneObject& obj = ctx.scene.objects[object];
  const Sphere keep = ctx.region.keepBall();
  const double dKeep = conversionDistance(ctx.region.center, ctx.region.keepRadius, bounds,
                                          ctx.config.minimalDistance);
  for (std::uint32_t k = 0; k < obj.optionCount; ++k) {
    const RepresentationOption& option = ctx.scene.options[obj.firstOption + k];
    const RepresentationCopy& copy = option.atFrontend;
    if (!copy.present) continue;
    result.anyPresent = true;
    if (!containsBall(option.validity, keep) || !containsBall(copy.validity, keep)) continue;
    const double accuracy = copy.relativeAccuracy * dKeep / (2.0 * bounds.radius);
    if (!result.usable || accuracy > result.absoluteAccuracy) {
      result.usable = true;
      result.absoluteAccuracy = accuracy;
      const double clearance = std::min(option.validity.clearance(ctx.region.center),
                                        copy.validity.clearance(ctx.region.center));
      const double room = clearance - ctx.region.keepRadius;
      result.secondsToExpiry = (ctx.config.maxSpeed > 0.0 && std::isfinite(room))
                                   ? std::min(kNever, room / ctx.config.maxSpeed)
                                   : kNever;
    }
  }
  return result;
}

// A kept frontend copy: every other copy the frontend holds of the object goes.
void removeOtherCopies(const PlanContext& ctx, std::uint32_t object, std::uint32_t keptOption,
                       Plan& plan) {
  const SceneObject& obj = ctx.scene.objects[object];
  for (std::uint32_t k = 0; k < obj.optionCount; ++k) {
    const std::uint32_t index = obj.firstOption + k;
    const RepresentationCopy& copy = ctx.scene.options[index].atFrontend;
    if (copy.present && index != keptOption) plan.removals.push_back({object, index, copy.id});
  }
}

void removeAllCopies(const PlanContext& ctx, std::uint32_t object, Plan& plan, bool addDecision) {
  const SceneObject& obj = ctx.scene.objects[object];
  bool any = false;
  for (std::uint32_t k = 0; k < obj.optionCount; ++k) {
    const std::uint32_t index = obj.firstOption + k;
    const RepresentationCopy& copy = ctx.scene.options[index].atFrontend;
    if (!copy.present) continue;
    plan.removals.push_back({object, index, copy.id});
    any = true;
  }
  if (any && addDecision) {
    ObjectDecision d;
    d.object = object;
    d.action = ObjectAction::kRemove;
    plan.decisions.push_back(d);
  }
}

}  // namespace

int candidateSourceRank(CandidateSource source) {
  switch (source) {
    case CandidateSource::kFrontendCopy:
      return 0;
    case CandidateSource::kPending:
      return 1;
    case CandidateSource::kBackboneCopy:
      return 2;
    case CandidateSource::kNew:
      return 3;
  }
  return 4;
}

int pickCandidate(const std::vector<LeafCandidate>& candidates, double need, bool trianglesFirst,
                  CandidateCost* pickedCost) {
  int best = -1;
  CandidateCost bestCost;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const LeafCandidate& c = candidates[i];
    if (!(c.maxRelativeAccuracy >= need * (1.0 - kAccuracyTolerance))) continue;
    const CandidateCost cost = candidateCost(c, need);
    if (best >= 0) {
      const double p = trianglesFirst ? cost.triangles : cost.linkBytes;
      const double bp = trianglesFirst ? bestCost.triangles : bestCost.linkBytes;
      const double s = trianglesFirst ? cost.linkBytes : cost.triangles;
      const double bs = trianglesFirst ? bestCost.linkBytes : bestCost.triangles;
      if (p > bp) continue;
      if (p == bp) {
        if (s > bs) continue;
        if (s == bs &&
            candidateSourceRank(c.source) >= candidateSourceRank(candidates[best].source))
          continue;
      }
    }
    best = static_cast<int>(i);
    bestCost = cost;
  }
  if (pickedCost && best >= 0) *pickedCost = bestCost;
  return best;
}

double bestCandidateAccuracy(const std::vector<LeafCandidate>& candidates) {
  double best = -kInf;
  for (const LeafCandidate& c : candidates) best = std::max(best, c.maxRelativeAccuracy);
  return best;
}

double lowestCandidateAccuracy(const std::vector<LeafCandidate>& candidates) {
  double low = kInf;
  for (const LeafCandidate& c : candidates) {
    const double start = c.source == CandidateSource::kNew
                             ? std::min(c.representation->relativeTriangles.minAccuracy(),
                                        c.representation->relativeLinkBytes.minAccuracy())
                             : c.maxRelativeAccuracy;
    low = std::min(low, std::min(start, c.maxRelativeAccuracy));
  }
  return low;
}

LeafSelection makeSelection(std::uint32_t node, std::uint32_t object,
                            const LeafCandidate& candidate, double need, double distance,
                            double diameter) {
  return makeSelection(node, object, candidate, need, distance, diameter,
                       candidateCost(candidate, need));
}

LeafSelection makeSelection(std::uint32_t node, std::uint32_t object,
                            const LeafCandidate& candidate, double need, double distance,
                            double diameter, const CandidateCost& cost) {
  LeafSelection s;
  s.node = node;
  s.object = object;
  s.rendered = true;
  s.candidate = candidate;
  s.need = need;
  s.distance = distance;
  s.diameter = diameter;
  if (candidate.source == CandidateSource::kNew) {
    // Generate the cheapest representation reaching `need`: left of the
    // curve that is its first point.
    const RepresentationOption& option = *candidate.representation;
    const double start =
        std::max(option.relativeTriangles.minAccuracy(), option.relativeLinkBytes.minAccuracy());
    s.frameAccuracy = std::min(candidate.maxRelativeAccuracy, std::max(need, start));
    s.relativeAccuracy = s.frameAccuracy;
  } else {
    s.frameAccuracy = candidate.maxRelativeAccuracy;
    s.relativeAccuracy = candidate.source == CandidateSource::kFrontendCopy
                             ? candidate.representation->atFrontend.relativeAccuracy
                         : candidate.source == CandidateSource::kBackboneCopy
                             ? candidate.representation->atBackbone.relativeAccuracy
                             : candidate.maxRelativeAccuracy;  // pending: credited value
  }
  // Exactly what the solvers charged, candidateCost(candidate, need) (flat
  // left of the curve, so the same as at frameAccuracy when both curves
  // share their domain).
  s.cost = cost;
  return s;
}

const std::vector<PendingCopy>* pendingFor(const PlannerStateImpl& state, std::uint32_t object) {
  // Nothing in flight (a standing or steadily served viewer): no hash and no
  // bucket read per leaf (the bucket array keeps its size once grown).
  if (state.pending.empty()) return nullptr;
  auto it = state.pending.find(object);
  return it == state.pending.end() ? nullptr : &it->second;
}

void beginStep(PlannerStateImpl& state, const SchedulingScene& scene, const SchedulerConfig& config,
               const ViewerState& viewer, double linkWindow) {
  const std::uint64_t fp = fingerprint(config);
  if (state.nodeCount != scene.nodes.size() || state.objectCount != scene.objects.size() ||
      state.configFingerprint != fp) {
    state.clearCaches();
    state.nodeCount = scene.nodes.size();
    state.objectCount = scene.objects.size();
    state.configFingerprint = fp;
    state.switchCounters.assign(scene.objects.size(), 0);
    state.scannedFrontend = false;
    state.pending.clear();
    state.aslodAllocations.clear();
    ++state.pendingGeneration;
  }
  for (ResourceCache& cache : state.cache) {
    cache.absolute.resize(scene.nodes.size());
    cache.relative.resize(scene.nodes.size());
  }
  // In-flight requests leave when their copy shows up or when they are
  // overdue (lost or rejected by the simplifier).
  const double timeout = config.linkDelay + config.generationDelay + config.plannedLifetime;
  for (auto it = state.pending.begin(); it != state.pending.end();) {
    std::vector<PendingCopy>& list = it->second;
    const std::size_t before = list.size();
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](const PendingCopy& p) {
                                if (p.option >= scene.options.size()) return true;
                                const RepresentationCopy& f = scene.options[p.option].atFrontend;
                                if (f.present && f.id == p.requestId) return true;
                                return viewer.timeSeconds - p.issuedAt > timeout;
                              }),
               list.end());
    if (list.size() != before) ++state.pendingGeneration;
    it = list.empty() ? state.pending.erase(it) : std::next(it);
  }
  // Settled entries carry their send time, so the log is not in time order.
  state.linkLog.erase(
      std::remove_if(state.linkLog.begin(), state.linkLog.end(),
                     [&](const LinkSend& s) { return s.time <= viewer.timeSeconds - linkWindow; }),
      state.linkLog.end());
  state.lastTime = viewer.timeSeconds;
}

double recentLinkBytes(const PlannerStateImpl& state, double now, double window) {
  double sum = 0.0;
  for (const LinkSend& s : state.linkLog)
    if (s.time > now - window) sum += s.bytes;
  return sum;
}

void finishPlan(const PlanContext& ctx, std::vector<LeafSelection>& selections,
                double targetAccuracy, std::optional<double> expiredCopyRoom, Plan& plan) {
  PlannerStateImpl& state = ctx.state;
  const double now = ctx.viewer.timeSeconds;
  plan.region = ctx.region;
  plan.targetAccuracy = targetAccuracy;
  plan.decisions.clear();
  plan.requests.clear();
  plan.removals.clear();
  plan.belowTarget.clear();
  plan.dropped.clear();
  plan.decisions.reserve(selections.size());

  std::vector<std::uint32_t> rendered;
  rendered.reserve(selections.size());
  double triangles = 0.0;
  double linkBytes = 0.0;
  double minAccuracy = kInf;
  std::uint32_t keeps = 0;
  std::uint32_t sends = 0;
  const double belowLimit = targetAccuracy * (1.0 - 1e-9);
  std::vector<const LeafSelection*> unrendered;

  for (LeafSelection& s : selections) {
    if (!s.rendered) {
      unrendered.push_back(&s);
      continue;
    }
    rendered.push_back(s.object);
    ObjectDecision d;
    d.object = s.object;
    d.option = static_cast<std::int32_t>(s.candidate.option);
    d.kind = s.candidate.representation->kind;
    d.source = s.candidate.source;
    d.relativeAccuracy = s.relativeAccuracy;
    d.absoluteAccuracy = s.absoluteAccuracy();
    d.triangles = s.cost.triangles;
    d.belowTarget = d.absoluteAccuracy < belowLimit;
    if (d.belowTarget) plan.belowTarget.push_back(s.object);
    minAccuracy = std::min(minAccuracy, d.absoluteAccuracy);
    triangles += d.triangles;
    switch (s.candidate.source) {
      case CandidateSource::kFrontendCopy: {
        d.action = ObjectAction::kKeep;
        ++keeps;
        removeOtherCopies(ctx, s.object, s.candidate.option, plan);
        break;
      }
      case CandidateSource::kPending:
        d.action = ObjectAction::kAwait;
        break;
      case CandidateSource::kBackboneCopy:
      case CandidateSource::kNew: {
        const bool isNew = s.candidate.source == CandidateSource::kNew;
        d.action = isNew ? ObjectAction::kRequest : ObjectAction::kSend;
        d.linkBytes = s.cost.linkBytes;
        linkBytes += d.linkBytes;
        const std::uint64_t id = isNew ? state.nextRequestId++ : s.candidate.copyId;
        if (d.linkBytes > 0.0) state.linkLog.push_back({now, d.linkBytes, id, false});
        PendingCopy p;
        p.option = s.candidate.option;
        p.requestId = id;
        p.relativeAccuracy = s.relativeAccuracy;
        p.triangles = s.cost.triangles;
        p.encodedBytes = s.cost.linkBytes;
        p.servesRegion = ctx.region.reachBall();
        p.issuedAt = now;
        state.pending[s.object].push_back(p);
        ++state.pendingGeneration;
        if (!isNew) {
          ++sends;
          break;
        }
        const CurrentCopy current = currentCopy(ctx, s.object, ctx.scene.nodes[s.node].bounds);
        RepresentationRequest r;
        r.requestId = id;
        r.object = s.object;
        r.option = s.candidate.option;
        r.kind = d.kind;
        r.relativeAccuracy = s.relativeAccuracy;
        r.expectedTriangles = s.cost.triangles;
        r.expectedBytes = s.cost.linkBytes;
        r.viewRegion = ctx.region.reachBall();
        r.plannedLifetime = ctx.config.plannedLifetime;
        if (!current.anyPresent) {
          r.reason = RequestReason::kMissing;
        } else if (!current.usable) {
          r.reason = RequestReason::kExpiring;
        } else if (current.absoluteAccuracy < belowLimit) {
          r.reason = RequestReason::kInsufficient;
        } else {
          r.reason = RequestReason::kCheaper;
          r.secondsToExpiry = current.secondsToExpiry;
        }
        const double gained =
            d.absoluteAccuracy - (current.usable ? current.absoluteAccuracy : 0.0);
        r.accuracyGainPerByte = gained / std::max(1.0, r.expectedBytes);
        plan.requests.push_back(r);
        break;
      }
    }
    plan.decisions.push_back(d);
  }

  // Unrendered leaves keep an expired copy where the triangles allow (a picture
  // the client already has beats a blank one: a link cut below the size of
  // any new representation otherwise empties the screen as the viewer moves
  // out of the held copies' regions); the rest lose their copies.
  // The order is recomputed from the node's bounds: most ways of leaving a
  // leaf unrendered do not fill in its distance and diameter.
  if (expiredCopyRoom && unrendered.size() > 1) {
    const ViewCone cone(ctx.viewer);
    std::vector<std::pair<double, const LeafSelection*>> ranked;
    ranked.reserve(unrendered.size());
    for (const LeafSelection* s : unrendered) {
      const Sphere& bounds = ctx.scene.nodes[s->node].bounds;
      const double distance = conversionDistance(ctx.region.center, ctx.region.reachRadius, bounds,
                                                 ctx.config.minimalDistance);
      ranked.emplace_back(cone.keepPriority(bounds, 2.0 * bounds.radius, distance), s);
    }
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    for (std::size_t i = 0; i < ranked.size(); ++i) unrendered[i] = ranked[i].second;
  }
  double room = expiredCopyRoom ? *expiredCopyRoom - triangles : -kInf;
  for (const LeafSelection* s : unrendered) {
    const SceneObject& obj = ctx.scene.objects[s->object];
    std::int32_t kept = -1;  // the most accurate held copy that fits
    for (std::uint32_t k = 0; k < obj.optionCount; ++k) {
      const RepresentationCopy& copy = ctx.scene.options[obj.firstOption + k].atFrontend;
      if (!copy.present || !(copy.triangles <= room)) continue;
      if (kept < 0 || copy.relativeAccuracy >
                          ctx.scene.options[static_cast<std::uint32_t>(kept)].atFrontend.relativeAccuracy)
        kept = static_cast<std::int32_t>(obj.firstOption + k);
    }
    if (kept < 0) {
      if (s->dropped) {
        plan.dropped.push_back(s->object);
      } else {
        plan.belowTarget.push_back(s->object);  // nothing eligible: cannot reach the target
      }
      removeAllCopies(ctx, s->object, plan, true);
      continue;
    }
    const RepresentationOption& option = ctx.scene.options[static_cast<std::uint32_t>(kept)];
    ObjectDecision d;
    d.object = s->object;
    d.action = ObjectAction::kKeep;
    d.option = kept;
    d.kind = option.kind;
    d.source = CandidateSource::kFrontendCopy;
    d.relativeAccuracy = option.atFrontend.relativeAccuracy;
    d.absoluteAccuracy = 0.0;
    d.triangles = option.atFrontend.triangles;
    d.belowTarget = true;
    plan.belowTarget.push_back(s->object);
    plan.decisions.push_back(d);
    removeOtherCopies(ctx, s->object, static_cast<std::uint32_t>(kept), plan);
    room -= d.triangles;
    triangles += d.triangles;
    ++keeps;
    rendered.push_back(s->object);
    ++plan.stats.expiredCopiesKept;
  }

  // Objects that lost their representation since the previous plan (culled
  // now): their frontend copies go. The first step scans every object once.
  std::vector<std::uint8_t> renderedNow(ctx.scene.objects.size(), 0);
  for (std::uint32_t o : rendered) renderedNow[o] = 1;
  for (const LeafSelection& s : selections)
    if (!s.rendered) renderedNow[s.object] = 2;  // already handled above
  auto retire = [&](std::uint32_t object) {
    if (object < renderedNow.size() && renderedNow[object] == 0) {
      renderedNow[object] = 2;
      removeAllCopies(ctx, object, plan, true);
    }
  };
  if (!state.scannedFrontend) {
    for (std::uint32_t o = 0; o < ctx.scene.objects.size(); ++o) retire(o);
    state.scannedFrontend = true;
  } else {
    for (std::uint32_t o : state.lastRendered) retire(o);
  }
  state.lastRendered = std::move(rendered);

  std::stable_sort(plan.requests.begin(), plan.requests.end(),
                   [](const RepresentationRequest& a, const RepresentationRequest& b) {
                     if (a.secondsToExpiry != b.secondsToExpiry)
                       return a.secondsToExpiry < b.secondsToExpiry;
                     if (a.accuracyGainPerByte != b.accuracyGainPerByte)
                       return a.accuracyGainPerByte > b.accuracyGainPerByte;
                     return a.object < b.object;
                   });

  plan.predictedTriangles = triangles;
  plan.linkBytesThisStep = linkBytes;
  plan.linkBytesPerSecond = linkBytes / ctx.config.plannedLifetime;
  plan.achievedMinAccuracy = minAccuracy;
  plan.stats.visibleObjects = static_cast<std::uint32_t>(selections.size());

  DecisionRow& row = plan.row;
  row.frame = ctx.viewer.frame;
  row.timeSeconds = now;
  row.scheduler = plan.scheduler;
  row.mode = plan.mode;
  row.targetAccuracy = targetAccuracy;
  row.achievedMinAccuracy = minAccuracy;
  row.predictedTriangles = triangles;
  row.linkBytesThisStep = linkBytes;
  row.linkBytesPerSecond = plan.linkBytesPerSecond;
  row.visibleObjects = plan.stats.visibleObjects;
  row.requests = static_cast<std::uint32_t>(plan.requests.size());
  row.sends = sends;
  row.keeps = keeps;
  row.removals = static_cast<std::uint32_t>(plan.removals.size());
  row.belowTarget = static_cast<std::uint32_t>(plan.belowTarget.size());
  row.dropped = static_cast<std::uint32_t>(plan.dropped.size());
  row.curveReuses = plan.stats.curveReuses;
  ++state.steps;
}

}  // namespace thinlod::backbone
