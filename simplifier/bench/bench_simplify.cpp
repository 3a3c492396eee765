// bench_simplify: time and surface error of thinlod's progressive mesh (one
// build, then extraction) against meshoptimizer's meshopt_simplify and
// OpenMesh's stock quadric decimater, in one run on the same inputs.
//
// Every method gets the same loaded mesh; the baselines get it welded by
// exact position first (untimed) so that seams from the loader do not become
// borders for them. Errors are measureSurfaceError (symmetric Hausdorff from
// surface samples, same options and seed for every method) against the loaded
// mesh, in % of its bounding-box diagonal. Times are thread CPU time, medians
// of --repeats runs (OpenMesh: one run, it takes seconds). Writes CSV, JSON
// and a markdown table to --out; progress goes to stderr.
// OpenMesh's VectorT leaves default-constructed data uninitialised on purpose;
// GCC then warns (-Wmaybe-uninitialized) inside OpenMesh: silenced for it only,
// as in common/include/thinlod/common/mesh/tri_mesh.h.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>
// clang-format off: OpenMesh wants MeshIO.hh before the kernel headers.
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
// clang-format on
#pragma GCC diagnostic pop

#include <meshoptimizer.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/surface_error.h"

namespace {

using thinlod::IndexedMesh;
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

double millisecondsOf(const std::function<void()>& work) {
  const double start = thinlod::threadCpuSeconds() * 1e3;
  work();
  return thinlod::threadCpuSeconds() * 1e3 - start;
}

// Median over `samples` of the mean time of `runsPerSample` back-to-back runs.
double medianMilliseconds(int samples, const std::function<void()>& work, int runsPerSample = 1) {
  std::vector<double> times;
  for (int i = 0; i < samples; ++i) {
    times.push_back(millisecondsOf([&] {
                      for (int r = 0; r < runsPerSample; ++r) work();
                    }) /
                    runsPerSample);
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

struct Row {
  std::string model;
  std::size_t inputTriangles = 0;
  double ratio = 0.0;  // 0 for the build row (all resolutions)
  std::string method;  // thinlod_build, thinlod_extract, thinlod_extract_into, meshopt, openmesh
  std::size_t targetTriangles = 0;
  std::size_t outputTriangles = 0;
  double milliseconds = 0.0;
  double maxErrorPercent = -1.0;  // -1: not measured (build rows)
  double meanErrorPercent = -1.0;
  std::size_t memoryBytes = 0;  // build rows: ProgressiveMesh::memoryBytes()
};

// Positions only, vertices with identical positions merged (what the
// baselines need to see the mesh's connectivity).
IndexedMesh weldedPositions(const IndexedMesh& mesh) {
  std::vector<unsigned int> remap(mesh.vertexCount());
  const std::size_t unique =
      meshopt_generateVertexRemap(remap.data(), mesh.indices.data(), mesh.indices.size(),
                                  mesh.positions.data(), mesh.vertexCount(), sizeof(glm::vec3));
  IndexedMesh out;
  out.positions.resize(unique);
  meshopt_remapVertexBuffer(out.positions.data(), mesh.positions.data(), mesh.vertexCount(),
                            sizeof(glm::vec3), remap.data());
  out.indices.resize(mesh.indices.size());
  meshopt_remapIndexBuffer(out.indices.data(), mesh.indices.data(), mesh.indices.size(),
                           remap.data());
  return out;
}

OmMesh toOpenMesh(const IndexedMesh& mesh, std::size_t& rejectedFaces) {
  OmMesh om;
  std::vector<OmMesh::VertexHandle> handles;
  handles.reserve(mesh.vertexCount());
  for (const glm::vec3& p : mesh.positions) handles.push_back(om.add_vertex({p.x, p.y, p.z}));
  rejectedFaces = 0;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const auto face = om.add_face(handles[mesh.indices[t]], handles[mesh.indices[t + 1]],
                                  handles[mesh.indices[t + 2]]);
    if (!face.is_valid()) ++rejectedFaces;  // non-manifold for OpenMesh's half-edges
  }
  return om;
}

IndexedMesh fromOpenMesh(const OmMesh& om) {
  IndexedMesh out;
  out.positions.reserve(om.n_vertices());
  for (const auto& v : om.vertices()) {
    const auto& p = om.point(v);
    out.positions.push_back({p[0], p[1], p[2]});
  }
  for (const auto& f : om.faces()) {
    for (const auto& v : om.fv_range(f)) out.indices.push_back(static_cast<std::uint32_t>(v.idx()));
  }
  return out;
}

struct Options {
  std::string modelsDir = std::string(THINLOD_SHARED_DIR) + "/models";
  // Every model in ../shared/models (the targets are per model).
  std::vector<std::string> models = {"cow.obj",         "stanford-bunny.obj", "horse.ply",
                                     "fandisk.obj",     "nefertiti.obj",      "ogre.obj",
                                     "spot.obj",        "teapot.obj",         "suzanne.obj",
                                     "cheburashka.obj", "woody.obj"};
  std::vector<double> ratios = {0.5, 0.1, 0.01};
  std::string outDir = "bench-results";
  int repeats = 5;
  int extractRepeats = 50;
  std::size_t samples = 100000;
  bool skipOpenMesh = false;
};

std::string percent(double v) {
  if (v < 0) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3f", v);
  return buffer;
}

std::string millis(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, v < 1.0 ? "%.4f" : "%.1f", v);
  return buffer;
}

std::string times(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1fx", v);
  return buffer;
}

// 1e-4 % of the bbox diagonal: about 16 float ulps of a coordinate there.
constexpr double kErrorFloorPercent = 1e-4;

const Row* findRow(const std::vector<Row>& rows, const std::string& model, double ratio,
                   const std::string& method) {
  for (const Row& r : rows) {
    if (r.model == model && r.method == method && r.ratio == ratio) return &r;
  }
  return nullptr;
}

int run(const Options& options, const std::string& commandLine) {
  std::vector<Row> rows;
  thinlod::simplifier::SurfaceErrorOptions errorOptions;
  errorOptions.samplesPerMesh = options.samples;
  for (const std::string& name : options.models) {
    const std::string path = options.modelsDir + "/" + name;
    std::cerr << "[bench] loading " << path << "\n";
    auto loaded = thinlod::loadMeshFile(path);
    if (!loaded.ok()) {
      std::cerr << "error: " << loaded.status().toString() << "\n";
      return 1;
    }
    const IndexedMesh& original = loaded->mesh;
    IndexedMesh input;  // positions + indices only: what every method simplifies
    input.positions = original.positions;
    input.indices = original.indices;
    const std::size_t triangles = input.triangleCount();

    auto measure = [&](Row& row, const IndexedMesh& simplified) {
      auto error = thinlod::simplifier::measureSurfaceError(input, simplified, errorOptions);
      if (!error.ok()) {
        std::cerr << "error: " << name << " " << row.method << ": " << error.status().toString()
                  << "\n";
        return;
      }
      row.maxErrorPercent = 100.0 * error->relativeMax();
      row.meanErrorPercent = 100.0 * error->relativeMean();
    };

    // Ours: build once (timed), then extract each ratio.
    std::cerr << "[bench] " << name << ": thinlod build\n";
    thinlod::simplifier::ProgressiveMesh pm;
    Row build{name, triangles, 0.0, "thinlod_build"};
    build.milliseconds = medianMilliseconds(options.repeats, [&] {
      auto built = thinlod::simplifier::ProgressiveMesh::build(input);
      if (!built.ok()) {
        std::cerr << "error: " << built.status().toString() << "\n";
        std::exit(1);
      }
      pm = std::move(built.value());
    });
    build.outputTriangles = pm.minTriangles();
    build.memoryBytes = pm.memoryBytes();
    rows.push_back(build);

    const IndexedMesh welded = weldedPositions(input);
    for (double ratio : options.ratios) {
      const std::size_t target = static_cast<std::size_t>(ratio * static_cast<double>(triangles));
      std::cerr << "[bench] " << name << " " << ratio * 100 << "%: thinlod extract\n";
      Row extract{name, triangles, ratio, "thinlod_extract", target};
      IndexedMesh extracted;
      extract.milliseconds = medianMilliseconds(
          5, [&] { extracted = pm.extract(target); }, options.extractRepeats);
      extract.outputTriangles = extracted.triangleCount();
      measure(extract, extracted);
      Row into{name, triangles, ratio, "thinlod_extract_into", target};
      IndexedMesh reused;
      into.milliseconds = medianMilliseconds(
          5, [&] { pm.extractInto(target, reused); }, options.extractRepeats);
      into.outputTriangles = reused.triangleCount();
      into.maxErrorPercent = extract.maxErrorPercent;  // same triangles
      into.meanErrorPercent = extract.meanErrorPercent;
      if (reused.indices != extracted.indices) {
        std::cerr << "error: extractInto differs from extract\n";
        return 1;
      }
      rows.push_back(extract);
      rows.push_back(into);

      std::cerr << "[bench] " << name << " " << ratio * 100 << "%: meshoptimizer\n";
      Row meshopt{name, triangles, ratio, "meshopt", target};
      IndexedMesh simplified;
      simplified.positions = welded.positions;
      meshopt.milliseconds = medianMilliseconds(options.repeats, [&] {
        simplified.indices.resize(welded.indices.size());
        float resultError = 0.0f;
        const std::size_t count = meshopt_simplify(
            simplified.indices.data(), welded.indices.data(), welded.indices.size(),
            &welded.positions[0].x, welded.vertexCount(), sizeof(glm::vec3), target * 3,
            /*target_error=*/1.0f, /*options=*/0, &resultError);
        simplified.indices.resize(count);
      });
      meshopt.outputTriangles = simplified.triangleCount();
      measure(meshopt, simplified);
      rows.push_back(meshopt);

      if (options.skipOpenMesh) continue;
      std::cerr << "[bench] " << name << " " << ratio * 100 << "%: OpenMesh decimater\n";
      Row openmesh{name, triangles, ratio, "openmesh", target};
      omerr().disable();  // add_face reports non-manifold faces there
      std::size_t rejected = 0;
      OmMesh om = toOpenMesh(welded, rejected);
      omerr().enable();
      if (rejected > 0) std::cerr << "[bench]   OpenMesh rejected " << rejected << " faces\n";
      openmesh.milliseconds = millisecondsOf([&] {
        OpenMesh::Decimater::DecimaterT<OmMesh> decimater(om);
        OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
        decimater.add(quadric);
        decimater.initialize();
        decimater.decimate_to_faces(0, target);
        om.garbage_collection();
      });
      const IndexedMesh decimated = fromOpenMesh(om);
      openmesh.outputTriangles = decimated.triangleCount();
      measure(openmesh, decimated);
      rows.push_back(openmesh);
    }
  }

  std::filesystem::create_directories(options.outDir);
  // CSV
  {
    std::ofstream csv(options.outDir + "/simplify.csv");
    csv << "model,input_triangles,ratio,method,target_triangles,output_triangles,time_ms,"
           "max_error_pct_diag,mean_error_pct_diag\n";
    for (const Row& r : rows) {
      csv << r.model << ',' << r.inputTriangles << ',' << r.ratio << ',' << r.method << ','
          << r.targetTriangles << ',' << r.outputTriangles << ',' << r.milliseconds << ','
          << r.maxErrorPercent << ',' << r.meanErrorPercent << '\n';
    }
  }
  // Summary against the targets of the simplifier issue.
  nlohmann::json summary = nlohmann::json::array();
  std::ostringstream md;
  md << "Command: `" << commandLine << "`\n\n";
  md << "Times: thread CPU ms, median of " << options.repeats
     << " runs (extraction: median of 5 means of " << options.extractRepeats
     << " runs; OpenMesh: one run). Errors: symmetric Hausdorff max / mean, % of bbox diagonal ("
     << options.samples << " samples per side plus vertices and edges).\n\n";
  md << "| model | ratio | tris (ours / mo / om) | build | extract | extractInto | meshopt | "
        "OpenMesh | extract speedup vs mo | build vs om | build / mo | err ours | err mo | "
        "err om |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& model : options.models) {
    const Row* build = findRow(rows, model, 0.0, "thinlod_build");
    if (build == nullptr) continue;
    for (double ratio : options.ratios) {
      const Row* ours = findRow(rows, model, ratio, "thinlod_extract");
      const Row* into = findRow(rows, model, ratio, "thinlod_extract_into");
      const Row* mo = findRow(rows, model, ratio, "meshopt");
      const Row* om = findRow(rows, model, ratio, "openmesh");
      if (!ours || !into || !mo) continue;
      nlohmann::json entry = {
          {"model", model},
          {"ratio", ratio},
          {"build_ms", build->milliseconds},
          {"built_bytes_per_input_triangle",
           static_cast<double>(build->memoryBytes) / static_cast<double>(build->inputTriangles)},
          {"extract_ms", ours->milliseconds},
          {"extract_into_ms", into->milliseconds},
          {"meshopt_ms", mo->milliseconds},
          {"extract_speedup_vs_meshopt", mo->milliseconds / ours->milliseconds},
          {"build_over_meshopt", build->milliseconds / mo->milliseconds},
          {"ours_triangles", ours->outputTriangles},
          {"meshopt_triangles", mo->outputTriangles},
          {"ours_max_pct", ours->maxErrorPercent},
          {"ours_mean_pct", ours->meanErrorPercent},
          {"meshopt_max_pct", mo->maxErrorPercent},
          {"meshopt_mean_pct", mo->meanErrorPercent}};
      double bestMax = mo->maxErrorPercent, bestMean = mo->meanErrorPercent;
      if (om) {
        entry["openmesh_ms"] = om->milliseconds;
        entry["openmesh_triangles"] = om->outputTriangles;
        entry["build_speedup_vs_openmesh"] = om->milliseconds / build->milliseconds;
        entry["openmesh_max_pct"] = om->maxErrorPercent;
        entry["openmesh_mean_pct"] = om->meanErrorPercent;
        bestMax = std::min(bestMax, om->maxErrorPercent);
        bestMean = std::min(bestMean, om->meanErrorPercent);
      }
      // Errors below kErrorFloorPercent are rounding noise of float positions
      // (woody at 50%: every method's error is ~1e-7 of the diagonal); the
      // ratios clamp both sides there so that noise is not a win or a miss.
      auto ratioOf = [](double ours, double best) {
        return std::max(ours, kErrorFloorPercent) / std::max(best, kErrorFloorPercent);
      };
      entry["max_error_over_best_baseline"] = ratioOf(ours->maxErrorPercent, bestMax);
      entry["mean_error_over_best_baseline"] = ratioOf(ours->meanErrorPercent, bestMean);
      summary.push_back(entry);
      md << "| " << model << " | " << ratio * 100 << "% | " << ours->outputTriangles << " / "
         << mo->outputTriangles << " / " << (om ? std::to_string(om->outputTriangles) : "-")
         << " | " << millis(build->milliseconds) << " | " << millis(ours->milliseconds) << " | "
         << millis(into->milliseconds) << " | " << millis(mo->milliseconds) << " | "
         << (om ? millis(om->milliseconds) : "-") << " | "
         << times(mo->milliseconds / ours->milliseconds) << " | "
         << (om ? times(om->milliseconds / build->milliseconds) : "-") << " | "
         << times(build->milliseconds / mo->milliseconds) << " | " << percent(ours->maxErrorPercent)
         << " / " << percent(ours->meanErrorPercent) << " | " << percent(mo->maxErrorPercent)
         << " / " << percent(mo->meanErrorPercent) << " | "
         << (om ? percent(om->maxErrorPercent) + " / " + percent(om->meanErrorPercent) : "-")
         << " |\n";
    }
  }
  md << "\nBuilt structure (ProgressiveMesh::memoryBytes, positions only as above):\n\n";
  md << "| model | input tris | build ms | bytes | bytes / input triangle "
        "|\n|---|---|---|---|---|\n";
  for (const std::string& model : options.models) {
    const Row* build = findRow(rows, model, 0.0, "thinlod_build");
    if (build == nullptr) continue;
    char line[200];
    std::snprintf(
        line, sizeof line, "| %s | %zu | %s | %zu | %.1f |\n", model.c_str(), build->inputTriangles,
        millis(build->milliseconds).c_str(), build->memoryBytes,
        static_cast<double>(build->memoryBytes) / static_cast<double>(build->inputTriangles));
    md << line;
  }
  // Targets of the simplifier issue, over every (model, ratio) row.
  double logMax = 0.0, logMean = 0.0, minExtractSpeedup = 1e300, maxBuildOverMeshopt = 0.0;
  double minBuildVsOpenMesh = 1e300;
  int withinError = 0;
  int atOrBelow = 0;  // the target: both errors <= the better baseline
  for (const nlohmann::json& e : summary) {
    logMax += std::log(e["max_error_over_best_baseline"].get<double>());
    logMean += std::log(e["mean_error_over_best_baseline"].get<double>());
    minExtractSpeedup = std::min(minExtractSpeedup, e["extract_speedup_vs_meshopt"].get<double>());
    maxBuildOverMeshopt = std::max(maxBuildOverMeshopt, e["build_over_meshopt"].get<double>());
    if (e.contains("build_speedup_vs_openmesh")) {
      minBuildVsOpenMesh =
          std::min(minBuildVsOpenMesh, e["build_speedup_vs_openmesh"].get<double>());
    }
    if (e["max_error_over_best_baseline"].get<double>() <= 1.1 &&
        e["mean_error_over_best_baseline"].get<double>() <= 1.1) {
      ++withinError;
    }
    if (e["max_error_over_best_baseline"].get<double>() <= 1.0 &&
        e["mean_error_over_best_baseline"].get<double>() <= 1.0) {
      ++atOrBelow;
    }
  }
  const double rowCount = std::max<double>(1.0, static_cast<double>(summary.size()));
  nlohmann::json targets = {{"min_extract_speedup_vs_meshopt", minExtractSpeedup},
                            {"max_build_over_meshopt", maxBuildOverMeshopt},
                            {"geomean_max_error_over_best_baseline", std::exp(logMax / rowCount)},
                            {"geomean_mean_error_over_best_baseline", std::exp(logMean / rowCount)},
                            {"rows_within_10pct_of_best_baseline", withinError},
                            {"rows_at_or_below_best_baseline", atOrBelow},
                            {"rows", summary.size()}};
  md << "\nTargets over all " << summary.size()
     << " rows: extraction speedup vs meshopt >= " << times(minExtractSpeedup)
     << " (target 100x); build / meshopt <= " << times(maxBuildOverMeshopt) << " (target 3x)";
  if (minBuildVsOpenMesh < 1e300) {
    targets["min_build_speedup_vs_openmesh"] = minBuildVsOpenMesh;
    md << "; build vs OpenMesh >= " << times(minBuildVsOpenMesh) << " (target 10x)";
  }
  char errorLine[300];
  std::snprintf(errorLine, sizeof errorLine,
                "; error / better baseline, geometric mean: max %.3f, mean %.3f; rows with both "
                "at or below the better baseline: %d of %zu; both within 10%%: %d of %zu.\n",
                std::exp(logMax / rowCount), std::exp(logMean / rowCount), atOrBelow,
                summary.size(), withinError, summary.size());
  md << errorLine;
  nlohmann::json json = {{"command", commandLine}, {"summary", summary}, {"targets", targets}};
  nlohmann::json jsonRows = nlohmann::json::array();
  for (const Row& r : rows) {
    jsonRows.push_back({{"model", r.model},
                        {"input_triangles", r.inputTriangles},
                        {"ratio", r.ratio},
                        {"method", r.method},
                        {"target_triangles", r.targetTriangles},
                        {"output_triangles", r.outputTriangles},
                        {"time_ms", r.milliseconds},
                        {"max_error_pct_diag", r.maxErrorPercent},
                        {"mean_error_pct_diag", r.meanErrorPercent},
                        {"memory_bytes", r.memoryBytes}});
  }
  json["rows"] = jsonRows;
  std::ofstream(options.outDir + "/simplify.json") << json.dump(2) << "\n";
  std::ofstream(options.outDir + "/simplify.md") << md.str();
  std::cout << md.str();
  std::cerr << "[bench] wrote " << options.outDir << "/simplify.{csv,json,md}\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Time and error of thinlod's progressive mesh vs meshoptimizer and OpenMesh"};
  Options options;
  app.add_option("--models-dir", options.modelsDir, "Directory of the shared models");
  app.add_option("--models", options.models, "Model files inside --models-dir");
  app.add_option("--ratios", options.ratios, "Target triangle ratios")->check(CLI::Range(0.0, 1.0));
  app.add_option("--out", options.outDir, "Directory for simplify.csv/.json/.md");
  app.add_option("--repeats", options.repeats, "Timing repeats (median)")
      ->check(CLI::PositiveNumber);
  app.add_option("--extract-repeats", options.extractRepeats, "Extraction timing repeats")
      ->check(CLI::PositiveNumber);
  app.add_option("--samples", options.samples, "Surface samples per mesh for the error")
      ->check(CLI::PositiveNumber);
  app.add_flag("--skip-openmesh", options.skipOpenMesh, "Leave out the slow OpenMesh baseline");
  CLI11_PARSE(app, argc, argv);
  std::string commandLine;
  for (int i = 0; i < argc; ++i) {
    if (i > 0) commandLine += ' ';
    commandLine += i == 0 ? std::filesystem::path(argv[0]).filename().string() : argv[i];
  }
  return run(options, commandLine);
}
