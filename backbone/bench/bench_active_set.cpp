// bench_active_set: the Gobbetti-Bouvier resolution optimiser (active set,
// with and without its projected trial step) against the bisection reference
// on the same random instances, 10^2 - 10^5 objects (fixed seed).
//
//   build/backbone/bench/bench_active_set --benchmark_counters_tabular=true
//
// Counters: iterations per solve, seconds per object per iteration (flat in n when
// the work per iteration is linear), and for the reference its bisection
// steps. After timing each result is checked against the reference
// (relative objective difference <= 1e-9, cost within budget).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "active_set_optimiser.h"

namespace thinlod::backbone {
namespace {

constexpr std::uint64_t kSeed = 19991024;

// Costs and weights as the scheduler makes them: c = T_max * t_tri with
// T_max 100..20000 triangles and t_tri 20 ns; weights = acuity * pixels per
// triangle over 4 decades; floors from the fill bound 0.01..0.3; the budget
// half-way between all floors and all at full. `drift` jitters the weights
// for a warm start from the unjittered optimum.
ResolutionProblem makeProblem(std::size_t n, double drift, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  ResolutionProblem p;
  p.exponent = 1.0;
  double minimum = 0.0;
  double full = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    ResolutionVariable v;
    v.cost = 2e-8 * std::exp(std::log(100.0) + unit(rng) * std::log(200.0));
    v.weight = std::exp(std::log(1e-2) + unit(rng) * std::log(1e4));
    v.minResolution = 0.01 + 0.29 * unit(rng);
    minimum += v.cost * v.minResolution;
    full += v.cost;
    p.variables.push_back(v);
  }
  p.budget = minimum + 0.5 * (full - minimum);
  if (drift > 0.0) {
    const auto first = solveResolutionsActiveSet(p, {});
    for (std::size_t i = 0; i < n; ++i) {
      p.variables[i].previousResolution = first->resolution[i];
      p.variables[i].weight *= 1.0 + drift * (2.0 * unit(rng) - 1.0);
    }
  }
  return p;
}

void check(benchmark::State& state, const ResolutionProblem& p, const ResolutionSolution& s) {
  const auto reference = solveResolutionsBisection(p);
  if (!reference.ok() || s.cost > p.budget ||
      std::abs(s.objective - reference->objective) > 1e-9 * reference->objective)
    state.SkipWithError("result differs from the reference");
}

void runActiveSet(benchmark::State& state, double drift, bool projected) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const ResolutionProblem p = makeProblem(n, drift, kSeed);
  ActiveSetOptions options;
  options.projectedTrial = projected;
  ResolutionSolution last;
  for (auto _ : state) {
    auto s = solveResolutionsActiveSet(p, options);
    benchmark::DoNotOptimize(s);
    last = std::move(s.value());
  }
  state.counters["iterations"] = last.iterations;
  // Seconds per (object x iteration), printed with an SI prefix (n = ns).
  state.counters["per_object_iteration"] =
      benchmark::Counter(static_cast<double>(last.iterations) * static_cast<double>(n) *
                             static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
  check(state, p, last);
}

void BM_ActiveSetCold(benchmark::State& state) { runActiveSet(state, 0.0, true); }
void BM_ActiveSetWarm(benchmark::State& state) { runActiveSet(state, 0.05, true); }
void BM_ActiveSetPlainCold(benchmark::State& state) { runActiveSet(state, 0.0, false); }
void BM_ActiveSetPlainWarm(benchmark::State& state) { runActiveSet(state, 0.05, false); }

void BM_Bisection(benchmark::State& state) {
  const std::size_t n = static_cast<std::size_t>(state.range(0));
  const ResolutionProblem p = makeProblem(n, 0.0, kSeed);
  ResolutionSolution last;
  for (auto _ : state) {
    auto s = solveResolutionsBisection(p);
    benchmark::DoNotOptimize(s);
    last = std::move(s.value());
  }
  state.counters["iterations"] = last.iterations;
  state.counters["per_object_iteration"] =
      benchmark::Counter(static_cast<double>(last.iterations) * static_cast<double>(n) *
                             static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
  if (last.cost > p.budget) state.SkipWithError("over budget");
}

BENCHMARK(BM_ActiveSetCold)->RangeMultiplier(10)->Range(100, 100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ActiveSetWarm)->RangeMultiplier(10)->Range(100, 100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ActiveSetPlainCold)
    ->RangeMultiplier(10)
    ->Range(100, 10000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ActiveSetPlainWarm)
    ->RangeMultiplier(10)
    ->Range(100, 100000)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Bisection)->RangeMultiplier(10)->Range(100, 100000)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace thinlod::backbone

BENCHMARK_MAIN();
