// bench_render: the frontend's workload on the render layer: 350 textured
// triangles at 640x480 with depth test and RGBA readback, drawn (a) as 350
// items each with its own texture, (b) as 350 items sharing one array texture,
// (c) as one MeshBatch in a single draw call. Not a test.
// Usage: bench_render [repetitions]. Prints CSV:
// backend,variant,draw_calls,texture_binds,median_ms,min_ms,p90_ms,cpu_ms_per_frame
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <vector>

#include "thinlod/common/core/cpu_time.h"
#include "thinlod/common/render/mesh_batch.h"
#include "thinlod/common/render/mesh_renderer.h"

using namespace thinlod;
using namespace thinlod::render;

namespace {

struct Timing {
  double median, min, p90, cpu;
};

template <typename F>
Timing timeFrames(int repetitions, F&& frame) {
  frame();
  std::vector<double> samples;
  const double cpuStart = processCpuSeconds() * 1e3;
  for (int i = 0; i < repetitions; ++i) {
    const auto start = std::chrono::steady_clock::now();
    frame();
    samples.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  const double cpu = (processCpuSeconds() * 1e3 - cpuStart) / repetitions;
  std::sort(samples.begin(), samples.end());
  return {samples[samples.size() / 2], samples.front(), samples[samples.size() * 9 / 10], cpu};
}

void check(const Status& status) {
  if (!status.ok()) {
    std::fprintf(stderr, "%s\n", status.toString().c_str());
    std::exit(1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int repetitions = argc > 1 ? std::max(3, std::atoi(argv[1])) : 31;
  constexpr int kTriangles = 350;
  constexpr int kTexture = 64;
  std::printf(
      "backend,variant,draw_calls,texture_binds,median_ms,min_ms,p90_ms,cpu_ms_per_frame\n");
  for (Backend backend : {Backend::kEgl, Backend::kOsMesa}) {
    auto context = createOffscreenContext(backend, 16, 16);
    if (!context.ok()) {
      std::fprintf(stderr, "%s\n", context.status().toString().c_str());
      return 1;
    }
    {
      auto renderer = MeshRenderer::create(**context).value();
      auto target = RenderTarget::create(**context, 640, 480).value();
      std::mt19937 rng(17);
      std::uniform_real_distribution<float> u(-1.0f, 1.0f);
      std::uniform_int_distribution<int> byte(0, 255);
      // 350 random textured triangles in [-1,1]^2 x [-1,1], one 64x64 image each.
      std::vector<IndexedMesh> triangles(kTriangles);
      std::vector<RgbaImage> images(kTriangles, RgbaImage(kTexture, kTexture));
      for (int i = 0; i < kTriangles; ++i) {
        const glm::vec3 c(u(rng), u(rng), u(rng));
        for (int k = 0; k < 3; ++k) {
          triangles[i].positions.push_back(c + 0.3f * glm::vec3(u(rng), u(rng), 0.1f * u(rng)));
        }
        triangles[i].uvs = {{0, 0}, {1, 0}, {0, 1}};
        triangles[i].indices = {0, 1, 2};
        for (auto& v : images[i].pixels) v = static_cast<std::uint8_t>(byte(rng));
      }
      Camera camera;
      camera.view = glm::lookAt(glm::vec3(0, 0, 4), glm::vec3(0), glm::vec3(0, 1, 0));
      camera.projection = glm::perspective(glm::radians(45.0f), 640.0f / 480.0f, 1.0f, 10.0f);
      Material base;
      base.lit = false;
      base.diffuse = glm::vec4(1.0f);
      base.alphaMode = AlphaMode::kMask;
      RgbaImage readback;

      // (a) one item and one texture per triangle.
      std::vector<DrawItem> separate;
      for (int i = 0; i < kTriangles; ++i) {
        DrawItem item{renderer->uploadMesh(triangles[i]).value(), glm::mat4(1.0f), base};
        item.material.texture = renderer->uploadTexture(images[i]).value();
        separate.push_back(item);
      }
      // (b) one item per triangle, all layers of one array texture (no rebinds).
      auto array = renderer->createTextureArray(kTexture, kTexture, kTriangles).value();
      for (int i = 0; i < kTriangles; ++i) check(renderer->setTextureLayer(array, i, images[i]));
      std::vector<DrawItem> layered = separate;
      for (int i = 0; i < kTriangles; ++i) {
        layered[i].material.texture = array;
        layered[i].material.textureLayer = i;
      }
      // (c) everything merged into one mesh with per-vertex layers: one draw call.
      MeshBatch batch;
      for (int i = 0; i < kTriangles; ++i) {
        MeshBatch::Part part;
        part.textureLayer = i;
        check(batch.append(triangles[i], part, "triangle"));
      }
      DrawItem merged{renderer->uploadMesh(batch.mesh(), batch.textureLayers()).value(),
                      glm::mat4(1.0f), base};
      merged.material.texture = array;

      struct Variant {
        const char* name;
        const std::vector<DrawItem>* items;
      };
      const std::vector<DrawItem> mergedItems = {merged};
      const std::vector<DrawItem> none;
      for (const Variant& v :
           {Variant{"clear+readback only", &none}, Variant{"350 items, 350 textures", &separate},
            Variant{"350 items, 1 array texture", &layered},
            Variant{"1 batch, 1 array texture", &mergedItems}}) {
        const Timing t = timeFrames(repetitions, [&] {
          check(renderer->beginFrame(*target, glm::vec4(0.0f)));
          check(renderer->draw(*v.items, camera, Lighting()));
          check(target->readColor(readback));
        });
        // Checked after timing: something was drawn unless nothing was asked for.
        std::size_t covered = 0;
        for (std::size_t i = 3; i < readback.pixels.size(); i += 4)
          covered += readback.pixels[i] != 0;
        if (!v.items->empty() && covered == 0) return 1;
        std::printf("%s,%s,%zu,%zu,%.3f,%.3f,%.3f,%.3f\n", backendName(backend), v.name,
                    renderer->stats().drawCalls, renderer->stats().textureBinds, t.median, t.min,
                    t.p90, t.cpu);
      }
    }
  }
  return 0;
}
