// The time-critical selection method (Gobbetti & Bouvier 1999): the cost
// model of frame_time_model.h, the degradation weights, and the active-set
// optimiser behind one SelectionMethod.
#include "thinlod/backbone/time_critical_scheduler.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "active_set_optimiser.h"
#include "frame_time_model.h"
#include "scheduler_common.h"
#include "selection_method.h"
#include "visible_tree.h"

namespace thinlod::backbone {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Item {
  std::uint32_t treeNode = 0;
  double maxTriangles = 0.0;  // T_max
  double floor = 1.0;         // lo
  double cost = 0.0;          // c: per unit of resolution (seconds or triangles)
  double fixed = 0.0;         // resolution-independent part (setup, fill when additive)
  double weight = 0.0;        // a = importance * acuity * N_pix / T_max
  double visibility = 0.0;    // keepPriority, for dropping
};

// Triangles a candidate costs at its lowest and at its highest accuracy.
double lowestTriangles(const LeafCandidate& c) {
  if (c.source != CandidateSource::kNew) return c.fixedTriangles;
  return candidateCost(c, c.representation->relativeTriangles.minAccuracy()).triangles;
}
double highestTriangles(const LeafCandidate& c) {
  return candidateCost(c, c.maxRelativeAccuracy).triangles;
}

class TimeCriticalMethod final : public SelectionMethod {
 public:
  explicit TimeCriticalMethod(const TimeCriticalConfig& config) : config_(config) {}
  const char* name() const override { return "active-set"; }
  bool modelsFrameTime() const override { return true; }
  Status accepts(const Budget& budget) const override {
    if (budget.maxLinkBytesPerSecond || budget.fixedAccuracy)
      return Status(ErrorCode::kUnsupported,
                    "active-set schedules a frame-time or polygon budget only (no link budget, "
                    "no fixed accuracy)");
    if (!frameBudget(budget) && !budget.maxTriangles)
      return Status(ErrorCode::kUnsupported,
                    "active-set needs a polygon budget or a frame-time budget");
    return Status::okStatus();
  }
  Result<Selection> select(const SelectionStep& step) const override;

 private:
  // The budget's frame time first, else the config's (tests).
  std::optional<double> frameBudget(const Budget& budget) const {
    return budget.maxFrameSeconds ? budget.maxFrameSeconds : config_.frameBudgetSeconds;
  }
  double acuity(const SelectionStep& step, const Sphere& bounds) const;
  TimeCriticalConfig config_;
};

double TimeCriticalMethod::acuity(const SelectionStep& step, const Sphere& bounds) const {
  if (!config_.useAcuity) return 1.0;
  const ViewerState& now = step.viewer;
  const double scale = config_.visualDegreesPerViewDegree;
  const double eccentricity =
      eccentricityDegrees(now.position, now.viewDirection, bounds.center, bounds.radius) * scale;
  double speed = 0.0;
  const std::optional<ViewerState>& before = step.state.timeCriticalViewer;
  if (before && now.timeSeconds > before->timeSeconds)
    speed = apparentSpeedDegreesPerSecond(before->position, before->viewDirection, now.position,
                                          now.viewDirection, bounds.center,
                                          now.timeSeconds - before->timeSeconds) *
            scale;
  return reddyAcuity(speed, eccentricity);
}

Result<Selection> TimeCriticalMethod::select(const SelectionStep& step) const {
  const SchedulingScene& scene = step.scene;
  PlannerStateImpl& state = step.state;
  const VisibleTree tree = buildVisibleTree(scene, step.config, step.region, state, step.stats);
  Selection selection;
  const std::optional<double> frameSeconds = frameBudget(step.budget);
  selection.mode = frameSeconds ? "frame-time" : "polygon";
  std::vector<LeafSelection>& out = selection.leaves;
  const bool frameMode = frameSeconds.has_value();
  FrameCostConstants costs = config_.costs;
  if (!frameMode) {  // polygon budget: t_tri = 1, everything else 0
    costs = FrameCostConstants{};
    costs.triangleSeconds = 1.0;
  }
  const ScreenProjection screen{config_.viewportWidth, config_.viewportHeight,
                                step.viewer.verticalFov};
  const ViewCone cone(step.viewer);

  std::vector<Item> items;
  for (const std::uint32_t k : visibleLeaves(tree, ChildOrder::kLastChildFirst)) {
    const VisibleNode& n = tree.nodes[k];
    if (n.candidates.empty()) {
      reportUnrenderable(tree, scene, k, out);
      continue;
    }
    Item item;
    item.treeNode = k;
    double lowest = std::numeric_limits<double>::infinity();
    double best = -std::numeric_limits<double>::infinity();
    for (const LeafCandidate& c : n.candidates) {
      lowest = std::min(lowest, lowestTriangles(c));
      if (c.maxRelativeAccuracy > best) {
        best = c.maxRelativeAccuracy;
        item.maxTriangles = highestTriangles(c);
      }
    }
    const std::uint32_t object = scene.nodes[n.sceneNode].object;
    const Sphere& bounds = scene.nodes[n.sceneNode].bounds;
    // Pixels from the nearest point of the predicted region (conservative:
    // the most fill the object can need over the planned lifetime).
    const double pixels =
        projectedSpherePixels(n.distance + 0.5 * n.diameter, 0.5 * n.diameter, screen);
    const ObjectFrameLoad load{item.maxTriangles, pixels};
    const double fill = pixels * costs.pixelSeconds;
    item.fixed = costs.setupSeconds + (costs.additive ? fill : 0.0);
    item.visibility = cone.keepPriority(bounds, n.diameter, n.distance);
    const double importance =
        object < config_.objectImportance.size() ? config_.objectImportance[object] : 1.0;
    if (item.maxTriangles > 0.0) {
      const double fillFloor = fillBoundResolution(costs, load);
      item.floor =
          std::clamp(std::max(std::max(lowest, 1.0) / item.maxTriangles, fillFloor), 1e-9, 1.0);
      item.cost = item.maxTriangles * costs.triangleSeconds;
      if (!costs.additive && fillFloor >= 1.0) {
        // Always fill-bound: the time is the fill whatever the resolution.
        item.cost = 0.0;
        item.fixed += fill;
      }
      item.weight = importance * acuity(step, bounds) * pixels / item.maxTriangles;
    } else {
      item.floor = 1.0;  // nothing to reduce
      item.fixed += costs.additive ? 0.0 : fill;
    }
    items.push_back(item);
  }

  // The budget for sum c_i r_i, and the objects it can hold at their floors.
  double available = 0.0;
  if (frameMode) {
    available = *frameSeconds - costs.initSeconds - costs.finalSeconds - config_.reserveSeconds;
  } else {
    available = step.hard.useTriangles ? step.hard.triangles : *step.budget.maxTriangles;
  }
  // A polygon cap next to the frame time: every variable's time cost is
  // T_max t_tri, so sum T_max r <= cap is the parallel constraint
  // sum c r <= cap t_tri; objects pinned at full (always fill-bound) take
  // their T_max off the cap. The tighter of the two binds (exact).
  const bool polygonCap = frameMode && step.hard.useTriangles;
  const double triangleCap = polygonCap ? step.hard.triangles : 0.0;
  auto pinnedTriangles = [](const Item& item) {
    return item.cost == 0.0 ? item.maxTriangles : 0.0;
  };
  double floorLoad = 0.0;
  double floorTriangles = 0.0;
  for (const Item& item : items) {
    floorLoad += item.fixed + item.cost * item.floor;
    floorTriangles += pinnedTriangles(item) + item.maxTriangles * item.floor * (item.cost > 0.0);
  }
  std::vector<std::uint8_t> dropped(items.size(), 0);
  if (floorLoad > available || (polygonCap && floorTriangles > triangleCap)) {
    std::vector<std::size_t> order(items.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return items[a].visibility < items[b].visibility;
    });
    for (std::size_t i : order) {
      if (floorLoad <= available && (!polygonCap || floorTriangles <= triangleCap)) break;
      dropped[i] = 1;
      floorLoad -= items[i].fixed + items[i].cost * items[i].floor;
      floorTriangles -= pinnedTriangles(items[i]) +
                        items[i].maxTriangles * items[i].floor * (items[i].cost > 0.0);
    }
  }

  ResolutionProblem problem;
  problem.exponent = config_.exponent;
  double fixedTotal = 0.0;
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (dropped[i]) continue;
    const Item& item = items[i];
    fixedTotal += item.fixed;
    ResolutionVariable v;
    v.weight = item.weight;
    v.cost = item.cost;
    v.minResolution = item.floor;
    const std::uint32_t object = scene.nodes[tree.nodes[item.treeNode].sceneNode].object;
    if (object < state.timeCriticalResolution.size())
      v.previousResolution = state.timeCriticalResolution[object];
    problem.variables.push_back(v);
    kept.push_back(i);
  }
  problem.budget = std::max(0.0, available - fixedTotal);
  if (polygonCap) {
    double pinned = 0.0;
    for (std::size_t i : kept) pinned += pinnedTriangles(items[i]);
    problem.budget =
        std::min(problem.budget, std::max(0.0, triangleCap - pinned) * costs.triangleSeconds);
  }
  ActiveSetOptions options;
  options.maxIterations = config_.maxIterations;
  options.timeBoxSeconds = config_.timeBoxSeconds;
  Result<ResolutionSolution> solved = solveResolutionsActiveSet(problem, options);
  if (!solved.ok()) return solved.status();
  // Rounding in the drop loop can leave the floors a hair over: the
  // optimiser then answers kInfeasible with the floors, which the frame's
  // budget verification trims further if needed.
  const std::vector<double>& r = solved->resolution;

  state.timeCriticalResolution.assign(scene.objects.size(), kNaN);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const VisibleNode& n = tree.nodes[items[i].treeNode];
    const std::uint32_t object = scene.nodes[n.sceneNode].object;
    if (dropped[i]) {
      LeafSelection s;
      s.node = n.sceneNode;
      s.object = object;
      s.dropped = true;
      out.push_back(s);
    }
  }
  for (std::size_t j = 0; j < kept.size(); ++j) {
    const Item& item = items[kept[j]];
    const VisibleNode& n = tree.nodes[item.treeNode];
    const std::uint32_t object = scene.nodes[n.sceneNode].object;
    const double allowed = r[j] * item.maxTriangles * (1.0 + 1e-12);
    // The most accurate candidate within r * T_max triangles (ties: fewer
    // triangles, then the candidate order, which puts copies first).
    int pick = -1;
    double pickAccuracy = -1.0;
    double pickTriangles = std::numeric_limits<double>::infinity();
    int cheapest = 0;
    double cheapestTriangles = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < n.candidates.size(); ++c) {
      const LeafCandidate& cand = n.candidates[c];
      const double low = lowestTriangles(cand);
      if (low < cheapestTriangles) {
        cheapestTriangles = low;
        cheapest = static_cast<int>(c);
      }
      double accuracy = -1.0;
      if (cand.source != CandidateSource::kNew) {
        if (cand.fixedTriangles <= allowed) accuracy = cand.maxRelativeAccuracy;
      } else if (const std::optional<double> a =
                     cand.representation->relativeTriangles.maxAccuracyWithin(allowed)) {
        accuracy = std::min(*a, cand.maxRelativeAccuracy);
      }
      if (accuracy < 0.0) continue;
      const double triangles = candidateCost(cand, accuracy).triangles;
      if (accuracy > pickAccuracy || (accuracy == pickAccuracy && triangles < pickTriangles)) {
        pick = static_cast<int>(c);
        pickAccuracy = accuracy;
        pickTriangles = triangles;
      }
    }
    // Hysteresis: the displayed copy stays while it fits the allowance and
    // is within the band of the best accuracy (no churn from small moves
    // of r; the budget holds since the copy fits r * T_max).
    if (pick >= 0 && n.candidates[pick].source != CandidateSource::kFrontendCopy &&
        config_.keepCopyAccuracyShare > 0.0) {
      for (std::size_t c = 0; c < n.candidates.size(); ++c) {
        const LeafCandidate& cand = n.candidates[c];
        if (cand.source != CandidateSource::kFrontendCopy || cand.fixedTriangles > allowed)
          continue;
        if (cand.maxRelativeAccuracy * (1.0 + config_.keepCopyAccuracyShare) < pickAccuracy)
          continue;
        pick = static_cast<int>(c);
        pickAccuracy = cand.maxRelativeAccuracy;
        break;
      }
    }
    if (pick < 0) {  // rounding below every candidate: its cheapest form
      pick = cheapest;
      const LeafCandidate& cand = n.candidates[cheapest];
      pickAccuracy = cand.source != CandidateSource::kNew
                         ? cand.maxRelativeAccuracy
                         : cand.representation->relativeTriangles.minAccuracy();
    }
    out.push_back(makeSelection(n.sceneNode, object, n.candidates[pick], pickAccuracy, n.distance,
                                n.diameter));
    state.timeCriticalResolution[object] = r[j];
  }
  state.timeCriticalViewer = step.viewer;
  return selection;
}

}  // namespace

Status validateTimeCriticalConfig(const TimeCriticalConfig& c) {
  if (c.frameBudgetSeconds && !(std::isfinite(*c.frameBudgetSeconds) && *c.frameBudgetSeconds > 0))
    return Status(ErrorCode::kInvalidArgument,
                  "TimeCriticalConfig.frameBudgetSeconds must be finite and > 0");
  THINLOD_RETURN_IF_ERROR(validateFrameCostConstants(c.costs));
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!(std::isfinite(c.reserveSeconds) && c.reserveSeconds >= 0.0))
    return Status(ErrorCode::kInvalidArgument,
                  "TimeCriticalConfig.reserveSeconds must be finite and >= 0");
  if (!positive(c.viewportWidth) || !positive(c.viewportHeight))
    return Status(ErrorCode::kInvalidArgument, "TimeCriticalConfig viewport must be > 0");
  if (!positive(c.exponent) || c.exponent > 16.0)
    return Status(ErrorCode::kInvalidArgument, "TimeCriticalConfig.exponent must be in (0, 16]");
  if (!positive(c.visualDegreesPerViewDegree))
    return Status(ErrorCode::kInvalidArgument,
                  "TimeCriticalConfig.visualDegreesPerViewDegree must be finite and > 0");
  for (std::size_t i = 0; i < c.objectImportance.size(); ++i)
    if (!(std::isfinite(c.objectImportance[i]) && c.objectImportance[i] >= 0.0))
      return Status(
          ErrorCode::kInvalidArgument,
          "TimeCriticalConfig.objectImportance[" + std::to_string(i) + "] must be finite and >= 0");
  if (!(std::isfinite(c.keepCopyAccuracyShare) && c.keepCopyAccuracyShare >= 0.0))
    return Status(ErrorCode::kInvalidArgument,
                  "TimeCriticalConfig.keepCopyAccuracyShare must be finite and >= 0");
  if (c.maxIterations < 1)
    return Status(ErrorCode::kInvalidArgument, "TimeCriticalConfig.maxIterations must be >= 1");
  if (std::isnan(c.timeBoxSeconds) || c.timeBoxSeconds < 0.0)
    return Status(ErrorCode::kInvalidArgument, "TimeCriticalConfig.timeBoxSeconds must be >= 0");
  return Status::okStatus();
}

Result<std::unique_ptr<Scheduler>> makeTimeCriticalScheduler(
    const SchedulerConfig& config, const TimeCriticalConfig& timeCritical) {
  THINLOD_RETURN_IF_ERROR(validateConfig(config));
  THINLOD_RETURN_IF_ERROR(validateTimeCriticalConfig(timeCritical));
  return std::make_unique<Scheduler>(config, std::make_unique<TimeCriticalMethod>(timeCritical));
}

}  // namespace thinlod::backbone
