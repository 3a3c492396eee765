// The shared frame of every planning step (selection_method.h says what it
// does around a method's selection).
#include "thinlod/backbone/scheduler.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "scheduler_common.h"
#include "selection_method.h"

namespace thinlod::backbone {
namespace {

// A method that overshoots a hard cap loses its least visible objects
// (lowest keepPriority first) until the plan fits: the budget is a cap on
// every plan, whatever the method.
void dropUntilWithin(const SchedulingScene& scene, const ViewerState& viewer,
                     std::vector<LeafSelection>& leaves, const JointBudget& hard) {
  std::vector<std::size_t> order;
  std::vector<double> priority(leaves.size(), 0.0);
  const ViewCone cone(viewer);
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (!leaves[i].rendered) continue;
    order.push_back(i);
    priority[i] = cone.keepPriority(scene.nodes[leaves[i].node].bounds, leaves[i].diameter,
                                    leaves[i].distance);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return priority[a] < priority[b]; });
  for (std::size_t i : order) {
    if (withinBudget(leaves, hard)) return;
    leaves[i].rendered = false;
    leaves[i].dropped = true;
  }
}

double lowestRenderedAccuracy(const std::vector<LeafSelection>& leaves) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const LeafSelection& s : leaves)
    if (s.rendered) lowest = std::min(lowest, s.absoluteAccuracy());
  return std::isfinite(lowest) ? lowest : 0.0;
}

}  // namespace

Scheduler::Scheduler(const SchedulerConfig& config, std::unique_ptr<const SelectionMethod> method)
    : config_(config), method_(std::move(method)) {}

Scheduler::~Scheduler() = default;

Status Scheduler::setConfig(const SchedulerConfig& config) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  config_ = config;
  return Status();
}

const char* Scheduler::name() const { return method_->name(); }

Status Scheduler::accepts(const Budget& budget) const {
  if (budget.maxFrameSeconds && !method_->modelsFrameTime())
    return Status(ErrorCode::kUnsupported, std::string(method_->name()) +
                                               " has no frame-cost model: a frame-time budget "
                                               "needs active-set");
  return method_->accepts(budget);
}

Result<Plan> Scheduler::plan(const SchedulingScene& scene, const ViewerState& viewer,
                             const Budget& budget, PlannerState& outer) const {
  const auto started = std::chrono::steady_clock::now();
  THINLOD_RETURN_IF_ERROR(validateViewer(viewer));
  THINLOD_RETURN_IF_ERROR(validateBudget(budget));
  if (scene.nodes.empty()) return Status(ErrorCode::kInvalidArgument, "scheduling scene: no nodes");
  THINLOD_RETURN_IF_ERROR(accepts(budget));
  PlannerStateImpl& state = outer.impl();
  beginStep(state, scene, config_, viewer, linkWindowSeconds(budget, config_));

  SchedulerConfig seen = config_;
  if (!method_->predictsMotion()) {
    seen.maxSpeed = 0.0;
    seen.maxAngularSpeed = 0.0;
  }
  const PredictedRegion region = predictRegion(viewer, seen);
  const JointBudget hard =
      method_->honoursBudgets() ? hardBudget(budget, state, viewer, config_) : JointBudget{};

  Plan plan;
  plan.scheduler = method_->name();
  const SelectionStep step{scene, seen, viewer, budget, region, hard, state, plan.stats};
  Result<Selection> selected = method_->select(step);
  if (!selected.ok()) return selected.status();
  Selection& selection = selected.value();
  if (!withinBudget(selection.leaves, hard)) dropUntilWithin(scene, viewer, selection.leaves, hard);
  plan.mode = selection.mode ? selection.mode : modeName(budget);
  const double target = selection.targetAccuracy.value_or(lowestRenderedAccuracy(selection.leaves));

  PlanContext context{scene, seen, viewer, region, state};
  // Expired copies fill only triangle room the polygon budget leaves. A method
  // with a frame-cost model keeps none: its budget is modelled time, which
  // this frame cannot check (active-set's frame-time mode may come from its
  // own config, not from Budget::maxFrameSeconds). Nor do baselines that
  // honour no budget (the static VRML LOD): they stay as published.
  std::optional<double> expiredCopyRoom;
  if (method_->honoursBudgets() && !method_->modelsFrameTime())
    expiredCopyRoom = budget.maxTriangles.value_or(std::numeric_limits<double>::infinity());
  finishPlan(context, selection.leaves, target, expiredCopyRoom, plan);
  // The selections are consumed: keep their storage for the next step.
  state.spareSelections = std::move(selection.leaves);
  plan.row.schedulingMicroseconds =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - started).count();
  return plan;
}

}  // namespace thinlod::backbone
