// The scheduler catalogue and the shared planning frame: every method is made
// by name, and the frame holds the hard budget whatever a method returns.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "scheduler_test_util.h"
#include "selection_method.h"
#include "thinlod/backbone/synthetic_scene.h"

namespace thinlod::backbone {
namespace {
using namespace testing;

TEST(SchedulerCatalogue, EveryNameAndAliasMakesTheSchedulerOfThatName) {
  std::set<std::string> names;
  for (const SchedulerEntry& e : schedulerCatalogue()) {
    EXPECT_TRUE(names.insert(e.name).second) << "duplicate name " << e.name;
    auto made = makeScheduler(e.name, SchedulerOptions{});
    ASSERT_TRUE(made.ok()) << e.name << ": " << made.status().message();
    EXPECT_STREQ((*made)->name(), e.name);
    if (*e.alias) {
      EXPECT_TRUE(names.insert(e.alias).second) << "alias " << e.alias << " is taken";
      auto byAlias = makeScheduler(e.alias, SchedulerOptions{});
      ASSERT_TRUE(byAlias.ok());
      EXPECT_STREQ((*byAlias)->name(), e.name);
    }
  }
  EXPECT_GE(names.count("accuracy-curve"), 1u);
}

TEST(SchedulerCatalogue, UnknownNameIsNotFoundAndListsTheKnownOnes) {
  auto made = makeScheduler("random", SchedulerOptions{});
  ASSERT_FALSE(made.ok());
  EXPECT_EQ(made.status().code(), ErrorCode::kNotFound);
  EXPECT_NE(made.status().message().find("accuracy-curve"), std::string::npos);
  EXPECT_NE(made.status().message().find("greedy-fs93"), std::string::npos);
}

TEST(SchedulerCatalogue, HelpListsTheDaemonMethodsButNotTheExperimentalOnes) {
  const std::string help = schedulerHelp();
  for (const SchedulerEntry& e : schedulerCatalogue())
    EXPECT_EQ(help.find(e.name) != std::string::npos, !e.forExperiments) << e.name;
}

TEST(SchedulerCatalogue, InvalidConfigIsRefusedByEveryFactory) {
  SchedulerOptions options;
  options.config.plannedLifetime = -1.0;
  for (const SchedulerEntry& e : schedulerCatalogue())
    EXPECT_FALSE(makeScheduler(e.name, options).ok()) << e.name;
}

// Every method that honours budgets stays within the polygon cap on random
// scenes, through the same frame.
TEST(SchedulerCatalogue, EveryBudgetedMethodHoldsThePolygonCap) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const SchedulerEntry& e : schedulerCatalogue()) {
    if (std::string(e.name) == "brute-force" || std::string(e.name) == "vrml-static") continue;
    std::uint64_t rendered = 0;  // the property must be tested on plans that draw something
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      SyntheticSceneOptions o;
      o.seed = seed;
      o.objects = 60;
      o.lodShare = 0.3;
      SchedulingScene scene = makeSyntheticScene(o).value();
      SchedulerOptions options;
      options.config.maxSpeed = 1.0;
      auto scheduler = makeScheduler(e.name, options).value();
      PlannerState state;
      Budget budget;
      budget.maxTriangles = 100.0 + 20000.0 * u(rng);
      for (int frame = 0; frame < 4; ++frame) {
        const glm::dvec3 at(100.0 * u(rng) - 50.0, 100.0 * u(rng) - 50.0, 10.0 + 20.0 * u(rng));
        auto plan = scheduler->plan(scene, viewerAt(at, -at, frame * 0.1), budget, state);
        ASSERT_TRUE(plan.ok()) << e.name << ": " << plan.status().message();
        EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles) << e.name << " seed " << seed;
        rendered += plan->predictedTriangles > 0.0 ? 1 : 0;
        applyPlan(scene, *plan);
      }
    }
    EXPECT_GT(rendered, 24u) << e.name;
  }
}

// When even the cheapest plan overshoots the cap, every budgeted method drops
// what the viewer cannot see now before anything in view, however much larger
// the unseen objects look (keepPriority; the city-walk case of the workbench,
// where near buildings behind the viewer used to push out the ones ahead).
TEST(SchedulerCatalogue, EveryBudgetedMethodDropsObjectsOutOfViewFirst) {
  SceneBuilder b;
  const int root = b.group(-1);
  for (int i = 0; i < 4; ++i)  // ahead, in the view cone: 10-16 m away
    b.leaf(root, {{0.5 * i, 0, -10.0 - 2.0 * i}, 0.5}, {meshOption(5, 100, 50, 1000)});
  // 55 degrees to the side, nearer (3-6 m): outside the current view cone
  // (about 33 degrees to its corners) but within a turn of the planned
  // lifetime, so they are visible to the scheduler and look larger.
  const glm::dvec3 side(std::sin(0.96), 0.0, -std::cos(0.96));
  for (int i = 0; i < 4; ++i)
    b.leaf(root, {side * (3.0 + i), 0.5}, {meshOption(5, 100, 50, 1000)});
  const SchedulingScene scene = b.build();
  for (const SchedulerEntry& e : schedulerCatalogue()) {
    if (std::string(e.name) == "brute-force" || std::string(e.name) == "vrml-static") continue;
    SchedulerOptions options;
    options.config = exactConfig();
    auto scheduler = makeScheduler(e.name, options).value();
    PlannerState state;
    Budget budget;
    budget.maxTriangles = 450.0;  // four objects at their cheapest 100 triangles
    ViewerState viewer = viewerAt({0, 0, 0}, {0, 0, -1});
    viewer.horizontalFov = 1.0;
    viewer.verticalFov = 0.8;
    auto plan = scheduler->plan(scene, viewer, budget, state);
    ASSERT_TRUE(plan.ok()) << e.name << ": " << plan.status().message();
    EXPECT_LE(plan->predictedTriangles, 450.0) << e.name;
    // All four unseen objects go; an in-view one only after them (active-set's
    // floors are coarser and also drop the farthest one ahead).
    std::vector<std::uint32_t> dropped = plan->dropped;
    std::sort(dropped.begin(), dropped.end());
    ASSERT_GE(dropped.size(), 4u) << e.name;
    EXPECT_EQ(std::vector<std::uint32_t>(dropped.end() - 4, dropped.end()),
              (std::vector<std::uint32_t>{4, 5, 6, 7}))
        << e.name;
    for (std::size_t k = 0; k + 4 < dropped.size(); ++k)  // ahead: the farthest first
      EXPECT_EQ(dropped[k], 4 - (dropped.size() - 4) + k) << e.name;
  }
}

// A method that ignores the budget: the frame must drop the least visible
// objects until the plan fits.
class OvershootingMethod final : public SelectionMethod {
 public:
  const char* name() const override { return "overshooting"; }
  Result<Selection> select(const SelectionStep& step) const override {
    Selection selection;
    std::vector<LeafCandidate> candidates;
    for (std::uint32_t n = 0; n < step.scene.nodes.size(); ++n) {
      const SceneNode& node = step.scene.nodes[n];
      if (node.kind != SceneNodeKind::kLeaf) continue;
      collectLeafCandidates(step.scene, node.object, step.region, step.config,
                            CandidateContext::kExact, nullptr, node.bounds, candidates);
      const double best = bestCandidateAccuracy(candidates);
      const int pick = pickCandidate(candidates, best, true);
      if (pick < 0) continue;
      const double distance = glm::length(node.bounds.center - step.viewer.position);
      selection.leaves.push_back(makeSelection(n, node.object, candidates[pick], best, distance,
                                               2.0 * node.bounds.radius));
    }
    return selection;
  }
};

TEST(SchedulingFrame, OvershootingSelectionIsCutToTheHardBudgetLeastVisibleFirst) {
  SceneBuilder b;
  const int root = b.group(-1);
  // Same object three times at growing distances: 1000 triangles each at best.
  for (double x : {3.0, 10.0, 40.0})
    b.leaf(root, Sphere{{x, 0.0, 0.0}, 0.5}, {meshOption(1.0, 10.0, 1000.0, 1000.0)});
  SchedulingScene scene = b.build();
  Scheduler scheduler(exactConfig(), std::make_unique<OvershootingMethod>());
  PlannerState state;
  Budget budget;
  budget.maxTriangles = 2000.0;
  auto plan = scheduler.plan(scene, viewerAt({0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}), budget, state);
  ASSERT_TRUE(plan.ok()) << plan.status().message();
  EXPECT_LE(plan->predictedTriangles, 2000.0);
  ASSERT_EQ(plan->dropped.size(), 1u);
  // The farthest (least visible) copy is the one dropped.
  EXPECT_EQ(plan->dropped[0], 2u);
}

}  // namespace
}  // namespace thinlod::backbone
