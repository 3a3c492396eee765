// service_hybrid_timing: the first hybrid curve request of a fresh
// SimplifierService, twice on one curve cache directory (not a test). The
// first service builds the graph and measures the ladder, the second reads
// the ladder from the cache and only rebuilds the graph (docs/hybrid.md,
// "Measured curve"). Model: the fly-through's generateScatteredParts(300, 2,
// 7), 96,000 triangles, written as a PLY and named by a one-Shape scene.
// Prints CSV: run,ms,graph_builds,ladders_measured,ladders_from_disk,units,accuracy
// (ms: the whole request, scene load included); the service's progress
// lines (graph + ladder time, "ms=") on stderr.
// Usage: service_hybrid_timing [kappa] [parts]
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/service.h"

using namespace thinlod;
using namespace thinlod::simplifier;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  const double kappa = argc > 1 ? std::atof(argv[1]) : 1.5;
  const int parts = argc > 2 ? std::atoi(argv[2]) : 300;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hybrid-timing-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const IndexedMesh mesh = generateScatteredParts(parts, 2, 7);
  if (Status saved = saveMeshFile(mesh, (dir / "parts.ply").string(), true); !saved.ok()) {
    std::fprintf(stderr, "%s\n", saved.toString().c_str());
    return 1;
  }
  const std::string scene = (dir / "parts.wrl").string();
  std::ofstream(scene) << "#VRML V2.0 utf8\nShape { geometry Inline { url \"parts.ply\" } }\n";

  ServiceOptions options;
  options.modelSearchPaths = {dir.string()};
  options.sceneRoot = dir.string();
  options.curveCacheDir = (dir / "curves").string();
  // The service's own split (graph + ladder, scene load excluded) goes to stderr.
  options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  protocol::SimplifyRequest request;  // as the backbone's startup curve request
  request.requestId = 1;
  request.objectId = 1;
  request.sourcePath = scene;
  request.target = protocol::SimplifyRequest::Target::kTriangles;
  request.targetTriangles = 2000;
  request.curvePoints = 32;
  request.representation = protocol::RepresentationKind::kHybrid;
  request.kappa = kappa;

  std::printf("run,ms,graph_builds,ladders_measured,ladders_from_disk,units,accuracy\n");
  int failures = 0;
  for (const char* run : {"first-empty-cache", "second-same-cache"}) {
    SimplifierService service(options);
    const auto start = Clock::now();
    const protocol::SimplifyResult r = service.simplify(request);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (!r.status.ok()) {
      std::fprintf(stderr, "%s: %s\n", run, r.status.toString().c_str());
      ++failures;
      continue;
    }
    const ServiceStats& s = service.stats();
    std::printf("%s,%.0f,%llu,%llu,%llu,%.1f,%.4g\n", run, ms,
                static_cast<unsigned long long>(s.hybridGraphBuilds),
                static_cast<unsigned long long>(s.hybridCurvesMeasured),
                static_cast<unsigned long long>(s.hybridCurvesFromDisk),
                r.triangleCount + r.pointCount / r.kappa, r.accuracy);
    std::fflush(stdout);
  }
  std::filesystem::remove_all(dir);
  return failures == 0 ? 0 : 1;
}
