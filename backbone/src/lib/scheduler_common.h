// Pieces shared by the scheduler implementations (private).
#pragma once

#include <vector>

#include "joint_solver.h"
#include "selection.h"

namespace thinlod::backbone {

const char* modeName(const Budget& budget);
// The budgets of this step as hard caps; link in bytes over the window
// (plannedLifetime), minus what was sent in the window already.
JointBudget hardBudget(const Budget& budget, const PlannerStateImpl& state,
                       const ViewerState& viewer, const SchedulerConfig& config);
JointBudget reserveShare(const JointBudget& budget, double share);
// Triangles and link bytes of the rendered selections.
CandidateCost renderedCost(const std::vector<LeafSelection>& selections);
bool withinBudget(const std::vector<LeafSelection>& selections, const JointBudget& budget);

// Hysteresis: where a valid frontend (or in-flight) copy meets the need but
// a different representation was picked, keep the copy when it costs at most
// (1 + preferCurrentShare) x the pick, or while the switch has been wanted
// for fewer than switchDelaySteps steps, as long as the extra cost fits the
// hard budget (cheapest extras first).
void preferCurrentCopies(const SchedulingScene& scene, const SchedulerConfig& config,
                         const PredictedRegion& region, PlannerStateImpl& state,
                         const JointBudget& hard, bool trianglesFirst,
                         std::vector<LeafSelection>& selections, PlanStats& stats);

}  // namespace thinlod::backbone
