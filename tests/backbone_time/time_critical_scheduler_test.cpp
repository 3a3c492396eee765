// The "active-set" scheduler: polygon and frame-time budgets held, the
// least visible objects dropped when even the floors do not fit, warm start
// across steps, registry names, unsupported budgets and bad configs.
#include "thinlod/backbone/time_critical_scheduler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "frame_time_model.h"
#include "scheduler_test_util.h"
#include "thinlod/backbone/synthetic_scene.h"

namespace thinlod::backbone {
namespace {
using namespace testing;

SchedulingScene scene(std::uint64_t seed, std::size_t objects) {
  SyntheticSceneOptions o;
  o.seed = seed;
  o.objects = objects;
  o.lodShare = 0.2;
  return makeSyntheticScene(o).value();
}

// A standing viewer: the predicted region is the viewer's position, so the
// pixels the method estimates can be recomputed here from the geometry.
SchedulerConfig standing() {
  SchedulerConfig c;
  c.maxSpeed = 0.0;
  c.maxAngularSpeed = 0.0;
  return c;
}

FrameCostConstants llvmpipeLike() {
  FrameCostConstants c;
  c.initSeconds = 5e-4;
  c.finalSeconds = 5e-4;
  c.setupSeconds = 2e-5;
  c.triangleSeconds = 1.5e-7;
  c.pixelSeconds = 2e-8;
  return c;
}

// The modelled frame time of a plan: fixed + sum over rendered objects of
// t_setup + max(triangles t_tri, N_pix t_pix), N_pix of the bounding sphere
// seen from the viewer (D clamped by minimalDistance, as the method does).
double modelledSeconds(const SchedulingScene& s, const Plan& plan, const ViewerState& viewer,
                       const FrameCostConstants& c, const SchedulerConfig& config) {
  std::vector<const SceneNode*> leafOf(s.objects.size(), nullptr);
  for (const SceneNode& n : s.nodes)
    if (n.kind == SceneNodeKind::kLeaf) leafOf[n.object] = &n;
  const ScreenProjection screen{640.0, 480.0, viewer.verticalFov};
  double t = c.initSeconds + c.finalSeconds;
  for (const ObjectDecision& d : plan.decisions) {
    if (d.action == ObjectAction::kRemove) continue;
    const Sphere& b = leafOf[d.object]->bounds;
    const double distance =
        std::max(glm::length(b.center - viewer.position) - b.radius, config.minimalDistance);
    const double pixels = projectedSpherePixels(distance + b.radius, b.radius, screen);
    t += c.setupSeconds + std::max(d.triangles * c.triangleSeconds, pixels * c.pixelSeconds);
  }
  return t;
}

// The optimiser's 5 ms time box (any-time, paper 4.1) makes a step's result
// depend on how fast the machine is: the tests of what it converges to run
// without it (the box itself: ActiveSet.ZeroTimeBoxReturnsTheFeasibleStartPoint).
TimeCriticalConfig untimed() {
  TimeCriticalConfig tc;
  tc.timeBoxSeconds = std::numeric_limits<double>::infinity();
  return tc;
}

// Budget has no frame-time field yet and needs some budget: a polygon cap
// that never binds.
Budget noPolygonCap() {
  Budget b;
  b.maxTriangles = 1e12;
  return b;
}

TEST(TimeCriticalScheduler, HoldsThePolygonBudgetAndUsesIt) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto scheduler = makeTimeCriticalScheduler(standing(), untimed()).value();
  double used = 0.0;
  double offered = 0.0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SchedulingScene s = scene(seed, 80);
    PlannerState state;
    Budget budget;
    budget.maxTriangles = 2000.0 + 40000.0 * u(rng);
    const ViewerState viewer = viewerAt({0.0, 0.0, 120.0}, {0.0, 0.0, -1.0});
    auto plan = scheduler->plan(s, viewer, budget, state);
    ASSERT_TRUE(plan.ok()) << plan.status().toString();
    EXPECT_STREQ(plan->mode, "polygon");
    EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles);
    used += plan->predictedTriangles;
    offered += *budget.maxTriangles;
  }
  // Candidates are discrete, so a little stays unused; most is spent.
  EXPECT_GT(used, 0.5 * offered);
}

TEST(TimeCriticalScheduler, HoldsTheFrameTimeBudget) {
  const FrameCostConstants costs = llvmpipeLike();
  int dropping = 0;
  for (double budgetMs : {2.0, 5.0, 10.0, 30.0}) {
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      SchedulingScene s = scene(seed, 120);
      TimeCriticalConfig tc = untimed();
      tc.frameBudgetSeconds = budgetMs * 1e-3;
      tc.costs = costs;
      auto scheduler = makeTimeCriticalScheduler(standing(), tc).value();
      PlannerState state;
      const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
      auto plan = scheduler->plan(s, viewer, noPolygonCap(), state);
      ASSERT_TRUE(plan.ok()) << plan.status().toString();
      EXPECT_STREQ(plan->mode, "frame-time");
      const double t = modelledSeconds(s, *plan, viewer, costs, standing());
      EXPECT_LE(t, *tc.frameBudgetSeconds * (1.0 + 1e-9)) << budgetMs << " ms, seed " << seed;
      if (budgetMs >= 10.0) {
        EXPECT_GT(t, 0.5 * *tc.frameBudgetSeconds);  // the budget is used
      }
      dropping += plan->dropped.empty() ? 0 : 1;
    }
  }
  EXPECT_GT(dropping, 0);  // the 2 ms budget cannot hold every floor: objects are dropped
}

// The daemon's way: the frame time in the Budget itself (--budget-frame-ms),
// the constants from the frontend's calibration in the config.
TEST(TimeCriticalScheduler, HoldsTheBudgetsFrameTimeField) {
  const FrameCostConstants costs = llvmpipeLike();
  SchedulerOptions options;
  options.config = standing();
  options.timeCritical = untimed();
  options.timeCritical.costs = costs;
  auto scheduler = makeScheduler("active-set", options).value();
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SchedulingScene s = scene(seed, 120);
    PlannerState state;
    Budget budget;
    budget.maxFrameSeconds = 8e-3;
    const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
    auto plan = scheduler->plan(s, viewer, budget, state);
    ASSERT_TRUE(plan.ok()) << plan.status().toString();
    EXPECT_STREQ(plan->mode, "frame-time");
    const double t = modelledSeconds(s, *plan, viewer, costs, standing());
    EXPECT_LE(t, *budget.maxFrameSeconds * (1.0 + 1e-9)) << "seed " << seed;
    EXPECT_GT(t, 0.5 * *budget.maxFrameSeconds);
  }
}

TEST(TimeCriticalScheduler, OtherMethodsRefuseAFrameTimeBudget) {
  Budget budget;
  budget.maxFrameSeconds = 8e-3;
  SchedulingScene s = scene(1, 20);
  const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
  for (const SchedulerEntry& e : schedulerCatalogue()) {
    if (std::string(e.name) == "active-set") continue;
    auto scheduler = makeScheduler(e.name, SchedulerOptions{}).value();
    PlannerState state;
    auto plan = scheduler->plan(s, viewer, budget, state);
    ASSERT_FALSE(plan.ok()) << e.name;
    EXPECT_EQ(plan.status().code(), ErrorCode::kUnsupported) << e.name;
    EXPECT_NE(plan.status().message().find("frame"), std::string::npos) << e.name;
  }
  budget.maxFrameSeconds = -1.0;
  EXPECT_FALSE(validateBudget(budget).ok());
}

TEST(TimeCriticalScheduler, FrameBudgetWithABindingPolygonCapHoldsBoth) {
  const FrameCostConstants costs = llvmpipeLike();
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SchedulingScene s = scene(seed, 120);
    TimeCriticalConfig tc = untimed();
    tc.frameBudgetSeconds = 30e-3;
    tc.costs = costs;
    auto scheduler = makeTimeCriticalScheduler(standing(), tc).value();
    PlannerState state;
    Budget budget;
    budget.maxTriangles = 20000.0;  // 3 ms of triangles: binds before 30 ms
    const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
    auto plan = scheduler->plan(s, viewer, budget, state);
    ASSERT_TRUE(plan.ok()) << plan.status().toString();
    EXPECT_LE(plan->predictedTriangles, 20000.0);
    EXPECT_GT(plan->predictedTriangles, 10000.0);
    EXPECT_LE(modelledSeconds(s, *plan, viewer, costs, standing()), 30e-3);
  }
}

TEST(TimeCriticalScheduler, ImpossibleFrameBudgetDropsTheLeastVisible) {
  SchedulingScene s = scene(5, 60);
  TimeCriticalConfig tc = untimed();
  tc.costs = llvmpipeLike();
  tc.frameBudgetSeconds = 1.2e-3;  // 1 ms fixed, 0.2 ms for objects: 10 setups at most
  auto scheduler = makeTimeCriticalScheduler(standing(), tc).value();
  PlannerState state;
  const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
  auto plan = scheduler->plan(s, viewer, noPolygonCap(), state);
  ASSERT_TRUE(plan.ok());
  EXPECT_FALSE(plan->dropped.empty());
  EXPECT_LE(modelledSeconds(s, *plan, viewer, tc.costs, standing()), 1.2e-3 * (1.0 + 1e-9));
  // Every kept object is at least as visible (diameter / distance) as every dropped one.
  auto visibility = [&](std::uint32_t object) {
    for (const SceneNode& n : s.nodes)
      if (n.kind == SceneNodeKind::kLeaf && n.object == object)
        return n.bounds.radius /
               std::max(glm::length(n.bounds.center - viewer.position) - n.bounds.radius, 0.1);
    return 0.0;
  };
  double worstKept = kInf;
  for (const ObjectDecision& d : plan->decisions)
    if (d.action != ObjectAction::kRemove) worstKept = std::min(worstKept, visibility(d.object));
  for (std::uint32_t o : plan->dropped) EXPECT_LE(visibility(o), worstKept * (1.0 + 1e-9));
}

// Expired copies (finishPlan) fill triangle room only; under a frame-time
// budget a dropped object's held copy is removed, so the modelled time holds.
TEST(TimeCriticalScheduler, DroppedObjectsLoseTheirExpiredCopiesUnderAFrameTimeBudget) {
  SchedulingScene s = scene(5, 60);
  for (const SceneObject& object : s.objects) {
    RepresentationCopy& copy = s.options[object.firstOption].atFrontend;
    copy.present = true;
    copy.id = 1000 + object.firstOption;
    copy.relativeAccuracy = 1.0;
    copy.triangles = 10.0;
    copy.encodedBytes = 2000.0;
    copy.validity = ConicRange::ball({1000.0, 0.0, 0.0}, 1.0);  // expired everywhere here
  }
  updateSubtreeVersions(s);
  TimeCriticalConfig tc = untimed();
  tc.costs = llvmpipeLike();
  tc.frameBudgetSeconds = 1.2e-3;
  auto scheduler = makeTimeCriticalScheduler(standing(), tc).value();
  PlannerState state;
  const ViewerState viewer = viewerAt({0.0, 0.0, 80.0}, {0.0, 0.0, -1.0});
  auto plan = scheduler->plan(s, viewer, noPolygonCap(), state);
  ASSERT_TRUE(plan.ok()) << plan.status().toString();
  ASSERT_FALSE(plan->dropped.empty());
  EXPECT_EQ(plan->stats.expiredCopiesKept, 0u);
  EXPECT_LE(modelledSeconds(s, *plan, viewer, tc.costs, standing()), 1.2e-3 * (1.0 + 1e-9));
  for (std::uint32_t o : plan->dropped) {
    const bool removed = std::any_of(plan->removals.begin(), plan->removals.end(),
                                     [&](const Removal& r) { return r.object == o; });
    EXPECT_TRUE(removed) << "object " << o;
  }
}

TEST(TimeCriticalScheduler, StandingViewerKeepsItsLoadFromStepToStep) {
  SchedulingScene s = scene(9, 100);
  auto scheduler = makeTimeCriticalScheduler(standing(), untimed()).value();
  PlannerState state;
  Budget budget;
  budget.maxTriangles = 20000.0;
  const ViewerState first = viewerAt({0.0, 0.0, 100.0}, {0.0, 0.0, -1.0}, 0.0, 0);
  auto a = scheduler->plan(s, first, budget, state);
  ASSERT_TRUE(a.ok());
  applyPlan(s, *a);
  const ViewerState second = viewerAt({0.0, 0.0, 100.0}, {0.0, 0.0, -1.0}, 0.1, 1);
  auto b = scheduler->plan(s, second, budget, state);
  ASSERT_TRUE(b.ok());
  EXPECT_LE(b->predictedTriangles, *budget.maxTriangles);
  EXPECT_NEAR(b->predictedTriangles, a->predictedTriangles, 0.02 * a->predictedTriangles);
}

// Hysteresis: a viewer drifting slowly moves every r a little; without the
// band each move replaces every copy whose triangle count differs, with it
// the copies stay while they fit their allowance and are within the band
// (measured: 508 replacements against 1000 over 11 steps of 100 objects).
// The budget holds either way.
TEST(TimeCriticalScheduler, ADriftingViewerKeepsItsCopiesWithinTheBand) {
  int replaced[2] = {0, 0};
  int kept[2] = {0, 0};
  for (int withBand = 0; withBand < 2; ++withBand) {
    SchedulingScene s = scene(9, 100);
    TimeCriticalConfig tc = untimed();
    tc.keepCopyAccuracyShare = withBand ? 0.15 : 0.0;
    auto scheduler = makeTimeCriticalScheduler(standing(), tc).value();
    PlannerState state;
    Budget budget;
    budget.maxTriangles = 20000.0;
    for (int step = 0; step < 12; ++step) {
      const ViewerState viewer =
          viewerAt({0.0, 0.0, 100.0 - 0.3 * step}, {0.0, 0.0, -1.0}, 0.1 * step, step);
      auto plan = scheduler->plan(s, viewer, budget, state);
      ASSERT_TRUE(plan.ok()) << plan.status().toString();
      EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles) << step;
      if (step > 0) {
        for (const ObjectDecision& d : plan->decisions) {
          replaced[withBand] += d.action == ObjectAction::kRequest ? 1 : 0;
          kept[withBand] += d.action == ObjectAction::kKeep ? 1 : 0;
        }
      }
      applyPlan(s, *plan);
    }
  }
  EXPECT_GT(replaced[0], 0);
  // About half the objects see their allowance shrink at each step: their
  // copies no longer fit and must go (the budget comes first); the band
  // saves the rest.
  EXPECT_LT(replaced[1] * 10, replaced[0] * 6) << replaced[1] << " vs " << replaced[0];
  EXPECT_GT(kept[1], kept[0]);
}

TEST(TimeCriticalScheduler, AcuityFavoursTheObjectInFocus) {
  // Two identical objects at the same distance, one straight ahead and one
  // 40 degrees off axis: the one in focus gets more triangles.
  SceneBuilder b;
  const int root = b.group(-1);
  const double d = 20.0;
  const double off = 40.0 * kPi / 180.0;
  b.leaf(root, Sphere{{0.0, 0.0, -d}, 1.0}, {meshOption(1.0, 20.0, 200.0, 4000.0)});
  b.leaf(root, Sphere{{d * std::sin(off), 0.0, -d * std::cos(off)}, 1.0},
         {meshOption(1.0, 20.0, 200.0, 4000.0)});
  SchedulingScene s = b.build();
  SchedulerConfig config = standing();
  config.maxViewDistance = 1000.0;
  auto scheduler = makeTimeCriticalScheduler(config, untimed()).value();
  PlannerState state;
  Budget budget;
  budget.maxTriangles = 3000.0;
  ViewerState viewer = viewerAt({0.0, 0.0, 0.0}, {0.0, 0.0, -1.0});
  viewer.horizontalFov = 2.0;
  auto plan = scheduler->plan(s, viewer, budget, state);
  ASSERT_TRUE(plan.ok()) << plan.status().toString();
  double focus = 0.0;
  double side = 0.0;
  for (const ObjectDecision& dec : plan->decisions)
    (dec.object == 0 ? focus : side) = dec.triangles;
  EXPECT_GT(focus, 1.5 * side);
  EXPECT_LE(focus + side, 3000.0);
}

TEST(TimeCriticalScheduler, RegisteredByNameAndAlias) {
  for (const char* name : {"active-set", "time-critical"}) {
    auto made = makeScheduler(name, SchedulerOptions{});
    ASSERT_TRUE(made.ok()) << made.status().toString();
    EXPECT_STREQ((*made)->name(), "active-set");
  }
}

TEST(TimeCriticalScheduler, RefusesBudgetsItCannotHonour) {
  auto polygon = makeTimeCriticalScheduler(standing(), untimed()).value();
  Budget none;
  EXPECT_EQ(polygon->accepts(none).code(), ErrorCode::kUnsupported);
  Budget link;
  link.maxTriangles = 100.0;
  link.maxLinkBytesPerSecond = 1e5;
  EXPECT_EQ(polygon->accepts(link).code(), ErrorCode::kUnsupported);
  Budget fixed;
  fixed.maxTriangles = 100.0;
  fixed.fixedAccuracy = 50.0;
  EXPECT_EQ(polygon->accepts(fixed).code(), ErrorCode::kUnsupported);
  TimeCriticalConfig tc;
  tc.frameBudgetSeconds = 0.01;
  auto frame = makeTimeCriticalScheduler(standing(), tc).value();
  EXPECT_EQ(frame->accepts(link).code(), ErrorCode::kUnsupported);
  EXPECT_TRUE(frame->accepts(noPolygonCap()).ok());
}

TEST(TimeCriticalScheduler, RejectsANegativeOrNaNHysteresisBand) {
  TimeCriticalConfig tc;
  tc.keepCopyAccuracyShare = -0.1;
  EXPECT_FALSE(validateTimeCriticalConfig(tc).ok());
  tc.keepCopyAccuracyShare = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(validateTimeCriticalConfig(tc).ok());
  tc.keepCopyAccuracyShare = 0.0;
  EXPECT_TRUE(validateTimeCriticalConfig(tc).ok());
}

TEST(TimeCriticalScheduler, RejectsBadConfigs) {
  std::vector<TimeCriticalConfig> bad(9);
  bad[0].frameBudgetSeconds = 0.0;
  bad[1].frameBudgetSeconds = std::numeric_limits<double>::quiet_NaN();
  bad[2].costs.triangleSeconds = -1.0;
  bad[3].reserveSeconds = -1.0;
  bad[4].viewportWidth = 0.0;
  bad[5].exponent = 0.0;
  bad[6].objectImportance = {1.0, std::numeric_limits<double>::infinity()};
  bad[7].maxIterations = 0;
  bad[8].timeBoxSeconds = -1.0;
  for (std::size_t i = 0; i < bad.size(); ++i) {
    auto made = makeTimeCriticalScheduler(standing(), bad[i]);
    ASSERT_FALSE(made.ok()) << i;
    EXPECT_EQ(made.status().code(), ErrorCode::kInvalidArgument);
  }
}

}  // namespace
}  // namespace thinlod::backbone
