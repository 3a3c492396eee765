// bench_impostor: times 256x256 simple and meshed impostors of shared models
// on each offscreen back-end, with an empty-frame baseline measured
// in the same run. Not a test.
// Usage: bench_impostor [repetitions] [models dir] [model,model,...]
// Prints CSV: backend,model,triangles,kind,size,median_ms,min_ms,p90_ms,cpu_ms,coverage,extra
// Models: the cow, the bunny (69k triangles) and two other large meshes
// (horse 97k, Nefertiti 100k). Meshed impostors use the service's settings
// (grid step size / 32, depth mesh simplified to ServiceOptions'
// meshedImpostorTriangles), so their times are what the daemon pays.
// Kinds: simple / meshed from the full mesh (the old path), simple-level /
// meshed-level from the coarsest progressive-mesh level within one texel
// (impostor_level.h, what the service renders), with their difference to
// the full-mesh capture of the same run in `extra`: max / mean absolute
// RGBA difference, coverage-mismatch texels (of texels covered in either),
// and for meshed the displacement of depth-mesh vertices on the same texel.
// Meshed rows give their parts (ImpostorTimings, wall ms, mean over the calls).
// The error curve is measured once per model (service curve options) and
// cached in MeshCurveCache::defaultDirectory().
// Kinds service-simple / service-meshed: the daemon's own path,
// SimplifierService::renderImpostor on a one-object scene of the model
// (level choice, framing, capture, depth-mesh Draco encode; texture codec
// raw, so no PNG encode), same eye, in the same run; `extra` holds the reply's
// credited accuracy and the thread CPU ms per call. gather-full-points /
// frame-full-points: two CPU steps of that path on the full mesh alone.
// (cpu_ms: process CPU time per call, all llvmpipe threads included; less
// sensitive than wall time to other processes competing for the 2 cores.
// thread_ms in `extra`: the calling thread's CPU time only.)
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <glm/geometric.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/simplifier/impostor.h"
#include "thinlod/simplifier/impostor_level.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"
#include "thinlod/simplifier/service.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Summary {
  double median = 0, min = 0, p90 = 0, cpu = 0, thread = 0;
};


Summary summarize(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  Summary s;
  s.min = samples.front();
  s.median = samples[samples.size() / 2];
  s.p90 = samples[std::min(samples.size() - 1, samples.size() * 9 / 10)];
  return s;
}

template <typename F>
Summary timeIt(int repetitions, F&& body) {
  std::vector<double> samples;
  body();  // warm-up: shader compile, first upload, target allocation
  const double cpuStart = processCpuSeconds() * 1e3;
  const double threadStart = threadCpuSeconds() * 1e3;
  for (int i = 0; i < repetitions; ++i) {
    const auto start = std::chrono::steady_clock::now();
    body();
    samples.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  Summary s = summarize(samples);
  s.cpu = (processCpuSeconds() * 1e3 - cpuStart) / repetitions;
  s.thread = (threadCpuSeconds() * 1e3 - threadStart) / repetitions;
  return s;
}

// Part timers (wall ms) averaged over the calls they were added for, the
// first (timeIt's warm-up) left out.
struct TimingMean {
  ImpostorTimings sum;
  int calls = 0;
  bool warmedUp = false;
  void add(const ImpostorTimings& t) {
    if (!warmedUp) {
      warmedUp = true;
      return;
    }
    sum.renderMs += t.renderMs;
    sum.meshMs += t.meshMs;
    sum.gridMs += t.gridMs;
    sum.simplifyMs += t.simplifyMs;
    sum.checkMs += t.checkMs;
    sum.checkDrawMs += t.checkDrawMs;
    sum.checkSilhouetteMs += t.checkSilhouetteMs;
    sum.checkDepthErrorMs += t.checkDepthErrorMs;
    ++calls;
  }
  ImpostorTimings mean() const {
    ImpostorTimings m = sum;
    const double k = calls > 0 ? 1.0 / calls : 0.0;
    for (double* v : {&m.renderMs, &m.meshMs, &m.gridMs, &m.simplifyMs, &m.checkMs,
                      &m.checkDrawMs, &m.checkSilhouetteMs, &m.checkDepthErrorMs})
      *v *= k;
    return m;
  }
};

// Depth-mesh vertices of `level` against those of `full` on the same texel
// (matched by uv: each grid node sits on one texel).
struct Displacement {
  double max = 0.0, p99 = 0.0, mean = 0.0;
  std::size_t matched = 0, vertices = 0;
};
Displacement vertexDisplacement(const IndexedMesh& full, const IndexedMesh& level, int size) {
  auto texel = [size](const glm::vec2& uv) {
    return std::make_pair(static_cast<int>(std::floor(uv.x * size)),
                          static_cast<int>(std::floor(uv.y * size)));
  };
  std::map<std::pair<int, int>, glm::vec3> byTexel;
  for (std::size_t i = 0; i < full.positions.size(); ++i) {
    byTexel[texel(full.uvs[i])] = full.positions[i];
  }
  Displacement d;
  d.vertices = level.positions.size();
  std::vector<double> moved;
  for (std::size_t i = 0; i < level.positions.size(); ++i) {
    auto found = byTexel.find(texel(level.uvs[i]));
    if (found == byTexel.end()) continue;
    moved.push_back(glm::length(found->second - level.positions[i]));
  }
  d.matched = moved.size();
  if (moved.empty()) return d;
  std::sort(moved.begin(), moved.end());
  d.max = moved.back();
  d.p99 = moved[std::min(moved.size() - 1, moved.size() * 99 / 100)];
  double sum = 0.0;
  for (double e : moved) sum += e;
  d.mean = sum / moved.size();
  return d;
}

std::string differenceText(const RgbaImage& full, const RgbaImage& level) {
  auto diff = compareImpostorTextures(full, level);
  if (!diff.ok()) {
    std::fprintf(stderr, "%s\n", diff.status().toString().c_str());
    std::exit(1);
  }
  char text[160];
  std::snprintf(text, sizeof text, "rgba_max=%d rgba_mean=%.3f coverage_mismatch=%zu/%zu",
                diff->maxAbs, diff->meanAbs, diff->coverageMismatch, diff->coveredEither);
  return text;
}

// The level the service would render `mesh` from at this framing.
struct ChosenLevel {
  std::shared_ptr<IndexedMesh> mesh;  // null: the full mesh
  double error = 0.0;                 // credited world error
  double tolerance = 0.0;
};
ChosenLevel chooseLevel(const IndexedMesh& mesh, const glm::vec3& eye) {
  auto pm = ProgressiveMesh::build(mesh);
  if (!pm.ok()) {
    std::fprintf(stderr, "%s\n", pm.status().toString().c_str());
    std::exit(1);
  }
  MeshCurveCache cache(MeshCurveCache::defaultDirectory());
  const MeshCurveOptions curveOptions = ServiceOptions::defaultCurveOptions();
  auto curves = cache.getOrMeasure(mesh, "bench_impostor qem default", *pm, curveOptions);
  if (!curves.ok()) {
    std::fprintf(stderr, "%s\n", curves.status().toString().c_str());
    std::exit(1);
  }
  std::vector<glm::vec3> points(mesh.positions.begin(), mesh.positions.end());
  auto framing = frameImpostor(points, eye, ImpostorOptions());
  if (!framing.ok()) std::exit(1);
  ChosenLevel chosen;
  chosen.tolerance = impostorLevelTolerance(*framing);
  const std::vector<double> credits =
      creditedRelativeErrors(curves->levels, curveOptions.minRelativeError);
  const double diameter = mesh.diameter();
  const auto level = chooseImpostorLevel(credits, diameter, chosen.tolerance);
  if (level) {
    chosen.mesh =
        std::make_shared<IndexedMesh>(pm->extract(curves->levels[*level].requestedTriangles));
    chosen.error = credits[*level] * diameter;
  }
  return chosen;
}

// The daemon's path for `file`: a service whose default scene holds the
// model alone (untransformed, so the same eye frames it the same way), its
// curves cached where chooseLevel keeps them.
struct ServiceCase {
  std::filesystem::path directory;
  std::unique_ptr<SimplifierService> service;
  std::uint64_t objectId = 0;
};
ServiceCase serviceFor(const std::string& models, const std::string& file,
                       render::Backend backend) {
  ServiceCase c;
  c.directory = std::filesystem::temp_directory_path() /
                ("bench_impostor_" + std::to_string(::getpid()));
  std::filesystem::create_directories(c.directory);
  const std::filesystem::path scenePath = c.directory / (file + ".wrl");
  {
    std::ofstream out(scenePath);
    out << "#VRML V2.0 utf8\n"
           "DirectionalLight { direction -0.3 -0.5 -1.0 }\n"
           "Shape { appearance Appearance { material Material { diffuseColor 0.8 0.8 0.8 } }\n"
           "  geometry Inline { url \""
        << file << "\" } }\n";
  }
  scene::SceneLoadOptions load;
  load.meshSearchPaths = {models};
  Result<scene::Scene> loaded = scene::loadSceneFile(scenePath.string(), load);
  Result<std::vector<scene::SceneObject>> objects =
      loaded.ok() ? scene::collectSceneObjects(*loaded)
                  : Result<std::vector<scene::SceneObject>>(loaded.status());
  if (!objects.ok() || objects->size() != 1) {
    std::fprintf(stderr, "service scene %s: %s\n", scenePath.c_str(),
                 objects.ok() ? "not one object" : objects.status().toString().c_str());
    std::exit(1);
  }
  c.objectId = objects->front().id;
  ServiceOptions options;
  options.modelSearchPaths = {models};
  options.sceneRoot = c.directory.string();
  options.defaultScenePath = scenePath.string();
  options.curveCacheDir = MeshCurveCache::defaultDirectory().string();
  options.backend = backend;
  c.service = std::make_unique<SimplifierService>(options);
  if (Status st = c.service->initializeRendering(); !st.ok()) {
    std::fprintf(stderr, "service rendering: %s\n", st.toString().c_str());
    std::exit(1);
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::max(3, std::atoi(argv[1])) : 21;
  const std::string models = argc > 2 ? argv[2] : std::string(THINLOD_SHARED_DIR) + "/models";
  // Optional third argument: the models to capture, comma-separated (a
  // profile of one of them); every one named must load.
  std::vector<std::string> files = {"cow.obj", "stanford-bunny.obj", "horse.ply", "nefertiti.obj"};
  if (argc > 3) {
    files.clear();
    std::string list = argv[3];
    for (std::size_t start = 0; start <= list.size();) {
      const std::size_t comma = std::min(list.find(',', start), list.size());
      if (comma > start) files.push_back(list.substr(start, comma - start));
      start = comma + 1;
    }
  }
  std::printf("backend,model,triangles,kind,size,median_ms,min_ms,p90_ms,cpu_ms,coverage,extra\n");
  std::map<std::string, ChosenLevel> levels;  // per model, shared by the back-ends
  for (render::Backend backend : {render::Backend::kEgl, render::Backend::kOsMesa}) {
    auto context = render::createOffscreenContext(backend, 16, 16);
    if (!context.ok()) {
      std::fprintf(stderr, "%s\n", context.status().toString().c_str());
      return 1;
    }
    auto impostors = ImpostorRenderer::create(**context);
    if (!impostors.ok()) {
      std::fprintf(stderr, "%s\n", impostors.status().toString().c_str());
      return 1;
    }
    const char* name = render::backendName(backend);
    MeshedImpostorOptions meshedOptions;  // as service_impostor.cpp sets them for 256 texels
    meshedOptions.gridStep = 256 / 32;
    meshedOptions.targetTriangles = ServiceOptions{}.meshedImpostorTriangles;
    for (const std::string& fileName : files) {
      const char* file = fileName.c_str();
      auto loaded = loadMeshFile(models + "/" + file);
      if (!loaded.ok()) {
        std::fprintf(stderr, "%s\n", loaded.status().toString().c_str());
        return 1;
      }
      ImpostorScene scene;
      ImpostorPart part;
      part.mesh = std::make_shared<IndexedMesh>(loaded->mesh);
      scene.parts.push_back(part);
      render::Light light;
      light.vector = glm::vec3(-0.3f, -0.5f, -1.0f);
      scene.lighting.lights.push_back(light);
      const BoundingSphere sphere = part.mesh->boundingSphere();
      const glm::vec3 eye = sphere.center + glm::vec3(0.3f, 0.2f, 1.0f) * (4.0f * sphere.radius);
      const std::size_t triangles = part.mesh->triangleCount();

      // Baseline: the same framing with nothing drawn but clear + colour readback.
      auto baselineContextTarget = render::RenderTarget::create(**context, 256, 256);
      if (!baselineContextTarget.ok()) {
        std::fprintf(stderr, "%s\n", baselineContextTarget.status().toString().c_str());
        return 1;
      }
      RgbaImage scratch;
      const Summary baseline = timeIt(repetitions, [&] {
        (void)(*baselineContextTarget)->clear(0, 0, 0, 0);
        (void)(*baselineContextTarget)->readColor(scratch);
      });
      std::printf("%s,%s,%zu,clear+readback,256,%.3f,%.3f,%.3f,%.3f,,\n", name, file, triangles,
                  baseline.median, baseline.min, baseline.p90, baseline.cpu);
      std::vector<float> depthScratch;
      const Summary withDepth = timeIt(repetitions, [&] {
        (void)(*baselineContextTarget)->clear(0, 0, 0, 0);
        (void)(*baselineContextTarget)->readColor(scratch);
        (void)(*baselineContextTarget)->readDepth(depthScratch);
      });
      std::printf("%s,%s,%zu,clear+readback+depth,256,%.3f,%.3f,%.3f,%.3f,,\n", name, file,
                  triangles, withDepth.median, withDepth.min, withDepth.p90, withDepth.cpu);

      SimpleImpostor simple;
      const Summary s = timeIt(repetitions, [&] {
        auto result = (*impostors)->renderSimple(scene, eye);
        if (!result.ok()) {
          std::fprintf(stderr, "%s\n", result.status().toString().c_str());
          std::exit(1);
        }
        simple = std::move(result).value();
      });
      // Checked after timing: the object is there and the range contains the eye.
      if (simple.coverage <= 0.01) return 1;
      std::printf("%s,%s,%zu,simple,256,%.3f,%.3f,%.3f,%.3f,%.3f,alpha=%.4frad thread_ms=%.3f\n",
                  name, file, triangles, s.median, s.min, s.p90, s.cpu, simple.coverage,
                  simple.validity.alpha(), s.thread);

      MeshedImpostor meshed;
      TimingMean meshedParts;
      const Summary m = timeIt(repetitions, [&] {
        auto result = (*impostors)->renderMeshed(scene, eye, meshedOptions);
        if (!result.ok()) {
          std::fprintf(stderr, "%s\n", result.status().toString().c_str());
          std::exit(1);
        }
        meshed = std::move(result).value();
        meshedParts.add((*impostors)->lastTimings());
      });
      const ImpostorTimings t = meshedParts.mean();
      std::printf(
          "%s,%s,%zu,meshed,256,%.3f,%.3f,%.3f,%.3f,%.3f,tris=%zu render=%.2fms mesh=%.2fms "
          "(grid=%.2f simplify=%.2f check=%.2f: draw=%.2f silhouette=%.2f depth_error=%.2f) "
          "thread_ms=%.3f alpha=%.4frad err=%.2e\n",
          name, file, triangles, m.median, m.min, m.p90, m.cpu, meshed.coverage,
          meshed.mesh.triangleCount(), t.renderMs, t.meshMs, t.gridMs, t.simplifyMs, t.checkMs,
          t.checkDrawMs, t.checkSilhouetteMs, t.checkDepthErrorMs, m.thread,
          meshed.validity.alpha(), meshed.meshDepthError);

      // The same captures from the chosen level (GPU copy cached by the renderer).
      if (levels.find(file) == levels.end()) levels[file] = chooseLevel(*part.mesh, eye);
      const ChosenLevel& chosen = levels[file];
      ImpostorScene levelScene = scene;
      if (chosen.mesh) levelScene.parts[0].mesh = chosen.mesh;
      const std::size_t levelTriangles = levelScene.parts[0].mesh->triangleCount();
      SimpleImpostor simpleLevel;
      const Summary sl = timeIt(repetitions, [&] {
        auto result = (*impostors)->renderSimple(levelScene, eye);
        if (!result.ok()) {
          std::fprintf(stderr, "%s\n", result.status().toString().c_str());
          std::exit(1);
        }
        simpleLevel = std::move(result).value();
      });
      std::printf(
          "%s,%s,%zu,simple-level,256,%.3f,%.3f,%.3f,%.3f,%.3f,thread_ms=%.3f level_error=%.3e "
          "tolerance=%.3e level_error_texels=%.3f %s\n",
          name, file, levelTriangles, sl.median, sl.min, sl.p90, sl.cpu, simpleLevel.coverage,
          sl.thread,
          chosen.error, chosen.tolerance,
          chosen.tolerance > 0 ? chosen.error / chosen.tolerance : 0.0,
          differenceText(simple.texture, simpleLevel.texture).c_str());
      MeshedImpostor meshedLevel;
      TimingMean levelParts;
      const Summary ml = timeIt(repetitions, [&] {
        auto result = (*impostors)->renderMeshed(levelScene, eye, meshedOptions);
        if (!result.ok()) {
          std::fprintf(stderr, "%s\n", result.status().toString().c_str());
          std::exit(1);
        }
        meshedLevel = std::move(result).value();
        levelParts.add((*impostors)->lastTimings());
      });
      const ImpostorTimings tl = levelParts.mean();
      const Displacement moved = vertexDisplacement(meshed.mesh, meshedLevel.mesh, 256);
      std::printf(
          "%s,%s,%zu,meshed-level,256,%.3f,%.3f,%.3f,%.3f,%.3f,render=%.2fms mesh=%.2fms "
          "(grid=%.2f simplify=%.2f check=%.2f: draw=%.2f silhouette=%.2f depth_error=%.2f) "
          "thread_ms=%.3f tris=%zu %s "
          "vertex_moved_max=%.3e p99=%.3e mean=%.3e matched=%zu/%zu radius=%.3e\n",
          name, file, levelTriangles, ml.median, ml.min, ml.p90, ml.cpu, meshedLevel.coverage,
          tl.renderMs, tl.meshMs, tl.gridMs, tl.simplifyMs, tl.checkMs, tl.checkDrawMs,
          tl.checkSilhouetteMs, tl.checkDepthErrorMs, ml.thread, meshedLevel.mesh.triangleCount(),
          differenceText(meshed.texture, meshedLevel.texture).c_str(), moved.max, moved.p99,
          moved.mean, moved.matched, moved.vertices, sphere.radius);

      // Two CPU steps of the service path on the full mesh: gathering the
      // referenced vertices in world space (what it did per request before
      // keeping them with the scene) and framing them (still per request:
      // it sets the texel size, hence the level).
      std::vector<glm::vec3> framingPoints;
      const Summary gather = timeIt(repetitions, [&] {
        framingPoints.clear();
        std::vector<unsigned char> referenced(part.mesh->vertexCount(), 0);
        for (std::uint32_t index : part.mesh->indices) referenced[index] = 1;
        for (std::size_t v = 0; v < referenced.size(); ++v) {
          if (referenced[v]) {
            framingPoints.push_back(glm::vec3(part.model * glm::vec4(part.mesh->positions[v], 1.0f)));
          }
        }
      });
      std::printf("%s,%s,%zu,gather-full-points,256,%.3f,%.3f,%.3f,%.3f,,thread_ms=%.3f points=%zu\n",
                  name, file, triangles, gather.median, gather.min, gather.p90, gather.cpu,
                  gather.thread, framingPoints.size());
      const Summary framed = timeIt(repetitions, [&] {
        if (!frameImpostor(framingPoints, eye, ImpostorOptions()).ok()) std::exit(1);
      });
      std::printf("%s,%s,%zu,frame-full-points,256,%.3f,%.3f,%.3f,%.3f,,thread_ms=%.3f\n", name,
                  file, triangles, framed.median, framed.min, framed.p90, framed.cpu, framed.thread);

      // The daemon's path (its own context; ours is made current again after).
      ServiceCase service = serviceFor(models, file, backend);
      for (auto kind : {protocol::RepresentationKind::kSimpleImpostor,
                        protocol::RepresentationKind::kMeshedImpostor}) {
        protocol::ImpostorRequest request;
        request.requestId = 1;
        request.objectIds = {service.objectId};
        request.eye = eye;
        request.textureWidth = request.textureHeight = 256;
        request.kind = kind;
        request.accuracyBound = ImpostorOptions().maxAngularError;
        request.textureCodec = protocol::TextureCodec::kRawRgba8;
        protocol::ImpostorResult reply;
        const Summary r = timeIt(repetitions, [&] {
          ++request.requestId;
          reply = service.service->renderImpostor(request);
          if (!reply.status.ok()) {
            std::fprintf(stderr, "service: %s\n", reply.status.toString().c_str());
            std::exit(1);
          }
        });
        const bool meshedKind = kind == protocol::RepresentationKind::kMeshedImpostor;
        std::printf("%s,%s,%zu,%s,256,%.3f,%.3f,%.3f,%.3f,,thread_ms=%.3f accuracy=%.1f "
                    "tris=%u levels_extracted=%llu\n",
                    name, file, triangles, meshedKind ? "service-meshed" : "service-simple",
                    r.median, r.min, r.p90, r.cpu, r.thread, reply.representation.accuracy,
                    reply.representation.triangleCount,
                    static_cast<unsigned long long>(service.service->stats().impostorLevelsExtracted));
      }
      service.service.reset();
      std::filesystem::remove_all(service.directory);
      if (Status st = (*context)->makeCurrent(); !st.ok()) {
        std::fprintf(stderr, "%s\n", st.toString().c_str());
        return 1;
      }
    }
    (*impostors).reset();
  }
  return 0;
}
