// simplify: one mesh file to another at a triangle ratio or count, through
// ProgressiveMesh (build once, extract the requested resolution).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "tool_output.h"

namespace thinlod::simplifier::tool {
namespace {

struct SimplifyArgs {
  std::string input;
  std::string output;
  double ratio = -1.0;
  long long triangles = -1;
  bool json = false;
  bool binary = false;
  BuildOptions build;  // the options below are bound to it: its defaults are theirs
};

void runSimplify(const SimplifyArgs& args) {
  const std::string command = "simplify";
  nlohmann::json result = {{"command", command}, {"input", args.input}, {"output", args.output}};
  nlohmann::json timings = nlohmann::json::object();
  using Clock = std::chrono::steady_clock;

  if (!isSupportedMeshExtension(args.output)) {
    fail(command,
         Status(ErrorCode::kUnsupported,
                args.output + ": unknown mesh file extension (expected obj, ply, off, stl)"),
         args.json, result);
  }
  progressLine(command, "loading " + args.input);
  auto start = Clock::now();
  Result<LoadedMesh> loaded = loadMeshFile(args.input);
  if (!loaded.ok()) fail(command, loaded.status(), args.json, result);
  timings["load"] = millisecondsSince(start);
  for (const std::string& warning : loaded->warnings) progressLine(command, "warning: " + warning);
  const IndexedMesh& mesh = loaded->mesh;
  result["input_triangles"] = mesh.triangleCount();
  result["input_vertices"] = mesh.vertexCount();

  BuildOptions options = args.build;
  int lastDecile = -1;
  options.progress = [&](double fraction) {
    const int decile = static_cast<int>(fraction * 10.0);
    if (decile == lastDecile) return;
    lastDecile = decile;
    progressLine(command, "simplifying " + std::to_string(decile * 10) + "%");
  };
  progressLine(command, "building the progressive mesh of " + std::to_string(mesh.triangleCount()) +
                            " triangles");
  start = Clock::now();
  Result<ProgressiveMesh> built = ProgressiveMesh::build(mesh, options);
  if (!built.ok()) {
    fail(command, Status(built.status().code(), args.input + ": " + built.status().message()),
         args.json, result);
  }
  timings["build"] = millisecondsSince(start);
  const ProgressiveMesh& pm = built.value();

  const std::size_t target =
      args.triangles >= 0 ? static_cast<std::size_t>(args.triangles)
                          : static_cast<std::size_t>(
                                std::llround(args.ratio * static_cast<double>(pm.maxTriangles())));
  start = Clock::now();
  const IndexedMesh simplified = pm.extract(target);
  timings["extract"] = millisecondsSince(start);

  progressLine(command, "writing " + std::to_string(simplified.triangleCount()) + " triangles to " +
                            args.output);
  start = Clock::now();
  const Status saved = saveMeshFile(simplified, args.output, args.binary);
  if (!saved.ok()) fail(command, saved, args.json, result);
  timings["save"] = millisecondsSince(start);

  result["ok"] = true;
  result["cleaned_triangles"] = pm.maxTriangles();
  result["min_triangles"] = pm.minTriangles();
  result["target_triangles"] = target;
  result["output_triangles"] = simplified.triangleCount();
  result["output_vertices"] = simplified.vertexCount();
  result["quadric_error"] = pm.quadricErrorAt(target);
  result["progressive_mesh_bytes"] = pm.memoryBytes();
  result["timings_ms"] = timings;
  if (args.json) std::cout << result.dump(2) << std::endl;
  if (target < pm.minTriangles()) {
    progressLine(command, "note: " + std::to_string(target) + " triangles requested, " +
                              std::to_string(pm.minTriangles()) +
                              " is as far as the topology allows");
  }
}

}  // namespace

void addSimplifyCommand(CLI::App& app) {
  auto args = std::make_shared<SimplifyArgs>();
  CLI::App* sub = app.add_subcommand(
      "simplify", "Simplify a mesh file (OBJ, PLY, OFF, STL) to a triangle ratio or count");
  sub->add_option("input", args->input, "Input mesh file")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", args->output, "Output mesh file (format from the extension)")
      ->required();
  CLI::Option_group* size = sub->add_option_group("size", "How many triangles to keep");
  size->add_option("--ratio", args->ratio, "Fraction of the input triangles to keep, in (0, 1]")
      ->check(CLI::Range(0.0, 1.0))
      ->check(CLI::Validator(
          [](std::string& value) {
            return std::stod(value) > 0.0 ? std::string() : std::string("must be > 0");
          },
          "> 0"));
  size->add_option("--triangles", args->triangles, "Number of triangles to keep")
      ->check(CLI::NonNegativeNumber);
  size->require_option(1);
  sub->add_flag("--json", args->json, "Print timings, sizes and errors as JSON on stdout");
  sub->add_flag("--binary", args->binary, "Write PLY/STL in binary");
  sub->add_flag("!--no-boundaries", args->build.preserveBoundaries,
                "Do not add the boundary-preserving planes");
  sub->add_flag("!--allow-flips", args->build.preventFlips,
                "Do not reject collapses that flip faces");
  sub->add_option("--boundary-weight", args->build.boundaryWeight,
                  "Weight of the boundary planes relative to face planes")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--attribute-weight", args->build.attributeWeight,
                  "Attribute-aware cost for uvs/colors (0: off; 0.01: a full-range change costs "
                  "like 10% of the diagonal)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--weld-epsilon", args->build.weldEpsilon,
                  "Weld vertices closer than this fraction of the bbox diagonal")
      ->check(CLI::NonNegativeNumber);
  sub->callback([args] { runSimplify(*args); });
}

}  // namespace thinlod::simplifier::tool
