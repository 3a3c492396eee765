// Budget fill (backbone/src/lib/budget_fill.h): the core on hand-made and
// random items, and the accuracy-curve scheduler with the fill on random
// synthetic scenes (fixed seeds): the budget is never exceeded, no object
// drops below the target, and >= 95 % of the budget is used when there is
// more detail to show.
#include "budget_fill.h"

#include <gtest/gtest.h>

#include <random>

#include "scheduler_test_util.h"

namespace thinlod::backbone {
namespace {
using namespace testing;

FillItem ladderItem(double weight, int steps, double trianglesPerStep, double start = 1.0) {
  // Option k: (start + k) units of accuracy for k * trianglesPerStep + 1 triangles.
  FillItem item;
  for (int k = 0; k <= steps; ++k)
    item.options.push_back({weight / (start + k), 1.0 + k * trianglesPerStep, 0.0, 1.0});
  return item;
}

double usedTriangles(const std::vector<FillItem>& items, const std::vector<std::size_t>& chosen) {
  double sum = 0.0;
  for (std::size_t i = 0; i < items.size(); ++i) sum += items[i].options[chosen[i]].triangles;
  return sum;
}

TEST(BudgetFill, NoCapMovesNothing) {
  const std::vector<FillItem> items{ladderItem(1.0, 5, 1.0)};
  const std::vector<std::size_t> chosen = fillByGain(items, FillCaps{});
  EXPECT_EQ(chosen, std::vector<std::size_t>{0});
}

TEST(BudgetFill, OverACapAlreadyMovesNothing) {
  std::vector<FillItem> items{ladderItem(1.0, 5, 1.0), ladderItem(1.0, 5, 1.0)};
  items[0].current = 3;  // 4 triangles
  items[1].current = 2;  // 3 triangles
  FillCaps caps;
  caps.useTriangles = true;
  caps.triangles = 6.0;
  EXPECT_EQ(fillByGain(items, caps), (std::vector<std::size_t>{3, 2}));
}

TEST(BudgetFill, TheLargerImageGainPerTriangleGoesFirst) {
  // Room for one step: the object with ten times the weight gets it.
  const std::vector<FillItem> items{ladderItem(1.0, 3, 10.0), ladderItem(10.0, 3, 10.0)};
  FillCaps caps;
  caps.useTriangles = true;
  caps.triangles = 2.0 + 10.0;
  EXPECT_EQ(fillByGain(items, caps), (std::vector<std::size_t>{0, 1}));
}

TEST(BudgetFill, AFreeBetterCopyIsTakenAndItsRoomReused) {
  // Item 0 has a better option that costs fewer triangles (a displayed copy);
  // the freed triangles then go to item 1.
  FillItem copy;
  copy.options.push_back({1.0, 5.0, 0.0, 1.0});
  copy.options.push_back({0.5, 1.0, 0.0, 1.0});
  const std::vector<FillItem> items{copy, ladderItem(1.0, 10, 1.0)};
  FillCaps caps;
  caps.useTriangles = true;
  caps.triangles = 6.0;  // exactly the current picks
  const std::vector<std::size_t> chosen = fillByGain(items, caps);
  EXPECT_EQ(chosen[0], 1u);
  EXPECT_EQ(chosen[1], 4u);
  EXPECT_LE(usedTriangles(items, chosen), 6.0);
}

TEST(BudgetFill, DiscountedNewRepresentationsLoseTiesToCopies) {
  FillItem item;
  item.options.push_back({1.0, 1.0, 0.0, 1.0});
  item.options.push_back({0.5, 3.0, 0.0, kNewGenerationGainScale});  // to generate
  item.options.push_back({0.5, 3.0, 0.0, 1.0});                      // a copy, same cost
  FillCaps caps;
  caps.useTriangles = true;
  caps.triangles = 3.0;
  EXPECT_EQ(fillByGain({item}, caps), std::vector<std::size_t>{2});
}

TEST(BudgetFill, LinkCapHoldsWhenTrianglesArePrimary) {
  FillItem item;
  item.options.push_back({1.0, 1.0, 100.0, 1.0});
  item.options.push_back({0.1, 2.0, 1000.0, 1.0});  // fits triangles, not link
  item.options.push_back({0.5, 3.0, 200.0, 1.0});
  FillCaps caps;
  caps.useTriangles = true;
  caps.triangles = 10.0;
  caps.useLink = true;
  caps.linkBytes = 500.0;
  EXPECT_EQ(fillByGain({item}, caps), std::vector<std::size_t>{2});
}

TEST(BudgetFill, LadderIsFixedIncreasingAndFine) {
  const std::vector<double> ladder = fillTriangleLadder(100000.0);
  ASSERT_GE(ladder.size(), 20u);
  for (int t = 1; t <= 20; ++t) EXPECT_EQ(ladder[t - 1], double(t));
  for (std::size_t i = 1; i < ladder.size(); ++i) {
    EXPECT_GT(ladder[i], ladder[i - 1]);
    EXPECT_LE(ladder[i], std::max(ladder[i - 1] + 1.0, ladder[i - 1] * kFillLadderStep));
    EXPECT_EQ(ladder[i], std::floor(ladder[i]));
  }
  EXPECT_LE(ladder.back(), 100000.0);
  EXPECT_GT(ladder.back() * kFillLadderStep + 1.0, 100000.0);
  // A prefix of the longer ladder: the same rungs whatever the room.
  const std::vector<double> shorter = fillTriangleLadder(537.0);
  ASSERT_LE(shorter.size(), ladder.size());
  for (std::size_t i = 0; i < shorter.size(); ++i) EXPECT_EQ(shorter[i], ladder[i]);
  EXPECT_TRUE(fillTriangleLadder(0.5).empty());
  EXPECT_TRUE(fillTriangleLadder(std::nan("")).empty());
}

TEST(BudgetFill, ImageErrorFollowsProjectedSizeAndAccuracy) {
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 10.0, 4.0, 1.0), 0.01 / 4.0);
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 5.0, 4.0, 1.0), 4.0 * fillImageError(1.0, 10.0, 4.0, 1.0));
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 10.0, 8.0, 0.25), fillImageError(1.0, 10.0, 4.0, 1.0) / 8.0);
  EXPECT_TRUE(std::isinf(fillImageError(1.0, 10.0, 0.0, 1.0)));
}

// The shading term adds weight / sqrt(a) per projected area: it dominates at
// high accuracy (a faceted curved surface still shades wrongly where its
// silhouette is already right), so the fill prefers the large smooth object.
TEST(BudgetFill, ShadingTermWeighsAccuracyBySquareRoot) {
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 10.0, 4.0, 1.0, 0.0), fillImageError(1.0, 10.0, 4.0, 1.0));
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 10.0, 4.0, 1.0, 2.0), 0.01 * (0.25 + 2.0 / 2.0));
  EXPECT_DOUBLE_EQ(fillImageError(1.0, 10.0, 100.0, 0.5, 1.0), 0.5 * 0.01 * (0.01 + 0.1));
  // Raising a from 100 to 400 on a near object gains more than raising a
  // far one from 4 to 16 with the term, less without it.
  const auto gain = [](double distance, double from, double to, double weight) {
    return fillImageError(1.0, distance, from, 1.0, weight) -
           fillImageError(1.0, distance, to, 1.0, weight);
  };
  EXPECT_LT(gain(1.0, 100.0, 400.0, 0.0), gain(4.0, 4.0, 16.0, 0.0));
  EXPECT_GT(gain(1.0, 100.0, 400.0, 1.0), gain(4.0, 4.0, 16.0, 1.0));
  // Meshes only: an impostor's texture carries its shading.
  for (OptionKind kind : {OptionKind::kOriginalMesh, OptionKind::kSimplifiedMesh, OptionKind::kHybrid})
    EXPECT_EQ(fillShadingWeight(kind, 1.5), 1.5);
  for (OptionKind kind : {OptionKind::kMeshedImpostor, OptionKind::kSimpleImpostor})
    EXPECT_EQ(fillShadingWeight(kind, 1.5), 0.0);
}

// Random items (including free upgrades, link costs, extreme magnitudes):
// the caps hold, no item ends with a larger error, and when no item can
// take even its next-cheapest upgrade the room left is below that step.
TEST(BudgetFillProperty, CapsHoldAndErrorsNeverRise) {
  for (int seed = 1; seed <= 400; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 104729u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double scale = std::pow(10.0, -6.0 + 12.0 * u(rng));  // extreme magnitudes
    std::vector<FillItem> items(1 + rng() % 12);
    double currentTriangles = 0.0;
    double currentLink = 0.0;
    for (FillItem& item : items) {
      const int options = 1 + static_cast<int>(rng() % 8);
      for (int k = 0; k < options; ++k)
        item.options.push_back({u(rng) * scale, std::floor(200.0 * u(rng)) * scale,
                                5000.0 * u(rng) * scale, u(rng) < 0.5 ? 1.0 : 0.8});
      item.current = rng() % item.options.size();
      currentTriangles += item.options[item.current].triangles;
      currentLink += item.options[item.current].linkBytes;
    }
    FillCaps caps;
    caps.useTriangles = u(rng) < 0.8;
    caps.useLink = !caps.useTriangles || u(rng) < 0.4;
    caps.triangles = currentTriangles * (0.9 + 2.0 * u(rng)) + 50.0 * scale * u(rng);
    caps.linkBytes = currentLink * (0.9 + 2.0 * u(rng)) + 2000.0 * scale * u(rng);
    const std::vector<std::size_t> chosen = fillByGain(items, caps);
    ASSERT_EQ(chosen.size(), items.size());
    double triangles = 0.0;
    double link = 0.0;
    for (std::size_t i = 0; i < items.size(); ++i) {
      ASSERT_LT(chosen[i], items[i].options.size());
      EXPECT_LE(items[i].options[chosen[i]].error, items[i].options[items[i].current].error)
          << "seed " << seed;
      triangles += items[i].options[chosen[i]].triangles;
      link += items[i].options[chosen[i]].linkBytes;
    }
    const bool startedOver = (caps.useTriangles && currentTriangles > caps.triangles) ||
                             (caps.useLink && currentLink > caps.linkBytes);
    if (startedOver) {
      for (std::size_t i = 0; i < items.size(); ++i)
        EXPECT_EQ(chosen[i], items[i].current) << "seed " << seed;
      continue;
    }
    if (caps.useTriangles) {
      EXPECT_LE(triangles, caps.triangles * (1.0 + 1e-12)) << "seed " << seed;
    }
    if (caps.useLink) {
      EXPECT_LE(link, caps.linkBytes * (1.0 + 1e-12)) << "seed " << seed;
    }
    // Maximal: no single remaining improvement fits.
    for (std::size_t i = 0; i < items.size(); ++i) {
      const FillOption& now = items[i].options[chosen[i]];
      for (const FillOption& o : items[i].options) {
        if (!(o.error < now.error)) continue;
        const bool fitsTriangles =
            !caps.useTriangles || triangles + o.triangles - now.triangles <= caps.triangles;
        const bool fitsLink = !caps.useLink || link + o.linkBytes - now.linkBytes <= caps.linkBytes;
        EXPECT_FALSE(fitsTriangles && fitsLink) << "seed " << seed << ": an upgrade still fits";
      }
    }
  }
}

// FillRetry::kIndexed (stalled items re-checked only when room grows in a
// capped resource, through a heap of their least extra cost) chooses exactly
// what the reference kEveryStalled does: random items with many moves that
// free room in one resource (cheaper in triangles or bytes, costlier in the
// other), ties, zero and extreme costs, every cap combination.
TEST(BudgetFillProperty, IndexedRetryChoosesWhatTheReferenceChooses) {
  int freeing = 0;
  for (int seed = 1; seed <= 600; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 15485863u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double scale = std::pow(10.0, -6.0 + 12.0 * u(rng));
    std::vector<FillItem> items(1 + rng() % 300);
    double currentTriangles = 0.0;
    double currentLink = 0.0;
    for (FillItem& item : items) {
      const int options = 1 + static_cast<int>(rng() % 10);
      for (int k = 0; k < options; ++k) {
        // Coarse grids make ties in errors, costs and ratios common.
        const double error = std::floor(8.0 * u(rng)) * scale;
        const double triangles = std::floor(20.0 * u(rng)) * scale;
        const double link = (u(rng) < 0.3 ? 0.0 : std::floor(50.0 * u(rng))) * scale;
        item.options.push_back({error, triangles, link, u(rng) < 0.5 ? 1.0 : 0.8});
      }
      item.current = rng() % item.options.size();
      currentTriangles += item.options[item.current].triangles;
      currentLink += item.options[item.current].linkBytes;
    }
    FillCaps caps;
    const int which = static_cast<int>(rng() % 3);
    caps.useTriangles = which != 1;
    caps.useLink = which != 0;
    caps.triangles = currentTriangles * (1.0 + 0.3 * u(rng)) + 5.0 * scale * u(rng);
    caps.linkBytes = currentLink * (1.0 + 0.3 * u(rng)) + 20.0 * scale * u(rng);
    const std::vector<std::size_t> fast = fillByGain(items, caps, FillRetry::kIndexed);
    const std::vector<std::size_t> reference = fillByGain(items, caps, FillRetry::kEveryStalled);
    ASSERT_EQ(fast, reference) << "seed " << seed;
    for (std::size_t i = 0; i < items.size(); ++i) {
      const FillOption& from = items[i].options[items[i].current];
      const FillOption& to = items[i].options[fast[i]];
      freeing += (to.triangles < from.triangles) || (to.linkBytes < from.linkBytes);
    }
  }
  EXPECT_GT(freeing, 1000);  // the room-freeing moves the retry is about really occur
}

// Fine ladders (every object has detail well beyond the budget): the fill
// uses >= 95 % of the budget.
TEST(BudgetFillProperty, UsesNearlyAllTheBudgetWhenThereIsMoreDetail) {
  for (int seed = 1; seed <= 200; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 7919u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<FillItem> items;
    const int count = 1 + static_cast<int>(rng() % 20);
    double minimum = 0.0;
    for (int i = 0; i < count; ++i) {
      // Options on the ladder: accuracy a(T) concave in the triangles T.
      FillItem item;
      const double weight = std::pow(100.0, u(rng));
      const double scale = 1.0 + 20.0 * u(rng);
      for (double t : fillTriangleLadder(5000.0))
        item.options.push_back({weight / (scale * std::sqrt(t)), t, 0.0, u(rng) < 0.5 ? 1.0 : 0.8});
      minimum += 1.0;
      items.push_back(std::move(item));
    }
    FillCaps caps;
    caps.useTriangles = true;
    caps.triangles = minimum + std::floor(2000.0 * u(rng));
    const std::vector<std::size_t> chosen = fillByGain(items, caps);
    const double used = usedTriangles(items, chosen);
    EXPECT_LE(used, caps.triangles) << "seed " << seed;
    EXPECT_GE(used, 0.95 * caps.triangles) << "seed " << seed << " items " << count;
  }
}

// The scheduler with the fill, on random synthetic scenes and viewers.
struct FlightCheck {
  int plans = 0;
  int filledPlans = 0;
  int usageRaised = 0;  // polygon budget: plans where the fill moved something
};

FlightCheck checkRandomScenes(bool link) {
  FlightCheck check;
  SchedulerConfig config;
  config.maxSpeed = 1.0;
  config.maxAngularSpeed = 1.0;
  SchedulerConfig noFill = config;
  noFill.fillBudget = false;
  auto filled = curveScheduler(config);
  auto plain = curveScheduler(noFill);
  for (int seed = 1; seed <= 40; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 31337u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    SyntheticSceneOptions options;
    options.seed = static_cast<std::uint64_t>(seed);
    options.objects = 20 + rng() % 200;
    options.worldSize = 20.0 + 80.0 * u(rng);
    options.lodShare = u(rng) < 0.5 ? 0.3 : 0.0;
    SchedulingScene scene = makeSyntheticScene(options).value();
    Budget budget;
    budget.maxTriangles = std::floor(50.0 + 2000.0 * u(rng));
    if (link) budget.maxLinkBytesPerSecond = 2.0e4 + 2.0e5 * u(rng);
    const glm::dvec3 direction{u(rng) - 0.5, u(rng) - 0.5, -1.0};
    PlannerState fs, ps;
    for (int step = 0; step < 6; ++step) {
      const ViewerState viewer = viewerAt({0.0, 0.0, 0.5 * options.worldSize - 0.3 * step},
                                          direction, 0.1 * step, static_cast<std::uint64_t>(step));
      auto plan = filled->plan(scene, viewer, budget, fs);
      auto reference = plain->plan(scene, viewer, budget, ps);
      EXPECT_TRUE(plan.ok() && reference.ok());
      if (!plan.ok() || !reference.ok()) break;
      ++check.plans;
      EXPECT_LE(plan->predictedTriangles, *budget.maxTriangles) << "seed " << seed;
      if (link) {
        EXPECT_LE(plan->linkBytesPerSecond, *budget.maxLinkBytesPerSecond * (1 + 1e-12))
            << "seed " << seed;
      }
      // Never below the target it reports.
      for (const ObjectDecision& d : plan->decisions) {
        if (d.action == ObjectAction::kRemove || d.belowTarget) continue;
        EXPECT_GE(d.absoluteAccuracy, plan->targetAccuracy * (1.0 - 1e-9))
            << "seed " << seed << " object " << d.object;
      }
      // The fill never gives back triangles the target's picks used.
      if (!link) {
        EXPECT_GE(plan->predictedTriangles, plan->stats.trianglesBeforeFill * (1.0 - 1e-12))
            << "seed " << seed << " step " << step;
        if (plan->stats.budgetFillUpgrades > 0) ++check.usageRaised;
      }
      if (step == 0) {
        // Nothing displayed yet: first representations stay the cheapest
        // (no fill), so the plan is the no-fill plan.
        EXPECT_DOUBLE_EQ(plan->targetAccuracy, reference->targetAccuracy) << "seed " << seed;
        EXPECT_DOUBLE_EQ(plan->predictedTriangles, reference->predictedTriangles);
        EXPECT_EQ(plan->stats.budgetFillUpgrades, 0u);
      }
      if (step == 1 && !link && plan->dropped.empty() && !plan->decisions.empty()) {
        // Step 0's objects are on display; polygon budget alone and every
        // object with detail beyond the budget (meshes of >= 200 triangles):
        // >= 95 % of the budget used.
        EXPECT_GE(plan->predictedTriangles, 0.95 * *budget.maxTriangles)
            << "seed " << seed << " objects " << options.objects << " fill upgrades "
            << plan->stats.budgetFillUpgrades;
      }
      if (plan->stats.budgetFillUpgrades > 0) ++check.filledPlans;
      applyPlan(scene, *plan);
    }
  }
  return check;
}

TEST(BudgetFillProperty, SchedulerKeepsThePolygonBudgetAndTheTarget) {
  const FlightCheck check = checkRandomScenes(false);
  EXPECT_GE(check.plans, 200);
  EXPECT_GT(check.filledPlans,
            check.plans / 4);  // the fill really runs (later steps often keep its copies)
  EXPECT_GT(check.usageRaised, 0);
}

TEST(BudgetFillProperty, SchedulerKeepsBothBudgetsAndTheTarget) {
  const FlightCheck check = checkRandomScenes(true);
  EXPECT_GE(check.plans, 200);
  EXPECT_GT(check.filledPlans, 0);
}

TEST(BudgetFill, FixedAccuracyDoesNotFill) {
  SchedulerConfig config;
  auto scheduler = curveScheduler(config);
  SyntheticSceneOptions options;
  options.objects = 50;
  const SchedulingScene scene = makeSyntheticScene(options).value();
  Budget budget;
  budget.maxTriangles = 100000.0;
  budget.fixedAccuracy = 50.0;
  PlannerState state;
  auto plan = scheduler->plan(scene, viewerAt({0, 0, 50}, {0, 0, -1}), budget, state);
  ASSERT_TRUE(plan.ok()) << plan.status().toString();
  EXPECT_EQ(plan->stats.budgetFillUpgrades, 0u);
}

}  // namespace
}  // namespace thinlod::backbone
