// bench_calibrate: fits the Gobbetti-Bouvier frame-time constants (t_init +
// t_final, t_setup, t_tri, t_pix; common/frame_cost.h) on the frontend's own
// renderer (FrontendRenderer on EGL or OSMesa) by least squares and writes
// them to a small TOML file for the backbone's time-critical scheduler.
//
// Frames: n lit sphere meshes (n = 0..64) of T triangles each (80..20k),
// laid out on a grid facing the camera at 10 m, each covering a disc of rho
// pixels (rho = 4..cell/2, so they do not overlap): triangle-bound and
// fill-bound frames both occur. Each configuration gets its own renderer,
// two warm-up frames (uploads, merged buffers), then the median wall time of
// --frames steady frames (FrameTiming::totalMs: draw + readback; no uploads).
// Configurations are measured in a shuffled order (fixed seed) so drifting
// machine load does not line up with one regressor. Covered pixels are the
// on-axis disc pi rho^2, the estimate the scheduler uses.
//
//   build/frontend/bench/bench_calibrate --backend egl --out frame_cost.toml
//
// Both the paper's max(triangles, pixels) model and an additive one are
// fitted; the better R^2 is written (llvmpipe rasterises on the CPU after
// vertex processing, so its stages add up rather than overlap).
// Output: the constants, R^2 and RMS residual on stderr; one CSV row per
// configuration on stdout (n, triangles, pixels, measured and predicted ms).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/core/frame_cost.h"
#include "thinlod/common/mesh/primitives.h"
#include "thinlod/frontend/frontend_renderer.h"

using namespace thinlod;
using namespace thinlod::frontend;

namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr double kPi = 3.14159265358979323846;
constexpr float kFovY = 0.7853981633974483f;  // 45 degrees
constexpr double kDistance = 10.0;

template <typename T>
T orDie(Result<T> result, const char* what) {
  if (!result.ok()) {
    std::fprintf(stderr, "bench_calibrate: %s: %s\n", what, result.status().toString().c_str());
    std::exit(1);
  }
  return std::move(result).value();
}
void orDie(const Status& status, const char* what) {
  if (!status.ok()) {
    std::fprintf(stderr, "bench_calibrate: %s: %s\n", what, status.toString().c_str());
    std::exit(1);
  }
}

struct Config {
  int objects = 0;
  int rings = 0;  // sphere tessellation: 2 * rings segments x rings bands
  double pixelRadius = 0.0;
};

struct Measured {
  Config config;
  double trianglesPerObject = 0.0;
  double pixelsPerObject = 0.0;
  double medianMs = 0.0;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"thinlod frame-time cost calibration (Gobbetti-Bouvier cost model)"};
  std::string backendName = "auto";
  std::string outPath = "frame_cost.toml";
  int frames = 7;
  double initShare = 0.5;
  app.add_option("--backend", backendName, "auto|egl|osmesa")
      ->check(CLI::IsMember({"auto", "egl", "osmesa"}));
  app.add_option("--out", outPath, "write the constants here (TOML)");
  app.add_option("--frames", frames, "steady frames per configuration (median)")
      ->check(CLI::Range(3, 1000));
  app.add_option("--init-share", initShare,
                 "share of the fitted fixed time reported as t_init (the rest is t_final)")
      ->check(CLI::Range(0.0, 1.0));
  CLI11_PARSE(app, argc, argv);

  const render::Backend backend = backendName == "egl"      ? render::Backend::kEgl
                                  : backendName == "osmesa" ? render::Backend::kOsMesa
                                                            : render::Backend::kAuto;
  auto context = orDie(render::createOffscreenContext(backend, kWidth, kHeight), "context");
  std::fprintf(stderr, "bench_calibrate: %s, %s\n", render::backendName(context->backend()),
               context->rendererName().c_str());

  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.25f);
  lighting.lights.push_back({render::Light::Type::kDirectional,
                             glm::normalize(glm::vec3(-0.4f, -1.0f, -0.6f)), glm::vec3(0.85f),
                             0.0f});
  render::Camera camera;
  camera.view = glm::lookAt(glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(0, 1, 0));
  camera.projection = glm::perspective(kFovY, static_cast<float>(kWidth) / kHeight, 0.1f, 100.0f);
  const double focal = 0.5 * kHeight / std::tan(0.5 * kFovY);

  // The design: object counts x tessellations x pixel radii, at most ~600k
  // triangles per frame.
  std::vector<Config> configs;
  const int objectCounts[] = {0, 1, 2, 4, 8, 16, 32, 64};
  const int ringCounts[] = {5, 9, 18, 36, 72};
  const double radii[] = {4.0, 16.0, 40.0, 100.0, 200.0};
  for (int n : objectCounts) {
    const int grid = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))));
    const double cell = std::min(kWidth, kHeight) / static_cast<double>(grid);
    for (int rings : ringCounts) {
      const double triangles = 4.0 * rings * (rings - 1);
      if (n * triangles > 6e5) continue;
      for (double rho : radii) {
        if (rho > 0.5 * cell) continue;
        configs.push_back({n, rings, rho});
        if (n == 0) break;
      }
      if (n == 0) break;
    }
  }
  std::mt19937 rng(2024);
  std::shuffle(configs.begin(), configs.end(), rng);

  std::vector<Measured> measured;
  std::vector<FrameTimeSample> samples;
  RgbaImage frame;
  for (const Config& c : configs) {
    FrontendRendererOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.uploadBytesPerFrame = std::numeric_limits<std::size_t>::max();
    auto renderer = orDie(FrontendRenderer::create(*context, options), "renderer");
    orDie(renderer->warmUp(lighting), "warm up");
    TessellationParams params;
    params.rings = std::max(2, c.rings);
    params.segments = 2 * params.rings;
    const auto mesh =
        std::make_shared<const IndexedMesh>(tessellate(PrimitiveShape::sphere(1.0f), params));
    const int grid =
        std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(c.objects)))));
    const double cell = std::min(kWidth, kHeight) / static_cast<double>(grid);
    // World radius whose image is a disc of rho pixels: rho = f R / sqrt(d^2 - R^2).
    const double radius =
        c.pixelRadius * kDistance / std::sqrt(focal * focal + c.pixelRadius * c.pixelRadius);
    SceneBatch batch;
    batch.plan = 1;
    for (int i = 0; i < c.objects; ++i) {
      const double px = (i % grid + 0.5) * cell - 0.5 * grid * cell;
      const double py = (i / grid + 0.5) * cell - 0.5 * grid * cell;
      SceneOperation op;
      op.id = static_cast<ObjectId>(i + 1);
      op.representation.kind = RepresentationKind::kMesh;
      op.representation.mesh = mesh;
      op.representation.color = glm::vec4(0.3f + 0.7f * (i % 3) / 2.0f, 0.6f, 0.4f, 1.0f);
      const glm::vec3 center(static_cast<float>(px * kDistance / focal),
                             static_cast<float>(py * kDistance / focal),
                             static_cast<float>(-kDistance));
      op.representation.transform = glm::scale(glm::translate(glm::mat4(1.0f), center),
                                               glm::vec3(static_cast<float>(radius)));
      batch.operations.push_back(std::move(op));
    }
    orDie(renderer->submit(std::move(batch)), "submit");
    for (int w = 0; w < 2; ++w) orDie(renderer->renderFrame(camera, lighting, frame), "warm frame");
    std::vector<double> times;
    for (int f = 0; f < frames; ++f) {
      const FrameReport report = orDie(renderer->renderFrame(camera, lighting, frame), "frame");
      if (report.uploadedObjects != 0) {
        std::fprintf(stderr, "bench_calibrate: uploads in a steady frame\n");
        return 1;
      }
      times.push_back(report.timing.totalMs);
    }
    Measured m;
    m.config = c;
    m.trianglesPerObject = static_cast<double>(mesh->triangleCount());
    m.pixelsPerObject = kPi * c.pixelRadius * c.pixelRadius;
    m.medianMs = median(times);
    measured.push_back(m);
    FrameTimeSample sample;
    sample.seconds = m.medianMs * 1e-3;
    for (int i = 0; i < c.objects; ++i)
      sample.objects.push_back({m.trianglesPerObject, m.pixelsPerObject});
    samples.push_back(std::move(sample));
  }

  // The paper's model (triangle and fill stages overlap: max) and the
  // additive one (a software rasteriser runs them one after the other); the
  // file gets the one that explains the frames better.
  const FrameCostFit bottleneck = orDie(fitFrameCostConstants(samples, initShare, false), "fit");
  const FrameCostFit additive = orDie(fitFrameCostConstants(samples, initShare, true), "fit");
  for (const FrameCostFit* f : {&bottleneck, &additive})
    std::fprintf(
        stderr,
        "  %-8s model: fixed %.4f ms, setup %.3f us, tri %.3f ns, pix %.3f ns: R^2 = %.4f, "
        "RMS %.3f ms\n",
        f->constants.additive ? "additive" : "max",
        1e3 * (f->constants.initSeconds + f->constants.finalSeconds),
        1e6 * f->constants.setupSeconds, 1e9 * f->constants.triangleSeconds,
        1e9 * f->constants.pixelSeconds, f->rSquared, 1e3 * f->rmsSeconds);
  const FrameCostFit fit = additive.rSquared > bottleneck.rSquared ? additive : bottleneck;
  const FrameCostConstants& k = fit.constants;
  std::printf("objects,triangles_per_object,pixels_per_object,measured_ms,predicted_ms\n");
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const Measured& m = measured[i];
    std::printf("%d,%.0f,%.0f,%.4f,%.4f\n", m.config.objects, m.trianglesPerObject,
                m.pixelsPerObject, m.medianMs, 1e3 * predictFrameSeconds(k, samples[i].objects));
  }
  std::fprintf(stderr,
               "bench_calibrate: %zu configurations, %d frames each; kept the %s model\n"
               "  t_init + t_final = %.4f ms (split %.2f / %.2f)\n"
               "  t_setup = %.3f us per object\n"
               "  t_tri   = %.3f ns per triangle\n"
               "  t_pix   = %.3f ns per pixel\n"
               "  R^2 = %.4f, RMS residual %.3f ms, %.0f%% of objects fill-bound\n",
               samples.size(), frames, k.additive ? "additive" : "max",
               1e3 * (k.initSeconds + k.finalSeconds), initShare, 1.0 - initShare,
               1e6 * k.setupSeconds, 1e9 * k.triangleSeconds, 1e9 * k.pixelSeconds, fit.rSquared,
               1e3 * fit.rmsSeconds, 100.0 * fit.fillBoundShare);
  char comment[512];
  std::snprintf(comment, sizeof comment,
                "thinlod frame-time cost constants (bench_calibrate)\n"
                "renderer: %s (%s), %dx%d, %s model\n"
                "R^2 = %.4f, RMS residual %.3f ms over %zu configurations\n"
                "init/final split %.2f/%.2f is not measured (only their sum is identifiable)",
                render::backendName(context->backend()), context->rendererName().c_str(), kWidth,
                kHeight, k.additive ? "additive" : "max (paper)", fit.rSquared,
                1e3 * fit.rmsSeconds, samples.size(), initShare, 1.0 - initShare);
  std::ofstream out(outPath);
  out << formatFrameCostToml(k, comment);
  if (!out) {
    std::fprintf(stderr, "bench_calibrate: cannot write %s\n", outPath.c_str());
    return 1;
  }
  std::fprintf(stderr, "bench_calibrate: wrote %s\n", outPath.c_str());
  return 0;
}
