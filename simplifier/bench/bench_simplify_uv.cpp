// bench_simplify_uv: textured-mesh simplification, ours against
// meshoptimizer in one run on the same inputs: geometric error (symmetric
// Hausdorff, measureSurfaceError) and uv error (measureUvError, defined in
// surface_error.h and docs/simplifier.md "UV error") at 50 / 10 / 1 % of the
// triangles, and how many seam edges tore open.
//
// Methods (every one gets the same input, welded by exact (position, uv)):
//   ours         ProgressiveMesh, default options (seams kept, no attribute term)
//   ours+attr    ... with attribute quadrics (attributeWeight = --attribute-weight)
//   ours-welded  ... with preserveSeams = false (what the progressive mesh did before:
//                vertices welded by position, one side's uv kept)
//   meshopt      meshopt_simplify of the installed meshoptimizer (0.18 on Debian 12:
//                it keeps seams by its own position remap; it has no attribute-aware
//                simplifier, meshopt_simplifyWithAttributes came in 0.20), target error
//                1.0 so that only the triangle count stops it
// Models: the package assimp-testmodels' textured files (Collada duck, glTF2
// BoxTextured, OBJ spider, Collada earthCylindrical), the shared spot.obj,
// the primitive sphere (one meridian seam) and a generated seam-rich
// charted sphere (tests/simplifier/qem_test_meshes.h). A model that is
// missing or has no uvs is reported and skipped.
// Prints a markdown table (stdout); progress on stderr. Not timed.
#include <meshoptimizer.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "qem_test_meshes.h"
#include "test_meshes.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/common/scene/scene_import.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/surface_error.h"

namespace {

using thinlod::IndexedMesh;
using thinlod::Result;
using thinlod::simplifier::BuildOptions;
using thinlod::simplifier::ProgressiveMesh;

struct Model {
  std::string name;
  IndexedMesh mesh;
};

// Positions and uvs only, vertices with equal (position, uv) merged.
IndexedMesh weldPositionUv(const IndexedMesh& in) {
  struct Vertex {
    float p[3];
    float uv[2];
  };
  std::vector<Vertex> vertices(in.vertexCount());
  for (std::size_t v = 0; v < in.vertexCount(); ++v) {
    vertices[v] = {{in.positions[v].x, in.positions[v].y, in.positions[v].z},
                   {in.uvs[v].x, in.uvs[v].y}};
  }
  std::vector<unsigned> remap(in.vertexCount());
  const std::size_t unique =
      meshopt_generateVertexRemap(remap.data(), in.indices.data(), in.indices.size(),
                                  vertices.data(), vertices.size(), sizeof(Vertex));
  IndexedMesh out;
  out.positions.resize(unique);
  out.uvs.resize(unique);
  for (std::size_t v = 0; v < in.vertexCount(); ++v) {
    if (remap[v] == ~0u) continue;
    out.positions[remap[v]] = in.positions[v];
    out.uvs[remap[v]] = in.uvs[v];
  }
  out.indices.resize(in.indices.size());
  meshopt_remapIndexBuffer(out.indices.data(), in.indices.data(), in.indices.size(), remap.data());
  return out;
}

// Edges between places (positions) not used by exactly two triangles.
int openPlaceEdges(const IndexedMesh& mesh) {
  using Place = std::array<float, 3>;
  std::map<std::pair<Place, Place>, int> counts;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = mesh.positions[mesh.indices[t + k]];
      const glm::vec3& q = mesh.positions[mesh.indices[t + (k + 1) % 3]];
      Place a{p.x, p.y, p.z}, b{q.x, q.y, q.z};
      if (b < a) std::swap(a, b);
      ++counts[{a, b}];
    }
  }
  int open = 0;
  for (const auto& entry : counts) open += entry.second != 2 ? 1 : 0;
  return open;
}

void addImported(std::vector<Model>& models, const std::string& name, const std::string& path) {
  if (!std::filesystem::exists(path)) {
    std::cerr << name << ": " << path << " is missing, skipped\n";
    return;
  }
  Result<thinlod::LoadedMesh> loaded = thinlod::scene::importSceneAsMesh(path);
  if (!loaded.ok()) {
    std::cerr << name << ": " << loaded.status().toString() << ", skipped\n";
    return;
  }
  if (loaded->mesh.uvs.empty()) {
    std::cerr << name << ": no uvs, skipped\n";
    return;
  }
  models.push_back({name, weldPositionUv(loaded->mesh)});
}

struct Row {
  std::string method;
  std::size_t triangles = 0;
  double geometricMaxPct = 0, geometricMeanPct = 0;
  double uvMean = 0, uvP95 = 0;
  double displacementMeanPct = 0, displacementP95Pct = 0, displacementMaxPct = 0;
  int openEdges = 0;
};

Row measure(const std::string& method, const IndexedMesh& input, const IndexedMesh& out,
            std::size_t samples) {
  Row row;
  row.method = method;
  row.triangles = out.triangleCount();
  thinlod::simplifier::SurfaceErrorOptions geometric;
  geometric.samplesPerMesh = samples;
  Result<thinlod::simplifier::SurfaceError> g =
      thinlod::simplifier::measureSurfaceError(input, out, geometric);
  thinlod::simplifier::UvErrorOptions uv;
  uv.samples = samples;
  Result<thinlod::simplifier::UvError> u = thinlod::simplifier::measureUvError(input, out, uv);
  if (!g.ok() || !u.ok()) {
    std::cerr << method << ": " << (g.ok() ? u.status() : g.status()).toString() << "\n";
    row.geometricMaxPct = NAN;
    return row;
  }
  row.geometricMaxPct = 100.0 * g->relativeMax();
  row.geometricMeanPct = 100.0 * g->relativeMean();
  row.uvMean = u->meanUv;
  row.uvP95 = u->p95Uv;
  row.displacementMeanPct = 100.0 * u->meanDisplacement / u->diagonal;
  row.displacementP95Pct = 100.0 * u->p95Displacement / u->diagonal;
  row.displacementMaxPct = 100.0 * u->maxDisplacement / u->diagonal;
  row.openEdges = openPlaceEdges(out);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "bench_simplify_uv: uv and geometric error of textured-mesh simplification, "
      "ours vs meshoptimizer"};
  std::string packageDir = "/usr/share/assimp/models";
  std::string modelsDir = std::string(THINLOD_SHARED_DIR) + "/models";
  std::size_t samples = 50000;
  float attributeWeight = 0.01f;
  app.add_option("--package-dir", packageDir, "assimp-testmodels' model folder");
  app.add_option("--models-dir", modelsDir, "shared models (spot.obj)");
  app.add_option("--samples", samples, "surface samples per measurement")
      ->check(CLI::PositiveNumber);
  app.add_option("--attribute-weight", attributeWeight, "attributeWeight of ours+attr")
      ->check(CLI::PositiveNumber);
  std::vector<double> ratios = {0.5, 0.1, 0.01};
  app.add_option("--ratios", ratios, "target fractions of the input's triangles");
  std::string only;
  app.add_option("--only", only, "run only the models whose name contains this");
  CLI11_PARSE(app, argc, argv);

  std::vector<Model> models;
  addImported(models, "duck (Collada)", packageDir + "/Collada/duck.dae");
  addImported(models, "BoxTextured (glTF2)",
              packageDir + "/glTF2/BoxTextured-glTF/BoxTextured.gltf");
  addImported(models, "spider (OBJ)", packageDir + "/OBJ/spider.obj");
  addImported(models, "earthCylindrical (Collada)", packageDir + "/Collada/earthCylindrical.DAE");
  addImported(models, "spot (shared)", modelsDir + "/spot.obj");
  models.push_back({"primitive sphere 128x64",
                    weldPositionUv(thinlod::tessellate(thinlod::PrimitiveShape::sphere(1.0f),
                                                       thinlod::TessellationParams{128, 64}))});
  models.push_back({"charted sphere (generated)",
                    weldPositionUv(thinlod::qemtest::makeChartedSphere(3, 16, 0.08f).mesh)});

  std::printf(
      "meshoptimizer %d.%d (meshopt_simplify; no attribute-aware simplifier in this "
      "version), %zu samples per measurement, ours+attr attributeWeight %g\n\n",
      MESHOPTIMIZER_VERSION / 1000, (MESHOPTIMIZER_VERSION % 1000) / 10, samples,
      static_cast<double>(attributeWeight));
  std::printf(
      "| model (triangles, open place edges) | target | method | triangles | geom max %% | "
      "geom mean %% | uv mean | uv p95 | texel displ. mean %% | p95 %% | max %% | "
      "open place edges |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Model& model : models) {
    if (!only.empty() && model.name.find(only) == std::string::npos) continue;
    const IndexedMesh& input = model.mesh;
    std::cerr << model.name << ": " << input.triangleCount() << " triangles\n";
    BuildOptions attr;
    attr.attributeWeight = attributeWeight;
    BuildOptions welded;
    welded.preserveSeams = false;
    struct Ours {
      const char* name;
      BuildOptions options;
    };
    std::vector<std::pair<std::string, ProgressiveMesh>> pms;
    for (const Ours& o :
         {Ours{"ours", BuildOptions{}}, Ours{"ours+attr", attr}, Ours{"ours-welded", welded}}) {
      Result<ProgressiveMesh> pm = ProgressiveMesh::build(input, o.options);
      if (!pm.ok()) {
        std::cerr << model.name << " " << o.name << ": " << pm.status().toString() << "\n";
        continue;
      }
      pms.emplace_back(o.name, std::move(pm.value()));
    }
    const int inputOpen = openPlaceEdges(input);
    for (double ratio : ratios) {
      const std::size_t target = std::max<std::size_t>(
          1, static_cast<std::size_t>(
                 std::lround(ratio * static_cast<double>(input.triangleCount()))));
      std::vector<Row> rows;
      for (const auto& [name, pm] : pms)
        rows.push_back(measure(name, input, pm.extract(target), samples));
      IndexedMesh mo = thinlod::testing::simplifyWithMeshoptimizer(input, target);
      mo.uvs = input.uvs;  // meshoptimizer's indices refer to the input's vertices
      rows.push_back(measure("meshopt", input, mo, samples));
      for (const Row& r : rows) {
        std::printf(
            "| %s (%zu, %d) | %.0f%% (%zu) | %s | %zu | %.3f | %.4f | %.5f | %.5f | %.4f | "
            "%.3f | %.3f | %d |\n",
            model.name.c_str(), input.triangleCount(), inputOpen, 100.0 * ratio, target,
            r.method.c_str(), r.triangles, r.geometricMaxPct, r.geometricMeanPct, r.uvMean, r.uvP95,
            r.displacementMeanPct, r.displacementP95Pct, r.displacementMaxPct, r.openEdges);
      }
      std::fflush(stdout);
    }
  }
  return 0;
}
