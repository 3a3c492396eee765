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

// Every leaf below tree node k as an unrendered LeafSelection (a subtree
// that renders nothing), groups recursively, LODs not descended.
void reportUnrenderable(const VisibleTree& tree, const SchedulingScene& scene, std::uint32_t k,
                        std::vector<LeafSelection>& out);

}  // namespace thinlod::backbone
