#include "curve_propagation.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>

namespace thinlod::backbone {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool sameRegion(const PredictedRegion& a, const PredictedRegion& b) {
  return a.center == b.center && a.reachRadius == b.reachRadius && a.keepRadius == b.keepRadius &&
         a.viewDirection == b.viewDirection && a.viewHalfAngle == b.viewHalfAngle &&
         a.maxViewDistance == b.maxViewDistance;
}

double angleBetween(const glm::dvec3& a, const glm::dvec3& b) {
  return std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));  // both unit
}

// How far `inner` may still grow (distance, angle) and stay inside `outer`.
void slackOf(const PredictedRegion& outer, const PredictedRegion& inner, double& distance,
             double& angle) {
  const double shift = glm::length(outer.center - inner.center);
  distance = std::min(outer.reachRadius - shift - inner.reachRadius,
                      outer.keepRadius - shift - inner.keepRadius);
  angle = outer.viewHalfAngle >= kPi
              ? kPi
              : outer.viewHalfAngle - angleBetween(outer.viewDirection, inner.viewDirection) -
                    inner.viewHalfAngle;
  distance = std::max(0.0, distance);
  angle = std::max(0.0, angle);
}

// The curve restricted to accuracies <= maxAccuracy (a representation whose
// other resource curve ends earlier cannot be generated beyond that).
AccuracyCurve restrictTo(const AccuracyCurve& curve, double maxAccuracy) {
  if (maxAccuracy >= curve.maxAccuracy()) return curve;
  std::vector<CurveSegment> kept;
  for (const CurveSegment& s : curve.segments())
    if (s.start < maxAccuracy) kept.push_back(s);
  if (!kept.empty()) {
    Result<AccuracyCurve> r = AccuracyCurve::fromSegments(std::move(kept), maxAccuracy);
    if (r.ok()) return std::move(r).value();
  }
  // Conservative fallback: one point costing what maxAccuracy costs.
  return AccuracyCurve::point(maxAccuracy, curve.resourcesFor(maxAccuracy));
}

// An upper bound of `curve` with fewer pieces: r <= r_s <= (1 + tolerance) r
// everywhere on the domain. One pass: each piece is a line anchored at its
// left end whose slope is the least that stays above every knot (values and
// left limits; a line over a linear piece is above it iff above both ends)
// and at most what keeps every covered knot within tolerance.
AccuracyCurve simplifyUpper(const AccuracyCurve& curve, double tolerance) {
  const std::vector<CurveSegment>& in = curve.segments();
  if (tolerance <= 0.0 || in.size() <= 8) return curve;
  std::vector<CurveSegment> out;
  double anchor = in[0].start;
  double base = in[0].value;
  double slope = 0.0;     // least slope above every covered point
  double allowed = kInf;  // largest slope within tolerance of them
  auto cover = [&](double x, double r, double& needed, double& room) {
    if (x <= anchor) return base <= (1.0 + tolerance) * r;
    needed = std::max(needed, (r - base) / (x - anchor));
    room = std::min(room, ((1.0 + tolerance) * r - base) / (x - anchor));
    return needed <= room;
  };
  for (std::size_t i = 0; i < in.size(); ++i) {
    const double end = i + 1 < in.size() ? in[i + 1].start : curve.maxAccuracy();
    const double left = in[i].value + in[i].slope * (end - in[i].start);
    double needed = slope;
    double room = allowed;
    if (cover(in[i].start, in[i].value, needed, room) && cover(end, left, needed, room)) {
      slope = needed;
      allowed = room;
      continue;
    }
    // Close the piece before segment i; restart at its start, never below
    // the line so far (monotone, still an upper bound).
    out.push_back({anchor, base, slope});
    base = std::max(in[i].value, base + slope * (in[i].start - anchor));
    anchor = in[i].start;
    needed = 0.0;
    room = kInf;
    cover(end, left, needed, room);
    slope = std::max(0.0, needed);
    allowed = room;
  }
  out.push_back({anchor, base, slope});
  Result<AccuracyCurve> simplified =
      AccuracyCurve::fromSegments(std::move(out), curve.maxAccuracy());
  return simplified.ok() ? std::move(simplified).value() : curve;
}

const AccuracyCurve& curveOf(const RepresentationOption& option, Resource resource) {
  return resource == Resource::kTriangles ? option.relativeTriangles : option.relativeLinkBytes;
}

}  // namespace

CurvePropagator::CurvePropagator(const SchedulingScene& scene, const SchedulerConfig& config,
                                 const PredictedRegion& region, PlannerStateImpl& state,
                                 Resource resource, PlanStats& stats)
    : scene_(scene),
      config_(config),
      region_(region),
      state_(state),
      cache_(state.cache[static_cast<int>(resource)]),
      resource_(resource),
      stats_(stats) {}

const AccuracyCurve& CurvePropagator::evaluateRoot() {
  EvaluatedCandidates& evaluated = state_.evaluatedCandidates;
  ++evaluated.epoch;
  evaluated.pool.clear();
  if (config_.reuseLeafWork && evaluated.byNode.size() != scene_.nodes.size())
    evaluated.byNode.assign(scene_.nodes.size(), EvaluatedCandidates::Span{});
  return evaluateAbsolute(0, false);
}

AccuracyCurve CurvePropagator::leafRelativeCurve(std::uint32_t n, const PredictedRegion& region,
                                                 CandidateContext context) {
  const SceneNode& node = scene_.nodes[n];
  const std::vector<PendingCopy>* pending =
      context == CandidateContext::kExact ? pendingFor(state_, node.object) : nullptr;
  collectLeafCandidates(scene_, node.object, region, config_, context, pending, node.bounds,
                        scratch_);
  if (config_.reuseLeafWork && context == CandidateContext::kExact && &region == &region_) {
    EvaluatedCandidates& evaluated = state_.evaluatedCandidates;
    if (n < evaluated.byNode.size()) {
      evaluated.byNode[n] = {evaluated.epoch, static_cast<std::uint32_t>(evaluated.pool.size()),
                             static_cast<std::uint32_t>(scratch_.size())};
      evaluated.pool.insert(evaluated.pool.end(), scratch_.begin(), scratch_.end());
    }
  }
  if (scratch_.empty()) return AccuracyCurve();
  std::vector<AccuracyCurve> owned;
  owned.reserve(scratch_.size());
  std::vector<const AccuracyCurve*> parts;
  parts.reserve(scratch_.size());
  for (const LeafCandidate& c : scratch_) {
    if (c.source == CandidateSource::kNew) {
      const AccuracyCurve& full = curveOf(*c.representation, resource_);
      if (c.maxRelativeAccuracy >= full.maxAccuracy()) {
        parts.push_back(&full);
        continue;
      }
      owned.push_back(restrictTo(full, c.maxRelativeAccuracy));
    } else {
      const double r = resource_ == Resource::kTriangles ? c.fixedTriangles : c.fixedLinkBytes;
      owned.push_back(AccuracyCurve::point(c.maxRelativeAccuracy, r));
    }
  }
  for (const AccuracyCurve& c : owned) parts.push_back(&c);
  if (parts.size() == 1) return *parts.front();
  return AccuracyCurve::lowerEnvelope(parts);
}

const AccuracyCurve& CurvePropagator::evaluateAbsolute(std::uint32_t n, bool parentInside) {
  AbsoluteEntry& e = cache_.absolute[n];
  const SceneNode& node = scene_.nodes[n];
  if (e.valid && e.subtreeVersion == node.subtreeVersion &&
      e.pendingGeneration == state_.pendingGeneration && sameRegion(e.region, region_)) {
    ++stats_.curveReuses;
    return e.curve;
  }
  e.valid = true;
  e.subtreeVersion = node.subtreeVersion;
  e.pendingGeneration = state_.pendingGeneration;
  e.region = region_;
  e.merged = false;
  e.visibility = parentInside ? Visibility::kInside : classifySphere(region_, node.bounds);
  if (e.visibility == Visibility::kCulled) {
    ++stats_.culledNodes;
    e.curve = AccuracyCurve();
    return e.curve;
  }
  ++stats_.visitedNodes;
  ++stats_.curveComputes;
  const double diameter = 2.0 * node.bounds.radius;
  e.distance =
      conversionDistance(region_.center, region_.reachRadius, node.bounds, config_.minimalDistance);
  const double toAbsolute = e.distance / diameter;
  if (node.kind == SceneNodeKind::kLeaf) {
    AccuracyCurve relative = leafRelativeCurve(n, region_, CandidateContext::kExact);
    e.curve = relative.empty() ? AccuracyCurve() : relative.scaledAccuracy(toAbsolute);
    return e.curve;
  }
  const bool inside = e.visibility == Visibility::kInside;
  if (inside && e.distance >= config_.mergeDistanceFactor * diameter) {
    // Far enough that one conversion for the whole subtree is valid (3.4).
    PredictedRegion grown =
        growRegion(region_, config_.cacheDistanceMargin * e.distance, config_.cacheAngleMargin);
    if (classifySphere(grown, node.bounds) != Visibility::kInside) grown = region_;
    Slack slack;
    const AccuracyCurve& relative = evaluateRelative(n, grown, slack);
    AbsoluteEntry& again = cache_.absolute[n];  // same storage; vectors never resize here
    again.merged = true;
    again.curve = relative.empty() ? AccuracyCurve() : relative.scaledAccuracy(toAbsolute);
    ++stats_.mergedGroups;
    return again.curve;
  }
  std::vector<const AccuracyCurve*> parts;
  parts.reserve(node.childCount);
  for (std::uint32_t i = 0; i < node.childCount; ++i) {
    const std::uint32_t slot = node.firstChild + i;
    if (node.kind == SceneNodeKind::kLod &&
        !containsBall(scene_.childRanges[slot], region_.reachBall()))
      continue;
    const AccuracyCurve& child = evaluateAbsolute(scene_.children[slot], inside);
    if (!child.empty()) parts.push_back(&child);
  }
  e.curve = simplifyUpper(node.kind == SceneNodeKind::kGroup ? AccuracyCurve::sum(parts)
                                                             : AccuracyCurve::lowerEnvelope(parts),
                          config_.curveTolerance);
  return e.curve;
}

const AccuracyCurve& CurvePropagator::evaluateRelative(std::uint32_t n,
                                                       const PredictedRegion& computeRegion,
                                                       Slack& slack) {
  RelativeEntry& r = cache_.relative[n];
  const SceneNode& node = scene_.nodes[n];
  if (r.valid && r.subtreeVersion == node.subtreeVersion && regionContains(r.region, region_)) {
    ++stats_.curveReuses;
    slackOf(r.region, region_, slack.distance, slack.angle);
    return r.curve;
  }
  ++stats_.curveComputes;
  slackOf(computeRegion, region_, slack.distance, slack.angle);
  AccuracyCurve curve;
  if (node.kind == SceneNodeKind::kLeaf) {
    curve = leafRelativeCurve(n, computeRegion, CandidateContext::kConservative);
  } else {
    const double diameter = 2.0 * node.bounds.radius;
    std::vector<AccuracyCurve> scaled;
    scaled.reserve(node.childCount);
    for (std::uint32_t i = 0; i < node.childCount; ++i) {
      const std::uint32_t slot = node.firstChild + i;
      if (node.kind == SceneNodeKind::kLod &&
          !containsBall(scene_.childRanges[slot], computeRegion.reachBall()))
        continue;
      const std::uint32_t c = scene_.children[slot];
      Slack childSlack;
      const AccuracyCurve& child = evaluateRelative(c, computeRegion, childSlack);
      slack.distance = std::min(slack.distance, childSlack.distance);
      slack.angle = std::min(slack.angle, childSlack.angle);
      if (child.empty()) continue;
      // Relative to this node's diameter: same distortion, larger size.
      scaled.push_back(child.scaledAccuracy(diameter / (2.0 * scene_.nodes[c].bounds.radius)));
    }
    std::vector<const AccuracyCurve*> parts;
    parts.reserve(scaled.size());
    for (const AccuracyCurve& s : scaled) parts.push_back(&s);
    curve = simplifyUpper(node.kind == SceneNodeKind::kGroup ? AccuracyCurve::sum(parts)
                                                             : AccuracyCurve::lowerEnvelope(parts),
                          config_.curveTolerance);
  }
  RelativeEntry& entry = cache_.relative[n];
  entry.valid = true;
  entry.subtreeVersion = node.subtreeVersion;
  entry.region = growRegion(region_, slack.distance, slack.angle);
  entry.curve = std::move(curve);
  return entry.curve;
}

void CurvePropagator::pushDown(double targetAccuracy, std::vector<LeafSelection>& out) {
  StepCandidates& kept = state_.stepCandidates;
  kept.reset();
  state_.deferredLeaves.clear();
  const std::size_t first = out.size();
  out_ = &out;
  pushAbsolute(0, targetAccuracy);
  decideDeferredLeaves();
  out_ = nullptr;
  if (config_.reuseLeafWork && first == 0) {
    kept.valid = kept.begin.size() == out.size() && kept.count.size() == out.size();
  } else {
    kept.reset();
  }
}

void CurvePropagator::emit(const LeafSelection& selection,
                           const std::vector<LeafCandidate>* candidates) {
  if (config_.reuseLeafWork) {
    StepCandidates& kept = state_.stepCandidates;
    kept.begin.push_back(static_cast<std::uint32_t>(kept.pool.size()));
    kept.count.push_back(candidates ? static_cast<std::uint32_t>(candidates->size()) : 0);
    if (candidates) kept.pool.insert(kept.pool.end(), candidates->begin(), candidates->end());
  }
  out_->push_back(selection);
}

LeafSelection CurvePropagator::unrenderedLeaf(std::uint32_t n) const {
  LeafSelection s;
  s.node = n;
  s.object = scene_.nodes[n].object;
  s.rendered = false;
  return s;
}

void CurvePropagator::deferLeaf(std::uint32_t n, double absoluteAccuracy, double relativeCap) {
  const std::uint32_t slot = static_cast<std::uint32_t>(out_->size());
  emit(unrenderedLeaf(n), nullptr);  // placeholder, overwritten in decideDeferredLeaves
  const SceneNode& node = scene_.nodes[n];
  DeferredLeaf d;
  d.object = node.object;
  d.slot = slot;
  d.node = n;
  d.bounds = node.bounds;
  d.absoluteAccuracy = absoluteAccuracy;
  d.relativeCap = relativeCap;
  if (const EvaluatedCandidates::Span* span = evaluatedSpan(n)) {
    d.evaluated = true;
    d.candidatesBegin = span->begin;
    d.candidateCount = span->count;
  }
  state_.deferredLeaves.push_back(d);
}

void CurvePropagator::decideDeferredLeaves() {
  std::vector<DeferredLeaf>& leaves = state_.deferredLeaves;
  if (leaves.empty()) return;
  // Stable LSD radix sort by object, 11 bits a pass (each object has one
  // leaf, so this is the order of (object, slot)).
  std::uint32_t maxObject = 0;
  for (const DeferredLeaf& d : leaves) maxObject = std::max(maxObject, d.object);
  std::vector<DeferredLeaf>& buffer = state_.deferredSorted;
  buffer.resize(leaves.size());
  constexpr int kBits = 11;
  constexpr std::uint32_t kBuckets = 1u << kBits;
  for (int shift = 0; shift < 32 && (maxObject >> shift) != 0; shift += kBits) {
    std::uint32_t counts[kBuckets + 1] = {};
    for (const DeferredLeaf& d : leaves) ++counts[((d.object >> shift) & (kBuckets - 1)) + 1];
    for (std::uint32_t b = 1; b <= kBuckets; ++b) counts[b] += counts[b - 1];
    for (const DeferredLeaf& d : leaves) buffer[counts[(d.object >> shift) & (kBuckets - 1)]++] = d;
    leaves.swap(buffer);
  }
  StepCandidates& kept = state_.stepCandidates;
  for (std::size_t at = 0; at < leaves.size(); ++at) {
    const DeferredLeaf& d = leaves[at];
    const EvaluatedCandidates::Span span{0, d.candidatesBegin, d.candidateCount};
    LeafSelection s = decideLeaf(d.node, d.object, d.bounds, d.absoluteAccuracy, d.relativeCap,
                                 d.evaluated ? &span : nullptr);
    kept.begin[d.slot] = static_cast<std::uint32_t>(kept.pool.size());
    kept.count[d.slot] = s.rendered ? static_cast<std::uint32_t>(scratch_.size()) : 0;
    if (s.rendered) kept.pool.insert(kept.pool.end(), scratch_.begin(), scratch_.end());
    (*out_)[d.slot] = s;
  }
  leaves.clear();
}

void CurvePropagator::reportUnrenderable(std::uint32_t n) {
  const SceneNode& node = scene_.nodes[n];
  if (node.kind == SceneNodeKind::kLeaf) {
    emit(unrenderedLeaf(n), nullptr);
  } else if (node.kind == SceneNodeKind::kGroup) {
    for (std::uint32_t i = 0; i < node.childCount; ++i)
      reportUnrenderable(scene_.children[node.firstChild + i]);
  }
  // An LOD without an eligible level renders nothing and names no object.
}

void CurvePropagator::pushAbsolute(std::uint32_t n, double accuracy) {
  const AbsoluteEntry& e = cache_.absolute[n];
  if (e.visibility == Visibility::kCulled) return;
  const SceneNode& node = scene_.nodes[n];
  const double diameter = 2.0 * node.bounds.radius;
  if (node.kind == SceneNodeKind::kLeaf) {
    if (e.curve.empty()) {
      reportUnrenderable(n);
      return;
    }
    if (config_.reuseLeafWork) {
      deferLeaf(n, accuracy, kInf);
    } else {
      chooseLeaf(n, accuracy, kInf);
    }
    return;
  }
  if (e.merged) {
    if (e.curve.empty()) {
      reportUnrenderable(n);
      return;
    }
    pushRelative(n, accuracy * diameter / e.distance, accuracy);
    return;
  }
  if (node.kind == SceneNodeKind::kGroup) {
    for (std::uint32_t i = 0; i < node.childCount; ++i)
      pushAbsolute(scene_.children[node.firstChild + i], accuracy);
    return;
  }
  if (e.curve.empty()) return;
  const double clamped = std::min(accuracy, e.curve.maxAccuracy());
  std::int64_t best = -1;
  double bestCost = kInf;
  for (std::uint32_t i = 0; i < node.childCount; ++i) {
    const std::uint32_t slot = node.firstChild + i;
    if (!containsBall(scene_.childRanges[slot], region_.reachBall())) continue;
    const AbsoluteEntry& child = cache_.absolute[scene_.children[slot]];
    if (child.visibility == Visibility::kCulled || child.curve.empty()) continue;
    if (child.curve.maxAccuracy() < clamped * (1.0 - kAccuracyTolerance)) continue;
    const double cost = child.curve.resourcesFor(std::min(clamped, child.curve.maxAccuracy()));
    if (cost < bestCost) {
      bestCost = cost;
      best = scene_.children[slot];
    }
  }
  if (best >= 0) pushAbsolute(static_cast<std::uint32_t>(best), clamped);
}

void CurvePropagator::pushRelative(std::uint32_t n, double relativeAccuracy,
                                   double absoluteAccuracy) {
  const RelativeEntry& r = cache_.relative[n];
  const SceneNode& node = scene_.nodes[n];
  if (r.curve.empty()) {
    reportUnrenderable(n);
    return;
  }
  const double clamped = std::min(relativeAccuracy, r.curve.maxAccuracy());
  if (node.kind == SceneNodeKind::kLeaf) {
    if (config_.reuseLeafWork) {
      deferLeaf(n, absoluteAccuracy, clamped);
    } else {
      chooseLeaf(n, absoluteAccuracy, clamped);
    }
    return;
  }
  const double diameter = 2.0 * node.bounds.radius;
  if (node.kind == SceneNodeKind::kGroup) {
    for (std::uint32_t i = 0; i < node.childCount; ++i) {
      const std::uint32_t c = scene_.children[node.firstChild + i];
      pushRelative(c, clamped * 2.0 * scene_.nodes[c].bounds.radius / diameter, absoluteAccuracy);
    }
    return;
  }
  std::int64_t best = -1;
  double bestCost = kInf;
  double bestAccuracy = 0.0;
  for (std::uint32_t i = 0; i < node.childCount; ++i) {
    const std::uint32_t slot = node.firstChild + i;
    if (!containsBall(scene_.childRanges[slot], r.region.reachBall())) continue;
    const std::uint32_t c = scene_.children[slot];
    const AccuracyCurve& child = cache_.relative[c].curve;
    if (child.empty()) continue;
    const double childAccuracy = clamped * 2.0 * scene_.nodes[c].bounds.radius / diameter;
    if (child.maxAccuracy() < childAccuracy * (1.0 - kAccuracyTolerance)) continue;
    const double cost = child.resourcesFor(std::min(childAccuracy, child.maxAccuracy()));
    if (cost < bestCost) {
      bestCost = cost;
      best = c;
      bestAccuracy = childAccuracy;
    }
  }
  if (best >= 0) pushRelative(static_cast<std::uint32_t>(best), bestAccuracy, absoluteAccuracy);
}

void CurvePropagator::chooseLeaf(std::uint32_t n, double absoluteAccuracy, double relativeCap) {
  const SceneNode& node = scene_.nodes[n];
  const LeafSelection s =
      decideLeaf(n, node.object, node.bounds, absoluteAccuracy, relativeCap, evaluatedSpan(n));
  emit(s, s.rendered ? &scratch_ : nullptr);
}

const EvaluatedCandidates::Span* CurvePropagator::evaluatedSpan(std::uint32_t n) const {
  const EvaluatedCandidates& evaluated = state_.evaluatedCandidates;
  if (config_.reuseLeafWork && n < evaluated.byNode.size() &&
      evaluated.byNode[n].epoch == evaluated.epoch)
    return &evaluated.byNode[n];
  return nullptr;
}

LeafSelection CurvePropagator::decideLeaf(std::uint32_t n, std::uint32_t object,
                                          const Sphere& bounds, double absoluteAccuracy,
                                          double relativeCap,
                                          const EvaluatedCandidates::Span* evaluated) {
  const double diameter = 2.0 * bounds.radius;
  const double distance =
      conversionDistance(region_.center, region_.reachRadius, bounds, config_.minimalDistance);
  if (evaluated) {
    const std::vector<LeafCandidate>& pool = state_.evaluatedCandidates.pool;
    scratch_.assign(pool.begin() + evaluated->begin,
                    pool.begin() + evaluated->begin + evaluated->count);
  } else {
    collectLeafCandidates(scene_, object, region_, config_, CandidateContext::kExact,
                          pendingFor(state_, object), bounds, scratch_);
  }
  double need = std::min(absoluteAccuracy * diameter / distance, relativeCap);
  need = std::min(need, bestCandidateAccuracy(scratch_));
  if (!config_.reuseLeafWork) {  // reference path, as before
    const int pick = pickCandidate(scratch_, need, resource_ == Resource::kTriangles);
    if (pick < 0) return unrenderedLeaf(n);
    return makeSelection(n, object, scratch_[pick], need, distance, diameter);
  }
  CandidateCost cost;
  const int pick = pickCandidate(scratch_, need, resource_ == Resource::kTriangles, &cost);
  if (pick < 0) return unrenderedLeaf(n);
  return makeSelection(n, object, scratch_[pick], need, distance, diameter, cost);
}

}  // namespace thinlod::backbone
