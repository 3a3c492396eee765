#include "visible_tree.h"

#include <algorithm>

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::int64_t buildNode(const SchedulingScene& scene, const SchedulerConfig& config,
                       const PredictedRegion& region, const PlannerStateImpl& state,
                       PlanStats& stats, VisibleTree& tree, std::uint32_t sceneNode,
                       bool parentInside) {
  const SceneNode& node = scene.nodes[sceneNode];
  const Visibility visibility =
      parentInside ? Visibility::kInside : classifySphere(region, node.bounds);
  if (visibility == Visibility::kCulled) {
    ++stats.culledNodes;
    return -1;
  }
  ++stats.visitedNodes;
  const std::size_t k = tree.nodes.size();
  tree.nodes.emplace_back();
  tree.nodes[k].kind = node.kind;
  tree.nodes[k].sceneNode = sceneNode;
  tree.nodes[k].diameter = 2.0 * node.bounds.radius;
  tree.nodes[k].distance =
      conversionDistance(region.center, region.reachRadius, node.bounds, config.minimalDistance);
  if (node.kind == SceneNodeKind::kLeaf) {
    std::vector<LeafCandidate> found;
    collectLeafCandidates(scene, node.object, region, config, CandidateContext::kExact,
                          pendingFor(state, node.object), node.bounds, found);
    tree.nodes[k].candidates = std::move(found);
    ++tree.leafCount;
    return static_cast<std::int64_t>(k);
  }
  std::vector<std::uint32_t> kids;
  for (std::uint32_t i = 0; i < node.childCount; ++i) {
    const std::uint32_t slot = node.firstChild + i;
    if (node.kind == SceneNodeKind::kLod &&
        !containsBall(scene.childRanges[slot], region.reachBall()))
      continue;
    const std::int64_t c = buildNode(scene, config, region, state, stats, tree,
                                     scene.children[slot], visibility == Visibility::kInside);
    if (c >= 0) kids.push_back(static_cast<std::uint32_t>(c));
  }
  tree.nodes[k].children = std::move(kids);
  return static_cast<std::int64_t>(k);
}

}  // namespace

VisibleTree buildVisibleTree(const SchedulingScene& scene, const SchedulerConfig& config,
                             const PredictedRegion& region, const PlannerStateImpl& state,
                             PlanStats& stats) {
  VisibleTree tree;
  buildNode(scene, config, region, state, stats, tree, 0, false);
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {
    VisibleNode& n = tree.nodes[i];
    n.maxAccuracy = -kInf;
    n.minAccuracy = kInf;
    if (n.kind == SceneNodeKind::kLeaf) {
      if (n.candidates.empty()) continue;
      n.maxAccuracy = bestCandidateAccuracy(n.candidates) * n.distance / n.diameter;
      n.minAccuracy = lowestCandidateAccuracy(n.candidates) * n.distance / n.diameter;
      continue;
    }
    for (std::uint32_t c : n.children) {
      n.maxAccuracy = std::max(n.maxAccuracy, tree.nodes[c].maxAccuracy);
      n.minAccuracy = std::min(n.minAccuracy, tree.nodes[c].minAccuracy);
    }
  }
  return tree;
}

std::vector<std::uint32_t> visibleLeaves(const VisibleTree& tree, ChildOrder order) {
  std::vector<std::uint32_t> leaves;
  leaves.reserve(tree.leafCount);
  std::vector<std::uint32_t> stack;
  if (!tree.nodes.empty()) stack.push_back(0);
  while (!stack.empty()) {
    const std::uint32_t k = stack.back();
    stack.pop_back();
    const VisibleNode& n = tree.nodes[k];
    if (n.kind == SceneNodeKind::kLeaf) {
      leaves.push_back(k);
    } else if (n.kind == SceneNodeKind::kGroup) {
      if (order == ChildOrder::kFirstChildFirst) {
        stack.insert(stack.end(), n.children.rbegin(), n.children.rend());
      } else {
        stack.insert(stack.end(), n.children.begin(), n.children.end());
      }
    } else if (!n.children.empty()) {
      stack.push_back(n.children.front());  // an LOD: its first eligible level
    }
  }
  return leaves;
}

void reportUnrenderable(const VisibleTree& tree, const SchedulingScene& scene, std::uint32_t k,
                        std::vector<LeafSelection>& out) {
  const VisibleNode& n = tree.nodes[k];
  if (n.kind == SceneNodeKind::kLeaf) {
    LeafSelection s;
    s.node = n.sceneNode;
    s.object = scene.nodes[n.sceneNode].object;
    out.push_back(s);
  } else if (n.kind == SceneNodeKind::kGroup) {
    for (std::uint32_t c : n.children) reportUnrenderable(tree, scene, c, out);
  }
}

}  // namespace thinlod::backbone
