// Not a ctest test: builds a ProgressiveMesh of a model, measures its
// accuracy curves with default options (12 levels, 100k samples per
// direction) and prints the levels, the fitted (A, R, K) triples and timings,
// then repeats through a MeshCurveCache to time a cache hit.
//   curve_measure <model.obj> <cache_dir>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "test_meshes.h"
#include "thinlod/simplifier/mesh_curve.h"

namespace {

using namespace thinlod;
using namespace thinlod::simplifier;

double since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

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
  auto start = std::chrono::steady_clock::now();
  Result<ProgressiveMesh> pm = ProgressiveMesh::build(*mesh);
  if (!pm.ok()) {
    std::fprintf(stderr, "%s\n", pm.status().toString().c_str());
    return 1;
  }
  std::printf("progressive mesh: %zu..%zu triangles, build %.1f ms\n", pm->minTriangles(),
              pm->maxTriangles(), since(start));
  start = std::chrono::steady_clock::now();
  Result<MeshCurves> curves = measureMeshCurves(*mesh, *pm);
  if (!curves.ok()) {
    std::fprintf(stderr, "%s\n", curves.status().toString().c_str());
    return 1;
  }
  std::printf("measure curves: %.1f ms\n", since(start));
  std::printf(
      "triangles,rel_max_error,rel_mean_error,accuracy,position_bits,bytes,"
      "encoded_accuracy\n");
  for (const CurveLevel& l : curves->levels) {
    std::printf("%zu,%.6g,%.6g,%.6g,%d,%zu,%.6g\n", l.triangles, l.relativeMaxError,
                l.relativeMeanError, l.accuracy, l.positionBits, l.encodedBytes, l.encodedAccuracy);
  }
  printCurve("triangles", curves->triangles);
  printCurve("bytes", curves->bytes);

  MeshCurveCache cache{std::filesystem::path(argv[2])};
  for (int run = 0; run < 2; ++run) {
    start = std::chrono::steady_clock::now();
    Result<MeshCurves> cached = cache.getOrMeasure(*mesh, "qem default", *pm);
    std::printf("cache run %d: %s, %.1f ms (hits %d, misses %d, rejected %d)\n", run,
                cached.ok() ? "ok" : cached.status().toString().c_str(), since(start),
                cache.stats().hits, cache.stats().misses, cache.stats().rejected);
  }
  return 0;
}
