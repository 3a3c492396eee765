// ASLOD allocation (aslod_allocation.h): the paper's formula, clamping with
// redistribution, exact rounding and hysteresis.
#include "aslod_allocation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "active_set_optimiser.h"

namespace thinlod::backbone {
namespace {

std::vector<AslodObject> wide(const std::vector<double>& weights, double maxTriangles = 1e9) {
  std::vector<AslodObject> objects;
  for (double w : weights) objects.push_back({w, 0.0, maxTriangles, std::nullopt});
  return objects;
}

std::int64_t sumOf(const std::vector<std::int64_t>& v) {
  return std::accumulate(v.begin(), v.end(), std::int64_t{0});
}

TEST(AslodAllocation, AlphaThreeUsesCubeRootsOfTheWeights) {
  AslodConfig config;
  config.alpha = 3.0;
  auto a = allocateAslod(wide({1.0, 8.0, 27.0}), 600.0, config);
  ASSERT_TRUE(a.ok()) << a.status().toString();
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{100, 200, 300}));
  EXPECT_NEAR(a->paperShare[2], 300.0, 1e-9);
}

TEST(AslodAllocation, ProportionalToAreaAtAlphaOne) {
  for (std::uint64_t seed = 1; seed <= 200; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> weights(1 + seed % 50);
    for (double& w : weights) w = std::pow(10.0, 6.0 * u(rng) - 3.0);
    const double budget = std::floor(1e6 * u(rng));
    auto a = allocateAslod(wide(weights), budget, AslodConfig{});
    ASSERT_TRUE(a.ok());
    const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
    for (std::size_t i = 0; i < weights.size(); ++i) {
      const double ideal = budget * weights[i] / total;
      EXPECT_LE(std::fabs(double(a->triangles[i]) - ideal), 1.0 + 1e-6 * ideal)
          << "seed " << seed << " object " << i;
      EXPECT_NEAR(a->paperShare[i], ideal, 1e-9 * budget);
    }
    EXPECT_EQ(a->total, std::int64_t(budget));
  }
}

TEST(AslodAllocation, MonotoneInArea) {
  for (double alpha : {0.5, 1.0, 2.0, 3.0, 10.0}) {
    for (std::uint64_t seed = 1; seed <= 100; ++seed) {
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      std::vector<double> weights(2 + seed % 40);
      for (double& w : weights) w = std::pow(10.0, 4.0 * u(rng));
      std::vector<AslodObject> objects = wide(weights, 5000.0);
      for (AslodObject& o : objects) o.minTriangles = 20.0;
      AslodConfig config;
      config.alpha = alpha;
      auto a = allocateAslod(objects, 100.0 * double(weights.size()) * (0.3 + u(rng)), config);
      ASSERT_TRUE(a.ok());
      for (std::size_t i = 0; i < weights.size(); ++i)
        for (std::size_t j = 0; j < weights.size(); ++j)
          if (weights[i] < weights[j]) {
            EXPECT_LE(a->triangles[i], a->triangles[j])
                << "alpha " << alpha << " seed " << seed << " objects " << i << " " << j;
          }
    }
  }
}

TEST(AslodAllocation, EqualSplitAsAlphaGrows) {
  std::vector<double> weights;
  for (int k = -6; k <= 6; ++k) weights.push_back(std::pow(10.0, k));
  double previousSpread = std::numeric_limits<double>::infinity();
  for (double alpha : {1.0, 2.0, 4.0, 16.0, 256.0, 1e6}) {
    AslodConfig config;
    config.alpha = alpha;
    auto a = allocateAslod(wide(weights), 13000.0, config);
    ASSERT_TRUE(a.ok());
    const auto [lo, hi] = std::minmax_element(a->triangles.begin(), a->triangles.end());
    const double spread = double(*hi - *lo);
    EXPECT_LE(spread, previousSpread) << "alpha " << alpha;
    previousSpread = spread;
    if (alpha >= 1e6) {
      EXPECT_LE(spread, 1.0);  // 13000 / 13 = 1000 each, within one triangle
      EXPECT_GE(*lo, 999);
      EXPECT_LE(*hi, 1001);
    }
  }
}

TEST(AslodAllocation, ExcessAboveTheMostDetailedIsRedistributed) {
  std::vector<AslodObject> objects = wide({1.0, 1.0, 2.0});
  objects[2].maxTriangles = 30.0;  // wants 50 of 100, can use 30
  auto a = allocateAslod(objects, 100.0, AslodConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{35, 35, 30}));
  EXPECT_EQ(a->clampedHigh, 1u);
}

TEST(AslodAllocation, ShortfallBelowTheCheapestIsTakenFromTheOthers) {
  std::vector<AslodObject> objects = wide({1e-6, 1.0, 1.0});
  objects[0].minTriangles = 59.5;  // rounds up to 60 whole triangles
  auto a = allocateAslod(objects, 100.0, AslodConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{60, 20, 20}));
  EXPECT_EQ(a->clampedLow, 1u);
}

TEST(AslodAllocation, EverythingFitsGivesEveryObjectItsMaximum) {
  std::vector<AslodObject> objects = wide({1.0, 5.0}, 40.0);
  objects[1].maxTriangles = 10.2;
  auto a = allocateAslod(objects, 1000.0, AslodConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{40, 11}));
  EXPECT_EQ(a->total, 51);
}

TEST(AslodAllocation, ZeroWeightsGetTheirMinimum) {
  std::vector<AslodObject> objects = wide({0.0, 0.0, 3.0}, 100.0);
  objects[0].minTriangles = 7.0;
  auto a = allocateAslod(objects, 50.0, AslodConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{7, 0, 43}));
  auto none = allocateAslod(wide({0.0, 0.0}, 100.0), 50.0, AslodConfig{});
  ASSERT_TRUE(none.ok());  // nobody has area: the budget is not forced on anyone
  EXPECT_EQ(none->triangles, (std::vector<std::int64_t>{0, 0}));
}

TEST(AslodAllocation, RejectsBadInputAndReportsAnImpossibleBudget) {
  AslodConfig bad;
  bad.alpha = 0.0;
  EXPECT_EQ(allocateAslod(wide({1.0}), 10.0, bad).status().code(), ErrorCode::kInvalidArgument);
  bad.alpha = std::nan("");
  EXPECT_FALSE(allocateAslod(wide({1.0}), 10.0, bad).ok());
  AslodConfig negative;
  negative.hysteresisShare = -0.1;
  EXPECT_FALSE(allocateAslod(wide({1.0}), 10.0, negative).ok());
  EXPECT_FALSE(allocateAslod(wide({std::nan("")}), 10.0, AslodConfig{}).ok());
  EXPECT_FALSE(allocateAslod(wide({-1.0}), 10.0, AslodConfig{}).ok());
  EXPECT_FALSE(allocateAslod(wide({1.0}), std::nan(""), AslodConfig{}).ok());
  EXPECT_FALSE(allocateAslod(wide({1.0}), -1.0, AslodConfig{}).ok());
  EXPECT_FALSE(
      allocateAslod(wide({1.0}, std::numeric_limits<double>::infinity()), 10.0, AslodConfig{})
          .ok());
  std::vector<AslodObject> inverted = wide({1.0}, 5.0);
  inverted[0].minTriangles = 6.0;
  EXPECT_EQ(allocateAslod(inverted, 10.0, AslodConfig{}).status().code(),
            ErrorCode::kInvalidArgument);
  std::vector<AslodObject> heavy = wide({1.0, 1.0}, 100.0);
  heavy[0].minTriangles = 6.0;
  heavy[1].minTriangles = 5.0;
  auto exhausted = allocateAslod(heavy, 10.9, AslodConfig{});
  EXPECT_EQ(exhausted.status().code(), ErrorCode::kResourceExhausted);
  EXPECT_NE(exhausted.status().message().find("11"), std::string::npos);
}

TEST(AslodAllocation, HysteresisHoldsSmallChangesOnly) {
  std::vector<AslodObject> objects = wide({1.0, 1.0, 2.0});
  objects[0].previous = 27;  // new 25: within 3, held
  objects[1].previous = 20;  // new 25: 5 away, moves
  objects[2].previous = 48;  // new 50: within 3, held (frees 2)
  AslodConfig config;
  config.hysteresisTriangles = 3.0;
  auto a = allocateAslod(objects, 100.0, config);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->triangles, (std::vector<std::int64_t>{27, 25, 48}));
  EXPECT_EQ(a->heldByHysteresis, 2u);
  EXPECT_EQ(a->total, 100);
}

TEST(AslodAllocation, HysteresisNeverBreaksTheBudget) {
  std::vector<AslodObject> objects = wide({1.0, 1.0, 1.0, 1.0});
  for (AslodObject& o : objects) o.previous = 27;  // new: 25 each, +2 each held = 108
  objects[3].previous = 29;
  AslodConfig config;
  config.hysteresisTriangles = 5.0;
  auto a = allocateAslod(objects, 100.0, config);
  ASSERT_TRUE(a.ok());
  EXPECT_LE(a->total, 100);
  EXPECT_EQ(a->total, sumOf(a->triangles));
  // The largest raise is undone first, then the three 27s: nothing stays held.
  EXPECT_EQ(a->triangles[3], 25);
  EXPECT_EQ(a->heldByHysteresis, 0u);
}

TEST(AslodAllocation, HysteresisReducesFlickerUnderJitter) {
  // Weights jitter by +-2 % every step: without epsilon most counts change
  // every step, with a 5 % share nearly none do; the budget holds always.
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> base(60);
  for (double& w : base) w = std::pow(10.0, 2.0 * u(rng));
  int changes[2] = {0, 0};
  for (int mode = 0; mode < 2; ++mode) {
    AslodConfig config;
    config.hysteresisShare = mode == 0 ? 0.0 : 0.05;
    std::vector<std::int64_t> previous;
    std::mt19937_64 jitter(7);
    for (int step = 0; step < 50; ++step) {
      std::vector<AslodObject> objects = wide(base, 1e5);
      for (std::size_t i = 0; i < objects.size(); ++i) {
        objects[i].weight *= 1.0 + 0.04 * (u(jitter) - 0.5);
        if (!previous.empty()) objects[i].previous = previous[i];
      }
      auto a = allocateAslod(objects, 20000.0, config);
      ASSERT_TRUE(a.ok());
      ASSERT_LE(a->total, 20000);
      if (!previous.empty())
        for (std::size_t i = 0; i < objects.size(); ++i)
          changes[mode] += a->triangles[i] != previous[i];
      previous = a->triangles;
    }
  }
  EXPECT_GT(changes[0], 60 * 49 / 2);
  EXPECT_LT(changes[1], changes[0] / 10);
}

TEST(AslodAllocation, RandomScenesNeverExceedTheBudget) {
  int feasible = 0;
  int exhausted = 0;
  for (std::uint64_t seed = 1; seed <= 1000; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const std::size_t n = 1 + seed % 120;
    const double magnitude = std::pow(10.0, double(seed % 13));  // 1 .. 1e12 triangles
    std::vector<AslodObject> objects(n);
    double sumLo = 0.0;
    double sumHi = 0.0;
    for (AslodObject& o : objects) {
      // Odd seeds: weights over 600 decades (shares underflow to 0 at small
      // alpha); even seeds: 6 decades, no zero weights.
      o.weight = seed % 2 ? (u(rng) < 0.1 ? 0.0 : std::pow(10.0, 600.0 * u(rng) - 300.0))
                          : std::pow(10.0, 6.0 * u(rng) - 3.0);
      o.minTriangles = u(rng) < 0.2 ? 0.0 : magnitude * u(rng) * 0.01;
      o.maxTriangles = o.minTriangles + magnitude * u(rng);
      if (u(rng) < 0.3)
        o.previous =
            std::int64_t(std::ceil(o.minTriangles + 0.5 * (o.maxTriangles - o.minTriangles)));
      sumLo += std::ceil(o.minTriangles);
      sumHi += std::ceil(o.maxTriangles);
    }
    AslodConfig config;
    config.alpha = std::pow(10.0, 3.0 * u(rng) - 1.0);
    config.hysteresisShare = u(rng) < 0.5 ? 0.0 : 0.1 * u(rng);
    const double budget = std::max(
        0.0, (sumLo + (sumHi - sumLo) * (1.4 * u(rng) - 0.2)) * (u(rng) < 0.05 ? 0.0 : 1.0));
    auto a = allocateAslod(objects, budget, config);
    if (sumLo > std::floor(budget)) {
      EXPECT_EQ(a.status().code(), ErrorCode::kResourceExhausted) << "seed " << seed;
      ++exhausted;
      continue;
    }
    ASSERT_TRUE(a.ok()) << "seed " << seed << ": " << a.status().toString();
    ++feasible;
    EXPECT_EQ(a->total, sumOf(a->triangles));
    EXPECT_LE(double(a->total), std::floor(budget)) << "seed " << seed;
    EXPECT_LE(double(a->target), std::min(std::floor(budget), sumHi));
    if (config.hysteresisShare == 0.0) {
      EXPECT_EQ(a->total, a->target) << "seed " << seed;
    }
    if (seed % 2 == 0) {
      EXPECT_EQ(double(a->target), std::min(std::floor(budget), sumHi)) << "seed " << seed;
    }
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_GE(double(a->triangles[i]), std::ceil(objects[i].minTriangles)) << "seed " << seed;
      EXPECT_LE(double(a->triangles[i]), std::ceil(objects[i].maxTriangles)) << "seed " << seed;
    }
  }
  EXPECT_GT(feasible, 700);
  EXPECT_GT(exhausted, 50);
}

}  // namespace
}  // namespace thinlod::backbone

// The cross-check between the two seed implementations (issue: "equal to the
// Gobbetti-Bouvier closed form when alpha = k + 1 and no bound is active").
// Gobbetti-Bouvier minimises sum a_i / r_i^k under sum c_i r_i <= P. With
// r_i = p_i / H (H triangles at full resolution, c_i = H) and a_i = w_i / H^k
// the objective is sum w_i / p_i^k, whose optimum under sum p_i = P is
// p_i = P w_i^(1/(k+1)) / sum_j w_j^(1/(k+1)): ASLOD with alpha = k + 1.

namespace thinlod::backbone {
namespace {

TEST(AslodCrossCheck, EqualsTheActiveSetOptimumWhenAlphaIsKPlusOneAndNoBoundBinds) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> area(1e-4, 1.0);
  constexpr double kFull = 1e6;  // H: no upper bound is reached
  constexpr double kBudget = 5000.0;
  for (double k : {1.0, 2.0, 3.0}) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<AslodObject> objects(50);
      ResolutionProblem problem;
      problem.exponent = k;
      problem.budget = kBudget;
      for (AslodObject& o : objects) {
        o.weight = area(rng);
        o.minTriangles = 0.0;
        o.maxTriangles = kFull;
        ResolutionVariable v;
        v.weight = o.weight / std::pow(kFull, k);
        v.cost = kFull;
        v.minResolution = 1e-12;  // no lower bound binds either
        problem.variables.push_back(v);
      }
      AslodConfig config;
      config.alpha = k + 1.0;
      auto aslod = allocateAslod(objects, kBudget, config);
      ASSERT_TRUE(aslod.ok()) << aslod.status().toString();
      auto optimum = solveResolutionsActiveSet(problem, ActiveSetOptions{});
      ASSERT_TRUE(optimum.ok()) << optimum.status().toString();
      ASSERT_EQ(optimum->outcome, ResolutionOutcome::kOptimal);
      for (std::size_t i = 0; i < objects.size(); ++i) {
        const double optimal = optimum->resolution[i] * kFull;
        // ASLOD's unrounded share is the closed form; its counts are whole
        // triangles (largest remainder), so within one of it.
        EXPECT_NEAR(aslod->paperShare[i], optimal, 1e-6 * kBudget) << "k " << k << " object " << i;
        EXPECT_LE(std::abs(double(aslod->triangles[i]) - optimal), 1.0 + 1e-6)
            << "k " << k << " object " << i;
      }
    }
  }
}

}  // namespace
}  // namespace thinlod::backbone
