// Span-of-level-changed selection (span_of_level_changed.h): the paper's
// examples and Table I, the budget, the heap against a linear-scan
// reference, and O(log m) heap work per change.
#include "span_of_level_changed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace thinlod::backbone {
namespace {

// Levels of a model with `full` faces kept at the given fractions.
std::vector<SlcLevel> levelsOf(double full, const std::vector<double>& fractions) {
  std::vector<SlcLevel> levels;
  for (double f : fractions) {
    const double faces = full * f;
    const int l = levelOfFaces(faces);
    if (!levels.empty() && levels.back().level == l) continue;
    levels.push_back({l, faces});
  }
  return levels;
}

TEST(SpanOfLevelChanged, PaperWorkedExample) {
  EXPECT_EQ(levelOfFaces(5000.0), 12);
  EXPECT_EQ(levelOfFaces(2000.0), 11);
  EXPECT_EQ(spanOfLevelChanged(12, 11), 12.0);
  EXPECT_EQ(spanOfLevelChanged(11, 12), 12.0);  // |.| and max: symmetric
}

TEST(SpanOfLevelChanged, LevelRoundsToTheNearestPowerOfTwo) {
  EXPECT_EQ(levelOfFaces(1.0), 0);
  EXPECT_EQ(levelOfFaces(0.3), 0);
  EXPECT_EQ(levelOfFaces(0.0), 0);
  EXPECT_EQ(levelOfFaces(1024.0), 10);
  EXPECT_EQ(levelOfFaces(1448.0), 10);  // log2 = 10.4998
  EXPECT_EQ(levelOfFaces(1449.0), 11);  // log2 = 10.5008
  EXPECT_EQ(levelOfFaces(std::ldexp(1.0, 53)), 53);
  // The paper's models (section VI): cow 5804 faces, armadillo 345944,
  // happy Buddha ("happy body") 1087716.
  EXPECT_EQ(levelOfFaces(5804.0), 13);
  EXPECT_EQ(levelOfFaces(345944.0), 18);
  EXPECT_EQ(levelOfFaces(1087716.0), 20);
}

TEST(SpanOfLevelChanged, TableOneMatrix) {
  // Table I of the paper: rows "to" level 18..12, columns "from" level 19..13.
  const double table[7][7] = {{19, 0, 0, 0, 0, 0, 0},        {38, 18, 0, 0, 0, 0, 0},
                              {57, 36, 17, 0, 0, 0, 0},      {76, 54, 34, 16, 0, 0, 0},
                              {95, 72, 51, 32, 15, 0, 0},    {114, 90, 68, 48, 30, 14, 0},
                              {133, 108, 85, 64, 45, 28, 13}};
  int checked = 0;
  for (int row = 0; row < 7; ++row) {
    for (int col = 0; col <= row; ++col) {
      EXPECT_EQ(spanOfLevelChanged(19 - col, 18 - row), table[row][col])
          << "from " << 19 - col << " to " << 18 - row;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 28);
}

TEST(SpanOfLevelChanged, PaperLevelPercentagesGiveTheseLevels) {
  const auto cow = levelsOf(5804, {1.0, 0.5, 0.25, 0.12, 0.06});
  const auto happy = levelsOf(1087716, {0.25, 0.12, 0.06, 0.03, 0.015, 0.0075, 0.0037, 0.0018});
  std::vector<int> cowLevels;
  for (const SlcLevel& l : cow) cowLevels.push_back(l.level);
  std::vector<int> happyLevels;
  for (const SlcLevel& l : happy) happyLevels.push_back(l.level);
  EXPECT_EQ(cowLevels, (std::vector<int>{13, 12, 11, 9, 8}));
  EXPECT_EQ(happyLevels, (std::vector<int>{18, 17, 16, 15, 14, 13, 12, 11}));
}

TEST(SpanOfLevelChanged, LiteralDistanceCoarsensTheNearestFirst) {
  // Two equal objects (same area: S = 1), one near and one far; the budget
  // forces exactly one change.
  std::vector<SlcObject> objects(2);
  for (SlcObject& o : objects) o.levels = {{12, 4096}, {11, 2048}};
  objects[0].distance = 10.0;
  objects[1].distance = 2.0;
  auto literal = selectBySpanOfLevelChanged(objects, 6144.0, SlcConfig{});
  ASSERT_TRUE(literal.ok());
  EXPECT_EQ(literal->levelIndex, (std::vector<std::uint32_t>{0, 1}));  // the near one
  SlcConfig inverse;
  inverse.distanceRule = SlcDistanceRule::kFarthestFirst;
  auto far = selectBySpanOfLevelChanged(objects, 6144.0, inverse);
  ASSERT_TRUE(far.ok());
  EXPECT_EQ(far->levelIndex, (std::vector<std::uint32_t>{1, 0}));
  EXPECT_EQ(far->changes, 1u);
}

TEST(SpanOfLevelChanged, SmallProjectedAreaAndLargeModelsGoFirst) {
  std::vector<SlcObject> objects(2);
  for (SlcObject& o : objects) o.levels = {{12, 4096}, {11, 2048}};
  objects[0].projectedArea = 4.0;
  objects[1].projectedArea = 1.0;  // S = 1: larger f
  auto a = selectBySpanOfLevelChanged(objects, 6144.0, SlcConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->levelIndex, (std::vector<std::uint32_t>{0, 1}));
  // Same d and S: the model with more faces has the larger SLC.
  std::vector<SlcObject> mixed(2);
  mixed[0].levels = {{13, 8192}, {12, 4096}};      // SLC 13
  mixed[1].levels = {{18, 262144}, {17, 131072}};  // SLC 18
  auto b = selectBySpanOfLevelChanged(mixed, 262144.0, SlcConfig{});
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(b->levelIndex, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(b->spanPerObject[1], 18.0);
}

TEST(SpanOfLevelChanged, NoChangeWhenTheBudgetHolds) {
  std::vector<SlcObject> objects(3);
  for (SlcObject& o : objects) o.levels = {{10, 1000}, {9, 500}};
  auto a = selectBySpanOfLevelChanged(objects, 3072.0, SlcConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->changes, 0u);
  EXPECT_EQ(a->total, 3072.0);
  SlcConfig real;
  real.measure = SlcBudgetMeasure::kTriangles;
  auto b = selectBySpanOfLevelChanged(objects, 3000.0, real);
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(b->changes, 0u);
}

TEST(SpanOfLevelChanged, ReportsWhenEvenTheCoarsestLevelsDoNotFit) {
  std::vector<SlcObject> objects(3);
  for (SlcObject& o : objects) o.levels = {{10, 1000}, {9, 500}, {7, 120}};
  objects[2].levels = {{5, 32}};  // a single level never enters the heap
  auto a = selectBySpanOfLevelChanged(objects, 255.0, SlcConfig{});
  ASSERT_TRUE(a.ok());
  EXPECT_FALSE(a->budgetMet);
  EXPECT_EQ(a->levelIndex, (std::vector<std::uint32_t>{2, 2, 0}));
  EXPECT_EQ(a->total, 128.0 + 128.0 + 32.0);
  EXPECT_EQ(a->changes, 4u);
}

TEST(SpanOfLevelChanged, RejectsBadInput) {
  std::vector<SlcObject> objects(1);
  EXPECT_EQ(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).status().code(),
            ErrorCode::kInvalidArgument);  // no levels
  objects[0].levels = {{10, 1000}, {10, 500}};
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());  // not decreasing
  objects[0].levels = {{10, 1000}, {9, 2000}};
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());  // more triangles
  objects[0].levels = {{63, 1000}};
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());
  objects[0].levels = {{10, std::nan("")}};
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());
  objects[0].levels = {{10, 1000}};
  objects[0].distance = 0.0;
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());
  objects[0].distance = 1.0;
  objects[0].projectedArea = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, 1.0, SlcConfig{}).ok());
  objects[0].projectedArea = 1.0;
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, std::nan(""), SlcConfig{}).ok());
  EXPECT_FALSE(selectBySpanOfLevelChanged(objects, -1.0, SlcConfig{}).ok());
  EXPECT_TRUE(selectBySpanOfLevelChanged({}, 0.0, SlcConfig{}).ok());
}

// The same selection by a linear scan for the largest importance (ties:
// lowest index), recomputing f from eq. 4-6 at every change.
std::vector<std::uint32_t> referenceSelection(const std::vector<SlcObject>& objects, double budget,
                                              const SlcConfig& config) {
  std::vector<std::uint32_t> at(objects.size(), 0);
  double nearest = std::numeric_limits<double>::infinity();
  double smallest = std::numeric_limits<double>::infinity();
  for (const SlcObject& o : objects) {
    nearest = std::min(nearest, o.distance);
    smallest = std::min(smallest, o.projectedArea);
  }
  auto total = [&]() {
    double t = 0.0;
    for (std::size_t i = 0; i < objects.size(); ++i)
      t += slcLevelCost(objects[i].levels[at[i]], config.measure);
    return t;
  };
  while (total() > budget) {
    int best = -1;
    double bestF = -1.0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const auto& levels = objects[i].levels;
      if (at[i] + 1 >= levels.size()) continue;
      const double d = config.distanceRule == SlcDistanceRule::kNearestFirst
                           ? nearest / objects[i].distance
                           : objects[i].distance / nearest;
      const double s = objects[i].projectedArea / smallest;
      const double f = d / s * spanOfLevelChanged(levels[at[i]].level, levels[at[i] + 1].level);
      if (f > bestF) {
        bestF = f;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) break;
    ++at[best];
  }
  return at;
}

std::vector<SlcObject> randomObjects(std::mt19937_64& rng, std::size_t m) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<SlcObject> objects(m);
  for (SlcObject& o : objects) {
    int level = 4 + int(u(rng) * 20);
    double triangles = std::ldexp(1.0, level) * (0.75 + 0.5 * u(rng));
    const int count = 1 + int(u(rng) * 8);
    for (int k = 0; k < count && level >= 0; ++k) {
      o.levels.push_back({level, triangles});
      level -= 1 + int(u(rng) * 2.5);
      triangles *= 0.2 + 0.5 * u(rng);
    }
    o.distance = std::pow(10.0, 3.0 * u(rng) - 1.0);
    o.projectedArea = std::pow(10.0, 4.0 * u(rng) - 2.0) / (o.distance * o.distance);
  }
  return objects;
}

TEST(SpanOfLevelChanged, BudgetHoldsAndMatchesTheLinearScanReference) {
  int met = 0;
  int unmet = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const std::vector<SlcObject> objects = randomObjects(rng, 1 + seed % 90);
    SlcConfig config;
    config.measure = seed % 2 ? SlcBudgetMeasure::kPowerOfTwo : SlcBudgetMeasure::kTriangles;
    config.distanceRule =
        seed % 3 ? SlcDistanceRule::kNearestFirst : SlcDistanceRule::kFarthestFirst;
    double finest = 0.0;
    double coarsest = 0.0;
    for (const SlcObject& o : objects) {
      finest += slcLevelCost(o.levels.front(), config.measure);
      coarsest += slcLevelCost(o.levels.back(), config.measure);
    }
    const double budget = coarsest * 0.9 + (finest - coarsest * 0.9) * u(rng) * u(rng);
    auto a = selectBySpanOfLevelChanged(objects, budget, config);
    ASSERT_TRUE(a.ok()) << a.status().toString();
    EXPECT_EQ(a->levelIndex, referenceSelection(objects, budget, config)) << "seed " << seed;
    double total = 0.0;
    for (std::size_t i = 0; i < objects.size(); ++i)
      total += slcLevelCost(objects[i].levels[a->levelIndex[i]], config.measure);
    EXPECT_EQ(total, a->total);
    if (a->budgetMet) {
      ++met;
      EXPECT_LE(a->total, budget) << "seed " << seed;
    } else {
      ++unmet;
      EXPECT_GT(a->total, budget);
      for (std::size_t i = 0; i < objects.size(); ++i)
        EXPECT_EQ(a->levelIndex[i] + 1, objects[i].levels.size()) << "seed " << seed;
    }
    std::uint64_t changes = 0;
    for (std::uint32_t c : a->changesPerObject) changes += c;
    EXPECT_EQ(changes, a->changes);
  }
  EXPECT_GT(met, 300);
  EXPECT_GT(unmet, 10);
}

TEST(SpanOfLevelChanged, HeapWorkIsLogarithmicPerChange) {
  for (std::size_t m : {2u, 10u, 100u, 1000u, 10000u, 100000u}) {
    std::mt19937_64 rng(m);
    const std::vector<SlcObject> objects = randomObjects(rng, m);
    double coarsest = 0.0;
    for (const SlcObject& o : objects)
      coarsest += slcLevelCost(o.levels.back(), SlcBudgetMeasure::kPowerOfTwo);
    auto a = selectBySpanOfLevelChanged(objects, coarsest, SlcConfig{});
    ASSERT_TRUE(a.ok());
    ASSERT_TRUE(a->budgetMet);
    ASSERT_GT(a->changes, m / 4);
    const double log2m = std::ceil(std::log2(double(m)));
    // One sift-down per change: at most 2 comparisons per heap level.
    EXPECT_LE(double(a->heapUpdateComparisons), double(a->changes) * 2.0 * log2m) << "m " << m;
    EXPECT_LE(double(a->heapBuildComparisons), 4.0 * double(m)) << "m " << m;
  }
}

}  // namespace
}  // namespace thinlod::backbone
