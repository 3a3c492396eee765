#include "joint_solver.h"

#include <algorithm>
#include <cmath>

#include "scheduler_common.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

JointSolver::JointSolver(const SchedulingScene& scene, const SchedulerConfig& config,
                         const PredictedRegion& region, const PlannerStateImpl& state,
                         const JointBudget& budget, PlanStats& stats)
    : scene_(scene),
      config_(config),
      region_(region),
      state_(state),
      budget_(budget),
      stats_(stats) {
  root_ = build(0, false);
  nodeSet_.assign(nodes_.size(), Span{});
  minTriangles_.assign(nodes_.size(), 0.0);
  minLink_.assign(nodes_.size(), 0.0);
  scalarT_.assign(nodes_.size(), 0.0);
  scalarL_.assign(nodes_.size(), 0.0);
  scalarPick_.assign(nodes_.size(), -1);
  invariant_.assign(nodes_.size(), 0);
  costTriangles_.assign(candidates_.size(), 0.0);
  costLink_.assign(candidates_.size(), 0.0);
  levelOk_.assign(children_.size(), 0);
  refreshAccuracyBounds();
}

std::int32_t JointSolver::build(std::uint32_t sceneNode, bool parentInside) {
  const SceneNode& node = scene_.nodes[sceneNode];
  const Visibility visibility =
      parentInside ? Visibility::kInside : classifySphere(region_, node.bounds);
  if (visibility == Visibility::kCulled) {
    ++stats_.culledNodes;
    return -1;
  }
  ++stats_.visitedNodes;
  const std::uint32_t k = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_[k].kind = node.kind;
  nodes_[k].sceneNode = sceneNode;
  nodes_[k].diameter = 2.0 * node.bounds.radius;
  nodes_[k].distance =
      conversionDistance(region_.center, region_.reachRadius, node.bounds, config_.minimalDistance);
  if (node.kind == SceneNodeKind::kLeaf) {
    std::vector<LeafCandidate> found;
    collectLeafCandidates(scene_, node.object, region_, config_, CandidateContext::kExact,
                          pendingFor(state_, node.object), node.bounds, found);
    nodes_[k].firstCandidate = static_cast<std::uint32_t>(candidates_.size());
    nodes_[k].candidateCount = static_cast<std::uint32_t>(found.size());
    candidates_.insert(candidates_.end(), found.begin(), found.end());
    if (config_.reuseLeafWork) {
      for (const LeafCandidate& c : found) {
        PooledCosts costs;
        if (c.source == CandidateSource::kNew) {
          costs.triangles = poolCurve(c.representation->relativeTriangles);
          costs.link = poolCurve(c.representation->relativeLinkBytes);
        }
        pooled_.push_back(costs);
      }
    }
    ++leafCount_;
    return static_cast<std::int32_t>(k);
  }
  const bool inside = visibility == Visibility::kInside;
  std::vector<std::uint32_t> kids;
  kids.reserve(node.childCount);
  for (std::uint32_t i = 0; i < node.childCount; ++i) {
    const std::uint32_t slot = node.firstChild + i;
    if (node.kind == SceneNodeKind::kLod &&
        !containsBall(scene_.childRanges[slot], region_.reachBall()))
      continue;
    const std::int32_t c = build(scene_.children[slot], inside);
    if (c >= 0) kids.push_back(static_cast<std::uint32_t>(c));
  }
  nodes_[k].firstChild = static_cast<std::uint32_t>(children_.size());
  nodes_[k].childCount = static_cast<std::uint32_t>(kids.size());
  children_.insert(children_.end(), kids.begin(), kids.end());
  if (node.kind == SceneNodeKind::kGroup) {
    nodes_[k].firstStage = static_cast<std::uint32_t>(stages_.size());
    stages_.resize(stages_.size() + kids.size());
  }
  return static_cast<std::int32_t>(k);
}

JointSolver::PooledCurve JointSolver::poolCurve(const AccuracyCurve& curve) {
  PooledCurve pooled;
  pooled.begin = static_cast<std::uint32_t>(segmentPool_.size());
  pooled.count = static_cast<std::uint32_t>(curve.segments().size());
  pooled.maxAccuracy = curve.maxAccuracy();
  segmentPool_.insert(segmentPool_.end(), curve.segments().begin(), curve.segments().end());
  return pooled;
}

// AccuracyCurve::resourcesFor on the pooled copy, step for step (the same
// comparisons, the same segment search, the same expression for the value),
// so the result is the same double. ReuseLeafWork's randomized both-budget
// tests and bench_scheduler's same_plans check it against the reference.
double JointSolver::curveCost(const PooledCurve& curve, double a) const {
  if (curve.count == 0) return 0.0;
  if (std::isnan(a) || a > curve.maxAccuracy) return kInf;
  const CurveSegment* first = segmentPool_.data() + curve.begin;
  const CurveSegment* last = first + curve.count;
  if (a <= first->start) return first->value;
  const CurveSegment* it = std::upper_bound(
      first, last, a, [](double value, const CurveSegment& s) { return value < s.start; });
  const CurveSegment& s = it == first ? *first : *(it - 1);
  return s.value + s.slope * (a - s.start);
}

void JointSolver::refreshAccuracyBounds() {
  // Children are created after their parent: reverse order is bottom-up.
  for (std::size_t i = nodes_.size(); i-- > 0;) {
    Node& n = nodes_[i];
    n.maxAccuracy = -kInf;
    n.minAccuracy = kInf;
    if (n.kind == SceneNodeKind::kLeaf) {
      if (n.dropped || n.candidateCount == 0) continue;
      const std::vector<LeafCandidate> view(
          candidates_.begin() + n.firstCandidate,
          candidates_.begin() + n.firstCandidate + n.candidateCount);
      const double scale = n.distance / n.diameter;
      n.maxAccuracy = bestCandidateAccuracy(view) * scale;
      n.minAccuracy = lowestCandidateAccuracy(view) * scale;
      continue;
    }
    for (std::uint32_t c = 0; c < n.childCount; ++c) {
      const Node& child = nodes_[children_[n.firstChild + c]];
      n.maxAccuracy = std::max(n.maxAccuracy, child.maxAccuracy);
      n.minAccuracy = std::min(n.minAccuracy, child.minAccuracy);
    }
  }
}

double JointSolver::lowestAccuracy() const {
  if (root_ < 0) return 0.0;
  const double low = nodes_[root_].minAccuracy;
  return std::isfinite(low) ? low : 0.0;
}

double JointSolver::highestAccuracy() const {
  return root_ < 0 ? -kInf : nodes_[root_].maxAccuracy;
}

JointSolver::Span JointSolver::finish(std::uint32_t begin, double limitTriangles,
                                      double limitLink) {
  const std::uint32_t end = static_cast<std::uint32_t>(arena_.size());
  std::uint32_t out = begin;
  for (std::uint32_t i = begin; i < end; ++i) {
    const Point& p = arena_[i];
    if (budget_.useTriangles && !(p.triangles <= limitTriangles)) continue;
    if (budget_.useLink && !(p.link <= limitLink)) continue;
    arena_[out++] = p;
  }
  arena_.resize(out);
  if (out == begin) return {begin, 0};
  auto first = arena_.begin() + begin;
  if (budget_.useTriangles && budget_.useLink) {
    std::sort(first, arena_.end(), [](const Point& a, const Point& b) {
      if (a.triangles != b.triangles) return a.triangles < b.triangles;
      if (a.link != b.link) return a.link < b.link;
      return a.tie < b.tie;
    });
    std::uint32_t kept = begin;
    double lastLink = kInf;
    for (std::uint32_t i = begin; i < out; ++i) {
      if (arena_[i].link < lastLink) {
        lastLink = arena_[i].link;
        arena_[kept++] = arena_[i];
      }
    }
    arena_.resize(kept);
    std::uint32_t size = kept - begin;
    const std::uint32_t cap = static_cast<std::uint32_t>(config_.paretoCap);
    if (size > cap) {
      // Keep both ends and evenly spaced points in between: a subset, so
      // every kept point is still achievable (lower answer, never over budget).
      ++stats_.paretoThinnings;
      for (std::uint32_t j = 0; j < cap; ++j) {
        const std::uint32_t from =
            static_cast<std::uint32_t>(std::llround(double(j) * (size - 1) / (cap - 1)));
        arena_[begin + j] = arena_[begin + from];
      }
      arena_.resize(begin + cap);
      size = cap;
    }
    return {begin, size};
  }
  const bool linkFirst = budget_.useLink && !budget_.useTriangles;
  auto better = [linkFirst](const Point& a, const Point& b) {
    const double pa = linkFirst ? a.link : a.triangles;
    const double pb = linkFirst ? b.link : b.triangles;
    if (pa != pb) return pa < pb;
    const double sa = linkFirst ? a.triangles : a.link;
    const double sb = linkFirst ? b.triangles : b.link;
    if (sa != sb) return sa < sb;
    return a.tie < b.tie;
  };
  auto best = std::min_element(first, arena_.end(), better);
  arena_[begin] = *best;
  arena_.resize(begin + 1);
  return {begin, 1};
}

void JointSolver::prepareCosts(std::uint32_t k, double accuracy) {
  const Node& n = nodes_[k];
  if (n.maxAccuracy == -kInf) return;
  const double clamped = std::min(accuracy, n.maxAccuracy);
  if (n.kind == SceneNodeKind::kLeaf) {
    const double x = clamped * n.diameter / n.distance;
    for (std::uint32_t i = 0; i < n.candidateCount; ++i) {
      const std::uint32_t c = n.firstCandidate + i;
      const LeafCandidate& candidate = candidates_[c];
      if (!(candidate.maxRelativeAccuracy >= x * (1.0 - kAccuracyTolerance))) {
        costTriangles_[c] = std::nan("");
        continue;
      }
      if (config_.reuseLeafWork) {  // candidateCost from the pooled curves
        if (candidate.source != CandidateSource::kNew) {
          costTriangles_[c] = candidate.fixedTriangles;
          costLink_[c] = candidate.fixedLinkBytes;
          continue;
        }
        const double a =
            std::min(std::min(x, candidate.maxRelativeAccuracy), candidate.maxRelativeAccuracy);
        costTriangles_[c] = curveCost(pooled_[c].triangles, a);
        costLink_[c] = curveCost(pooled_[c].link, a);
        continue;
      }
      const CandidateCost cost =
          candidateCost(candidate, std::min(x, candidate.maxRelativeAccuracy));
      costTriangles_[c] = cost.triangles;
      costLink_[c] = cost.linkBytes;
    }
    return;
  }
  for (std::uint32_t c = 0; c < n.childCount; ++c) {
    const std::uint32_t child = children_[n.firstChild + c];
    if (n.kind == SceneNodeKind::kLod) {
      const bool ok = nodes_[child].maxAccuracy >= clamped * (1.0 - kAccuracyTolerance);
      levelOk_[n.firstChild + c] = ok;
      if (ok) prepareCosts(child, clamped);
    } else {
      prepareCosts(child, accuracy);
    }
  }
}

void JointSolver::computeMinima(std::uint32_t k) {
  const Node& n = nodes_[k];
  double t = 0.0;
  double l = 0.0;
  if (n.maxAccuracy != -kInf) {
    if (n.kind == SceneNodeKind::kLeaf) {
      t = kInf;
      l = kInf;
      for (std::uint32_t i = 0; i < n.candidateCount; ++i) {
        const std::uint32_t c = n.firstCandidate + i;
        if (std::isnan(costTriangles_[c])) continue;
        t = std::min(t, costTriangles_[c]);
        l = std::min(l, costLink_[c]);
      }
    } else if (n.kind == SceneNodeKind::kLod) {
      t = kInf;
      l = kInf;
      for (std::uint32_t c = 0; c < n.childCount; ++c) {
        if (!levelOk_[n.firstChild + c]) continue;
        const std::uint32_t child = children_[n.firstChild + c];
        computeMinima(child);
        t = std::min(t, minTriangles_[child]);
        l = std::min(l, minLink_[child]);
      }
    } else {
      for (std::uint32_t c = 0; c < n.childCount; ++c) {
        const std::uint32_t child = children_[n.firstChild + c];
        computeMinima(child);
        t += minTriangles_[child];
        l += minLink_[child];
      }
    }
  }
  minTriangles_[k] = t;
  minLink_[k] = l;
}

namespace {
// Is (t1, l1) a strictly better choice than (t2, l2) for weight w?
bool scalarBetter(double t1, double l1, double t2, double l2, double w) {
  if (std::isinf(w)) return l1 < l2 || (l1 == l2 && t1 < t2);
  const double v1 = t1 + w * l1;
  const double v2 = t2 + w * l2;
  return v1 < v2 || (v1 == v2 && (t1 < t2 || (t1 == t2 && l1 < l2)));
}
}  // namespace

void JointSolver::scalarPass(std::uint32_t k, double weight, double& triangles, double& link) {
  if (invariantReady_ && invariant_[k]) {
    // Same totals and pick for every weight (see markInvariant): the values
    // the full recursion would compute again, bit for bit.
    triangles = scalarT_[k];
    link = scalarL_[k];
    return;
  }
  const Node& n = nodes_[k];
  double t = 0.0;
  double l = 0.0;
  std::int32_t pick = -1;
  if (n.maxAccuracy != -kInf) {
    if (n.kind == SceneNodeKind::kLeaf) {
      t = kInf;
      l = kInf;
      for (std::uint32_t i = 0; i < n.candidateCount; ++i) {
        const std::uint32_t c = n.firstCandidate + i;
        if (std::isnan(costTriangles_[c])) continue;
        if (pick < 0 || scalarBetter(costTriangles_[c], costLink_[c], t, l, weight)) {
          t = costTriangles_[c];
          l = costLink_[c];
          pick = static_cast<std::int32_t>(i);
        }
      }
    } else if (n.kind == SceneNodeKind::kLod) {
      t = kInf;
      l = kInf;
      for (std::uint32_t c = 0; c < n.childCount; ++c) {
        if (!levelOk_[n.firstChild + c]) continue;
        double ct = 0.0;
        double cl = 0.0;
        scalarPass(children_[n.firstChild + c], weight, ct, cl);
        if (pick < 0 || scalarBetter(ct, cl, t, l, weight)) {
          t = ct;
          l = cl;
          pick = static_cast<std::int32_t>(c);
        }
      }
    } else {
      for (std::uint32_t c = 0; c < n.childCount; ++c) {
        double ct = 0.0;
        double cl = 0.0;
        scalarPass(children_[n.firstChild + c], weight, ct, cl);
        t += ct;
        l += cl;
      }
    }
  }
  scalarPick_[k] = pick;
  triangles = t;
  link = l;
  if (config_.reuseLeafWork && !invariantReady_) markInvariant(k, t, l);
}

// A node's choice is the same for every weight w >= 0 (infinity included)
// when its pick is at most every alternative in both resources: then
// t + w l of the pick is <= that of each alternative in floating point too
// (rounding is monotone), and scalarBetter's ties (triangles, then bytes,
// then the earlier index) keep the same pick. A leaf: its picked candidate
// against the others; a group: every child invariant (same sums in the
// same order); an LOD: every qualifying level invariant and the picked
// level dominating the others. Set by the first pass after prepareCosts
// (the costs of one accuracy), read by the later passes of that accuracy.
void JointSolver::markInvariant(std::uint32_t k, double t, double l) {
  const Node& n = nodes_[k];
  scalarT_[k] = t;
  scalarL_[k] = l;
  bool invariant = true;
  if (n.maxAccuracy != -kInf) {
    if (n.kind == SceneNodeKind::kLeaf) {
      for (std::uint32_t i = 0; i < n.candidateCount && invariant; ++i) {
        const std::uint32_t c = n.firstCandidate + i;
        if (std::isnan(costTriangles_[c])) continue;
        invariant = t <= costTriangles_[c] && l <= costLink_[c];
      }
    } else if (n.kind == SceneNodeKind::kLod) {
      for (std::uint32_t c = 0; c < n.childCount && invariant; ++c) {
        if (!levelOk_[n.firstChild + c]) continue;
        const std::uint32_t child = children_[n.firstChild + c];
        invariant = invariant_[child] && t <= scalarT_[child] && l <= scalarL_[child];
      }
    } else {
      for (std::uint32_t c = 0; c < n.childCount && invariant; ++c)
        invariant = invariant_[children_[n.firstChild + c]];
    }
  }
  invariant_[k] = invariant;
}

JointSolver::Verdict JointSolver::lagrangianScreen(double& certificateWeight) {
  const std::uint32_t root = static_cast<std::uint32_t>(root_);
  const double bt = budget_.triangles;
  const double bl = budget_.linkBytes;
  auto fits = [&](double t, double l) { return t <= bt && l <= bl; };
  double t = 0.0;
  double l = 0.0;
  scalarPass(root, 0.0, t, l);  // fewest triangles
  invariantReady_ = config_.reuseLeafWork;
  if (!(t <= bt)) return Verdict::kInfeasible;
  if (fits(t, l)) {
    certificateWeight = 0.0;
    return Verdict::kFeasible;
  }
  scalarPass(root, kInf, t, l);  // fewest bytes
  if (!(l <= bl)) return Verdict::kInfeasible;
  if (fits(t, l)) {
    certificateWeight = kInf;
    return Verdict::kFeasible;
  }
  // Bisect the weight (log scale around budgetT / budgetL): too many bytes
  // -> weigh bytes more; too many triangles -> less.
  const double scale = bl > 0.0 ? std::max(bt, 1e-300) / bl : 1.0;
  double lo = std::log(scale) - 40.0;
  double hi = std::log(scale) + 40.0;
  for (int i = 0; i < 48; ++i) {
    const double w = std::exp(0.5 * (lo + hi));
    scalarPass(root, w, t, l);
    if (fits(t, l)) {
      certificateWeight = w;
      return Verdict::kFeasible;
    }
    // Every feasible choice has t + w l <= bt + w bl; the minimum above
    // that bound (with a rounding margin) proves that none exists.
    if (t + w * l > (bt + w * bl) * (1.0 + 1e-12)) return Verdict::kInfeasible;
    if (l > bl) {
      lo = std::log(w);
    } else {
      hi = std::log(w);
    }
  }
  return Verdict::kUnknown;
}

void JointSolver::extractScalar(std::uint32_t k, double accuracy, double weight,
                                std::vector<LeafSelection>& out) {
  const Node& n = nodes_[k];
  if (n.maxAccuracy == -kInf) {
    reportNothing(k, false, out);
    return;
  }
  const double clamped = std::min(accuracy, n.maxAccuracy);
  const std::int32_t pick = scalarPick_[k];
  if (n.kind == SceneNodeKind::kLeaf) {
    const LeafCandidate& c = candidates_[n.firstCandidate + pick];
    const double x = clamped * n.diameter / n.distance;
    out.push_back(makeSelection(n.sceneNode, scene_.nodes[n.sceneNode].object, c,
                                std::min(x, c.maxRelativeAccuracy), n.distance, n.diameter));
  } else if (n.kind == SceneNodeKind::kLod) {
    extractScalar(children_[n.firstChild + pick], clamped, weight, out);
  } else {
    for (std::uint32_t c = 0; c < n.childCount; ++c)
      extractScalar(children_[n.firstChild + c], accuracy, weight, out);
  }
}

// Precondition: prepareCosts(root, accuracy) ran last (feasible() does it).
bool JointSolver::paretoFeasible(double accuracy) {
  ++stats_.paretoPasses;
  ++paretoPasses_;
  arena_.clear();
  return evaluate(static_cast<std::uint32_t>(root_), accuracy, budget_.triangles, budget_.linkBytes)
             .size > 0;
}

JointSolver::Span JointSolver::evaluate(std::uint32_t k, double accuracy, double limitTriangles,
                                        double limitLink) {
  const Node n = nodes_[k];
  if (n.maxAccuracy == -kInf) {
    const std::uint32_t begin = static_cast<std::uint32_t>(arena_.size());
    arena_.push_back({0.0, 0.0, -1, -1, 0});
    nodeSet_[k] = {begin, 1};
    return nodeSet_[k];
  }
  const double clamped = std::min(accuracy, n.maxAccuracy);
  if (n.kind == SceneNodeKind::kLeaf) {
    const double x = clamped * n.diameter / n.distance;
    const std::uint32_t begin = static_cast<std::uint32_t>(arena_.size());
    for (std::uint32_t i = 0; i < n.candidateCount; ++i) {
      const std::uint32_t at = n.firstCandidate + i;
      const LeafCandidate& c = candidates_[at];
      if (config_.reuseLeafWork) {
        // feasible() prepared this accuracy's costs just before (same
        // clamping down the tree, NaN exactly where the test below fails):
        // the same numbers without two curve look-ups per candidate.
        if (std::isnan(costTriangles_[at])) continue;
        arena_.push_back({costTriangles_[at], costLink_[at], static_cast<std::int32_t>(i), -1,
                          candidateSourceRank(c.source)});
        continue;
      }
      if (!(c.maxRelativeAccuracy >= x * (1.0 - kAccuracyTolerance))) continue;
      const CandidateCost cost = candidateCost(c, std::min(x, c.maxRelativeAccuracy));
      arena_.push_back({cost.triangles, cost.linkBytes, static_cast<std::int32_t>(i), -1,
                        candidateSourceRank(c.source)});
    }
    nodeSet_[k] = finish(begin, limitTriangles, limitLink);
    return nodeSet_[k];
  }
  if (n.kind == SceneNodeKind::kLod) {
    std::vector<std::pair<std::uint32_t, Span>> levels;
    for (std::uint32_t c = 0; c < n.childCount; ++c) {
      const std::uint32_t child = children_[n.firstChild + c];
      if (!(nodes_[child].maxAccuracy >= clamped * (1.0 - kAccuracyTolerance))) continue;
      const Span s = evaluate(child, clamped, limitTriangles, limitLink);
      if (s.size > 0) levels.push_back({c, s});
    }
    const std::uint32_t begin = static_cast<std::uint32_t>(arena_.size());
    for (const auto& [position, span] : levels) {
      for (std::uint32_t j = 0; j < span.size; ++j) {
        const Point q = arena_[span.begin + j];
        arena_.push_back({q.triangles, q.link, static_cast<std::int32_t>(position),
                          static_cast<std::int32_t>(j), 0});
      }
    }
    nodeSet_[k] = finish(begin, limitTriangles, limitLink);
    return nodeSet_[k];
  }
  // Group: fold the children's sets with pairwise sums, one stage per child.
  // A partial sum over children 0..c leaves room only for what children
  // c+1.. need at least; a child's own set leaves room for all its siblings.
  double restTriangles = 0.0;
  double restLink = 0.0;
  for (std::uint32_t c = 0; c < n.childCount; ++c) {
    const std::uint32_t child = children_[n.firstChild + c];
    restTriangles += minTriangles_[child];
    restLink += minLink_[child];
  }
  Span previous{0, 0};
  for (std::uint32_t c = 0; c < n.childCount; ++c) {
    const std::uint32_t child = children_[n.firstChild + c];
    const double siblingsT = restTriangles - minTriangles_[child];
    const double siblingsL = restLink - minLink_[child];
    const Span s = evaluate(child, accuracy, limitTriangles - siblingsT, limitLink - siblingsL);
    if (s.size == 0) {
      nodeSet_[k] = {0, 0};
      return nodeSet_[k];
    }
    double laterT = 0.0;
    double laterL = 0.0;
    for (std::uint32_t j = c + 1; j < n.childCount; ++j) {
      laterT += minTriangles_[children_[n.firstChild + j]];
      laterL += minLink_[children_[n.firstChild + j]];
    }
    const std::uint32_t begin = static_cast<std::uint32_t>(arena_.size());
    if (c == 0) {
      arena_.reserve(arena_.size() + s.size);
      for (std::uint32_t j = 0; j < s.size; ++j) {
        const Point q = arena_[s.begin + j];
        arena_.push_back({q.triangles, q.link, -1, static_cast<std::int32_t>(j), 0});
      }
    } else {
      arena_.reserve(arena_.size() + std::size_t{previous.size} * s.size);
      for (std::uint32_t i = 0; i < previous.size; ++i) {
        const Point p = arena_[previous.begin + i];
        for (std::uint32_t j = 0; j < s.size; ++j) {
          const Point q = arena_[s.begin + j];
          arena_.push_back({p.triangles + q.triangles, p.link + q.link,
                            static_cast<std::int32_t>(i), static_cast<std::int32_t>(j), 0});
        }
      }
    }
    previous = finish(begin, limitTriangles - laterT, limitLink - laterL);
    stages_[n.firstStage + c] = previous;
    if (previous.size == 0) {
      nodeSet_[k] = previous;
      return previous;
    }
  }
  nodeSet_[k] = previous;
  return previous;
}

bool JointSolver::feasible(double accuracy) {
  ++stats_.solverEvaluations;
  lastByScalar_ = false;
  if (root_ < 0) return true;
  const std::uint32_t root = static_cast<std::uint32_t>(root_);
  prepareCosts(root, accuracy);
  invariantReady_ = false;  // the next scalar pass marks the weight-invariant nodes anew
  computeMinima(root);
  if (budget_.useTriangles && !(minTriangles_[root] <= budget_.triangles)) return false;
  if (budget_.useLink && !(minLink_[root] <= budget_.linkBytes)) return false;
  if (!(budget_.useTriangles && budget_.useLink)) {
    // One budget (or none): the cheapest choice decides.
    lastByScalar_ = true;
    lastWeight_ = budget_.useLink && !budget_.useTriangles ? kInf : 0.0;
    return true;
  }
  double weight = 0.0;
  switch (lagrangianScreen(weight)) {
    case Verdict::kFeasible:
      ++stats_.lagrangianDecisions;
      lastByScalar_ = true;
      lastWeight_ = weight;
      return true;
    case Verdict::kInfeasible:
      ++stats_.lagrangianDecisions;
      return false;
    case Verdict::kUnknown:
      break;
  }
  if (paretoPasses_ >= config_.maxParetoPasses) {
    ++stats_.undecidedAccuracies;  // treated as infeasible: lower, never over budget
    return false;
  }
  return paretoFeasible(accuracy);
}

std::size_t JointSolver::dropUntilFeasible(const ViewerState& viewer) {
  if (feasible(0.0)) return 0;
  // feasible(0) left every leaf's cheapest cost at accuracy 0 in
  // minTriangles_/minLink_ (at 0 every LOD level qualifies). A leaf costing
  // nothing in each budget the cheapest plan overruns cannot make room:
  // dropping it only blanks it. The typical one holds a frontend copy (no
  // link bytes) while the link cannot carry anything new (a cut link), and
  // dropping it would take a picture the client already has off the screen.
  // So only leaves that cost something in an overrun budget are dropped;
  // when no budget overruns alone (the pair does), every leaf may be.
  const std::uint32_t root = static_cast<std::uint32_t>(root_);
  const bool trianglesShort = budget_.useTriangles && !(minTriangles_[root] <= budget_.triangles);
  const bool linkShort = budget_.useLink && !(minLink_[root] <= budget_.linkBytes);
  std::vector<std::uint32_t> leaves;
  std::vector<std::uint32_t> freeLeaves;
  std::vector<double> priority(nodes_.size(), 0.0);
  const ViewCone cone(viewer);
  for (std::uint32_t k = 0; k < nodes_.size(); ++k) {
    const Node& n = nodes_[k];
    if (n.kind != SceneNodeKind::kLeaf || n.candidateCount == 0) continue;
    const bool helps = (!trianglesShort && !linkShort) ||
                       (trianglesShort && !(minTriangles_[k] <= 0.0)) ||
                       (linkShort && !(minLink_[k] <= 0.0));
    (helps ? leaves : freeLeaves).push_back(k);
    priority[k] = cone.keepPriority(scene_.nodes[n.sceneNode].bounds, n.diameter, n.distance);
  }
  // The free leaves go after every other in the order below, so the search
  // reaches them only if dropping all the others still does not fit (not
  // expected: their cheapest costs are 0 in the overrun budgets).
  const std::size_t helpful = leaves.size();
  auto byPriority = [&](std::uint32_t a, std::uint32_t b) {
    if (priority[a] != priority[b]) return priority[a] < priority[b];
    return nodes_[a].sceneNode < nodes_[b].sceneNode;
  };
  std::sort(leaves.begin(), leaves.end(), byPriority);
  std::sort(freeLeaves.begin(), freeLeaves.end(), byPriority);
  leaves.insert(leaves.end(), freeLeaves.begin(), freeLeaves.end());
  auto apply = [&](std::size_t count) {
    for (std::size_t i = 0; i < leaves.size(); ++i) nodes_[leaves[i]].dropped = i < count;
    refreshAccuracyBounds();
  };
  // Dropping more never costs more: binary search the fewest drops, first
  // among the leaves that cost something in an overrun budget.
  std::size_t lo = 0;  // infeasible
  std::size_t hi = leaves.size();
  if (helpful < leaves.size()) {
    apply(helpful);
    if (feasible(0.0)) {
      hi = helpful;
    } else {
      lo = helpful;
    }
  }
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    apply(mid);
    if (feasible(0.0)) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  apply(hi);
  return hi;
}

std::optional<double> JointSolver::search(double lo, double hi, std::optional<double> hint) {
  if (!feasible(lo)) return std::nullopt;
  if (feasible(hi)) return hi;
  if (hint && *hint > lo && *hint < hi) {
    if (feasible(*hint)) {
      lo = *hint;
    } else {
      hi = *hint;
    }
  }
  for (int i = 0; i < 200 && hi > lo * (1.0 + 1e-11); ++i) {
    const double mid = lo > 0.0 ? std::sqrt(lo) * std::sqrt(hi) : 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    if (feasible(mid)) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return lo;
}

std::optional<double> JointSolver::maximise(std::optional<double> cap, std::optional<double> hint) {
  const double top = highestAccuracy();
  if (top == -kInf) return cap ? *cap : kInf;  // nothing renderable constrains the target
  const double ceiling = cap ? std::min(top, *cap) : top;
  const double lo = std::min(lowestAccuracy(), ceiling);
  const double hi = ceiling;
  const std::optional<double> best = search(lo, hi, hint);
  if (!best) return std::nullopt;
  // Above the best any object reaches nothing costs more: a reachable cap
  // (fixed accuracy) is the target itself.
  if (cap && *best >= ceiling) return *cap;
  return best;
}

void JointSolver::extract(double accuracy, std::vector<LeafSelection>& out) {
  if (root_ < 0) return;
  const std::uint32_t rootNode = static_cast<std::uint32_t>(root_);
  const int savedPasses = paretoPasses_;
  paretoPasses_ = std::min(paretoPasses_, config_.maxParetoPasses - 1);  // allow one more pass
  const bool ok = feasible(accuracy);
  paretoPasses_ = std::max(paretoPasses_, savedPasses);
  if (!ok) return;  // callers extract accuracies found feasible
  if (lastByScalar_) {
    double t = 0.0;
    double l = 0.0;
    scalarPass(rootNode, lastWeight_, t, l);
    extractScalar(rootNode, accuracy, lastWeight_, out);
    return;
  }
  const Span root{nodeSet_[rootNode]};
  std::uint32_t best = 0;
  double bestScore = kInf;
  for (std::uint32_t i = 0; i < root.size; ++i) {
    const Point& p = arena_[root.begin + i];
    const double st =
        budget_.useTriangles && budget_.triangles > 0.0 ? p.triangles / budget_.triangles : 0.0;
    const double sl = budget_.useLink && budget_.linkBytes > 0.0 ? p.link / budget_.linkBytes : 0.0;
    const double score = std::max(st, sl);
    if (score < bestScore) {
      bestScore = score;
      best = i;
    }
  }
  extractNode(rootNode, accuracy, best, out);
}

void JointSolver::reportNothing(std::uint32_t k, bool underLod,
                                std::vector<LeafSelection>& out) const {
  // A subtree that renders nothing: its visible leaves are reported (under
  // an LOD only the dropped ones, the other levels were never candidates).
  const Node& n = nodes_[k];
  if (n.kind == SceneNodeKind::kLeaf) {
    if (underLod && !n.dropped) return;
    LeafSelection s;
    s.node = n.sceneNode;
    s.object = scene_.nodes[n.sceneNode].object;
    s.rendered = false;
    s.dropped = n.dropped;
    out.push_back(s);
    return;
  }
  for (std::uint32_t c = 0; c < n.childCount; ++c)
    reportNothing(children_[n.firstChild + c], underLod || n.kind == SceneNodeKind::kLod, out);
}

void JointSolver::extractNode(std::uint32_t k, double accuracy, std::uint32_t index,
                              std::vector<LeafSelection>& out) {
  const Node& n = nodes_[k];
  if (n.maxAccuracy == -kInf) {
    reportNothing(k, false, out);
    return;
  }
  const double clamped = std::min(accuracy, n.maxAccuracy);
  const Point p = arena_[nodeSet_[k].begin + index];
  if (n.kind == SceneNodeKind::kLeaf) {
    const LeafCandidate& c = candidates_[n.firstCandidate + p.from];
    const double x = clamped * n.diameter / n.distance;
    out.push_back(makeSelection(n.sceneNode, scene_.nodes[n.sceneNode].object, c,
                                std::min(x, c.maxRelativeAccuracy), n.distance, n.diameter));
    return;
  }
  if (n.kind == SceneNodeKind::kLod) {
    extractNode(children_[n.firstChild + p.from], clamped, static_cast<std::uint32_t>(p.child),
                out);
    return;
  }
  std::uint32_t at = index;
  for (std::uint32_t c = n.childCount; c-- > 0;) {
    const Point q = arena_[stages_[n.firstStage + c].begin + at];
    extractNode(children_[n.firstChild + c], accuracy, static_cast<std::uint32_t>(q.child), out);
    at = static_cast<std::uint32_t>(std::max(0, q.from));
  }
}

}  // namespace thinlod::backbone
