// bench_kappa: kappa = point rate / triangle rate on the frontend's renderer
// (Cohen-Aliaga-Zhang 5.3; docs/hybrid.md, "Measured kappa"). N small
// primitives scattered over a 640x480 viewport, each covering the same
// screen area (a disc of diameter D pixels, or a triangle of area pi D^2/4),
// drawn in ONE call as the frontend batches them: triangles through
// MeshRenderer (lit, vertex colours: the frontend's batch variant), discs
// through DiscRenderer (pre-lit, instanced quads). Frame = beginFrame + draw
// + RGBA readback; the empty frame, measured in the same run, is
// subtracted. Triangle and disc frames alternate so load changes hit both.
// Not a test. Usage:
//   bench_kappa [--backend auto|egl|osmesa] [--count N] [--repetitions R]
// Prints a markdown table: diameter, ms per frame (empty / triangles /
// discs), primitives per ms, kappa.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/render/disc_renderer.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/render_target.h"

using namespace thinlod;
using namespace thinlod::render;

namespace {

constexpr int kWidth = 640, kHeight = 480;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Orthographic camera: world x, y in pixels (origin bottom-left), z in [-1, 1].
Camera pixelCamera() {
  Camera camera;
  camera.view = glm::mat4(1.0f);
  camera.projection = glm::ortho(0.0f, float(kWidth), 0.0f, float(kHeight), -2.0f, 2.0f);
  return camera;
}

struct Workload {
  IndexedMesh triangles;
  DiscPoints discs;
};

Workload makeWorkload(int count, double diameter, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> x(4.0f, kWidth - 4.0f), y(4.0f, kHeight - 4.0f),
      z(-0.9f, 0.9f), angle(0.0f, 6.2831853f);
  Workload w;
  const double area = 3.14159265358979 * diameter * diameter / 4.0;
  // Equilateral triangle of that area: side s, area sqrt(3)/4 s^2.
  const float side = static_cast<float>(std::sqrt(4.0 * area / std::sqrt(3.0)));
  const float circumradius = side / std::sqrt(3.0f);
  for (int i = 0; i < count; ++i) {
    const glm::vec3 c(x(rng), y(rng), z(rng));
    const std::array<std::uint8_t, 4> color{static_cast<std::uint8_t>(rng()),
                                            static_cast<std::uint8_t>(rng()), 128, 255};
    const float a = angle(rng);
    const auto base = static_cast<std::uint32_t>(w.triangles.positions.size());
    for (int k = 0; k < 3; ++k) {
      const float t = a + 2.0943951f * k;
      w.triangles.positions.emplace_back(c.x + circumradius * std::cos(t),
                                         c.y + circumradius * std::sin(t), c.z);
      w.triangles.normals.emplace_back(0.0f, 0.0f, 1.0f);
      w.triangles.colors.push_back(color);
      w.triangles.indices.push_back(base + k);
    }
    w.discs.centres.push_back(c);
    w.discs.radii.push_back(static_cast<float>(diameter / 2.0));
    w.discs.colors.push_back(color);
  }
  return w;
}

}  // namespace

int main(int argc, char** argv) {
  Backend backend = Backend::kAuto;
  int count = 20000;
  int repetitions = 15;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--backend") {
      const std::string b = argv[i + 1];
      backend = b == "egl" ? Backend::kEgl : b == "osmesa" ? Backend::kOsMesa : Backend::kAuto;
    } else if (flag == "--count") {
      count = std::max(1, std::atoi(argv[i + 1]));
    } else if (flag == "--repetitions") {
      repetitions = std::max(3, std::atoi(argv[i + 1]));
    } else {
      std::fprintf(stderr, "unknown flag %s\n", argv[i]);
      return 2;
    }
  }
  auto context = createOffscreenContext(backend, kWidth, kHeight);
  if (!context.ok()) {
    std::fprintf(stderr, "%s\n", context.status().toString().c_str());
    return 1;
  }
  auto target = RenderTarget::create(**context, kWidth, kHeight);
  auto meshes = MeshRenderer::create(**context);
  auto discs = DiscRenderer::create(**context, DiscStyle::kInstancedQuads);
  auto sprites = DiscRenderer::create(**context, DiscStyle::kPointSprites);
  if (!target.ok() || !meshes.ok() || !discs.ok() || !sprites.ok()) {
    std::fprintf(stderr, "renderer set-up failed\n");
    return 1;
  }
  std::printf("renderer: %s %s; %d primitives per frame, %d x %d, %d repetitions\n\n",
              backendName((*context)->backend()), (*context)->rendererName().c_str(), count, kWidth,
              kHeight, repetitions);
  std::printf(
      "| diameter px | empty ms | %d triangles ms | %d quad discs ms | %d sprite discs ms "
      "| triangles/ms | quad discs/ms | sprite discs/ms | kappa quads | kappa sprites "
      "|\n|---|---|---|---|---|---|---|---|---|---|\n",
      count, count, count);
  const Camera camera = pixelCamera();
  Material material;
  material.useVertexColors = true;
  Lighting lighting;
  lighting.lights = {Light{}};
  RgbaImage image;
  bool checked = true;
  for (double diameter : {1.0, 2.0, 3.0, 5.0, 8.0}) {
    const Workload w = makeWorkload(count, diameter, 42);
    auto mesh = (*meshes)->uploadMesh(w.triangles);
    auto disc = (*discs)->upload(w.discs);
    auto sprite = (*sprites)->upload(w.discs);
    if (!mesh.ok() || !disc.ok() || !sprite.ok()) {
      std::fprintf(stderr, "upload failed\n");
      return 1;
    }
    const DrawItem meshItem{*mesh, glm::mat4(1.0f), material};
    const DiscDrawItem discItem{*disc, glm::mat4(1.0f)};
    const DiscDrawItem spriteItem{*sprite, glm::mat4(1.0f)};
    auto frame = [&](int which) {
      const auto start = std::chrono::steady_clock::now();
      Status s = (*meshes)->beginFrame(**target, glm::vec4(0, 0, 0, 1));
      if (s.ok() && which == 1) s = (*meshes)->draw(&meshItem, 1, camera, lighting);
      if (s.ok() && which == 2) s = (*discs)->draw(&discItem, 1, camera);
      if (s.ok() && which == 3) s = (*sprites)->draw(&spriteItem, 1, camera);
      if (s.ok()) s = (*target)->readColor(image);
      if (!s.ok()) {
        std::fprintf(stderr, "%s\n", s.toString().c_str());
        std::exit(1);
      }
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
          .count();
    };
    for (int which = 0; which < 4; ++which) frame(which);  // warm-up (shader variants)
    std::vector<double> empty, tris, points, spritePoints;
    std::size_t spriteLit = 0;
    for (int r = 0; r < repetitions; ++r) {
      empty.push_back(frame(0));
      tris.push_back(frame(1));
      spritePoints.push_back(frame(3));
      if (r == 0) {
        for (std::size_t i = 0; i < image.pixels.size(); i += 4) spriteLit += image.pixels[i] > 0;
      }
      points.push_back(frame(2));
    }
    // Check after timing: the last disc frame drew something.
    std::size_t lit = 0;
    for (std::size_t i = 0; i < image.pixels.size(); i += 4)
      lit += image.pixels[i + 3] && (image.pixels[i] | image.pixels[i + 1]);
    checked &= lit > 0 && spriteLit > 0;
    const double e = median(empty), t = median(tris), p = median(points), q = median(spritePoints);
    const double triangleRate = count / std::max(t - e, 1e-6);
    const double discRate = count / std::max(p - e, 1e-6);
    const double spriteRate = count / std::max(q - e, 1e-6);
    std::printf("| %.0f | %.2f | %.2f | %.2f | %.2f | %.0f | %.0f | %.0f | %.2f | %.2f |\n",
                diameter, e, t, p, q, triangleRate, discRate, spriteRate, discRate / triangleRate,
                spriteRate / triangleRate);
    (*meshes)->deleteMesh(*mesh);
    (*discs)->remove(*disc);
    (*sprites)->remove(*sprite);
  }
  if (!checked) {
    std::fprintf(stderr, "a disc frame came out empty\n");
    return 1;
  }
  return 0;
}
