// Baselines on the same input and output as the accuracy-curve scheduler:
// VRML97 static LOD, Funkhouser-Sequin greedy cost/benefit, brute force.
#include <algorithm>
#include <cmath>
#include <queue>

#include "scheduler_common.h"
#include "selection_method.h"
#include "visible_tree.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------- VRML97

class VrmlStaticMethod final : public SelectionMethod {
 public:
  explicit VrmlStaticMethod(const VrmlStaticConfig& vrml) : vrml_(vrml) {}
  const char* name() const override { return "vrml-static"; }
  // VRML97 looks at the current position only (no motion, no rotation) and
  // knows no budgets.
  bool predictsMotion() const override { return false; }
  bool honoursBudgets() const override { return false; }

  Result<Selection> select(const SelectionStep& step) const override {
    Selection selection;
    selection.mode = "static";
    std::vector<LeafCandidate> candidates;
    walk(step, 0, false, selection.leaves, candidates);
    return selection;
  }

 private:
  void walk(const SelectionStep& step, std::uint32_t n, bool parentInside,
            std::vector<LeafSelection>& out, std::vector<LeafCandidate>& candidates) const {
    const SchedulingScene& scene = step.scene;
    const PredictedRegion& region = step.region;
    PlanStats& stats = step.stats;
    const SceneNode& node = scene.nodes[n];
    const Visibility v = parentInside ? Visibility::kInside : classifySphere(region, node.bounds);
    if (v == Visibility::kCulled) {
      ++stats.culledNodes;
      return;
    }
    ++stats.visitedNodes;
    if (node.kind == SceneNodeKind::kGroup) {
      for (std::uint32_t i = 0; i < node.childCount; ++i)
        walk(step, scene.children[node.firstChild + i], v == Visibility::kInside, out, candidates);
      return;
    }
    if (node.kind == SceneNodeKind::kLod) {
      // VRML: the first level whose range holds the viewer.
      for (std::uint32_t i = 0; i < node.childCount; ++i) {
        const std::uint32_t slot = node.firstChild + i;
        if (containsBall(scene.childRanges[slot], {region.center, 0.0})) {
          walk(step, scene.children[slot], v == Visibility::kInside, out, candidates);
          return;
        }
      }
      return;
    }
    const double diameter = 2.0 * node.bounds.radius;
    const double distance =
        conversionDistance(region.center, 0.0, node.bounds, step.config.minimalDistance);
    collectLeafCandidates(scene, node.object, region, step.config, CandidateContext::kExact,
                          pendingFor(step.state, node.object), node.bounds, candidates);
    const double ratio = distance / diameter;
    std::size_t band = 0;
    while (band < vrml_.bandDistanceOverDiameter.size() &&
           ratio >= vrml_.bandDistanceOverDiameter[band])
      ++band;
    double need = vrml_.bandRelativeAccuracy[band];
    need = std::min(need, bestCandidateAccuracy(candidates));
    const int pick = pickCandidate(candidates, need, true);
    if (pick < 0) {
      LeafSelection s;
      s.node = n;
      s.object = node.object;
      out.push_back(s);
      return;
    }
    out.push_back(makeSelection(n, node.object, candidates[pick], need, distance, diameter));
  }

  VrmlStaticConfig vrml_;
};

// ---------------------------------------------------- Funkhouser-Sequin

class GreedyMethod final : public SelectionMethod {
 public:
  explicit GreedyMethod(const GreedyConfig& greedy) : greedy_(greedy) {}
  const char* name() const override { return "greedy-fs93"; }
  Status accepts(const Budget& budget) const override {
    return requirePolygonBudget(name(), budget);
  }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  struct Level {
    std::uint32_t candidate;
    double relative;  // leaf frame
    double triangles;
    double benefit;
  };
  struct Item {
    std::uint32_t treeNode;  // the leaf
    std::vector<Level> levels;
    std::size_t current = 0;
    std::uint32_t version = 0;
  };

  void addLevels(const VisibleNode& leaf, Item& item) const;

  GreedyConfig greedy_;
};

void GreedyMethod::addLevels(const VisibleNode& leaf, Item& item) const {
  const double toAbsolute = leaf.distance / leaf.diameter;
  const double weight = leaf.diameter / leaf.distance;  // projected size
  auto benefit = [&](double relative) {
    const double a = relative * toAbsolute;
    return weight * a / (a + greedy_.halfBenefitAccuracy);
  };
  for (std::uint32_t i = 0; i < leaf.candidates.size(); ++i) {
    const LeafCandidate& c = leaf.candidates[i];
    if (c.source != CandidateSource::kNew) {
      item.levels.push_back(
          {i, c.maxRelativeAccuracy, c.fixedTriangles, benefit(c.maxRelativeAccuracy)});
      continue;
    }
    const AccuracyCurve& curve = c.representation->relativeTriangles;
    const double low = curve.minAccuracy();
    const double high = c.maxRelativeAccuracy;
    std::vector<double> samples;
    for (const CurveSegment& s : curve.segments())
      if (s.start <= high) samples.push_back(s.start);
    samples.push_back(high);
    const int n = std::max(2, greedy_.levelsPerCurve);
    for (int j = 0; j < n && high > low; ++j)
      samples.push_back(low * std::pow(high / low, double(j) / (n - 1)));
    for (double x : samples) {
      const double r = std::min(x, high);
      item.levels.push_back({i, r, candidateCost(c, r).triangles, benefit(r)});
    }
  }
  // Sort by cost; drop levels that cost more for no more benefit.
  std::sort(item.levels.begin(), item.levels.end(), [](const Level& a, const Level& b) {
    if (a.triangles != b.triangles) return a.triangles < b.triangles;
    return a.benefit > b.benefit;
  });
  std::vector<Level> kept;
  for (const Level& l : item.levels)
    if (kept.empty() || l.benefit > kept.back().benefit) kept.push_back(l);
  item.levels = std::move(kept);
}

Result<Selection> GreedyMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  const VisibleTree tree =
      buildVisibleTree(scene, step.config, step.region, step.state, step.stats);
  Selection selection;
  selection.mode = "polygon";
  std::vector<LeafSelection>& selections = selection.leaves;
  std::vector<Item> items;
  // LOD nodes: FS93 has one object with levels; an LOD is resolved to its
  // first eligible level, whose leaves become objects.
  for (const std::uint32_t k : visibleLeaves(tree, ChildOrder::kLastChildFirst)) {
    const VisibleNode& n = tree.nodes[k];
    if (n.candidates.empty()) {
      reportUnrenderable(tree, scene, k, selections);
      continue;
    }
    Item item;
    item.treeNode = k;
    addLevels(n, item);
    items.push_back(std::move(item));
  }
  const double cap = *step.budget.maxTriangles;
  double used = 0.0;
  for (const Item& item : items) used += item.levels.front().triangles;
  // Over budget at the cheapest levels: drop the least visible objects.
  std::vector<std::uint8_t> dropped(items.size(), 0);
  if (used > cap) {
    std::vector<std::size_t> order(items.size());
    std::vector<double> priority(items.size());
    const ViewCone cone(step.viewer);
    for (std::size_t i = 0; i < order.size(); ++i) {
      order[i] = i;
      const VisibleNode& n = tree.nodes[items[i].treeNode];
      priority[i] = cone.keepPriority(step.scene.nodes[n.sceneNode].bounds, n.diameter, n.distance);
    }
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return priority[a] < priority[b]; });
    for (std::size_t i : order) {
      if (used <= cap) break;
      dropped[i] = 1;
      used -= items[i].levels.front().triangles;
    }
  }
  // Incremental greedy: repeatedly take the upgrade with the best benefit
  // gain per extra triangle that still fits.
  struct Upgrade {
    double ratio;
    std::size_t item;
    std::size_t level;
    std::uint32_t version;
    bool operator<(const Upgrade& o) const { return ratio < o.ratio; }
  };
  std::priority_queue<Upgrade> heap;
  auto bestUpgrade = [&](std::size_t i) {
    const Item& item = items[i];
    const Level& now = item.levels[item.current];
    double bestRatio = -1.0;
    std::size_t bestLevel = 0;
    for (std::size_t j = item.current + 1; j < item.levels.size(); ++j) {
      const double extra = item.levels[j].triangles - now.triangles;
      if (extra > cap - used) continue;
      const double gain = item.levels[j].benefit - now.benefit;
      const double ratio = extra > 0.0 ? gain / extra : kInf;
      if (ratio > bestRatio) {
        bestRatio = ratio;
        bestLevel = j;
      }
    }
    if (bestRatio > 0.0) heap.push({bestRatio, i, bestLevel, item.version});
  };
  for (std::size_t i = 0; i < items.size(); ++i)
    if (!dropped[i]) bestUpgrade(i);
  while (!heap.empty()) {
    const Upgrade u = heap.top();
    heap.pop();
    Item& item = items[u.item];
    if (u.version != item.version) continue;
    const double extra = item.levels[u.level].triangles - item.levels[item.current].triangles;
    if (extra > cap - used) {
      ++item.version;
      bestUpgrade(u.item);  // something smaller may still fit
      continue;
    }
    used += extra;
    item.current = u.level;
    ++item.version;
    bestUpgrade(u.item);
  }
  for (std::size_t i = 0; i < items.size(); ++i) {
    const VisibleNode& n = tree.nodes[items[i].treeNode];
    if (dropped[i]) {
      LeafSelection s;
      s.node = n.sceneNode;
      s.object = scene.nodes[n.sceneNode].object;
      s.dropped = true;
      selections.push_back(s);
      continue;
    }
    const Level& level = items[i].levels[items[i].current];
    selections.push_back(makeSelection(n.sceneNode, scene.nodes[n.sceneNode].object,
                                       n.candidates[level.candidate], level.relative, n.distance,
                                       n.diameter));
  }
  return selection;
}

// ------------------------------------------------------------ brute force

class BruteForceMethod final : public SelectionMethod {
 public:
  explicit BruteForceMethod(const BruteForceConfig& brute) : brute_(brute) {}
  const char* name() const override { return "brute-force"; }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  BruteForceConfig brute_;
};

struct BruteSearch {
  const VisibleTree& tree;
  const JointBudget& budget;
  std::vector<std::uint32_t> choice;  // per tree node: candidate or child position

  // Cost of the configuration at accuracy a; false when a chosen option
  // cannot reach what the clamping asks of it.
  bool cost(std::uint32_t k, double a, double& triangles, double& link) const {
    const VisibleNode& n = tree.nodes[k];
    if (n.maxAccuracy == -kInf) return true;
    const double clamped = std::min(a, n.maxAccuracy);
    if (n.kind == SceneNodeKind::kLeaf) {
      const LeafCandidate& c = n.candidates[choice[k]];
      const double x = clamped * n.diameter / n.distance;
      if (!(c.maxRelativeAccuracy >= x * (1.0 - kAccuracyTolerance))) return false;
      const CandidateCost cc = candidateCost(c, std::min(x, c.maxRelativeAccuracy));
      triangles += cc.triangles;
      link += cc.linkBytes;
      return true;
    }
    if (n.kind == SceneNodeKind::kLod) {
      const std::uint32_t child = n.children[choice[k]];
      if (!(tree.nodes[child].maxAccuracy >= clamped * (1.0 - kAccuracyTolerance))) return false;
      return cost(child, clamped, triangles, link);
    }
    for (std::uint32_t c : n.children)
      if (!cost(c, a, triangles, link)) return false;
    return true;
  }

  bool feasible(double a, double* triangles = nullptr, double* link = nullptr) const {
    double t = 0.0;
    double l = 0.0;
    if (!cost(0, a, t, l)) return false;
    if (triangles) *triangles = t;
    if (link) *link = l;
    return (!budget.useTriangles || t <= budget.triangles) &&
           (!budget.useLink || l <= budget.linkBytes);
  }

  void select(std::uint32_t k, double a, const SchedulingScene& scene,
              std::vector<LeafSelection>& out) const {
    const VisibleNode& n = tree.nodes[k];
    if (n.maxAccuracy == -kInf) {
      reportUnrenderable(tree, scene, k, out);
      return;
    }
    const double clamped = std::min(a, n.maxAccuracy);
    if (n.kind == SceneNodeKind::kLeaf) {
      const LeafCandidate& c = n.candidates[choice[k]];
      const double x = clamped * n.diameter / n.distance;
      out.push_back(makeSelection(n.sceneNode, scene.nodes[n.sceneNode].object, c,
                                  std::min(x, c.maxRelativeAccuracy), n.distance, n.diameter));
    } else if (n.kind == SceneNodeKind::kLod) {
      select(n.children[choice[k]], clamped, scene, out);
    } else {
      for (std::uint32_t c : n.children) select(c, a, scene, out);
    }
  }
};

Result<Selection> BruteForceMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  const Budget& budget = step.budget;
  const JointBudget& hard = step.hard;
  const VisibleTree tree =
      buildVisibleTree(scene, step.config, step.region, step.state, step.stats);
  Selection selection;
  std::vector<LeafSelection>& selections = selection.leaves;
  double target = budget.fixedAccuracy.value_or(kInf);
  if (!tree.nodes.empty() && tree.nodes[0].maxAccuracy != -kInf) {
    // Mixed-radix enumeration of every leaf and LOD choice.
    std::vector<std::uint32_t> radix(tree.nodes.size(), 1);
    double combinations = 1.0;
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
      const VisibleNode& n = tree.nodes[k];
      if (n.kind == SceneNodeKind::kLeaf && !n.candidates.empty())
        radix[k] = static_cast<std::uint32_t>(n.candidates.size());
      if (n.kind == SceneNodeKind::kLod && !n.children.empty())
        radix[k] = static_cast<std::uint32_t>(n.children.size());
      combinations *= radix[k];
    }
    if (combinations > brute_.maxCombinations)
      return Status(ErrorCode::kResourceExhausted, "brute-force: " + std::to_string(combinations) +
                                                       " combinations exceed " +
                                                       std::to_string(brute_.maxCombinations));
    BruteSearch search{tree, hard, std::vector<std::uint32_t>(tree.nodes.size(), 0)};
    const double lowest = std::min(tree.nodes[0].minAccuracy, tree.nodes[0].maxAccuracy);
    double high = tree.nodes[0].maxAccuracy;
    if (budget.fixedAccuracy) high = std::min(high, *budget.fixedAccuracy);
    const double low = std::min(lowest, high);
    double best = -kInf;
    std::vector<std::uint32_t> bestChoice;
    auto advance = [&](std::vector<std::uint32_t>& c) {
      for (std::size_t k = 0; k < c.size(); ++k) {
        if (++c[k] < radix[k]) return true;
        c[k] = 0;
      }
      return false;
    };
    do {
      // Only configurations that beat the best so far are bisected.
      const double from = best == -kInf ? low : best;
      if (!search.feasible(from)) continue;
      double lo = from;
      double hi = high;
      if (search.feasible(hi)) {
        lo = hi;
      } else {
        for (int i = 0; i < 200 && hi > lo * (1.0 + 1e-11); ++i) {
          const double mid = lo > 0.0 ? std::sqrt(lo) * std::sqrt(hi) : 0.5 * (lo + hi);
          if (!(mid > lo && mid < hi)) break;
          if (search.feasible(mid)) {
            lo = mid;
          } else {
            hi = mid;
          }
        }
      }
      if (lo > best || bestChoice.empty()) {
        best = lo;
        bestChoice = search.choice;
      }
    } while (advance(search.choice));
    if (bestChoice.empty())
      return Status(ErrorCode::kResourceExhausted,
                    "brute-force: no configuration fits the budget without dropping objects");
    // Among configurations reaching the best accuracy, the one with the most
    // headroom (same rule as the joint solver); unbudgeted: fewest triangles.
    const bool budgeted = hard.useTriangles || hard.useLink;
    double bestScore = kInf;
    double bestTriangles = kInf;
    std::fill(search.choice.begin(), search.choice.end(), 0);
    do {
      double t = 0.0;
      double l = 0.0;
      if (!search.feasible(best, &t, &l)) continue;
      double score = t;
      if (budgeted) {
        const double st = hard.useTriangles && hard.triangles > 0.0 ? t / hard.triangles : 0.0;
        const double sl = hard.useLink && hard.linkBytes > 0.0 ? l / hard.linkBytes : 0.0;
        score = std::max(st, sl);
      }
      if (score < bestScore || (score == bestScore && t < bestTriangles)) {
        bestScore = score;
        bestTriangles = t;
        bestChoice = search.choice;
      }
    } while (advance(search.choice));
    search.choice = bestChoice;
    // A fixed accuracy that every object reaches or exceeds its best at is
    // the target itself (same convention as the accuracy-curve scheduler).
    target = budget.fixedAccuracy && best >= high ? *budget.fixedAccuracy : best;
    search.select(0, target, scene, selections);
  }
  selection.targetAccuracy = target;
  return selection;
}

Status checkVrml(const VrmlStaticConfig& vrml) {
  if (vrml.bandRelativeAccuracy.size() != vrml.bandDistanceOverDiameter.size() + 1)
    return Status(ErrorCode::kInvalidArgument,
                  "VrmlStaticConfig: bandRelativeAccuracy needs one entry more than "
                  "bandDistanceOverDiameter");
  for (std::size_t i = 0; i < vrml.bandDistanceOverDiameter.size(); ++i) {
    const double d = vrml.bandDistanceOverDiameter[i];
    if (!std::isfinite(d) || d <= 0.0 || (i > 0 && d <= vrml.bandDistanceOverDiameter[i - 1]))
      return Status(ErrorCode::kInvalidArgument,
                    "VrmlStaticConfig.bandDistanceOverDiameter must be finite, > 0, increasing");
  }
  for (double a : vrml.bandRelativeAccuracy)
    if (!std::isfinite(a) || a <= 0.0)
      return Status(ErrorCode::kInvalidArgument,
                    "VrmlStaticConfig.bandRelativeAccuracy must be finite and > 0");
  return Status::okStatus();
}

}  // namespace

Result<std::unique_ptr<Scheduler>> makeVrmlStaticScheduler(const SchedulerConfig& config,
                                                           const VrmlStaticConfig& vrml) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  THINLOD_RETURN_IF_ERROR(checkVrml(vrml));
  return std::make_unique<Scheduler>(config, std::make_unique<VrmlStaticMethod>(vrml));
}

Result<std::unique_ptr<Scheduler>> makeGreedyScheduler(const SchedulerConfig& config,
                                                       const GreedyConfig& greedy) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  if (greedy.levelsPerCurve < 2 || greedy.levelsPerCurve > 1000)
    return Status(ErrorCode::kInvalidArgument, "GreedyConfig.levelsPerCurve must be in [2, 1000]");
  if (!std::isfinite(greedy.halfBenefitAccuracy) || greedy.halfBenefitAccuracy <= 0.0)
    return Status(ErrorCode::kInvalidArgument,
                  "GreedyConfig.halfBenefitAccuracy must be finite and > 0");
  return std::make_unique<Scheduler>(config, std::make_unique<GreedyMethod>(greedy));
}

Result<std::unique_ptr<Scheduler>> makeBruteForceScheduler(const SchedulerConfig& config,
                                                           const BruteForceConfig& brute) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  if (!(brute.maxCombinations >= 1.0))
    return Status(ErrorCode::kInvalidArgument, "BruteForceConfig.maxCombinations must be >= 1");
  return std::make_unique<Scheduler>(config, std::make_unique<BruteForceMethod>(brute));
}

}  // namespace thinlod::backbone
