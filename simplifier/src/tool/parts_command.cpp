// parts: writes the generated multi-manifold model of the hybrid experiments
// (generateScatteredParts: separate closed bumpy icospheres in a unit box) to
// a mesh file, so scenes (the workbench's parts-fly case) can name it;
// positions only (no per-part colours, see below).
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "commands.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "tool_output.h"

namespace thinlod::simplifier::tool {
namespace {

struct PartsArgs {
  std::string output;
  int parts = 300;
  int level = 2;
  std::uint32_t seed = 7;
};

void runParts(const PartsArgs& args) {
  const std::string command = "parts";
  if (!isSupportedMeshExtension(args.output)) {
    fail(command,
         Status(ErrorCode::kUnsupported,
                args.output + ": unknown mesh file extension (expected obj, ply, off, stl)"),
         false);
  }
  IndexedMesh mesh = generateScatteredParts(args.parts, args.level, args.seed);
  // Without the per-part colours: a scene colours the model with its
  // Material, and the frontend's reference (full meshes) and its simplified
  // copies would otherwise disagree on whether vertex colours apply.
  mesh.colors.clear();
  const Status saved = saveMeshFile(mesh, args.output, true);
  if (!saved.ok()) fail(command, saved, false);
  progressLine(command, "wrote " + std::to_string(mesh.triangleCount()) + " triangles (" +
                            std::to_string(args.parts) + " parts) to " + args.output);
}

}  // namespace

void addPartsCommand(CLI::App& app) {
  auto args = std::make_shared<PartsArgs>();
  CLI::App* sub = app.add_subcommand(
      "parts", "Write the generated multi-manifold model (docs/hybrid.md) to a mesh file");
  sub->add_option("-o,--output", args->output, "Output mesh file (format from the extension)")
      ->required();
  sub->add_option("--parts", args->parts, "Separate closed parts")->check(CLI::Range(1, 100000));
  sub->add_option("--level", args->level, "Icosphere subdivision level of each part (20 * 4^level "
                                          "triangles)")
      ->check(CLI::Range(0, 5));
  sub->add_option("--seed", args->seed, "Random seed of sizes, places and bumps");
  sub->callback([args] { runParts(*args); });
}

}  // namespace thinlod::simplifier::tool
