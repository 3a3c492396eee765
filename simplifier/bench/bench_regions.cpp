// bench_regions: regions (ASLOD coarse view dependence, docs/regions.md)
// against one whole-mesh progressive mesh, in the same run:
// - build: RegionMesh (per-region QEM) vs ProgressiveMesh::build of the whole
//   mesh (thread CPU seconds);
// - triangles at equal error: every region at the same fraction of its
//   triangles, the assembled mesh's Hausdorff error (measureSurfaceError,
//   relative to the bbox diagonal), and the fewest whole-mesh triangles that
//   reach that error (bisection over extract(n));
// - per frame: assembleInto at random per-region levels (seeded) vs the bare
//   extractInto of the same region meshes (what the crack-free assembly adds:
//   ownership filter, foreign lookups, compaction) vs one whole-mesh
//   extractInto at the same triangle count;
// - border rules: coarsest triangles, and how many random frames are not a
//   closed manifold (kPaperUnchecked: the paper's rule, unguarded).
// Models: a 261 x 261 height-grid terrain cut into 6 x 6 grid regions (the
// paper's Silvretta set-up), Garland's cow and the Stanford bunny cut by
// recursive bisection. Prints a markdown report to stdout.
//   bench_regions [--models-dir DIR] [--frames N] [--samples N]
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/regions.h"
#include "thinlod/simplifier/surface_error.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Model {
  std::string name;
  IndexedMesh mesh;
  std::size_t regions = 0;
  std::vector<std::uint32_t> labels;  // empty: recursive bisection
};

// Height grid n x n over [0,1]^2, a few octaves of smooth bumps (deterministic).
Model makeTerrain(int n, int cells) {
  Model m;
  m.name = "terrain " + std::to_string(n) + "x" + std::to_string(n);
  m.regions = static_cast<std::size_t>(cells * cells);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float x = static_cast<float>(i) / static_cast<float>(n - 1);
      const float y = static_cast<float>(j) / static_cast<float>(n - 1);
      const float z = 0.08f * std::sin(6.1f * x) * std::cos(4.3f * y) +
                      0.03f * std::sin(17.0f * x + 3.0f * y) +
                      0.01f * std::cos(41.0f * y - 13.0f * x);
      m.mesh.positions.push_back({x, y, z});
      const int ci = std::min(cells - 1, i * cells / (n - 1));
      const int cj = std::min(cells - 1, j * cells / (n - 1));
      m.labels.push_back(static_cast<std::uint32_t>(cj * cells + ci));
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const std::uint32_t a = static_cast<std::uint32_t>(j * n + i), b = a + 1,
                          c = a + static_cast<std::uint32_t>(n), d = c + 1;
      m.mesh.indices.insert(m.mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return m;
}

Result<RegionMesh> buildRegions(const Model& m, BorderRule rule) {
  RegionBuildOptions options;
  options.borderRule = rule;
  if (m.labels.empty()) return RegionMesh::buildPartitioned(m.mesh, m.regions, options);
  return RegionMesh::build(m.mesh, m.labels, m.regions, options);
}

double relativeError(const IndexedMesh& original, const IndexedMesh& simplified,
                     std::size_t samples) {
  SurfaceErrorOptions options;
  options.samplesPerMesh = samples;
  Result<SurfaceError> e = measureSurfaceError(original, simplified, options);
  return e.ok() ? e->relativeMax() : -1.0;
}

// Fewest whole-mesh triangles whose error is <= target (bisection; error is
// close to monotone in the triangle count, the bisection assumes it).
std::size_t trianglesForError(const IndexedMesh& original, const ProgressiveMesh& pm, double target,
                              std::size_t samples) {
  std::size_t lo = pm.minTriangles(), hi = pm.maxTriangles();
  while (hi - lo > std::max<std::size_t>(2, hi / 200)) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (relativeError(original, pm.extract(mid), samples) <= target) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return pm.triangleCountAt(hi);
}

// Every directed edge once and its reverse present: each edge on exactly two
// consistently oriented triangles.
bool closedManifold(const IndexedMesh& mesh) {
  std::vector<std::uint64_t> directed;
  directed.reserve(mesh.indices.size());
  for (std::size_t i = 0; i < mesh.indices.size(); i += 3) {
    for (std::size_t k = 0; k < 3; ++k) {
      directed.push_back(std::uint64_t{mesh.indices[i + k]} << 32 | mesh.indices[i + (k + 1) % 3]);
    }
  }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  for (std::uint64_t e : directed) {
    const std::uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(directed.begin(), directed.end(), reverse)) return false;
  }
  return true;
}

// Smallest owned target of region r whose progressive-mesh collapse cost
// stays <= cost (quadricErrorAt is monotone in the target).
std::size_t regionTargetForCost(const RegionMesh& regions, std::size_t r, double cost) {
  const ProgressiveMesh& pm = regions.progressiveMesh(r);
  const std::size_t foreign = pm.maxTriangles() - regions.maxTriangles(r);
  std::size_t lo = regions.minTriangles(r), hi = regions.maxTriangles(r);
  if (pm.quadricErrorAt(lo + foreign) <= cost) return lo;
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (pm.quadricErrorAt(mid + foreign) <= cost) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"regions (coarse view dependence) vs one whole-mesh progressive mesh"};
  std::string modelsDir = std::string(THINLOD_SHARED_DIR) + "/models";
  int frames = 200;
  std::size_t samples = 30000;
  app.add_option("--models-dir", modelsDir, "directory with cow.obj and stanford-bunny.obj");
  app.add_option("--frames", frames, "random per-region level sets per model");
  app.add_option("--samples", samples, "surface samples per side for the measured error");
  CLI11_PARSE(app, argc, argv);

  std::vector<Model> models;
  models.push_back(makeTerrain(261, 6));
  for (auto [file, regions] : {std::pair{"cow.obj", 8}, std::pair{"stanford-bunny.obj", 16}}) {
    Result<LoadedMesh> loaded = loadMeshFile(modelsDir + "/" + file);
    if (!loaded.ok()) {
      std::cerr << loaded.status().toString() << "\n";
      return 1;
    }
    Model m;
    m.name = file;
    m.mesh.positions = loaded->mesh.positions;
    m.mesh.indices = loaded->mesh.indices;
    m.regions = static_cast<std::size_t>(regions);
    models.push_back(std::move(m));
  }

  std::printf("# bench_regions output\n\n");
  for (const Model& model : models) {
    std::cerr << model.name << ": build\n";
    double t0 = threadCpuSeconds();
    Result<ProgressiveMesh> whole = ProgressiveMesh::build(model.mesh);
    const double wholeSeconds = threadCpuSeconds() - t0;
    t0 = threadCpuSeconds();
    Result<RegionMesh> regions = buildRegions(model, BorderRule::kLowerIdSide);
    const double regionSeconds = threadCpuSeconds() - t0;
    if (!whole.ok() || !regions.ok()) {
      std::cerr << (whole.ok() ? regions.status() : whole.status()).toString() << "\n";
      return 1;
    }
    const IndexedMesh& original = regions->mesh();
    std::size_t kept = 0, minimum = 0;
    for (std::size_t r = 0; r < regions->regionCount(); ++r) {
      kept += regions->keptVertices(r);
      minimum += regions->minTriangles(r);
    }
    std::printf("## %s: %zu triangles, %zu regions\n\n", model.name.c_str(),
                original.triangleCount(), regions->regionCount());
    std::printf("| build | CPU s | coarsest triangles | kept vertices | memory MB |\n");
    std::printf("|---|---|---|---|---|\n");
    std::printf("| whole mesh (baseline) | %.3f | %zu | 0 | %.1f |\n", wholeSeconds,
                whole->minTriangles(), whole->memoryBytes() / 1e6);
    std::printf("| regions, lower-id side collapses | %.3f | %zu | %zu | %.1f |\n\n", regionSeconds,
                minimum, kept, regions->memoryBytes() / 1e6);

    std::cerr << model.name << ": equal error\n";
    std::printf(
        "Regions at the levels of one collapse-cost threshold (the whole mesh's cost at a "
        "fraction of its triangles; each region takes its smallest level within that cost) "
        "and, naively, every region at the same fraction of its triangles; against the fewest "
        "whole-mesh triangles with the same error (Hausdorff max / bbox diagonal, %zu samples "
        "per side):\n\n",
        samples);
    std::printf(
        "| allocation | fraction | region triangles | region error | whole-mesh triangles at "
        "that error | whole-mesh error at the region triangles |\n|---|---|---|---|---|---|\n");
    for (int byCost = 1; byCost >= 0; --byCost) {
      for (double fraction : {0.5, 0.2, 0.1, 0.05, 0.02}) {
        std::vector<std::size_t> levels;
        const double cost = whole->quadricErrorAt(
            static_cast<std::size_t>(std::lround(fraction * whole->maxTriangles())));
        for (std::size_t r = 0; r < regions->regionCount(); ++r) {
          levels.push_back(
              byCost ? regionTargetForCost(*regions, r, cost)
                     : static_cast<std::size_t>(std::lround(fraction * regions->maxTriangles(r))));
        }
        Result<IndexedMesh> assembled = regions->assemble(levels);
        if (!assembled.ok()) return 1;
        const double regionError = relativeError(original, *assembled, samples);
        const std::size_t equal = trianglesForError(original, *whole, regionError, samples);
        const double wholeError =
            relativeError(original, whole->extract(assembled->triangleCount()), samples);
        std::printf("| %s | %.2f | %zu | %.5f | %zu | %.5f |\n",
                    byCost ? "equal collapse cost" : "equal fraction", fraction,
                    assembled->triangleCount(), regionError, equal, wholeError);
      }
    }

    std::cerr << model.name << ": frames\n";
    std::mt19937 rng(42);
    std::vector<std::vector<std::size_t>> frameLevels;
    for (int f = 0; f < frames; ++f) {
      std::vector<std::size_t> levels;
      for (std::size_t r = 0; r < regions->regionCount(); ++r) {
        levels.push_back(std::uniform_int_distribution<std::size_t>(regions->minTriangles(r),
                                                                    regions->maxTriangles(r))(rng));
      }
      frameLevels.push_back(std::move(levels));
    }
    IndexedMesh out, scratch;
    AssembleStats stats;
    std::size_t triangles = 0;
    t0 = threadCpuSeconds();
    for (const auto& levels : frameLevels) {
      if (!regions->assembleInto(levels, out, &stats).ok()) return 1;
      triangles += out.triangleCount();
    }
    const double assembleSeconds = threadCpuSeconds() - t0;
    t0 = threadCpuSeconds();
    std::size_t bareTriangles = 0;
    for (const auto& levels : frameLevels) {
      for (std::size_t r = 0; r < regions->regionCount(); ++r) {
        // The region meshes' own targets (owned + the foreign-owned triangles
        // they also hold), as assembleInto extracts them.
        const std::size_t target =
            levels[r] >= regions->maxTriangles(r)
                ? regions->progressiveMesh(r).maxTriangles()
                : levels[r] + regions->progressiveMesh(r).maxTriangles() - regions->maxTriangles(r);
        regions->progressiveMesh(r).extractInto(target, scratch);
        bareTriangles += scratch.triangleCount();
      }
    }
    const double bareSeconds = threadCpuSeconds() - t0;
    t0 = threadCpuSeconds();
    for (const auto& levels : frameLevels) {
      std::size_t total = 0;
      for (std::size_t r = 0; r < levels.size(); ++r)
        total += regions->triangleCountAt(r, levels[r]);
      whole->extractInto(total, scratch);
    }
    const double wholeExtractSeconds = threadCpuSeconds() - t0;
    const double perFrame = 1e6 / frames;
    std::printf(
        "\nPer frame (%d frames, random per-region levels, seed 42; mean %.0f triangles, %.0f "
        "foreign lookups of which %.0f moved):\n\n",
        frames, static_cast<double>(triangles) / frames,
        static_cast<double>(stats.foreignLookups) / frames,
        static_cast<double>(stats.lookupsThatMoved) / frames);
    std::printf("| per frame | CPU us |\n|---|---|\n");
    std::printf("| whole-mesh extractInto, same triangles (baseline) | %.1f |\n",
                wholeExtractSeconds * perFrame);
    std::printf("| region extractInto only (no filter, no lookup) | %.1f |\n",
                bareSeconds * perFrame);
    std::printf("| assembleInto (crack-free: filter + lookup + compaction) | %.1f |\n",
                assembleSeconds * perFrame);
    std::printf("| crack-free overhead over bare extraction | %.1f |\n\n",
                (assembleSeconds - bareSeconds) * perFrame);
    (void)bareTriangles;

    std::cerr << model.name << ": border rules\n";
    std::printf(
        "| border rule | coarsest triangles | kept vertices | frames not a closed manifold |\n");
    std::printf("|---|---|---|---|\n");
    for (auto [rule, name] :
         {std::pair{BorderRule::kLowerIdSide, "lower-id side collapses"},
          std::pair{BorderRule::kBothSidesKept, "both sides kept"},
          std::pair{BorderRule::kPaperUnchecked, "paper (both sides, unchecked)"}}) {
      Result<RegionMesh> r = buildRegions(model, rule);
      if (!r.ok()) return 1;
      std::size_t k = 0;
      std::vector<std::size_t> coarsest(r->regionCount(), 0);
      for (std::size_t i = 0; i < r->regionCount(); ++i) k += r->keptVertices(i);
      Result<IndexedMesh> c = r->assemble(coarsest);
      if (!c.ok()) return 1;
      const bool openInput = !closedManifold(r->mesh());
      int bad = 0;
      std::mt19937 frameRng(42);
      for (int f = 0; f < frames && !openInput; ++f) {
        std::vector<std::size_t> levels;
        for (std::size_t i = 0; i < r->regionCount(); ++i) {
          levels.push_back(std::uniform_int_distribution<std::size_t>(
              r->minTriangles(i), r->maxTriangles(i))(frameRng));
        }
        Result<IndexedMesh> m = r->assemble(levels);
        if (!m.ok()) return 1;
        bad += closedManifold(*m) ? 0 : 1;
      }
      std::printf("| %s | %zu | %zu | %s |\n", name, c->triangleCount(), k,
                  openInput ? "n/a (open input)"
                            : (std::to_string(bad) + " / " + std::to_string(frames)).c_str());
    }
    std::printf("\n");
  }
  return 0;
}
