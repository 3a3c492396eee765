// Accuracy-curve (and conic-range) benchmarks: sum / lower envelope / inversion of single
// curves with 2-64 knots, and propagation through balanced Group/LOD trees
// of 10^3-10^6 random leaf curves (fixed seed). Items are knots (per-curve
// benchmarks), queries (inversion), or leaves (trees).
//
// Baseline, measured in the same run: BM_TreeProbeOneAccuracy evaluates the
// same tree at one accuracy by brute force (what a scheduler without
// propagated curves must repeat for every probe of a bisection over a).
//
//   build-*/common/bench/bench_curves --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "thinlod/common/core/accuracy_curve.h"
#include "thinlod/common/core/conic_range.h"

namespace thinlod {
namespace {

constexpr std::uint64_t kSeed = 20020611;

// A measured-looking leaf: accuracy in [1, 1000] (relative, 1/d), triangles
// growing roughly linearly with accuracy, occasional jumps.
AccuracyCurve randomLeaf(std::mt19937_64& rng, int knots) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<CurveSegment> segments;
  double a = 1.0 + 20.0 * unit(rng);
  double r = 10.0 + 100.0 * unit(rng);
  for (int i = 0; i < knots; ++i) {
    const double slope = 5.0 + 50.0 * unit(rng);
    if (!segments.empty()) {
      const CurveSegment& p = segments.back();
      r = p.value + p.slope * (a - p.start) + (unit(rng) < 0.3 ? 50.0 * unit(rng) : 0.0);
    }
    segments.push_back(CurveSegment{a, r, slope});
    a += 1.0 + 1000.0 / knots * unit(rng);
  }
  return AccuracyCurve::fromSegments(segments, a).value();
}

std::vector<AccuracyCurve> randomLeaves(int count, int knots) {
  std::mt19937_64 rng(kSeed);
  std::vector<AccuracyCurve> leaves;
  leaves.reserve(count);
  for (int i = 0; i < count; ++i) leaves.push_back(randomLeaf(rng, knots));
  return leaves;
}

void BM_Sum2(benchmark::State& state) {
  const int knots = static_cast<int>(state.range(0));
  const auto leaves = randomLeaves(2, knots);
  for (auto _ : state) {
    AccuracyCurve s = AccuracyCurve::sum({&leaves[0], &leaves[1]});
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations() * 2 * knots);
}
BENCHMARK(BM_Sum2)->RangeMultiplier(2)->Range(2, 64);

void BM_Envelope2(benchmark::State& state) {
  const int knots = static_cast<int>(state.range(0));
  const auto leaves = randomLeaves(2, knots);
  std::vector<int> owners;
  for (auto _ : state) {
    AccuracyCurve e = AccuracyCurve::lowerEnvelope({&leaves[0], &leaves[1]}, &owners);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(state.iterations() * 2 * knots);
}
BENCHMARK(BM_Envelope2)->RangeMultiplier(2)->Range(2, 64);

void BM_Invert(benchmark::State& state) {
  const int knots = static_cast<int>(state.range(0));
  const AccuracyCurve curve = randomLeaves(1, knots)[0];
  std::mt19937_64 rng(kSeed);
  const double top = curve.resourcesFor(curve.maxAccuracy());
  std::vector<double> budgets(1024);
  for (double& b : budgets) b = std::uniform_real_distribution<double>(0.0, top)(rng);
  std::size_t i = 0;
  double checksum = 0.0;
  for (auto _ : state) {
    const std::optional<double> a = curve.maxAccuracyWithin(budgets[i++ & 1023]);
    checksum += a ? *a : 0.0;
  }
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Invert)->RangeMultiplier(2)->Range(2, 64);

void BM_Evaluate(benchmark::State& state) {
  const int knots = static_cast<int>(state.range(0));
  const AccuracyCurve curve = randomLeaves(1, knots)[0];
  std::mt19937_64 rng(kSeed);
  std::vector<double> as(1024);
  for (double& a : as) {
    a = std::uniform_real_distribution<double>(curve.minAccuracy(), curve.maxAccuracy())(rng);
  }
  std::size_t i = 0;
  double checksum = 0.0;
  for (auto _ : state) checksum += curve.resourcesFor(as[i++ & 1023]);
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Evaluate)->RangeMultiplier(2)->Range(2, 64);

void BM_FitConservative(benchmark::State& state) {
  // Measured (accuracy, triangles) samples of a progressive mesh: noisy
  // r ~ a^1.5. Fitted to 8 segments; items are samples.
  const int count = static_cast<int>(state.range(0));
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<AccuracySample> samples(count);
  for (AccuracySample& s : samples) {
    s.accuracy = 1.0 + 999.0 * unit(rng);
    s.resources = std::pow(s.accuracy, 1.5) * (0.9 + 0.2 * unit(rng));
  }
  std::size_t segments = 0;
  for (auto _ : state) {
    auto fit = AccuracyCurve::fitConservative(samples, 8);
    segments = fit->segments().size();
    benchmark::DoNotOptimize(fit);
  }
  state.counters["segments"] = static_cast<double>(segments);
  state.SetItemsProcessed(state.iterations() * count);
}
BENCHMARK(BM_FitConservative)
    ->RangeMultiplier(10)
    ->Range(10, 100000)
    ->Unit(benchmark::kMicrosecond);

void BM_ConicIntersect(benchmark::State& state) {
  // range(0) = 0: nested ranges (exact path); 1: partly overlapping cones
  // with different centres (the ball fallback). Items are intersections.
  const bool fallback = state.range(0) == 1;
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::pair<ConicRange, ConicRange>> pairs;
  for (int i = 0; i < 256; ++i) {
    const glm::dvec3 c(unit(rng), unit(rng), unit(rng));
    const ConicRange a = ConicRange::make(c, 1.0, 20.0, {0, 0, 1}, 0.8).value();
    const ConicRange b =
        fallback ? ConicRange::make(c + glm::dvec3(3, 0, 0), 2.0, 15.0, {0.3, 0, 1}, 0.7).value()
                 : ConicRange::ball(c + glm::dvec3(0, 0, 8), 1.0);
    pairs.emplace_back(a, b);
  }
  std::size_t i = 0;
  double checksum = 0.0;
  for (auto _ : state) {
    const auto& [a, b] = pairs[i++ & 255];
    checksum += a.intersect(b).maxDistance();
  }
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ConicIntersect)->Arg(0)->Arg(1);

// Balanced tree, fan-out 4; levels alternate LOD (lowest level: 4 versions
// of an object) and Group. Propagates level by level, freeing the children.
constexpr int kFanOut = 4;
constexpr int kLeafKnots = 4;

std::vector<AccuracyCurve> reduceLevel(const std::vector<AccuracyCurve>& level, bool lod) {
  std::vector<AccuracyCurve> parents;
  parents.reserve((level.size() + kFanOut - 1) / kFanOut);
  std::vector<const AccuracyCurve*> children;
  for (std::size_t i = 0; i < level.size(); i += kFanOut) {
    children.clear();
    for (std::size_t j = i; j < std::min(level.size(), i + kFanOut); ++j) {
      children.push_back(&level[j]);
    }
    parents.push_back(lod ? AccuracyCurve::lowerEnvelope(children) : AccuracyCurve::sum(children));
  }
  return parents;
}

AccuracyCurve propagate(const std::vector<AccuracyCurve>& leaves) {
  std::vector<AccuracyCurve> level = reduceLevel(leaves, true);
  bool lod = false;
  while (level.size() > 1) {
    level = reduceLevel(level, lod);
    lod = !lod;
  }
  return level.front();
}

// An accuracy inside every leaf's domain: there no node clamps or runs out,
// so the brute-force probe below is a plain min/sum tree.
double commonAccuracy(const std::vector<AccuracyCurve>& leaves) {
  double a = std::numeric_limits<double>::infinity();
  for (const AccuracyCurve& leaf : leaves) a = std::min(a, leaf.maxAccuracy());
  return a;
}

// The same tree evaluated at one accuracy by brute force.
double probe(const std::vector<AccuracyCurve>& leaves, double a) {
  std::vector<double> level;
  level.reserve(leaves.size());
  for (const AccuracyCurve& leaf : leaves) level.push_back(leaf.resourcesFor(a));
  bool lod = true;
  while (level.size() > 1) {
    std::vector<double> parents;
    for (std::size_t i = 0; i < level.size(); i += kFanOut) {
      double v = lod ? std::numeric_limits<double>::infinity() : 0.0;
      for (std::size_t j = i; j < std::min(level.size(), i + kFanOut); ++j) {
        v = lod ? std::min(v, level[j]) : v + level[j];
      }
      parents.push_back(v);
    }
    level = std::move(parents);
    lod = !lod;
  }
  return level.front();
}

void BM_TreePropagate(benchmark::State& state) {
  const int leafCount = static_cast<int>(state.range(0));
  const auto leaves = randomLeaves(leafCount, kLeafKnots);
  std::size_t rootKnots = 0;
  for (auto _ : state) {
    const AccuracyCurve root = propagate(leaves);
    rootKnots = root.segments().size();
    benchmark::DoNotOptimize(root);
  }
  // Check after timing: the root agrees with brute force where both are finite.
  const AccuracyCurve root = propagate(leaves);
  const double a = commonAccuracy(leaves);
  const double expected = probe(leaves, a);
  const double got = root.resourcesFor(a);
  if (!(std::fabs(got - expected) <= 1e-9 * expected)) {
    state.SkipWithError("root curve disagrees with brute force");
  }
  state.counters["root_knots"] = static_cast<double>(rootKnots);
  state.SetItemsProcessed(state.iterations() * leafCount);
}
BENCHMARK(BM_TreePropagate)
    ->RangeMultiplier(10)
    ->Range(1000, 1000000)
    ->Unit(benchmark::kMillisecond);

void BM_TreeProbeOneAccuracy(benchmark::State& state) {
  const int leafCount = static_cast<int>(state.range(0));
  const auto leaves = randomLeaves(leafCount, kLeafKnots);
  double checksum = 0.0;
  const double a = commonAccuracy(leaves);
  for (auto _ : state) checksum += probe(leaves, a);
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations() * leafCount);
}
BENCHMARK(BM_TreeProbeOneAccuracy)
    ->RangeMultiplier(10)
    ->Range(1000, 1000000)
    ->Unit(benchmark::kMillisecond);

void BM_TreeRootInvert(benchmark::State& state) {
  // Once propagated, a budget query at the root is one inversion.
  const int leafCount = static_cast<int>(state.range(0));
  const AccuracyCurve root = propagate(randomLeaves(leafCount, kLeafKnots));
  const double budget = 0.5 * root.resourcesFor(root.maxAccuracy());
  double checksum = 0.0;
  for (auto _ : state) checksum += root.maxAccuracyWithin(budget).value_or(0.0);
  benchmark::DoNotOptimize(checksum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TreeRootInvert)->RangeMultiplier(10)->Range(1000, 1000000);

}  // namespace
}  // namespace thinlod

BENCHMARK_MAIN();
