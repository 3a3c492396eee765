// The aslod and span-of-level-changed schedulers (allocation_schedulers.h)
// through the shared frame: budgets on random flights and extreme
// magnitudes, the allocation following projected area, the paper's literal
// distance rule and its inverse, hysteresis.
#include "thinlod/backbone/allocation_schedulers.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "backbone/scheduler_test_util.h"
#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/synthetic_scene.h"

namespace thinlod::backbone {
namespace {
using namespace testing;

std::unique_ptr<Scheduler> aslod(const SchedulerConfig& c, AslodSchedulerConfig a = {}) {
  auto made = makeAslodScheduler(c, a);
  EXPECT_TRUE(made.ok()) << made.status().toString();
  return std::move(made).value();
}

std::unique_ptr<Scheduler> slc(const SchedulerConfig& c, SpanOfLevelChangedConfig s = {}) {
  auto made = makeSpanOfLevelChangedScheduler(c, s);
  EXPECT_TRUE(made.ok()) << made.status().toString();
  return std::move(made).value();
}

std::vector<std::unique_ptr<Scheduler>> allVariants(const SchedulerConfig& c) {
  std::vector<std::unique_ptr<Scheduler>> out;
  out.push_back(aslod(c));
  AslodSchedulerConfig fs;
  fs.alpha = 3.0;
  fs.hysteresisShare = 0.0;
  out.push_back(aslod(c, fs));
  out.push_back(slc(c));
  SpanOfLevelChangedConfig far;
  far.coarsenFarthestFirst = true;
  out.push_back(slc(c, far));
  return out;
}

std::map<std::uint32_t, double> trianglesByObject(const Plan& plan) {
  std::map<std::uint32_t, double> t;
  for (const ObjectDecision& d : plan.decisions)
    if (d.action != ObjectAction::kRemove) t[d.object] = d.triangles;
  return t;
}

TEST(AllocationSchedulers, RegisteredByNameAndNeedAPolygonBudget) {
  for (const char* name : {"aslod", "span-of-level-changed", "slc"}) {
    auto made = makeScheduler(name, SchedulerOptions{});
    ASSERT_TRUE(made.ok()) << name;
    Budget link;
    link.maxLinkBytesPerSecond = 1e6;
    EXPECT_EQ((*made)->accepts(link).code(), ErrorCode::kUnsupported) << name;
    SyntheticSceneOptions o;
    SchedulingScene scene = makeSyntheticScene(o).value();
    PlannerState state;
    EXPECT_EQ((*made)->plan(scene, viewerAt({0, 0, 60}, {0, 0, -1}), link, state).status().code(),
              ErrorCode::kUnsupported);
  }
  EXPECT_STREQ(makeScheduler("slc", SchedulerOptions{}).value()->name(), "span-of-level-changed");
  AslodSchedulerConfig bad;
  bad.alpha = -1.0;
  EXPECT_FALSE(makeAslodScheduler(SchedulerConfig{}, bad).ok());
  SchedulerConfig badConfig;
  badConfig.plannedLifetime = 0.0;
  EXPECT_FALSE(makeSpanOfLevelChangedScheduler(badConfig, {}).ok());
}

TEST(AllocationSchedulers, BudgetHoldsOnRandomFlights) {
  std::uint64_t renderedPlans = 0;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SyntheticSceneOptions o;
    o.seed = seed;
    o.objects = 80;
    o.worldSize = 30.0;
    o.lodShare = 0.3;
    const SchedulingScene original = makeSyntheticScene(o).value();
    SchedulerConfig c;
    c.maxSpeed = 0.5;
    for (auto& scheduler : allVariants(c)) {
      SchedulingScene scene = original;
      PlannerState state;
      Budget budget;
      budget.maxTriangles = std::floor(50.0 + 40000.0 * u(rng) * u(rng));
      glm::dvec3 at(0.0, 0.0, 25.0);
      for (int frame = 0; frame < 12; ++frame) {
        at += glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, -0.3);
        const ViewerState v =
            viewerAt(at, glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, -1.0), 0.2 * frame, frame);
        auto plan = scheduler->plan(scene, v, budget, state);
        ASSERT_TRUE(plan.ok()) << scheduler->name() << ": " << plan.status().toString();
        EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles)
            << scheduler->name() << " seed " << seed << " frame " << frame;
        double sum = 0.0;
        for (const ObjectDecision& d : plan->decisions) sum += d.triangles;
        EXPECT_LE(sum, *budget.maxTriangles);
        renderedPlans += plan->predictedTriangles > 0.0;
        applyPlan(scene, *plan);
      }
    }
  }
  EXPECT_GT(renderedPlans, 16u * 4u * 12u * 9u / 10u);
}

TEST(AllocationSchedulers, ExtremeMagnitudesKeepTheBudgetAndStayFinite) {
  const double lengths[] = {1e-5, 1e-2, 1.0, 1e3, 1e6};
  const double triangleScales[] = {1e-3, 1.0, 1e4, 1e9};
  int plans = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double length = lengths[seed % 5];
    const double scale = triangleScales[(seed / 5) % 4];
    SyntheticSceneOptions o;
    o.seed = seed;
    o.objects = 30;
    o.worldSize = 20.0 * length;
    o.minRadius = 0.05 * length;
    o.maxRadius = 2.0 * length;
    o.minTriangles = 2.0 * scale;
    o.maxTriangles = 1e5 * scale;
    o.lodShare = 0.3;
    const SchedulingScene original = makeSyntheticScene(o).value();
    SchedulerConfig c;
    c.maxSpeed = 0.5 * length;
    c.minimalDistance = 0.01 * length;
    const double budgets[] = {0.0, 1e-3 * scale, 500.0 * scale * u(rng), 1e300};
    Budget budget;
    budget.maxTriangles = budgets[seed % 4];
    for (auto& scheduler : allVariants(c)) {
      SchedulingScene scene = original;
      PlannerState state;
      for (std::uint64_t frame = 0; frame < 4; ++frame) {
        const glm::dvec3 at = glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) + 0.4) * 25.0 * length;
        const ViewerState v = viewerAt(at, {u(rng) - 0.5, u(rng) - 0.5, -1.0}, 0.3 * frame, frame);
        auto plan = scheduler->plan(scene, v, budget, state);
        ASSERT_TRUE(plan.ok()) << scheduler->name() << " seed " << seed << ": "
                               << plan.status().toString();
        ++plans;
        EXPECT_TRUE(std::isfinite(plan->predictedTriangles));
        EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles) << scheduler->name();
        for (const ObjectDecision& d : plan->decisions) {
          EXPECT_TRUE(std::isfinite(d.triangles));
          EXPECT_FALSE(std::isnan(d.absoluteAccuracy));
        }
        applyPlan(scene, *plan);
      }
    }
  }
  EXPECT_EQ(plans, 40 * 4 * 4);
}

// Two identical objects on the view axis, one near and one far.
SchedulingScene nearAndFar(double nearZ, double farZ) {
  SceneBuilder b;
  const int root = b.group(-1);
  b.leaf(root, {{0.3, 0, nearZ}, 0.5}, {meshOption(1.0, 16.0, 400.0, 20000.0)});
  b.leaf(root, {{-0.3, 0, farZ}, 0.5}, {meshOption(1.0, 16.0, 400.0, 20000.0)});
  return b.build();
}

TEST(AllocationSchedulers, AslodFollowsProjectedAreaAtAlphaOne) {
  const SchedulingScene scene = nearAndFar(-3.0, -12.0);
  AslodSchedulerConfig config;
  config.hysteresisShare = 0.0;
  auto scheduler = aslod(exactConfig(), config);
  PlannerState state;
  Budget budget;
  budget.maxTriangles = 3000.0;
  auto plan = scheduler->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, state);
  ASSERT_TRUE(plan.ok());
  const auto t = trianglesByObject(*plan);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_GT(t.at(0), t.at(1));
  EXPECT_LE(t.at(0) + t.at(1), 3000.0);
  // The mesh curve is linear, so each object renders (almost) exactly its
  // allocation: the ratio is the solid-angle ratio of the two spheres.
  auto solidAngle = [](double r, double centre) {
    return 2.0 * kPi * (1.0 - std::sqrt(1.0 - r * r / (centre * centre)));
  };
  const SchedulerConfig c = exactConfig();
  const double reach = c.maxSpeed * (c.plannedLifetime + c.linkDelay + c.generationDelay);
  const double nearCentre = std::sqrt(0.09 + 9.0) - reach;
  const double farCentre = std::sqrt(0.09 + 144.0) - reach;
  const double expected = solidAngle(0.5, nearCentre) / solidAngle(0.5, farCentre);
  EXPECT_NEAR(t.at(0) / t.at(1), expected, 0.01 * expected);
  EXPECT_GT(t.at(0) + t.at(1), 2990.0);
}

TEST(AllocationSchedulers, AslodLargerAlphaSplitsMoreEvenly) {
  const SchedulingScene scene = nearAndFar(-3.0, -12.0);
  Budget budget;
  budget.maxTriangles = 3000.0;
  double previousRatio = std::numeric_limits<double>::infinity();
  for (double alpha : {1.0, 3.0, 30.0}) {
    AslodSchedulerConfig config;
    config.alpha = alpha;
    PlannerState state;
    auto plan =
        aslod(exactConfig(), config)->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, state);
    ASSERT_TRUE(plan.ok());
    const auto t = trianglesByObject(*plan);
    const double ratio = t.at(0) / t.at(1);
    EXPECT_LT(ratio, previousRatio) << "alpha " << alpha;
    EXPECT_GE(ratio, 1.0);
    previousRatio = ratio;
  }
  EXPECT_LT(previousRatio, 1.1);
}

// Eq. 6 with the sphere's solid angle: for two equal objects S ~ D^2 and the
// literal d ~ 1 / D, so f ~ D and the FAR one still drops first; the
// distance rule alone decides between objects of equal projected area.
TEST(AllocationSchedulers, SpanOfLevelChangedAreaTermDominatesForEqualObjects) {
  const SchedulingScene scene = nearAndFar(-3.0, -12.0);
  Budget budget;
  budget.maxTriangles = 20000.0;  // both at full detail need 40000
  PlannerState state;
  auto plan = slc(exactConfig())->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, state);
  ASSERT_TRUE(plan.ok());
  const auto t = trianglesByObject(*plan);
  EXPECT_GT(t.at(0), t.at(1));
  EXPECT_LE(t.at(0) + t.at(1), 20000.0);
}

TEST(AllocationSchedulers, SpanOfLevelChangedLiteralDistanceCoarsensTheNearObject) {
  // Equal solid angles (radius / centre distance 1/6 both), so S = 1 for both
  // and only d differs: D = 2.5 m and 10 m.
  SceneBuilder b;
  const int root = b.group(-1);
  b.leaf(root, {{0, 0, -3.0}, 0.5}, {meshOption(1.0, 16.0, 400.0, 20000.0)});
  b.leaf(root, {{0, 0, -12.0}, 2.0}, {meshOption(1.0, 16.0, 400.0, 20000.0)});
  const SchedulingScene scene = b.build();
  SchedulerConfig still = exactConfig();
  still.maxSpeed = 0.0;  // reach ball of radius 0: the solid angles are exactly equal
  Budget budget;
  budget.maxTriangles = 20000.0;
  PlannerState literalState;
  auto literal = slc(still)->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, literalState);
  ASSERT_TRUE(literal.ok());
  const auto t = trianglesByObject(*literal);
  EXPECT_LT(t.at(0), t.at(1));  // the paper's d = D_nearest / D: the nearest drops first
  EXPECT_LE(t.at(0) + t.at(1), 20000.0);
  SpanOfLevelChangedConfig far;
  far.coarsenFarthestFirst = true;
  PlannerState farState;
  auto inverse = slc(still, far)->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, farState);
  ASSERT_TRUE(inverse.ok());
  const auto ti = trianglesByObject(*inverse);
  EXPECT_GT(ti.at(0), ti.at(1));
  EXPECT_LE(ti.at(0) + ti.at(1), 20000.0);
}

TEST(AllocationSchedulers, SpanOfLevelChangedRendersPowerOfTwoLevelsOrCurveEnds) {
  const SchedulingScene scene = nearAndFar(-3.0, -12.0);
  for (double cap : {100.0, 1000.0, 5000.0, 30000.0, 50000.0}) {
    Budget budget;
    budget.maxTriangles = cap;
    PlannerState state;
    auto plan = slc(exactConfig())->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, state);
    ASSERT_TRUE(plan.ok());
    for (const auto& [object, triangles] : trianglesByObject(*plan)) {
      const bool end = triangles == 16.0 || triangles == 20000.0;
      const double l = std::log2(triangles);
      EXPECT_TRUE(end || std::fabs(l - std::round(l)) < 1e-9)
          << "cap " << cap << " object " << object << ": " << triangles;
    }
    EXPECT_LE(plan->predictedTriangles, cap);
  }
}

TEST(AllocationSchedulers, AslodHysteresisReducesRequestsOfAJitteringViewer) {
  SyntheticSceneOptions o;
  o.seed = 5;
  o.objects = 40;
  o.worldSize = 20.0;
  o.simpleImpostor = false;
  o.meshedImpostor = false;
  const SchedulingScene original = makeSyntheticScene(o).value();
  std::size_t requests[2] = {0, 0};
  for (int mode = 0; mode < 2; ++mode) {
    AslodSchedulerConfig config;
    config.hysteresisShare = mode == 0 ? 0.0 : 0.1;
    auto scheduler = aslod(exactConfig(), config);
    SchedulingScene scene = original;
    PlannerState state;
    Budget budget;
    budget.maxTriangles = 20000.0;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int frame = 0; frame < 30; ++frame) {
      const glm::dvec3 at(0.3 * u(rng), 0.3 * u(rng), 30.0 + 0.3 * u(rng));
      auto plan =
          scheduler->plan(scene, viewerAt(at, {0, 0, -1}, 0.1 * frame, frame), budget, state);
      ASSERT_TRUE(plan.ok());
      ASSERT_LE(plan->predictedTriangles, 20000.0);
      if (frame >= 5) requests[mode] += plan->requests.size();
      applyPlan(scene, *plan);
    }
  }
  EXPECT_GT(requests[0], 100u);  // without epsilon the jitter re-requests most objects
  EXPECT_LT(requests[1], requests[0] / 4);
}

}  // namespace
}  // namespace thinlod::backbone

namespace thinlod::backbone {
namespace {
using namespace testing;

TEST(AllocationSchedulers, AslodGivesTheSlackOfACandidateGapToTheOthers) {
  // Equal projected areas, 80 triangles each by the formula; B's candidates
  // are a 2-triangle impostor and meshes from 100 triangles on, so B renders
  // 2 and A receives the other 78.
  SceneBuilder b;
  const int root = b.group(-1);
  b.leaf(root, {{1.0, 0, -5.0}, 0.5}, {meshOption(1.0, 16.0, 400.0, 20000.0)});
  b.leaf(root, {{-1.0, 0, -5.0}, 0.5},
         {meshOption(4.0, 100.0, 400.0, 5000.0),
          pointOption(OptionKind::kSimpleImpostor, 2.0, 2.0, 6000.0)});
  const SchedulingScene scene = b.build();
  AslodSchedulerConfig config;
  config.hysteresisShare = 0.0;
  PlannerState state;
  Budget budget;
  budget.maxTriangles = 160.0;
  auto plan =
      aslod(exactConfig(), config)->plan(scene, viewerAt({0, 0, 0}, {0, 0, -1}), budget, state);
  ASSERT_TRUE(plan.ok());
  const auto t = trianglesByObject(*plan);
  EXPECT_EQ(t.at(1), 2.0);
  EXPECT_GE(t.at(0), 157.0);
  EXPECT_LE(plan->predictedTriangles, 160.0);
}

}  // namespace
}  // namespace thinlod::backbone
