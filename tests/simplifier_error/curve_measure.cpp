// Not a ctest test: builds a ProgressiveMesh of a model, measures its
// accuracy curves with default options (12 levels, 100k samples per
// direction) and prints the levels, the fitted (A, R, K) triples and timings,
// then repeats through a MeshCurveCache to time a cache hit.
//   curve_measure <model.obj> <cache_dir>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "test_meshes.h"
#include "thinlod/common/core/cpu_time.h"
#include "thinlod/simplifier/mesh_curve.h"

namespace {

using namespace thinlod;
using namespace thinlod::simplifier;

struct Stopwatch {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  double cpu = threadCpuSeconds() * 1e3;
  double wallMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall)
        .count();
  }
  double cpuMs() const { return threadCpuSeconds() * 1e3 - cpu; }
};

void printCurve(const char* name, const AccuracyCurve& curve) {
  std::printf("%s curve (maxAccuracy %.6g):", name, curve.maxAccuracy());
  for (const CurveTriple& t : curve.triples())
    std::printf(" (A=%.6g R=%.6g K=%.6g)", t.A, t.R, t.K);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s <model.obj> <cache_dir>\n", argv[0]);
    return 2;
  }
  Result<IndexedMesh> mesh = testing::readObjPositions(argv[1]);
  if (!mesh.ok()) {
    std::fprintf(stderr, "%s\n", mesh.status().toString().c_str());
    return 1;
  }
  Stopwatch watch;
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(*mesh);
  if (!pm.ok()) {
    std::fprintf(stderr, "%s\n", pm.status().toString().c_str());
    return 1;
  }
  std::printf("progressive mesh: %zu..%zu triangles, build %.1f ms wall, %.1f ms cpu\n",
              pm->minTriangles(), pm->maxTriangles(), watch.wallMs(), watch.cpuMs());
  watch = Stopwatch();
  Result<MeshCurves> curves = measureMeshCurves(*mesh, *pm);
  if (!curves.ok()) {
    std::fprintf(stderr, "%s\n", curves.status().toString().c_str());
    return 1;
  }
  std::printf("measure curves: %.1f ms wall, %.1f ms cpu\n", watch.wallMs(), watch.cpuMs());
  std::printf(
      "triangles,rel_max_error,rel_mean_error,accuracy,position_bits,bytes,"
      "encoded_accuracy\n");
  for (const CurveLevel& l : curves->levels) {
    std::printf("%zu,%.6g,%.6g,%.6g,%d,%zu,%.6g\n", l.triangles, l.relativeMaxError,
                l.relativeMeanError, l.accuracy, l.positionBits, l.encodedBytes, l.encodedAccuracy);
  }
  printCurve("triangles", curves->triangles);
  printCurve("bytes", curves->bytes);

  // How much the fitted triangle curve over-estimates the measured staircase
  // for several segment budgets: ratio curve / staircase over 2000
  // log-spaced accuracies across the domain (1 = exact staircase).
  std::vector<AccuracySample> samples;
  for (const CurveLevel& l : curves->levels) {
    samples.push_back({l.accuracy, static_cast<double>(l.triangles)});
  }
  auto staircase = [&](double a) {
    double best = INFINITY;
    for (const AccuracySample& s : samples) {
      if (s.accuracy >= a) best = std::min(best, s.resources);
    }
    return best;
  };
  for (int segments : {1, 2, 3, 4, 6, 8, 12}) {
    Result<AccuracyCurve> fit = AccuracyCurve::fitConservative(samples, segments);
    if (!fit.ok()) continue;
    const double lo = std::log(fit->minAccuracy()), hi = std::log(fit->maxAccuracy());
    double sumLog = 0.0, worst = 1.0;
    const int n = 2000;
    for (int i = 0; i <= n; ++i) {
      const double a = std::min(std::exp(lo + (hi - lo) * i / n), fit->maxAccuracy());
      const double ratio = fit->resourcesFor(a) / staircase(a);
      sumLog += std::log(ratio);
      worst = std::max(worst, ratio);
    }
    std::printf("fit with %2d segments: geometric-mean over-estimate %.3f, worst %.3f\n", segments,
                std::exp(sumLog / (n + 1)), worst);
  }

  MeshCurveCache cache{std::filesystem::path(argv[2])};
  for (int run = 0; run < 2; ++run) {
    watch = Stopwatch();
    Result<MeshCurves> cached = cache.getOrMeasure(*mesh, "qem default", *pm);
    std::printf("cache run %d: %s, %.1f ms wall, %.1f ms cpu (hits %d, misses %d, rejected %d)\n",
                run, cached.ok() ? "ok" : cached.status().toString().c_str(), watch.wallMs(),
                watch.cpuMs(), cache.stats().hits, cache.stats().misses, cache.stats().rejected);
  }
  return 0;
}
