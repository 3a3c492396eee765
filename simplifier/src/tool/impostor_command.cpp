// impostor: render a simple or meshed impostor of one mesh file offscreen
// (Pasman & Jansen section 3.6) and write its texture, its depth mesh, its
// validity range and the link-encoded sizes. The viewpoint is placed on a
// direction from the object's bounding-sphere centre, a number of radii away.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <glm/geometric.hpp>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/simplifier/impostor.h"
#include "tool_output.h"

namespace thinlod::simplifier::tool {
namespace {

struct ImpostorArgs {
  std::string input;
  std::string output;      // texture: raw RGBA frame in the link format (.tltx)
  std::string meshOutput;  // meshed: depth mesh (any mesh format mesh_io writes)
  bool meshed = false;
  MeshedImpostorOptions impostor;  // --size, --max-angular-error: its defaults are theirs
  double radii = 4.0;
  std::vector<float> direction{0.0f, 0.0f, 1.0f};
  std::string backend = render::backendName(render::Backend::kAuto);
  bool json = false;
};

Result<render::Backend> parseBackend(const std::string& name) {
  if (name == "auto") return render::Backend::kAuto;
  if (name == "egl") return render::Backend::kEgl;
  if (name == "osmesa") return render::Backend::kOsMesa;
  return Status(ErrorCode::kInvalidArgument, "--backend must be auto, egl or osmesa, not " + name);
}

nlohmann::json validityJson(const ConicRange& range) {
  return {{"center", {range.center().x, range.center().y, range.center().z}},
          {"distance",
           {range.minDistance(), std::isfinite(range.maxDistance())
                                     ? nlohmann::json(range.maxDistance())
                                     : nlohmann::json("inf")}},
          {"direction", {range.direction().x, range.direction().y, range.direction().z}},
          {"half_angle", range.alpha()}};
}

void runImpostor(const ImpostorArgs& args) {
  const std::string command = "impostor";
  nlohmann::json result = {{"command", command}, {"input", args.input}};
  nlohmann::json timings = nlohmann::json::object();
  using Clock = std::chrono::steady_clock;

  const glm::vec3 direction(args.direction[0], args.direction[1], args.direction[2]);
  const float length = glm::length(direction);
  if (!std::isfinite(length) || length <= 0.0f) {
    fail(command, Status(ErrorCode::kInvalidArgument, "--direction must be a non-zero vector"),
         args.json, result);
  }
  Result<render::Backend> backend = parseBackend(args.backend);
  if (!backend.ok()) fail(command, backend.status(), args.json, result);

  progressLine(command, "loading " + args.input);
  auto start = Clock::now();
  Result<LoadedMesh> loaded = loadMeshFile(args.input);
  if (!loaded.ok()) fail(command, loaded.status(), args.json, result);
  timings["load"] = millisecondsSince(start);
  auto mesh = std::make_shared<IndexedMesh>(std::move(loaded->mesh));
  if (mesh->normals.empty()) mesh->computeNormals();
  const BoundingSphere sphere = mesh->boundingSphere();
  const glm::vec3 eye =
      sphere.center + direction / length * static_cast<float>(args.radii) * sphere.radius;

  start = Clock::now();
  Result<std::unique_ptr<render::OffscreenContext>> context =
      render::createOffscreenContext(*backend, 16, 16);
  if (!context.ok()) fail(command, context.status(), args.json, result);
  Result<std::unique_ptr<ImpostorRenderer>> renderer = ImpostorRenderer::create(**context);
  if (!renderer.ok()) fail(command, renderer.status(), args.json, result);
  timings["context"] = millisecondsSince(start);
  result["backend"] = render::backendName((*context)->backend());

  ImpostorScene scene;
  scene.parts.push_back({mesh, glm::mat4(1.0f), render::Material{}});
  scene.lighting.lights.push_back({});  // one directional light along -Z
  const MeshedImpostorOptions& options = args.impostor;

  RgbaImage texture;
  ConicRange validity;
  progressLine(command, std::string("rendering a ") + (args.meshed ? "meshed" : "simple") +
                            " impostor, " + std::to_string(options.textureSize) + " texels");
  start = Clock::now();
  if (args.meshed) {
    Result<MeshedImpostor> impostor = (*renderer)->renderMeshed(scene, eye, options);
    if (!impostor.ok()) fail(command, impostor.status(), args.json, result);
    timings["render"] = millisecondsSince(start);
    texture = std::move(impostor->texture);
    validity = impostor->validity;
    result["mesh_triangles"] = impostor->mesh.triangleCount();
    result["coverage"] = impostor->coverage;
    if (!args.meshOutput.empty()) {
      Status saved = saveMeshFile(impostor->mesh, args.meshOutput);
      if (!saved.ok()) fail(command, saved, args.json, result);
    }
    Result<std::vector<std::uint8_t>> encodedMesh = codec::encodeMesh(impostor->mesh);
    if (encodedMesh.ok()) result["mesh_encoded_bytes"] = encodedMesh->size();
  } else {
    Result<SimpleImpostor> impostor = (*renderer)->renderSimple(scene, eye, options);
    if (!impostor.ok()) fail(command, impostor.status(), args.json, result);
    timings["render"] = millisecondsSince(start);
    texture = std::move(impostor->texture);
    validity = impostor->validity;
    result["coverage"] = impostor->coverage;
    result["quad"] = {{"width", impostor->quad.width}, {"height", impostor->quad.height}};
  }
  result["validity"] = validityJson(validity);

  // The link cost of the texture in each codec (the backbone schedules with these).
  nlohmann::json sizes = nlohmann::json::object();
  std::vector<std::uint8_t> zstdFrame;
  for (auto [name, textureCodec] : {std::pair{"zstd", codec::TextureCodec::kZstd},
                                    std::pair{"png", codec::TextureCodec::kPng}}) {
    start = Clock::now();
    Result<std::vector<std::uint8_t>> frame = codec::encodeTextureWith(texture, textureCodec);
    if (!frame.ok()) fail(command, frame.status(), args.json, result);
    timings[std::string("encode_") + name] = millisecondsSince(start);
    sizes[name] = frame->size();
    if (textureCodec == codec::TextureCodec::kZstd) zstdFrame = std::move(frame).value();
  }
  result["texture_encoded_bytes"] = sizes;
  if (!args.output.empty()) {
    std::ofstream out(args.output, std::ios::binary);
    out.write(reinterpret_cast<const char*>(zstdFrame.data()),
              static_cast<std::streamsize>(zstdFrame.size()));
    if (!out) {
      fail(command, Status(ErrorCode::kIoError, args.output + ": could not write the texture"),
           args.json, result);
    }
    progressLine(command, "wrote " + args.output + " (zstd texture frame, " +
                              std::to_string(zstdFrame.size()) + " bytes)");
  }
  result["ok"] = true;
  result["timings_ms"] = timings;
  if (args.json) std::cout << result.dump(2) << std::endl;
}

}  // namespace

void addImpostorCommand(CLI::App& app) {
  auto args = std::make_shared<ImpostorArgs>();
  CLI::App* sub = app.add_subcommand(
      "impostor", "Render a simple or meshed impostor of a mesh file and report its link cost");
  sub->add_option("input", args->input, "Input mesh file")->required()->check(CLI::ExistingFile);
  sub->add_option("-o,--output", args->output,
                  "Write the texture as a link-format zstd frame (decode with thinlod::codec)");
  sub->add_option("--mesh-output", args->meshOutput, "Meshed: write the depth mesh (OBJ/PLY/OFF)");
  sub->add_flag("--meshed", args->meshed, "Meshed impostor (texture + depth mesh)");
  sub->add_option("--size", args->impostor.textureSize, "Texture edge in texels")
      ->check(CLI::Range(8, 4096));
  sub->add_option("--radii", args->radii, "Viewpoint distance in bounding radii")
      ->check(CLI::Range(1.1, 1e6));
  sub->add_option("--direction", args->direction, "Direction from the centre to the viewpoint")
      ->expected(3);
  sub->add_option("--max-angular-error", args->impostor.maxAngularError,
                  "Radians: the bound the validity range guarantees")
      ->check(CLI::Range(1e-9, 3.2));
  sub->add_option("--backend", args->backend, "Offscreen back-end: auto, egl or osmesa");
  sub->add_flag("--json", args->json, "Print the result as JSON on stdout");
  sub->callback([args] { runImpostor(*args); });
}

}  // namespace thinlod::simplifier::tool
