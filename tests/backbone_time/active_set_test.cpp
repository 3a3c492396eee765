// The active-set resolution optimiser against an independent reference
// (bisection on the Lagrange multiplier) and its own invariants: every
// iterate feasible, objective never increasing, cut-off runs feasible,
// extreme magnitudes, infeasible budgets, input validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "active_set_optimiser.h"

namespace thinlod::backbone {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Recomputed here, not taken from the library: sum c_i r_i in index order.
double costOf(const ResolutionProblem& p, const std::vector<double>& r) {
  double c = 0.0;
  for (std::size_t i = 0; i < r.size(); ++i) c += p.variables[i].cost * r[i];
  return c;
}

bool withinBounds(const ResolutionProblem& p, const std::vector<double>& r) {
  if (r.size() != p.variables.size()) return false;
  for (std::size_t i = 0; i < r.size(); ++i)
    if (!(r[i] >= p.variables[i].minResolution && r[i] <= 1.0)) return false;
  return true;
}

// Scaled KKT residual of r for the problem, computed from r alone: the
// multiplier lambda is estimated from the free objects (median of
// k a_i r_i^-(k+1) / c_i) or, with none free, as the point of the interval
// the bounds allow; residuals are relative to lambda c_i.
double kktResidual(const ResolutionProblem& p, const std::vector<double>& r) {
  const double k = p.exponent;
  std::vector<double> freeLambdas;
  double lowerNeed = 0.0;                         // lambda must be >= this (objects at 1)
  double upperAllow = kInf;                       // lambda must be <= this (objects at lo)
  auto marginal = [&](std::size_t i, double x) {  // k a x^-(k+1) / c
    const ResolutionVariable& v = p.variables[i];
    return std::exp(std::log(k) + std::log(v.weight) - (k + 1.0) * std::log(x) - std::log(v.cost));
  };
  for (std::size_t i = 0; i < r.size(); ++i) {
    const ResolutionVariable& v = p.variables[i];
    if (v.cost == 0.0 || v.weight == 0.0 || v.minResolution == 1.0) continue;
    if (r[i] > v.minResolution && r[i] < 1.0) {
      freeLambdas.push_back(marginal(i, r[i]));
    } else if (r[i] == 1.0) {
      upperAllow = std::min(upperAllow, marginal(i, 1.0));  // nu = k a - lambda c >= 0
    } else {
      lowerNeed = std::max(lowerNeed, marginal(i, v.minResolution));  // mu >= 0
    }
  }
  double residual = 0.0;
  double lambda = 0.0;
  if (!freeLambdas.empty()) {
    std::sort(freeLambdas.begin(), freeLambdas.end());
    lambda = freeLambdas[freeLambdas.size() / 2];
    for (double l : freeLambdas) residual = std::max(residual, std::abs(l - lambda) / lambda);
  } else {
    lambda = std::isfinite(upperAllow) ? upperAllow : lowerNeed;
  }
  // Lower bounds: mu_i = lambda c_i - k a_i lo^-(k+1) >= 0, relative to lambda c_i.
  if (lambda > 0.0) {
    residual = std::max(residual, std::max(0.0, lowerNeed - lambda) / lambda);
    residual = std::max(residual, std::max(0.0, lambda - upperAllow) / lambda);
  }
  // Complementary slackness: lambda > 0 needs the budget used up.
  const double c = costOf(p, r);
  if (lambda > 0.0 && std::isfinite(p.budget) && p.budget > 0.0)
    residual = std::max(residual, (p.budget - c) / p.budget);
  if (c > p.budget) residual = kInf;
  return residual;
}

double logUniform(std::mt19937_64& rng, double low, double high) {
  std::uniform_real_distribution<double> u(std::log(low), std::log(high));
  return std::exp(u(rng));
}

ResolutionProblem randomProblem(std::mt19937_64& rng, std::size_t n, double weightLow,
                                double weightHigh) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double exponents[] = {0.5, 1.0, 2.0, 3.0, 1.5};
  ResolutionProblem p;
  p.exponent = exponents[rng() % 5];
  double minimum = 0.0;
  double full = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ResolutionVariable v;
    v.weight = logUniform(rng, weightLow, weightHigh);
    v.cost = logUniform(rng, 1e-6, 1e-2);
    v.minResolution = logUniform(rng, 1e-3, 0.6);
    minimum += v.cost * v.minResolution;
    full += v.cost;
    p.variables.push_back(v);
  }
  p.budget = minimum + unit(rng) * (full - minimum);
  return p;
}

ActiveSetOptions recording(bool projectedTrial = true) {
  ActiveSetOptions o;
  o.recordIterates = true;
  o.projectedTrial = projectedTrial;
  return o;
}

// Objective change from `a` to `b` summed over the objects that changed,
// with the size of the changed terms (the rounding scale of that sum). The
// total objective of extreme instances is dominated by a few huge terms, so
// comparing totals would test rounding, not the method.
struct Change {
  double change = 0.0;
  double scale = 0.0;
};
Change objectiveChange(const ResolutionProblem& p, const std::vector<double>& a,
                       const std::vector<double>& b) {
  Change c;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i] || p.variables[i].weight == 0.0) continue;
    const double before = p.variables[i].weight / std::pow(a[i], p.exponent);
    const double after = p.variables[i].weight / std::pow(b[i], p.exponent);
    c.change += after - before;
    c.scale += before + after;
  }
  return c;
}

void expectIteratesFeasibleAndMonotone(const ResolutionProblem& p, const ResolutionSolution& s) {
  ASSERT_FALSE(s.iterates.empty());
  for (std::size_t j = 0; j < s.iterates.size(); ++j) {
    const std::vector<double>& r = s.iterates[j].resolution;
    ASSERT_TRUE(withinBounds(p, r)) << "iterate " << j;
    ASSERT_LE(costOf(p, r), p.budget) << "iterate " << j;
    if (j == 0) continue;
    const Change c = objectiveChange(p, s.iterates[j - 1].resolution, r);
    ASSERT_LE(c.change, 1e-13 * c.scale) << "iterate " << j;
  }
  EXPECT_EQ(s.iterates.back().resolution, s.resolution);
}

class ActiveSetVariants : public ::testing::TestWithParam<bool> {};

TEST_P(ActiveSetVariants, MatchesBisectionReferenceOnRandomInstances) {
  std::mt19937_64 rng(1999);
  int interior = 0;
  int releases = 0;
  for (int seed = 0; seed < 400; ++seed) {
    const std::size_t n = 1 + rng() % 200;
    const ResolutionProblem p = randomProblem(rng, n, 1e-3, 1e3);
    const auto active = solveResolutionsActiveSet(p, recording(GetParam()));
    const auto reference = solveResolutionsBisection(p);
    ASSERT_TRUE(active.ok()) << active.status().toString();
    ASSERT_TRUE(reference.ok()) << reference.status().toString();
    ASSERT_EQ(active->outcome, ResolutionOutcome::kOptimal) << "seed " << seed;
    ASSERT_EQ(reference->outcome, ResolutionOutcome::kOptimal) << "seed " << seed;
    EXPECT_LE(kktResidual(p, active->resolution), 1e-9) << "seed " << seed;
    EXPECT_LE(kktResidual(p, reference->resolution), 1e-9) << "seed " << seed;
    double maxDiff = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      maxDiff = std::max(maxDiff, std::abs(active->resolution[i] - reference->resolution[i]) /
                                      reference->resolution[i]);
    EXPECT_LE(maxDiff, 1e-9) << "seed " << seed;
    EXPECT_NEAR(active->objective, reference->objective, 1e-9 * reference->objective);
    expectIteratesFeasibleAndMonotone(p, *active);
    for (std::size_t i = 0; i < n; ++i)
      interior +=
          active->resolution[i] > p.variables[i].minResolution && active->resolution[i] < 1.0;
    releases += active->releases;
  }
  EXPECT_GT(interior, 1000);  // the instances are not all at their bounds
  EXPECT_GT(releases, 0);     // the multiplier test released bounds on the way
}

INSTANTIATE_TEST_SUITE_P(Trial, ActiveSetVariants, ::testing::Values(true, false),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "projected" : "plain";
                         });

TEST(ActiveSet, SwapsBoundsWhenTheWarmStartIsWrong) {
  // Warm start with the cheap-to-improve object at its floor and the
  // expensive one at full: the optimum swaps them.
  ResolutionProblem p;
  p.exponent = 1.0;
  p.variables = {{1.0, 1.0, 0.1, 0.1}, {1e-4, 1.0, 0.1, 1.0}};
  p.budget = 1.1;
  const auto s = solveResolutionsActiveSet(p, recording());
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->outcome, ResolutionOutcome::kOptimal);
  EXPECT_NEAR(s->resolution[0], 1.0, 1e-12);
  EXPECT_NEAR(s->resolution[1], 0.1, 1e-12);
  expectIteratesFeasibleAndMonotone(p, *s);
}

TEST(ActiveSet, WarmStartFromTheOptimumStaysThere) {
  std::mt19937_64 rng(7);
  for (int seed = 0; seed < 50; ++seed) {
    ResolutionProblem p = randomProblem(rng, 100, 1e-2, 1e2);
    const auto cold = solveResolutionsActiveSet(p, {});
    ASSERT_TRUE(cold.ok());
    for (std::size_t i = 0; i < p.variables.size(); ++i)
      p.variables[i].previousResolution = cold->resolution[i];
    const auto warm = solveResolutionsActiveSet(p, recording());
    ASSERT_TRUE(warm.ok());
    EXPECT_EQ(warm->outcome, ResolutionOutcome::kOptimal);
    for (std::size_t i = 0; i < p.variables.size(); ++i)
      EXPECT_NEAR(warm->resolution[i], cold->resolution[i], 1e-12 * cold->resolution[i]);
    expectIteratesFeasibleAndMonotone(p, *warm);
  }
}

// The next frame: weights drift by up to `drift`, the budget too, and every
// tenth object is new when `newObjects` (NaN previous: starts at its floor).
// The warm start point is never worse than the cold one (componentwise at
// least the floors, and the objective decreases in every resolution); the
// iteration counts are printed, not asserted: with the variable-fixing
// trial a cold start converges in about two iterations on these instances.
void compareWarmAndCold(double drift, bool newObjects) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(1.0 - drift, 1.0 + drift);
  long warmIterations = 0;
  long coldIterations = 0;
  double warmStartGap = 0.0;
  double coldStartGap = 0.0;
  for (int seed = 0; seed < 50; ++seed) {
    ResolutionProblem p = randomProblem(rng, 500, 1e-2, 1e2);
    const auto first = solveResolutionsActiveSet(p, {});
    ASSERT_TRUE(first.ok());
    for (std::size_t i = 0; i < p.variables.size(); ++i) {
      p.variables[i].weight *= jitter(rng);
      p.variables[i].previousResolution = newObjects && i % 10 == 0 ? kNaN : first->resolution[i];
    }
    p.budget *= jitter(rng);
    ResolutionProblem coldProblem = p;
    for (ResolutionVariable& v : coldProblem.variables) v.previousResolution = kNaN;
    const auto warm = solveResolutionsActiveSet(p, recording());
    const auto cold = solveResolutionsActiveSet(coldProblem, {});
    ActiveSetOptions none;
    none.maxIterations = 0;
    const auto warmStart = solveResolutionsActiveSet(p, none);
    const auto coldStart = solveResolutionsActiveSet(coldProblem, none);
    ASSERT_TRUE(warm.ok() && cold.ok() && warmStart.ok() && coldStart.ok());
    ASSERT_EQ(warm->outcome, ResolutionOutcome::kOptimal);
    ASSERT_EQ(cold->outcome, ResolutionOutcome::kOptimal);
    EXPECT_LE(kktResidual(p, warm->resolution), 1e-9);
    EXPECT_NEAR(warm->objective, cold->objective, 1e-9 * cold->objective);
    expectIteratesFeasibleAndMonotone(p, *warm);
    EXPECT_LE(warmStart->objective, coldStart->objective);
    EXPECT_LE(costOf(p, warmStart->resolution), p.budget);
    warmIterations += warm->iterations;
    coldIterations += cold->iterations;
    warmStartGap += warmStart->objective / warm->objective - 1.0;
    coldStartGap += coldStart->objective / warm->objective - 1.0;
  }
  std::printf(
      "drift %.0f%%%s: iterations per solve warm %.2f cold %.2f; start-point gap warm "
      "%.3g cold %.3g\n",
      100 * drift, newObjects ? ", 10% new" : "", warmIterations / 50.0, coldIterations / 50.0,
      warmStartGap / 50, coldStartGap / 50);
}

TEST(ActiveSet, WarmStartAfterASmallDrift) { compareWarmAndCold(0.01, false); }

TEST(ActiveSet, WarmStartWithNewObjectsAndLargerDrift) { compareWarmAndCold(0.1, true); }

TEST_P(ActiveSetVariants, CutOffRunsReturnFeasibleImprovingAnswers) {
  std::mt19937_64 rng(23);
  int cutOffs = 0;
  for (int seed = 0; seed < 40; ++seed) {
    const ResolutionProblem p = randomProblem(rng, 300, 1e-3, 1e3);
    ActiveSetOptions plain;
    plain.projectedTrial = GetParam();
    const auto optimum = solveResolutionsActiveSet(p, plain);
    ASSERT_TRUE(optimum.ok());
    ASSERT_EQ(optimum->outcome, ResolutionOutcome::kOptimal);
    ActiveSetOptions zero = plain;
    zero.maxIterations = 0;
    const auto start = solveResolutionsActiveSet(p, zero);
    ASSERT_TRUE(start.ok());
    std::vector<double> previous = start->resolution;
    // Every cap for short runs, about 25 evenly spaced caps for long ones.
    const int stride = std::max(1, optimum->iterations / 25);
    for (int cap = 1; cap <= optimum->iterations; cap += stride) {
      ActiveSetOptions o = plain;
      o.maxIterations = cap;
      ++cutOffs;
      const auto cut = solveResolutionsActiveSet(p, o);
      ASSERT_TRUE(cut.ok());
      EXPECT_TRUE(withinBounds(p, cut->resolution));
      EXPECT_LE(costOf(p, cut->resolution), p.budget);
      const Change c = objectiveChange(p, previous, cut->resolution);
      EXPECT_LE(c.change, 1e-13 * c.scale) << "cap " << cap;
      EXPECT_GE(cut->objective, optimum->objective * (1.0 - 1e-12));
      if (cap < optimum->iterations) {
        EXPECT_EQ(cut->outcome, ResolutionOutcome::kIterationCap);
      }
      previous = cut->resolution;
    }
  }
  EXPECT_GE(cutOffs, 40);
}

TEST(ActiveSet, ZeroTimeBoxReturnsTheFeasibleStartPoint) {
  std::mt19937_64 rng(5);
  ResolutionProblem p = randomProblem(rng, 1000, 1e-3, 1e3);
  // A warm start far over budget: the start point must be scaled into it.
  for (ResolutionVariable& v : p.variables) v.previousResolution = 1.0;
  ActiveSetOptions o;
  o.timeBoxSeconds = 0.0;
  const auto s = solveResolutionsActiveSet(p, o);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->outcome, ResolutionOutcome::kTimeBox);
  EXPECT_EQ(s->iterations, 0);
  EXPECT_TRUE(withinBounds(p, s->resolution));
  EXPECT_LE(costOf(p, s->resolution), p.budget);
}

TEST_P(ActiveSetVariants, ExtremeWeightMagnitudes) {
  std::mt19937_64 rng(1e12);
  for (int seed = 0; seed < 100; ++seed) {
    const ResolutionProblem p = randomProblem(rng, 1 + rng() % 300, 1e-12, 1e12);
    const auto active = solveResolutionsActiveSet(p, recording(GetParam()));
    const auto reference = solveResolutionsBisection(p);
    ASSERT_TRUE(active.ok() && reference.ok());
    ASSERT_EQ(active->outcome, ResolutionOutcome::kOptimal) << "seed " << seed;
    EXPECT_LE(kktResidual(p, active->resolution), 1e-9) << "seed " << seed;
    EXPECT_NEAR(active->objective, reference->objective, 1e-9 * reference->objective);
    expectIteratesFeasibleAndMonotone(p, *active);
  }
}

TEST_P(ActiveSetVariants, TinyAndHugeBudgetsAndCosts) {
  std::mt19937_64 rng(3);
  for (double costScale : {1e-12, 1.0, 1e9}) {
    for (double share : {1e-12, 1e-6, 0.5, 1.0 - 1e-9}) {
      ResolutionProblem p = randomProblem(rng, 200, 1e-3, 1e3);
      double minimum = 0.0;
      double full = 0.0;
      for (ResolutionVariable& v : p.variables) {
        v.cost *= costScale;
        minimum += v.cost * v.minResolution;
        full += v.cost;
      }
      p.budget = minimum + share * (full - minimum);
      const auto s = solveResolutionsActiveSet(p, recording(GetParam()));
      ASSERT_TRUE(s.ok());
      ASSERT_TRUE(s->outcome == ResolutionOutcome::kOptimal ||
                  s->outcome == ResolutionOutcome::kInfeasible ||
                  s->outcome == ResolutionOutcome::kAllAtFull)
          << resolutionOutcomeName(s->outcome);
      if (s->outcome == ResolutionOutcome::kOptimal) {
        EXPECT_LE(kktResidual(p, s->resolution), 1e-9) << costScale << " " << share;
        expectIteratesFeasibleAndMonotone(p, *s);
      } else {
        // Only when rounding puts the budget at one end of the range.
        EXPECT_TRUE(share < 1e-9 || share > 1.0 - 1e-8);
      }
    }
  }
}

TEST(ActiveSet, InfeasibleBudgetSaysSoAndReturnsTheFloor) {
  ResolutionProblem p;
  p.variables = {{1.0, 2.0, 0.5}, {1.0, 1.0, 0.25}};
  p.budget = 1.0;  // floors cost 1.25
  for (const auto& s : {solveResolutionsActiveSet(p, {}), solveResolutionsBisection(p)}) {
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(s->outcome, ResolutionOutcome::kInfeasible);
    EXPECT_EQ(s->resolution, (std::vector<double>{0.5, 0.25}));
    EXPECT_DOUBLE_EQ(s->minimumCost, 1.25);
    EXPECT_GT(s->cost, p.budget);
  }
  p.budget = -1.0;
  EXPECT_EQ(solveResolutionsActiveSet(p, {})->outcome, ResolutionOutcome::kInfeasible);
}

TEST(ActiveSet, EverythingFitsAtFullResolution) {
  ResolutionProblem p;
  p.variables = {{1.0, 2.0, 0.5}, {1.0, 1.0, 0.25, 0.3}};
  for (double budget : {3.0, 1e300, kInf}) {
    p.budget = budget;
    const auto s = solveResolutionsActiveSet(p, {});
    ASSERT_TRUE(s.ok());
    EXPECT_EQ(s->outcome, ResolutionOutcome::kAllAtFull);
    EXPECT_EQ(s->resolution, (std::vector<double>{1.0, 1.0}));
  }
  p.variables.clear();
  p.budget = 0.0;
  const auto empty = solveResolutionsActiveSet(p, {});
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->outcome, ResolutionOutcome::kAllAtFull);
  EXPECT_TRUE(empty->resolution.empty());
}

TEST(ActiveSet, ZeroWeightZeroCostAndFixedObjects) {
  ResolutionProblem p;
  p.exponent = 1.0;
  p.variables = {
      {0.0, 1.0, 0.2},  // no degradation: stays at its floor
      {5.0, 0.0, 0.2},  // free of cost: full resolution
      {1.0, 1.0, 1.0},  // cannot change
      {1.0, 1.0, 0.1}, {4.0, 1.0, 0.1},
  };
  p.budget = 0.2 + 1.0 + 1.5;  // 1.5 left for the last two
  const auto s = solveResolutionsActiveSet(p, recording());
  ASSERT_TRUE(s.ok());
  ASSERT_EQ(s->outcome, ResolutionOutcome::kOptimal);
  EXPECT_EQ(s->resolution[0], 0.2);
  EXPECT_EQ(s->resolution[1], 1.0);
  EXPECT_EQ(s->resolution[2], 1.0);
  // k = 1: r proportional to sqrt(a / c): 1 : 2, sum 1.5 -> 0.5 and 1.0.
  EXPECT_NEAR(s->resolution[3], 0.5, 1e-12);
  EXPECT_NEAR(s->resolution[4], 1.0, 1e-12);
  EXPECT_LE(kktResidual(p, s->resolution), 1e-9);
  expectIteratesFeasibleAndMonotone(p, *s);
  const auto reference = solveResolutionsBisection(p);
  ASSERT_TRUE(reference.ok());
  EXPECT_NEAR(reference->resolution[3], 0.5, 1e-9);
}

TEST(ActiveSet, MultiplierMatchesTheFreeObjects) {
  std::mt19937_64 rng(99);
  const ResolutionProblem p = randomProblem(rng, 50, 1e-2, 1e2);
  const auto s = solveResolutionsActiveSet(p, {});
  ASSERT_TRUE(s.ok());
  ASSERT_EQ(s->outcome, ResolutionOutcome::kOptimal);
  int checked = 0;
  for (std::size_t i = 0; i < p.variables.size(); ++i) {
    const ResolutionVariable& v = p.variables[i];
    const double r = s->resolution[i];
    if (r <= v.minResolution || r >= 1.0) continue;
    const double lambda = p.exponent * v.weight * std::pow(r, -(p.exponent + 1.0)) / v.cost;
    EXPECT_NEAR(lambda, s->multiplier, 1e-9 * s->multiplier);
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(ActiveSet, LargeColdStartConverges) {
  std::mt19937_64 rng(100000);
  const ResolutionProblem p = randomProblem(rng, 100000, 1e-3, 1e3);
  const auto s = solveResolutionsActiveSet(p, {});
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->outcome, ResolutionOutcome::kOptimal);
  EXPECT_LE(kktResidual(p, s->resolution), 1e-9);
  const auto reference = solveResolutionsBisection(p);
  ASSERT_TRUE(reference.ok());
  EXPECT_NEAR(s->objective, reference->objective, 1e-9 * reference->objective);
}

TEST(ActiveSet, RejectsInvalidInput) {
  const ResolutionVariable good{1.0, 1.0, 0.5};
  auto withVariable = [&](ResolutionVariable v) {
    ResolutionProblem p;
    p.variables = {good, v};
    p.budget = 1.0;
    return p;
  };
  const ResolutionProblem bad[] = {
      withVariable({kNaN, 1.0, 0.5}),      withVariable({-1.0, 1.0, 0.5}),
      withVariable({kInf, 1.0, 0.5}),      withVariable({1.0, kNaN, 0.5}),
      withVariable({1.0, -1.0, 0.5}),      withVariable({1.0, 1.0, 0.0}),
      withVariable({1.0, 1.0, 1.5}),       withVariable({1.0, 1.0, kNaN}),
      withVariable({1.0, 1.0, 0.5, kInf}),
  };
  for (const ResolutionProblem& p : bad) {
    const auto s = solveResolutionsActiveSet(p, {});
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.status().code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(s.status().message().find("variables[1]"), std::string::npos) << s.status().message();
    EXPECT_FALSE(solveResolutionsBisection(p).ok());
  }
  ResolutionProblem p = withVariable(good);
  p.budget = kNaN;
  EXPECT_FALSE(solveResolutionsActiveSet(p, {}).ok());
  p.budget = 1.0;
  p.exponent = 0.0;
  EXPECT_FALSE(solveResolutionsActiveSet(p, {}).ok());
  p.exponent = kInf;
  EXPECT_FALSE(solveResolutionsActiveSet(p, {}).ok());
  p.exponent = 1.0;
  ActiveSetOptions o;
  o.maxIterations = -1;
  EXPECT_FALSE(solveResolutionsActiveSet(p, o).ok());
  o = {};
  o.timeBoxSeconds = kNaN;
  EXPECT_FALSE(solveResolutionsActiveSet(p, o).ok());
}

}  // namespace
}  // namespace thinlod::backbone
