// bench_hybrid: the hybrid simplification experiment of docs/results/hybrid.md
// (Cohen-Aliaga-Zhang Figures 6-9): graph statistics and build time, and
// primitive units vs object-space error for kappa in {3, 10}, tau in {1, 5}
// against triangles only, on the bunny and a generated multi-manifold model.
// For every configuration the cut at each error is also measured
// (measureHybridSurfaceError) so the table shows how tight the bounds are,
// and every configuration's measured ladder (measureHybridLevels, what the
// service's curves are made of) is set against the progressive mesh's.
// Prints a markdown report to stdout; progress to stderr.
//   bench_hybrid [--models-dir DIR] [--parts N] [--samples N]
#include <time.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Config {
  std::string name;
  HybridOptions options;
};

double unitsAt(const std::vector<HybridCurveStep>& steps, double error) {
  double units = steps.front().units;
  for (const HybridCurveStep& s : steps) {
    if (s.error > error) break;
    units = s.units;
  }
  return units;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hybrid triangle + point simplification experiment"};
  std::string modelsDir = std::string(THINLOD_SHARED_DIR) + "/models";
  int parts = 300;
  std::size_t samples = 20000;
  app.add_option("--models-dir", modelsDir, "directory with stanford-bunny.obj");
  app.add_option("--parts", parts, "parts of the generated multi-manifold model");
  app.add_option("--samples", samples, "surface samples per side for the measured error");
  CLI11_PARSE(app, argc, argv);

  struct Model {
    std::string name;
    IndexedMesh mesh;
  };
  std::vector<Model> models;
  Result<LoadedMesh> bunny = loadMeshFile(modelsDir + "/stanford-bunny.obj");
  if (!bunny.ok()) {
    std::cerr << bunny.status().toString() << "\n";
    return 1;
  }
  IndexedMesh bunnyMesh;
  bunnyMesh.positions = bunny->mesh.positions;
  bunnyMesh.indices = bunny->mesh.indices;
  models.push_back({"bunny", std::move(bunnyMesh)});
  models.push_back({"scattered-" + std::to_string(parts), generateScatteredParts(parts, 2, 7)});

  std::vector<Config> configs;
  {
    HybridOptions o;
    o.enablePoints = false;
    configs.push_back({"triangles only", o});
  }
  for (double kappa : {3.0, 10.0}) {
    for (double tau : {1.0, 5.0}) {
      HybridOptions o;
      o.kappa = kappa;
      o.tau = tau;
      char name[64];
      std::snprintf(name, sizeof(name), "kappa=%g tau=%g", kappa, tau);
      configs.push_back({name, o});
    }
  }
  const std::vector<double> relativeErrors = {0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2};

  std::printf("# bench_hybrid output\n\n");
  for (const Model& model : models) {
    std::printf("## %s (%zu input triangles)\n\n", model.name.c_str(), model.mesh.triangleCount());
    std::printf(
        "| configuration | input tris | graph tris | graph points | collapses | "
        "replacements | merges | build CPU s | build wall s "
        "|\n|---|---|---|---|---|---|---|---|---|\n");
    std::vector<std::vector<HybridCurveStep>> curves;
    std::vector<HybridGraph> graphs;
    for (const Config& c : configs) {
      std::cerr << model.name << ": " << c.name << "\n";
      const auto start = std::chrono::steady_clock::now();
      const double cpuStart = threadCpuSeconds();
      Result<HybridGraph> g = buildHybridGraph(model.mesh, c.options);
      const double cpu = threadCpuSeconds() - cpuStart;
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (!g.ok()) {
        std::cerr << g.status().toString() << "\n";
        return 1;
      }
      const HybridGraphStats& s = g->stats();
      std::printf("| %s | %zu | %zu | %zu | %zu | %zu | %zu | %.2f | %.2f |\n", c.name.c_str(),
                  s.inputTriangles, s.graphTriangles, s.graphPoints, s.edgeCollapses,
                  s.pointReplacements, s.pointMerges, cpu, seconds);
      curves.push_back(g->unitsVersusError());
      graphs.push_back(std::move(*g));
    }
    const double diagonal = graphs.front().diagonal();
    std::printf(
        "\nPrimitive units (triangles + points / kappa) of the cut at an object-space "
        "error bound (%% of the bbox diagonal %.4g):\n\n| error %% |",
        diagonal);
    for (const Config& c : configs) std::printf(" %s |", c.name.c_str());
    std::printf("\n|---|");
    for (std::size_t i = 0; i < configs.size(); ++i) std::printf("---|");
    std::printf("\n");
    for (double e : relativeErrors) {
      std::printf("| %.1f |", 100.0 * e);
      for (const auto& curve : curves) std::printf(" %.0f |", unitsAt(curve, e * diagonal));
      std::printf("\n");
    }
    std::printf(
        "\nMeasured two-sided Hausdorff distance of those cuts (sampled, %zu samples "
        "per side, %% of the diagonal) / stored bound of the cut:\n\n| error %% |",
        samples);
    for (const Config& c : configs) std::printf(" %s |", c.name.c_str());
    std::printf("\n|---|");
    for (std::size_t i = 0; i < configs.size(); ++i) std::printf("---|");
    std::printf("\n");
    SurfaceErrorOptions eo;
    eo.samplesPerMesh = samples;
    for (double e : {0.005, 0.02, 0.1}) {
      std::printf("| %.1f |", 100.0 * e);
      for (const HybridGraph& g : graphs) {
        HybridCut cut(g);
        cut.adaptToError(e * diagonal);
        Result<SurfaceError> m =
            measureHybridSurfaceError(model.mesh, cut.triangleMesh(), cut.pointList(), eo);
        if (!m.ok()) {
          std::cerr << m.status().toString() << "\n";
          return 1;
        }
        std::printf(" %.3f / %.3f |", 100.0 * m->max() / diagonal,
                    100.0 * cut.errorBound() / diagonal);
      }
      std::printf("\n");
    }
    // The footing of the service's curves (docs/hybrid.md, "Measured
    // curve"): every configuration's measured ladder, and the progressive
    // mesh the scheduler offers beside it (its measured curve).
    std::printf(
        "\nPrimitive units to reach a *measured* error (%% of the diagonal): the fewest units "
        "of a rung of the measured ladder (12 rungs, %zu samples per side) credited with at "
        "most that error, a rung credited with the worst error measured at it or any finer "
        "rung (the service's rule); last column the QEM progressive mesh's measured ladder "
        "(the mesh option):\n\n| measured error %% |",
        samples);
    for (const Config& c : configs) std::printf(" %s |", c.name.c_str());
    std::printf(" progressive mesh |\n|---|");
    for (std::size_t i = 0; i <= configs.size(); ++i) std::printf("---|");
    std::printf("\n");
    // (units, credited error) per column, increasing units.
    std::vector<std::vector<std::pair<double, double>>> ladders;
    auto credit = [](std::vector<std::pair<double, double>> rungs) {
      for (std::size_t i = rungs.size(); i-- > 1;)
        rungs[i - 1].second = std::max(rungs[i - 1].second, rungs[i].second);
      return rungs;
    };
    for (const HybridGraph& g : graphs) {
      Result<std::vector<HybridMeasuredLevel>> levels = measureHybridLevels(model.mesh, g, 12, eo);
      if (!levels.ok()) {
        std::cerr << levels.status().toString() << "\n";
        return 1;
      }
      std::vector<std::pair<double, double>> rungs;
      for (const HybridMeasuredLevel& l : *levels) rungs.push_back({l.step.units, l.measuredError});
      ladders.push_back(credit(rungs));
    }
    {
      Result<ProgressiveMesh> pm = ProgressiveMesh::build(model.mesh);
      if (!pm.ok()) {
        std::cerr << pm.status().toString() << "\n";
        return 1;
      }
      MeshCurveOptions mo;
      mo.levels = 12;
      mo.measureEncodedBytes = false;
      mo.error = eo;
      Result<MeshCurves> curves = measureMeshCurves(model.mesh, *pm, mo);
      if (!curves.ok()) {
        std::cerr << curves.status().toString() << "\n";
        return 1;
      }
      std::vector<std::pair<double, double>> rungs;
      for (const CurveLevel& l : curves->levels)
        rungs.push_back({static_cast<double>(l.triangles),
                         l.relativeMaxError * referenceLength(referenceSphere(model.mesh))});
      ladders.push_back(credit(rungs));
    }
    for (double e : {0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2}) {
      std::printf("| %.1f |", 100.0 * e);
      for (const auto& rungs : ladders) {
        double units = -1.0;
        for (const auto& [u, err] : rungs) {
          if (err <= e * diagonal) {
            units = u;
            break;
          }
        }
        if (units < 0.0) {
          std::printf(" - |");
        } else {
          std::printf(" %.0f |", units);
        }
      }
      std::printf("\n");
    }
    std::printf("\n");
  }
  return 0;
}
