#include "joint_solver.h"

#include <algorithm>
#include <cmath>

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::int32_t sourceTie(CandidateSource source) {
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

JointSolver::Span JointSolver::finish(std::uint32_t begin) {
  const std::uint32_t end = static_cast<std::uint32_t>(arena_.size());
  std::uint32_t out = begin;
  for (std::uint32_t i = begin; i < end; ++i) {
    const Point& p = arena_[i];
    if (budget_.useTriangles && !(p.triangles <= budget_.triangles)) continue;
    if (budget_.useLink && !(p.link <= budget_.linkBytes)) continue;
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

JointSolver::Span JointSolver::evaluate(std::uint32_t k, double accuracy) {
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
      const LeafCandidate& c = candidates_[n.firstCandidate + i];
      if (!(c.maxRelativeAccuracy >= x * (1.0 - kAccuracyTolerance))) continue;
      const CandidateCost cost = candidateCost(c, std::min(x, c.maxRelativeAccuracy));
      arena_.push_back(
          {cost.triangles, cost.linkBytes, static_cast<std::int32_t>(i), -1, sourceTie(c.source)});
    }
    nodeSet_[k] = finish(begin);
    return nodeSet_[k];
  }
  if (n.kind == SceneNodeKind::kLod) {
    std::vector<std::pair<std::uint32_t, Span>> levels;
    for (std::uint32_t c = 0; c < n.childCount; ++c) {
      const std::uint32_t child = children_[n.firstChild + c];
      if (!(nodes_[child].maxAccuracy >= clamped * (1.0 - kAccuracyTolerance))) continue;
      const Span s = evaluate(child, clamped);
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
    nodeSet_[k] = finish(begin);
    return nodeSet_[k];
  }
  // Group: fold the children's sets with pairwise sums, one stage per child.
  Span previous{0, 0};
  for (std::uint32_t c = 0; c < n.childCount; ++c) {
    const Span s = evaluate(children_[n.firstChild + c], accuracy);
    if (s.size == 0) {
      nodeSet_[k] = {0, 0};
      return nodeSet_[k];
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
    previous = finish(begin);
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
  if (root_ < 0) return true;
  arena_.clear();
  return evaluate(static_cast<std::uint32_t>(root_), accuracy).size > 0;
}

std::size_t JointSolver::dropUntilFeasible() {
  if (feasible(0.0)) return 0;
  std::vector<std::uint32_t> leaves;
  for (std::uint32_t k = 0; k < nodes_.size(); ++k)
    if (nodes_[k].kind == SceneNodeKind::kLeaf && nodes_[k].candidateCount > 0) leaves.push_back(k);
  std::sort(leaves.begin(), leaves.end(), [this](std::uint32_t a, std::uint32_t b) {
    const double ia = nodes_[a].diameter / nodes_[a].distance;
    const double ib = nodes_[b].diameter / nodes_[b].distance;
    if (ia != ib) return ia < ib;
    return nodes_[a].sceneNode < nodes_[b].sceneNode;
  });
  auto apply = [&](std::size_t count) {
    for (std::size_t i = 0; i < leaves.size(); ++i) nodes_[leaves[i]].dropped = i < count;
    refreshAccuracyBounds();
  };
  // Dropping more never costs more: binary search the fewest drops.
  std::size_t lo = 0;  // infeasible
  std::size_t hi = leaves.size();
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

std::optional<double> JointSolver::maximise(std::optional<double> cap, std::optional<double> hint) {
  double hi = highestAccuracy();
  if (hi == -kInf) return cap ? *cap : kInf;  // nothing renderable constrains the target
  double lo = lowestAccuracy();
  if (cap) {
    hi = std::min(hi, *cap);
    lo = std::min(lo, hi);
  }
  if (!feasible(lo)) return std::nullopt;
  // Above the best any object reaches nothing costs more: a reachable cap
  // (fixed accuracy) is the target itself.
  if (feasible(hi)) return cap ? *cap : hi;
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

void JointSolver::extract(double accuracy, std::vector<LeafSelection>& out) {
  if (root_ < 0) return;
  arena_.clear();
  ++stats_.solverEvaluations;
  const Span root = evaluate(static_cast<std::uint32_t>(root_), accuracy);
  if (root.size == 0) return;  // caller only extracts feasible accuracies
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
  extractNode(static_cast<std::uint32_t>(root_), accuracy, best, out);
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
