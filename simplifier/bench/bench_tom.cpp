// bench_tom: the project's progressive mesh measured as Gobbetti & Bouvier
// (1999, section 3) measure their TOM (totally ordered mesh), on the paper's
// three meshes (Stanford bunny, Hoppe's fandisk, Garland's cow):
// 1. memory against a plain face-vertex mesh (positions + normals, 32-bit
//    floats and indices) and against a typical LOD chain (5 face-vertex
//    levels: 1, 1/2, 1/4, 1/8, 1/16 of the triangles, extracted from the same
//    order): ProgressiveMesh::memoryBytes (what our structure holds) and the
//    paper's own accounting (face-vertex + one vertex index per vertex);
// 2. vertices traversed per extracted triangle across resolutions
//    (ProgressiveMesh::traversedVerticesAt: corners plus substitution-chain
//    hops; the paper's "extra vertices traversed" = traversed / (3 T) - 1);
// 3. rates across resolutions (triangles/s, median of --frames): TOM
//    traversal alone (extractInto into reused buffers), TOM rendering
//    (extract + replicate + upload + draw each frame) and streamlined rendering (the same
//    resolution uploaded once and drawn), with K copies of the mesh merged
//    into one mesh (one draw call) so one frame holds about --frame-triangles
//    triangles, shrunk to a few pixels so fill does not bound it (the
//    paper's set-up); GL is EGL or OSMesa.
//
//   bench_tom --backend osmesa
//
// Output: three markdown tables on stdout.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"
#include "thinlod/simplifier/progressive_mesh.h"

using namespace thinlod;
using Clock = std::chrono::steady_clock;

namespace {

template <typename T>
T orDie(Result<T> result, const char* what) {
  if (!result.ok()) {
    std::fprintf(stderr, "bench_tom: %s: %s\n", what, result.status().toString().c_str());
    std::exit(1);
  }
  return std::move(result).value();
}
void orDie(const Status& status, const char* what) {
  if (!status.ok()) {
    std::fprintf(stderr, "bench_tom: %s: %s\n", what, status.toString().c_str());
    std::exit(1);
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Face-vertex bytes: position + normal per vertex, three 32-bit indices per triangle.
double faceVertexBytes(std::size_t vertices, std::size_t triangles) {
  return double(vertices) * 24.0 + double(triangles) * 12.0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"thinlod TOM measures (Gobbetti-Bouvier 1999, section 3)"};
  std::string backendName = "auto";
  std::string modelsDir = std::string(THINLOD_SHARED_DIR) + "/models";
  int frames = 7;
  double frameTriangles = 400000.0;
  app.add_option("--backend", backendName, "auto|egl|osmesa")
      ->check(CLI::IsMember({"auto", "egl", "osmesa"}));
  app.add_option("--models-dir", modelsDir, "where bunny, fandisk and cow are");
  app.add_option("--frames", frames, "timed frames per point (median)")->check(CLI::Range(3, 200));
  app.add_option("--frame-triangles", frameTriangles, "triangles drawn per timed frame")
      ->check(CLI::Range(1e3, 1e8));
  CLI11_PARSE(app, argc, argv);

  const render::Backend backend = backendName == "egl"      ? render::Backend::kEgl
                                  : backendName == "osmesa" ? render::Backend::kOsMesa
                                                            : render::Backend::kAuto;
  constexpr int kSide = 256;
  auto context = orDie(render::createOffscreenContext(backend, kSide, kSide), "context");
  auto renderer = orDie(render::MeshRenderer::create(*context), "renderer");
  auto target = orDie(render::RenderTarget::create(*context, kSide, kSide), "target");
  std::fprintf(stderr, "bench_tom: %s, %s\n", render::backendName(context->backend()),
               context->rendererName().c_str());
  render::Lighting lighting;
  lighting.lights.push_back({render::Light::Type::kDirectional,
                             glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f)), glm::vec3(0.8f),
                             0.0f});

  struct Named {
    const char* name;
    const char* file;
  };
  const Named models[] = {
      {"bunny", "stanford-bunny.obj"}, {"fandisk", "fandisk.obj"}, {"cow", "cow.obj"}};
  const double fractions[] = {1.0, 0.75, 0.5, 0.25, 0.1, 0.05, 0.02};

  std::printf("## Memory (KiB; percentages of the face-vertex mesh)\n\n");
  std::printf(
      "| mesh | vertices | triangles | face-vertex | TOM, paper's accounting | ProgressiveMesh "
      "(held) | LOD chain (5 levels) | build s |\n| --- | --- | --- | --- | --- | --- | --- | --- "
      "|\n");
  struct Built {
    const char* name;
    simplifier::ProgressiveMesh pm;
  };
  std::vector<Built> built;
  for (const Named& m : models) {
    IndexedMesh mesh = orDie(loadMeshFile(modelsDir + "/" + m.file), m.file).mesh;
    mesh.computeNormals();  // the paper's meshes carry normals
    const auto start = Clock::now();
    simplifier::ProgressiveMesh pm = orDie(simplifier::ProgressiveMesh::build(mesh), "build");
    const double buildSeconds = seconds(start, Clock::now());
    const std::size_t v = pm.vertexCount(), t = pm.maxTriangles();
    const double plain = faceVertexBytes(v, t);
    const double paper = plain + double(v) * 4.0;  // + the substitution index per vertex
    const double held = double(pm.memoryBytes());
    double lod = 0.0;
    for (double f : {1.0, 0.5, 0.25, 0.125, 0.0625}) {
      const auto n = static_cast<std::size_t>(std::llround(f * double(t)));
      lod += faceVertexBytes(pm.vertexCountAt(n), pm.triangleCountAt(n));
    }
    std::printf(
        "| %s | %zu | %zu | %.0f | %.0f (%.0f %%) | %.0f (%.0f %%) | %.0f (%.0f %%) | %.2f |\n",
        m.name, v, t, plain / 1024, paper / 1024, 100 * paper / plain, held / 1024,
        100 * held / plain, lod / 1024, 100 * lod / plain, buildSeconds);
    built.push_back({m.name, std::move(pm)});
  }

  std::printf(
      "\n## Traversal: vertices visited per extracted triangle (extra = traversed / (3 T) - "
      "1)\n\n| mesh |");
  for (double f : fractions) std::printf(" %.0f %% |", 100 * f);
  std::printf(" coarsest |\n| --- |");
  for (std::size_t i = 0; i <= std::size(fractions); ++i) std::printf(" --- |");
  std::printf("\n");
  for (const Built& b : built) {
    std::printf("| %s |", b.name);
    std::vector<std::size_t> targets;
    for (double f : fractions)
      targets.push_back(
          std::max(b.pm.minTriangles(), static_cast<std::size_t>(f * double(b.pm.maxTriangles()))));
    targets.push_back(b.pm.minTriangles());
    for (std::size_t n : targets) {
      const double triangles = double(b.pm.triangleCountAt(n));
      const double traversed = double(b.pm.traversedVerticesAt(n));
      std::printf(" %.3f (+%.1f %%) |", traversed / triangles,
                  100.0 * (traversed / (3.0 * triangles) - 1.0));
    }
    std::printf("\n");
  }

  std::printf(
      "\n## Rates across resolutions (million triangles/s, median of %d frames of ~%.0fk "
      "triangles, %s)\n\n| mesh | resolution | triangles | TOM traversal | TOM rendering "
      "(extract + replicate + upload + draw) | streamlined rendering (draw only) |\n| --- | --- | --- | --- "
      "| --- | --- |\n",
      frames, frameTriangles / 1000, render::backendName(context->backend()));
  render::Camera camera;
  camera.view = glm::lookAt(glm::vec3(0, 0, 0), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  camera.projection = glm::perspective(0.785f, 1.0f, 0.1f, 1000.0f);
  for (const Built& b : built) {
    // Shrink the mesh to a few pixels (radius 1 m at 100 m: about 6 px).
    const IndexedMesh full = b.pm.extract(b.pm.maxTriangles());
    const BoundingSphere sphere = full.boundingSphere();
    const float scale = 1.0f / sphere.radius;
    IndexedMesh work;
    for (double f : fractions) {
      const auto n = static_cast<std::size_t>(f * double(b.pm.maxTriangles()));
      const std::size_t triangles = b.pm.triangleCountAt(n);
      const int copies = std::max(1, static_cast<int>(std::ceil(frameTriangles / triangles)));
      // The copies merged into one mesh (one draw call: our renderers batch,
      // and per-call overhead would otherwise dominate small resolutions).
      auto replicate = [copies](const IndexedMesh& one, IndexedMesh& many) {
        const std::size_t v = one.positions.size();
        many.positions.resize(v * copies);
        many.normals.resize(one.normals.size() * copies);
        many.indices.resize(one.indices.size() * copies);
        for (int c = 0; c < copies; ++c) {
          std::copy(one.positions.begin(), one.positions.end(), many.positions.begin() + c * v);
          std::copy(one.normals.begin(), one.normals.end(), many.normals.begin() + c * v);
          const std::size_t base = one.indices.size() * std::size_t(c);
          for (std::size_t i = 0; i < one.indices.size(); ++i)
            many.indices[base + i] = one.indices[i] + static_cast<std::uint32_t>(c * v);
        }
      };
      render::DrawItem item;
      item.model = glm::translate(
          glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, -100.0f)), glm::vec3(scale)),
          -sphere.center);
      std::vector<double> traversal, tomRendering, streamlined;
      // TOM traversal alone (the extraction into reused buffers).
      for (int k = 0; k < frames; ++k) {
        const auto t0 = Clock::now();
        for (int c = 0; c < copies; ++c) b.pm.extractInto(n, work);
        traversal.push_back(double(triangles) * copies / seconds(t0, Clock::now()));
      }
      // Streamlined: uploaded once, drawn.
      IndexedMesh merged;
      b.pm.extractInto(n, work);
      replicate(work, merged);
      const render::MeshHandle fixed = orDie(renderer->uploadMesh(merged), "upload");
      const render::MeshHandle rebuilt = orDie(renderer->uploadMesh(merged), "upload");
      item.mesh = fixed;
      orDie(renderer->beginFrame(*target, glm::vec4(0, 0, 0, 1)), "begin");  // warm-up
      orDie(renderer->draw(&item, 1, camera, lighting), "draw");
      orDie(renderer->finish(), "finish");
      for (int k = 0; k < frames; ++k) {
        const auto t0 = Clock::now();
        orDie(renderer->beginFrame(*target, glm::vec4(0, 0, 0, 1)), "begin");
        orDie(renderer->draw(&item, 1, camera, lighting), "draw");
        orDie(renderer->finish(), "finish");
        streamlined.push_back(double(triangles) * copies / seconds(t0, Clock::now()));
        if (renderer->stats().triangles != triangles * copies) {
          std::fprintf(stderr, "bench_tom: drew %zu triangles, expected %zu\n",
                       renderer->stats().triangles, triangles * copies);
          return 1;
        }
      }
      // TOM rendering: each frame extracts the resolution, replicates it,
      // re-uploads and draws it (a client switching resolution every frame).
      item.mesh = rebuilt;
      for (int k = 0; k < frames; ++k) {
        const auto t0 = Clock::now();
        b.pm.extractInto(n, work);
        replicate(work, merged);
        orDie(renderer->updateMesh(rebuilt, merged), "update");
        orDie(renderer->beginFrame(*target, glm::vec4(0, 0, 0, 1)), "begin");
        orDie(renderer->draw(&item, 1, camera, lighting), "draw");
        orDie(renderer->finish(), "finish");
        tomRendering.push_back(double(triangles) * copies / seconds(t0, Clock::now()));
      }
      renderer->deleteMesh(fixed);
      renderer->deleteMesh(rebuilt);
      std::printf("| %s | %.0f %% | %zu | %.1f | %.2f | %.2f |\n", b.name, 100 * f, triangles,
                  median(traversal) / 1e6, median(tomRendering) / 1e6, median(streamlined) / 1e6);
    }
  }
  return 0;
}
