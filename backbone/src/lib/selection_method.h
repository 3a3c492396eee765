// SelectionMethod: the one step that differs between schedulers (private).
//
// Scheduler::plan (scheduler.cpp) is the shared frame written once: it
// validates the viewer, budget and scene, begins the step on the planner
// state, predicts the region, computes the hard budget, calls the method's
// select(), verifies the hard budget on what came back (dropping the least
// visible objects if a method overshoots), builds the plan (keep / send /
// request / remove, requests, link log) and times the whole step.
//
// A method only decides one LeafSelection per visible leaf (selection.h) and
// the uniform target it reports. To add one: derive from SelectionMethod in a
// .cpp of backbone/src/lib, and add one entry to the catalogue in
// scheduler_registry.cpp; nothing else changes.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "joint_solver.h"
#include "selection.h"

namespace thinlod::backbone {

// What the shared prologue computed for this step.
struct SelectionStep {
  const SchedulingScene& scene;
  const SchedulerConfig& config;  // as the method sees it (see predictsMotion)
  const ViewerState& viewer;
  const Budget& budget;
  const PredictedRegion& region;
  const JointBudget& hard;  // this step's budgets as hard caps
  PlannerStateImpl& state;
  PlanStats& stats;
};

struct Selection {
  std::vector<LeafSelection> leaves;  // one per visible leaf, in any order
  // The uniform absolute target (rad^-1) the plan reports; unset: the lowest
  // absolute accuracy among rendered leaves (0 when none).
  std::optional<double> targetAccuracy;
  const char* mode = nullptr;  // nullptr: modeName(budget)
};

// The accepts() of a method that schedules a polygon budget only.
inline Status requirePolygonBudget(const char* method, const Budget& budget) {
  if (!budget.maxTriangles)
    return Status(ErrorCode::kUnsupported, std::string(method) + " needs Budget.maxTriangles");
  return Status::okStatus();
}

class SelectionMethod {
 public:
  virtual ~SelectionMethod() = default;
  virtual const char* name() const = 0;
  // kUnsupported when the method cannot honour this budget (for example a
  // polygon-only method given a link budget alone).
  virtual Status accepts(const Budget& budget) const {
    (void)budget;
    return Status::okStatus();
  }
  // false: the method looks at the current position only (VRML97): the
  // frame plans with maxSpeed = maxAngularSpeed = 0.
  virtual bool predictsMotion() const { return true; }
  // false: the method ignores budgets by definition (VRML97 static LOD) and
  // the frame does not cap it.
  virtual bool honoursBudgets() const { return true; }
  // true: the method has a frame-cost model and takes Budget::maxFrameSeconds
  // (the frame refuses a frame-time budget for the others).
  virtual bool modelsFrameTime() const { return false; }
  virtual Result<Selection> select(const SelectionStep& step) const = 0;
};

}  // namespace thinlod::backbone
