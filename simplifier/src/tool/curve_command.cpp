// curve: the measured accuracy curves of one mesh file (Pasman & Jansen
// section 3.2): build the progressive mesh, extract a geometric ladder of
// resolutions, measure each one's symmetric Hausdorff error, fit the
// triangles and encoded-bytes curves (measureMeshCurves).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.h"
#include "thinlod/common/core/parallel_for.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "tool_output.h"

namespace thinlod::simplifier::tool {
namespace {

struct CurveArgs {
  std::string input;
  std::string output;      // optional: the curves as JSON (the curve cache format)
  MeshCurveOptions curve;  // the options below are bound to it: its defaults are theirs
  bool json = false;
};

nlohmann::json triplesOf(const AccuracyCurve& curve) {
  nlohmann::json triples = nlohmann::json::array();
  for (const CurveTriple& t : curve.triples())
    triples.push_back({{"A", t.A}, {"R", t.R}, {"K", t.K}});
  return {{"triples", triples}, {"maxAccuracy", curve.empty() ? 0.0 : curve.maxAccuracy()}};
}

void runCurve(const CurveArgs& args) {
  const std::string command = "curve";
  nlohmann::json result = {{"command", command}, {"input", args.input}};
  nlohmann::json timings = nlohmann::json::object();
  using Clock = std::chrono::steady_clock;

  progressLine(command, "loading " + args.input);
  auto start = Clock::now();
  Result<LoadedMesh> loaded = loadMeshFile(args.input);
  if (!loaded.ok()) fail(command, loaded.status(), args.json, result);
  timings["load"] = millisecondsSince(start);
  const IndexedMesh& mesh = loaded->mesh;
  result["input_triangles"] = mesh.triangleCount();

  progressLine(command, "building the progressive mesh");
  start = Clock::now();
  Result<ProgressiveMesh> built = ProgressiveMesh::build(mesh);
  if (!built.ok()) {
    fail(command, Status(built.status().code(), args.input + ": " + built.status().message()),
         args.json, result);
  }
  timings["build"] = millisecondsSince(start);

  const MeshCurveOptions& options = args.curve;
  progressLine(command, "measuring " + std::to_string(options.levels) + " levels (" +
                            std::to_string(options.error.samplesPerMesh) + " samples per side, " +
                            std::to_string(resolveThreadCount(options.threads)) + " threads)");
  start = Clock::now();
  Result<MeshCurves> curves = measureMeshCurves(mesh, built.value(), options);
  if (!curves.ok()) fail(command, curves.status(), args.json, result);
  timings["measure"] = millisecondsSince(start);

  nlohmann::json levels = nlohmann::json::array();
  for (const CurveLevel& level : curves->levels) {
    levels.push_back({{"triangles", level.triangles},
                      {"relative_max_error", level.relativeMaxError},
                      {"relative_hausdorff_error", level.relativeHausdorffError},
                      {"relative_texture_error", level.relativeTextureError},
                      {"relative_mean_error", level.relativeMeanError},
                      {"accuracy", level.accuracy},
                      {"encoded_bytes", level.encodedBytes},
                      {"position_bits", level.positionBits}});
    char line[160];
    std::snprintf(line, sizeof line,
                  "%8zu triangles  max error %.4f%%  mean %.5f%%  accuracy %.1f  %zu bytes",
                  level.triangles, 100.0 * level.relativeMaxError, 100.0 * level.relativeMeanError,
                  level.accuracy, level.encodedBytes);
    progressLine(command, line);
  }
  if (!args.output.empty()) {
    std::ofstream out(args.output);
    out << serializeMeshCurves(
        *curves, meshCurveCacheKey(mesh, "qem thinlod-simplifier curve", built->minTriangles(),
                                   built->maxTriangles(), options));
    if (!out) {
      fail(command, Status(ErrorCode::kIoError, args.output + ": could not write the curves"),
           args.json, result);
    }
    progressLine(command, "wrote " + args.output);
  }
  result["ok"] = true;
  result["levels"] = levels;
  result["triangles_curve"] = triplesOf(curves->triangles);
  if (options.measureEncodedBytes) result["bytes_curve"] = triplesOf(curves->bytes);
  result["timings_ms"] = timings;
  if (args.json) std::cout << result.dump(2) << std::endl;
}

}  // namespace

void addCurveCommand(CLI::App& app) {
  auto args = std::make_shared<CurveArgs>();
  CLI::App* sub = app.add_subcommand(
      "curve", "Measure the accuracy curves (triangles and encoded bytes) of a mesh file");
  sub->add_option("input", args->input, "Input mesh file")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", args->output, "Write the curves as JSON to this file");
  sub->add_option("--levels", args->curve.levels, "Resolutions measured (geometric ladder)")
      ->check(CLI::Range(2, 64));
  sub->add_option("--segments", args->curve.maxSegments, "Segments of each fitted curve")
      ->check(CLI::Range(1, 64));
  sub->add_option("--samples", args->curve.error.samplesPerMesh,
                  "Surface samples per side for the error")
      ->check(CLI::Range(std::size_t{100}, std::size_t{10'000'000}));
  sub->add_flag("!--no-bytes", args->curve.measureEncodedBytes, "Skip the encoded-bytes curve");
  args->curve.threads = 0;  // the tool, like the daemon, measures on every core
  sub->add_option("--threads", args->curve.threads,
                  "Levels measured at once (0: one per hardware thread); the curves are the "
                  "same for any count")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  sub->add_flag("--json", args->json, "Print levels, curves and timings as JSON on stdout");
  sub->callback([args] { runCurve(*args); });
}

}  // namespace thinlod::simplifier::tool
