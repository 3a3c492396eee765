// bench_impostor: times 256x256 simple and meshed impostors of the shared cow
// and bunny on each offscreen back-end, with an empty-frame baseline measured
// in the same run. Not a test. Usage: bench_impostor [repetitions] [models dir]
// Prints CSV: backend,model,triangles,kind,size,median_ms,min_ms,p90_ms,cpu_ms,coverage,extra
// (cpu_ms: process CPU time per call, all llvmpipe threads included; less
// sensitive than wall time to other processes competing for the 2 cores).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "thinlod/common/mesh_io.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/simplifier/impostor.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Summary {
  double median = 0, min = 0, p90 = 0, cpu = 0;
};

double cpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

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
  const double cpuStart = cpuMs();
  for (int i = 0; i < repetitions; ++i) {
    const auto start = std::chrono::steady_clock::now();
    body();
    samples.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  Summary s = summarize(samples);
  s.cpu = (cpuMs() - cpuStart) / repetitions;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::max(3, std::atoi(argv[1])) : 21;
  const std::string models = argc > 2 ? argv[2] : std::string(THINLOD_SHARED_DIR) + "/models";
  std::printf("backend,model,triangles,kind,size,median_ms,min_ms,p90_ms,cpu_ms,coverage,extra\n");
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
    for (const char* file : {"cow.obj", "stanford-bunny.obj"}) {
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
      std::printf("%s,%s,%zu,simple,256,%.3f,%.3f,%.3f,%.3f,%.3f,alpha=%.4frad\n", name, file,
                  triangles, s.median, s.min, s.p90, s.cpu, simple.coverage,
                  simple.validity.alpha());

      MeshedImpostor meshed;
      const Summary m = timeIt(repetitions, [&] {
        auto result = (*impostors)->renderMeshed(scene, eye);
        if (!result.ok()) {
          std::fprintf(stderr, "%s\n", result.status().toString().c_str());
          std::exit(1);
        }
        meshed = std::move(result).value();
      });
      const ImpostorTimings& t = (*impostors)->lastTimings();
      std::printf(
          "%s,%s,%zu,meshed,256,%.3f,%.3f,%.3f,%.3f,%.3f,tris=%zu render=%.2fms mesh=%.2fms "
          "alpha=%.4frad err=%.2e\n",
          name, file, triangles, m.median, m.min, m.p90, m.cpu, meshed.coverage,
          meshed.mesh.triangleCount(), t.renderMs, t.meshMs, meshed.validity.alpha(),
          meshed.meshDepthError);
    }
    (*impostors).reset();
  }
  return 0;
}
