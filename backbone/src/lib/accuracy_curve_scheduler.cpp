// The paper's scheduler: accuracy curves up the tree, one uniform target at
// the root, the target pushed down, hysteresis on top (docs/scheduling.md).
#include <algorithm>
#include <cmath>

#include "budget_fill.h"
#include "curve_propagation.h"
#include "joint_solver.h"
#include "scheduler_common.h"
#include "selection_method.h"

namespace thinlod::backbone {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

class AccuracyCurveMethod final : public SelectionMethod {
 public:
  const char* name() const override { return "accuracy-curve"; }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  static double stickyTarget(double chosen, const std::optional<double>& previous,
                             double hysteresis) {
    if (previous && std::isfinite(chosen) && *previous <= chosen &&
        chosen < *previous * (1.0 + hysteresis))
      return *previous;  // a small gain is not worth changing every object
    return chosen;
  }
};

Result<Selection> AccuracyCurveMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  const Budget& budget = step.budget;
  const PredictedRegion& region = step.region;
  const JointBudget& hard = step.hard;
  PlannerStateImpl& state = step.state;
  PlanStats& stats = step.stats;
  const SchedulerConfig& config = step.config;
  // A fixed accuracy spends what it needs up to the cap; a maximised target
  // leaves a reserve for keeping current copies (hysteresis).
  const JointBudget reserved =
      budget.fixedAccuracy ? hard : reserveShare(hard, config.budgetReserveShare);
  const bool trianglesFirst = !(hard.useLink && !hard.useTriangles);

  state.stepCandidates.reset();
  std::vector<LeafSelection> selections;
  if (config.reuseLeafWork) {
    selections.swap(state.spareSelections);  // last step's storage: no allocation, no page faults
    selections.clear();
    selections.reserve(state.lastSelectionCount);  // no regrowth copies
  }
  double target = budget.fixedAccuracy.value_or(kInf);
  bool useSolver = hard.useTriangles && hard.useLink;
  if (!useSolver) {
    const Resource primary = trianglesFirst ? Resource::kTriangles : Resource::kLink;
    CurvePropagator propagator(scene, config, region, state, primary, stats);
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
      target = stickyTarget(*chosen, state.previousTarget, config.targetHysteresis);
      propagator.pushDown(target, selections);
      // The pushed-down picks cost at most what the curves charged; verify
      // anyway (rounding): the budget is a hard cap, the solver is the net.
      useSolver = !withinBudget(selections, hard);
    } else {
      useSolver = true;
    }
  }
  if (useSolver) {
    state.stepCandidates.reset();  // the solver's selections have none stored
    stats.usedExactSolver = true;
    selections.clear();
    JointSolver solver(scene, config, region, state, reserved, stats);
    std::optional<double> best = solver.maximise(budget.fixedAccuracy, std::nullopt);
    if (!best) {
      JointSolver full(scene, config, region, state, hard, stats);
      best = full.maximise(budget.fixedAccuracy, std::nullopt);
      if (!best) {
        full.dropUntilFeasible(step.viewer);
        best = full.maximise(budget.fixedAccuracy, std::nullopt);
      }
      target = best ? stickyTarget(*best, state.previousTarget, config.targetHysteresis) : 0.0;
      if (best) full.extract(target, selections);
    } else {
      target = stickyTarget(*best, state.previousTarget, config.targetHysteresis);
      solver.extract(target, selections);
    }
  }
  // Solver sums and plan sums round differently; the cap is hard, so step
  // the target down by a hair until the plan itself fits (never seen in
  // tests, bounded here).
  for (int retry = 0; retry < 8 && useSolver && !withinBudget(selections, hard); ++retry) {
    target *= 1.0 - 1e-9 * double(1 << (2 * retry));
    selections.clear();
    JointSolver again(scene, config, region, state, hard, stats);
    if (again.feasible(target)) again.extract(target, selections);
  }
  if (!withinBudget(selections, hard)) {
    for (LeafSelection& s : selections) {
      s.rendered = false;  // last resort: render nothing, report as dropped
      s.dropped = true;
    }
  }
  preferCurrentCopies(scene, config, region, state, hard, trianglesFirst, selections, stats);
  // Budget fill (budget_fill.h): what the uniform target leaves of the hard
  // budget goes where the image gains most; no leaf drops below its need. A
  // fixed accuracy spends only what it needs. After the hysteresis pass, which
  // would otherwise swap the fill's upgrades back to cheaper displayed copies.
  if (config.fillBudget && !budget.fixedAccuracy) {
    stats.trianglesBeforeFill = renderedCost(selections).triangles;
    // Each round starts from the picks the previous one raised (a round
    // lifts a leaf at most kMaxFillRungs rungs); a leaf raised in several
    // rounds counts once.
    struct Pick {
      std::int32_t option;
      std::uint64_t copy;
      double triangles;
    };
    std::vector<Pick> before;
    before.reserve(selections.size());
    for (const LeafSelection& s : selections)
      before.push_back({s.rendered ? std::int32_t(s.candidate.option) : -1, s.candidate.copyId,
                        s.cost.triangles});
    for (int round = 0; round < config.fillRounds; ++round) {
      if (fillRemainingBudget(scene, config, step.viewer, region, state, hard, selections)
              .upgraded == 0)
        break;
    }
    for (std::size_t i = 0; i < selections.size(); ++i) {
      const LeafSelection& s = selections[i];
      const std::int32_t option = s.rendered ? std::int32_t(s.candidate.option) : -1;
      if (option != before[i].option || s.candidate.copyId != before[i].copy ||
          s.cost.triangles != before[i].triangles)
        ++stats.budgetFillUpgrades;
    }
  }
  state.stepCandidates.reset();  // valid for this step's selections only
  state.previousTarget = target;
  state.lastSelectionCount = selections.size();

  Selection selection;
  selection.leaves = std::move(selections);
  selection.targetAccuracy = target;
  return selection;
}

}  // namespace

Result<std::unique_ptr<Scheduler>> makeAccuracyCurveScheduler(const SchedulerConfig& config) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  return std::make_unique<Scheduler>(config, std::make_unique<AccuracyCurveMethod>());
}

}  // namespace thinlod::backbone
