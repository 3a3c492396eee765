// The visible part of a scene for one predicted region, with each leaf's
// exact candidates (private; used by the baselines).
#pragma once

#include <vector>

#include "selection.h"

namespace thinlod::backbone {

struct VisibleNode {
  SceneNodeKind kind = SceneNodeKind::kGroup;
  std::uint32_t sceneNode = 0;
  std::vector<std::uint32_t> children;  // visible (and, for LODs, eligible) children
  std::vector<LeafCandidate> candidates;
  double distance = 0.0;
  double diameter = 0.0;
  double maxAccuracy = 0.0;  // absolute; -inf when it renders nothing
  double minAccuracy = 0.0;
};

struct VisibleTree {
  std::vector<VisibleNode> nodes;  // parents before children; [0] is the root when not empty
  std::size_t leafCount = 0;
};

VisibleTree buildVisibleTree(const SchedulingScene& scene, const SchedulerConfig& config,
                             const PredictedRegion& region, const PlannerStateImpl& state,
                             PlanStats& stats);

// The order in which a group's visible children are walked by
// visibleLeaves (each method keeps the order its plans were made in: the
// order decides ties and the order of the plan's decisions).
enum class ChildOrder : std::uint8_t {
  kFirstChildFirst,  // preorder
  kLastChildFirst,   // a stack pushing children in order: last child first
};

// The leaves the object-level methods (greedy-fs93, aslod,
// span-of-level-changed, active-set) decide on, as tree node indices in walk
// order: a group descends into every visible child, an LOD only into its
// first eligible level (these methods know objects with levels, not LOD
// nodes). Leaves without any candidate are included; the caller reports
// them unrendered. An LOD without an eligible level contributes nothing.
std::vector<std::uint32_t> visibleLeaves(const VisibleTree& tree, ChildOrder order);

// Every leaf below tree node k as an unrendered LeafSelection (a subtree
// that renders nothing), groups recursively, LODs not descended.
void reportUnrenderable(const VisibleTree& tree, const SchedulingScene& scene, std::uint32_t k,
                        std::vector<LeafSelection>& out);

}  // namespace thinlod::backbone
