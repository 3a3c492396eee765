// The paper's scheduler: accuracy curves up the tree, one uniform target at
// the root, the target pushed down, hysteresis on top (docs/scheduling.md).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "curve_propagation.h"
#include "joint_solver.h"
#include "scheduler_common.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

class AccuracyCurveScheduler final : public Scheduler {
 public:
  explicit AccuracyCurveScheduler(const SchedulerConfig& config) : config_(config) {}
  const char* name() const override { return "accuracy-curve"; }
  Result<Plan> plan(const SchedulingScene& scene, const ViewerState& viewer, const Budget& budget,
                    PlannerState& outer) const override;

 private:
  double stickyTarget(double chosen, const std::optional<double>& previous) const {
    if (previous && std::isfinite(chosen) && *previous <= chosen &&
        chosen < *previous * (1.0 + config_.targetHysteresis))
      return *previous;  // a small gain is not worth changing every object
    return chosen;
  }

  SchedulerConfig config_;
};

Result<Plan> AccuracyCurveScheduler::plan(const SchedulingScene& scene, const ViewerState& viewer,
                                          const Budget& budget, PlannerState& outer) const {
  const auto started = std::chrono::steady_clock::now();
  THINLOD_RETURN_IF_ERROR(validateViewer(viewer));
  THINLOD_RETURN_IF_ERROR(validateBudget(budget));
  if (scene.nodes.empty()) return Status(ErrorCode::kInvalidArgument, "scheduling scene: no nodes");
  PlannerStateImpl& state = outer.impl();
  beginStep(state, scene, config_, viewer);
  const PredictedRegion region = predictRegion(viewer, config_);

  Plan plan;
  plan.scheduler = name();
  plan.mode = modeName(budget);
  const JointBudget hard = hardBudget(budget, state, viewer, config_);
  // A fixed accuracy spends what it needs up to the cap; a maximised target
  // leaves a reserve for keeping current copies (hysteresis).
  const JointBudget reserved =
      budget.fixedAccuracy ? hard : reserveShare(hard, config_.budgetReserveShare);
  const bool trianglesFirst = !(hard.useLink && !hard.useTriangles);

  std::vector<LeafSelection> selections;
  double target = budget.fixedAccuracy.value_or(kInf);
  bool useSolver = hard.useTriangles && hard.useLink;
  if (!useSolver) {
    const Resource primary = trianglesFirst ? Resource::kTriangles : Resource::kLink;
    CurvePropagator propagator(scene, config_, region, state, primary, plan.stats);
    const AccuracyCurve& root = propagator.evaluateRoot();
    std::optional<double> chosen = target;
    if (!root.empty() && (hard.useTriangles || hard.useLink)) {
      const double soft = trianglesFirst ? reserved.triangles : reserved.linkBytes;
      const double cap = trianglesFirst ? hard.triangles : hard.linkBytes;
      chosen = root.maxAccuracyWithin(soft);
      if (!chosen) chosen = root.maxAccuracyWithin(cap);  // spend the reserve before dropping
      if (chosen) chosen = std::min(*chosen, target);
    }
    if (chosen) {
      target = stickyTarget(*chosen, state.previousTarget);
      propagator.pushDown(target, selections);
      // The pushed-down picks cost at most what the curves charged; verify
      // anyway (rounding): the budget is a hard cap, the solver is the net.
      useSolver = !withinBudget(selections, hard);
    } else {
      useSolver = true;
    }
  }
  if (useSolver) {
    plan.stats.usedExactSolver = true;
    selections.clear();
    JointSolver solver(scene, config_, region, state, reserved, plan.stats);
    std::optional<double> best = solver.maximise(budget.fixedAccuracy, std::nullopt);
    if (!best) {
      JointSolver full(scene, config_, region, state, hard, plan.stats);
      best = full.maximise(budget.fixedAccuracy, std::nullopt);
      if (!best) {
        full.dropUntilFeasible();
        best = full.maximise(budget.fixedAccuracy, std::nullopt);
      }
      target = best ? stickyTarget(*best, state.previousTarget) : 0.0;
      if (best) full.extract(target, selections);
    } else {
      target = stickyTarget(*best, state.previousTarget);
      solver.extract(target, selections);
    }
  }
  // Solver sums and plan sums round differently; the cap is hard, so step
  // the target down by a hair until the plan itself fits (never seen in
  // tests, bounded here).
  for (int retry = 0; retry < 8 && useSolver && !withinBudget(selections, hard); ++retry) {
    target *= 1.0 - 1e-9 * double(1 << (2 * retry));
    selections.clear();
    JointSolver again(scene, config_, region, state, hard, plan.stats);
    if (again.feasible(target)) again.extract(target, selections);
  }
  if (!withinBudget(selections, hard)) {
    for (LeafSelection& s : selections) {
      s.rendered = false;  // last resort: render nothing, report as dropped
      s.dropped = true;
    }
  }
  preferCurrentCopies(scene, config_, region, state, hard, trianglesFirst, selections, plan.stats);
  state.previousTarget = target;

  PlanContext context{scene, config_, viewer, region, state};
  finishPlan(context, selections, target, plan);
  plan.row.schedulingMicroseconds =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - started).count();
  return plan;
}

}  // namespace

Result<std::unique_ptr<Scheduler>> makeAccuracyCurveScheduler(const SchedulerConfig& config) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  return std::unique_ptr<Scheduler>(new AccuracyCurveScheduler(config));
}

}  // namespace thinlod::backbone
