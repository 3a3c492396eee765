// Pieces shared by the scheduler implementations (private).
#pragma once

#include <vector>

#include "joint_solver.h"
#include "selection.h"

namespace thinlod::backbone {

const char* modeName(const Budget& budget);
// The link window W: plannedLifetime, or burst / rate (at most an hour) when
// the budget's linkBurstBytes is larger than a lifetime's bytes. Every window
// of length W then carries at most rate x W <= burst, which the shaper's
// token bucket of that burst admits (any longer span T is within
// ceil(T / W) rate W < burst + rate x T). After a rate change the log holds
// only the old window's sends, so a cut that widens W may count too few for
// a while; the shaper's bucket, which keeps no more tokens across the
// change, holds the cap then.
double linkWindowSeconds(const Budget& budget, const SchedulerConfig& config);
// The budgets of this step as hard caps; link in bytes over the window W,
// minus what was sent in the window already.
JointBudget hardBudget(const Budget& budget, const PlannerStateImpl& state,
                       const ViewerState& viewer, const SchedulerConfig& config);
JointBudget reserveShare(const JointBudget& budget, double share);
// Triangles and link bytes of the rendered selections.
CandidateCost renderedCost(const std::vector<LeafSelection>& selections);
bool withinBudget(const std::vector<LeafSelection>& selections, const JointBudget& budget);

// What an object outside the current view cone counts for against one inside
// it: it only shows after a turn within the planned lifetime.
inline constexpr double kOffScreenWeight = 0.02;
// The current view cone (the diagonal half field of view), its constants
// computed once per step.
class ViewCone {
 public:
  explicit ViewCone(const ViewerState& viewer);
  // 1 when `bounds` meets the cone or holds the viewer, else kOffScreenWeight.
  double onScreenWeight(const Sphere& bounds) const;
  // The order in which every method drops objects when even its cheapest
  // plan overshoots a hard cap (lowest first): every object in the cone ranks
  // above every object outside it (those only a turn would show, and the
  // next step replans after a turn), and within each class the one that
  // looks larger from the predicted region (diameter / distance) ranks
  // higher: in [1, 2) in view, [0, 1) outside. Ties: the caller's order.
  double keepPriority(const Sphere& bounds, double diameter, double distance) const;

 private:
  glm::dvec3 position_;
  glm::dvec3 direction_;
  double directionLength_ = 0.0;
  double halfDiagonal_ = 0.0;
};

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
