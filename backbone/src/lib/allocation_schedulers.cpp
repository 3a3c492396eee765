// The ASLOD allocation and the span-of-level-changed heap as selection
// methods of the shared frame (allocation_schedulers.h). The algorithms are
// aslod_allocation.h and span_of_level_changed.h; this file maps the visible
// tree's candidates onto their inputs and their answers back to selections.
#include "thinlod/backbone/allocation_schedulers.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "aslod_allocation.h"
#include "scheduler_common.h"
#include "selection_method.h"
#include "span_of_level_changed.h"
#include "thinlod/backbone/scheduler.h"
#include "visible_tree.h"

namespace thinlod::backbone {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Solid angle (sr) of a sphere of radius r whose surface is D away:
// 2 pi (1 - sqrt(1 - x^2)), x = r / (D + r), written without cancellation.
double sphereSolidAngle(double radius, double distance) {
  const double x = radius / (distance + radius);
  const double x2 = x * x;
  return 2.0 * kPi * x2 / (1.0 + std::sqrt(std::max(0.0, 1.0 - x2)));
}

struct VisibleLeaf {
  std::uint32_t treeNode;
  std::uint32_t object;
  double projectedArea;
};

// The leaves the methods decide on (visibleLeaves: LOD nodes resolved to
// their first eligible level, as greedy-fs93 does); leaves without any
// eligible candidate are reported unrendered.
std::vector<VisibleLeaf> collectLeaves(const VisibleTree& tree, const SchedulingScene& scene,
                                       std::vector<LeafSelection>& unrendered) {
  std::vector<VisibleLeaf> leaves;
  for (const std::uint32_t k : visibleLeaves(tree, ChildOrder::kFirstChildFirst)) {
    const VisibleNode& n = tree.nodes[k];
    const std::uint32_t object = scene.nodes[n.sceneNode].object;
    if (n.candidates.empty()) {
      LeafSelection s;
      s.node = n.sceneNode;
      s.object = object;
      unrendered.push_back(s);
      continue;
    }
    leaves.push_back({k, object, sphereSolidAngle(0.5 * n.diameter, n.distance)});
  }
  return leaves;
}

// Marks the least visible leaves (lowest keepPriority) dropped until the
// sum of `floor` over the others is at most cap; returns the kept flags.
// Leaves whose floor is not finite are dropped first, whatever their size.
std::vector<std::uint8_t> dropLeastVisible(const SelectionStep& step, const VisibleTree& tree,
                                           const std::vector<VisibleLeaf>& leaves,
                                           const std::vector<double>& floor, double cap) {
  std::vector<std::uint8_t> kept(leaves.size(), 1);
  double used = 0.0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (std::isfinite(floor[i])) {
      used += floor[i];
    } else {
      kept[i] = 0;
    }
  }
  if (used <= cap) return kept;
  std::vector<std::size_t> order(leaves.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<double> priority(leaves.size());
  const ViewCone cone(step.viewer);
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const VisibleNode& n = tree.nodes[leaves[i].treeNode];
    priority[i] = cone.keepPriority(step.scene.nodes[n.sceneNode].bounds, n.diameter, n.distance);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return priority[a] < priority[b]; });
  for (std::size_t i : order) {
    if (used <= cap) break;
    if (!kept[i]) continue;
    kept[i] = 0;
    used -= floor[i];
  }
  return kept;
}

LeafSelection droppedSelection(const VisibleNode& n, std::uint32_t object) {
  LeafSelection s;
  s.node = n.sceneNode;
  s.object = object;
  s.dropped = true;
  return s;
}

double cheapestTriangles(const LeafCandidate& c) {
  if (c.source != CandidateSource::kNew) return c.fixedTriangles;
  return candidateCost(c, c.representation->relativeTriangles.minAccuracy()).triangles;
}

// ------------------------------------------------------------------ ASLOD

class AslodMethod final : public SelectionMethod {
 public:
  explicit AslodMethod(const AslodSchedulerConfig& config) : config_(config) {}
  const char* name() const override { return "aslod"; }
  Status accepts(const Budget& budget) const override {
    return requirePolygonBudget(name(), budget);
  }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  AslodSchedulerConfig config_;
};

// The most accurate candidate whose cost fits `allocation` (ties: fewer
// triangles, then copies before new ones); -1 when none fits.
int mostAccurateWithin(const std::vector<LeafCandidate>& candidates, double allocation,
                       double& accuracy) {
  int best = -1;
  double bestTriangles = 0.0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const LeafCandidate& c = candidates[i];
    double a = 0.0;
    if (c.source == CandidateSource::kNew) {
      const std::optional<double> within =
          c.representation->relativeTriangles.maxAccuracyWithin(allocation);
      if (!within) continue;
      a = std::min(*within, c.maxRelativeAccuracy);
    } else {
      if (!(c.fixedTriangles <= allocation)) continue;
      a = c.maxRelativeAccuracy;
    }
    const double t = candidateCost(c, a).triangles;
    if (!(t <= allocation)) continue;
    const bool better = best < 0 || a > accuracy ||
                        (a == accuracy &&
                         (t < bestTriangles || (t == bestTriangles &&
                                                candidateSourceRank(c.source) <
                                                    candidateSourceRank(candidates[best].source))));
    if (better) {
      best = static_cast<int>(i);
      accuracy = a;
      bestTriangles = t;
    }
  }
  return best;
}

Result<Selection> AslodMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  const VisibleTree tree =
      buildVisibleTree(scene, step.config, step.region, step.state, step.stats);
  Selection selection;
  selection.mode = "polygon";
  const std::vector<VisibleLeaf> leaves = collectLeaves(tree, scene, selection.leaves);

  std::vector<AslodObject> objects(leaves.size());
  std::vector<double> cheapest(leaves.size());
  const double countLimit = 9007199254740992.0 / double(leaves.size() + 1);  // 2^53 / (n + 1)
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const VisibleNode& n = tree.nodes[leaves[i].treeNode];
    double low = std::numeric_limits<double>::infinity();
    for (const LeafCandidate& c : n.candidates) low = std::min(low, cheapestTriangles(c));
    // Most a leaf can use: the cheapest way to its best accuracy.
    const double best = bestCandidateAccuracy(n.candidates);
    const int top = pickCandidate(n.candidates, best, true);
    const double high =
        top >= 0 ? std::max(low, candidateCost(n.candidates[top], best).triangles) : low;
    objects[i].weight = leaves[i].projectedArea;
    objects[i].minTriangles = low;
    objects[i].maxTriangles = std::min(high, std::max(low, countLimit));
    // Allocations are whole triangles, exact in a double: an object needing
    // more than its share of 2^53 cannot be allocated and is dropped.
    cheapest[i] = low <= countLimit ? std::ceil(low) : std::numeric_limits<double>::infinity();
    auto previous = step.state.aslodAllocations.find(leaves[i].object);
    if (previous != step.state.aslodAllocations.end()) objects[i].previous = previous->second;
  }
  const double cap = std::floor(step.hard.triangles);
  const std::vector<std::uint8_t> kept = dropLeastVisible(step, tree, leaves, cheapest, cap);
  std::vector<AslodObject> allocated;
  for (std::size_t i = 0; i < leaves.size(); ++i)
    if (kept[i]) allocated.push_back(objects[i]);

  AslodConfig config;
  config.alpha = config_.alpha;
  config.hysteresisTriangles = config_.hysteresisTriangles;
  config.hysteresisShare = config_.hysteresisShare;
  // Gaps: the paper assumes progressive meshes that use any count; here an
  // object's candidates may leave a gap (a 2-triangle impostor, then meshes
  // from 100 triangles on) and an allocation inside it renders the cheaper
  // side. Such an object is capped at what it renders and the allocation is
  // redone, so the others receive the slack (allocations of uncapped objects
  // only grow from round to round; at most kGapRounds rounds).
  constexpr int kGapRounds = 8;
  std::vector<int> picks(allocated.size(), -1);
  std::vector<double> accuracies(allocated.size(), 0.0);
  std::vector<std::uint32_t> keptLeaf;
  for (std::size_t i = 0; i < leaves.size(); ++i)
    if (kept[i]) keptLeaf.push_back(static_cast<std::uint32_t>(i));
  Result<AslodAllocation> allocation = Status(ErrorCode::kInternal, "aslod: no allocation");
  for (int round = 0; round < kGapRounds; ++round) {
    allocation = allocateAslod(allocated, cap, config);
    if (!allocation.ok()) return allocation.status();
    bool capped = false;
    for (std::size_t k = 0; k < allocated.size(); ++k) {
      const VisibleNode& n = tree.nodes[leaves[keptLeaf[k]].treeNode];
      const double p = static_cast<double>(allocation->triangles[k]);
      picks[k] = mostAccurateWithin(n.candidates, p, accuracies[k]);
      if (picks[k] < 0) continue;
      const double used = candidateCost(n.candidates[picks[k]], accuracies[k]).triangles;
      if (std::ceil(used) < p && used < allocated[k].maxTriangles) {
        allocated[k].maxTriangles = std::max(allocated[k].minTriangles, used);
        capped = true;
      }
    }
    if (!capped) break;
  }

  step.state.aslodAllocations.clear();
  std::size_t next = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const VisibleNode& n = tree.nodes[leaves[i].treeNode];
    if (!kept[i]) {
      selection.leaves.push_back(droppedSelection(n, leaves[i].object));
      continue;
    }
    const std::size_t k = next++;
    step.state.aslodAllocations[leaves[i].object] = allocation->triangles[k];
    if (picks[k] < 0) {  // cannot happen: p >= ceil(cheapest); kept defensive
      selection.leaves.push_back(droppedSelection(n, leaves[i].object));
      continue;
    }
    selection.leaves.push_back(makeSelection(n.sceneNode, leaves[i].object, n.candidates[picks[k]],
                                             accuracies[k], n.distance, n.diameter));
  }
  return selection;
}

// --------------------------------------------------- span of level changed

class SpanOfLevelChangedMethod final : public SelectionMethod {
 public:
  explicit SpanOfLevelChangedMethod(const SpanOfLevelChangedConfig& config) : config_(config) {}
  const char* name() const override { return "span-of-level-changed"; }
  Status accepts(const Budget& budget) const override {
    return requirePolygonBudget(name(), budget);
  }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  SpanOfLevelChangedConfig config_;
};

struct LevelChoice {
  int level;
  double triangles;
  double accuracy;  // relative, leaf frame
  std::uint32_t candidate;
};

// An object's discrete levels, finest first: every candidate's curve sampled
// at 2^l triangles inside its range plus both ends (copies: their one
// point); dominated choices (more triangles, not more accuracy) dropped; per
// level the most accurate choice, except at the coarsest level, which keeps
// the cheapest so the object's cheapest representation stays available.
std::vector<LevelChoice> levelsOf(const std::vector<LeafCandidate>& candidates) {
  std::vector<LevelChoice> all;
  for (std::uint32_t i = 0; i < candidates.size(); ++i) {
    const LeafCandidate& c = candidates[i];
    auto add = [&](double accuracy) {
      const double t = candidateCost(c, accuracy).triangles;
      all.push_back({std::min(62, levelOfFaces(t)), t, accuracy, i});
    };
    if (c.source != CandidateSource::kNew) {
      add(c.maxRelativeAccuracy);
      continue;
    }
    const AccuracyCurve& curve = c.representation->relativeTriangles;
    const double low = std::min(curve.minAccuracy(), c.maxRelativeAccuracy);
    const double tLow = candidateCost(c, low).triangles;
    const double tHigh = candidateCost(c, c.maxRelativeAccuracy).triangles;
    add(low);
    add(c.maxRelativeAccuracy);
    for (int l = levelOfFaces(tLow); l <= std::min(62, levelOfFaces(tHigh) + 1); ++l) {
      const double t = std::ldexp(1.0, l);
      if (!(t > tLow && t < tHigh)) continue;
      const std::optional<double> a = curve.maxAccuracyWithin(t);
      if (a) add(std::min(*a, c.maxRelativeAccuracy));
    }
  }
  std::sort(all.begin(), all.end(), [&](const LevelChoice& a, const LevelChoice& b) {
    if (a.triangles != b.triangles) return a.triangles < b.triangles;
    if (a.accuracy != b.accuracy) return a.accuracy > b.accuracy;
    return candidateSourceRank(candidates[a.candidate].source) <
           candidateSourceRank(candidates[b.candidate].source);
  });
  std::vector<LevelChoice> kept;  // cheapest first
  for (const LevelChoice& c : all) {
    if (!kept.empty() && !(c.accuracy > kept.back().accuracy)) continue;  // dominated
    if (!kept.empty() && kept.back().level == c.level) {
      if (kept.size() > 1) kept.back() = c;  // more accurate, same level
      continue;
    }
    kept.push_back(c);
  }
  std::reverse(kept.begin(), kept.end());
  return kept;
}

Result<Selection> SpanOfLevelChangedMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  const VisibleTree tree =
      buildVisibleTree(scene, step.config, step.region, step.state, step.stats);
  Selection selection;
  selection.mode = "polygon";
  const std::vector<VisibleLeaf> leaves = collectLeaves(tree, scene, selection.leaves);

  std::vector<std::vector<LevelChoice>> choices(leaves.size());
  std::vector<double> coarsest(leaves.size());
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    choices[i] = levelsOf(tree.nodes[leaves[i].treeNode].candidates);
    coarsest[i] = choices[i].back().triangles;
  }
  const double cap = step.hard.triangles;
  const std::vector<std::uint8_t> kept = dropLeastVisible(step, tree, leaves, coarsest, cap);
  std::vector<SlcObject> objects;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (!kept[i]) continue;
    SlcObject o;
    for (const LevelChoice& c : choices[i]) o.levels.push_back({c.level, c.triangles});
    o.distance = tree.nodes[leaves[i].treeNode].distance;
    o.projectedArea = leaves[i].projectedArea;
    if (!(o.projectedArea > 0.0)) o.projectedArea = std::numeric_limits<double>::min();
    objects.push_back(std::move(o));
  }
  SlcConfig config;
  config.measure = SlcBudgetMeasure::kTriangles;
  config.distanceRule = config_.coarsenFarthestFirst ? SlcDistanceRule::kFarthestFirst
                                                     : SlcDistanceRule::kNearestFirst;
  Result<SlcSelection> chosen = selectBySpanOfLevelChanged(objects, cap, config);
  if (!chosen.ok()) return chosen.status();
  std::size_t next = 0;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    const VisibleNode& n = tree.nodes[leaves[i].treeNode];
    if (!kept[i]) {
      selection.leaves.push_back(droppedSelection(n, leaves[i].object));
      continue;
    }
    const LevelChoice& c = choices[i][chosen->levelIndex[next++]];
    selection.leaves.push_back(makeSelection(n.sceneNode, leaves[i].object,
                                             n.candidates[c.candidate], c.accuracy, n.distance,
                                             n.diameter));
  }
  return selection;
}

}  // namespace

Result<std::unique_ptr<Scheduler>> makeAslodScheduler(const SchedulerConfig& config,
                                                      const AslodSchedulerConfig& aslod) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  AslodConfig check;
  check.alpha = aslod.alpha;
  check.hysteresisTriangles = aslod.hysteresisTriangles;
  check.hysteresisShare = aslod.hysteresisShare;
  THINLOD_RETURN_IF_ERROR(validateAslodConfig(check));
  return std::make_unique<Scheduler>(config, std::make_unique<AslodMethod>(aslod));
}

Result<std::unique_ptr<Scheduler>> makeSpanOfLevelChangedScheduler(
    const SchedulerConfig& config, const SpanOfLevelChangedConfig& slc) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  return std::make_unique<Scheduler>(config, std::make_unique<SpanOfLevelChangedMethod>(slc));
}

}  // namespace thinlod::backbone
