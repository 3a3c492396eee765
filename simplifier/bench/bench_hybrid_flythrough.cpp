// bench_hybrid_flythrough: the fly-through of Cohen, Aliaga & Zhang section 6
// (docs/results/hybrid.md, "Fly-through"): about 70 instances of the
// generated multi-manifold model (generateScatteredParts) along a path, every
// instance cut at a screen-space tolerance (3 pixels) in the hybrid graph and
// in the same graph built with triangles only; per frame the primitive units
// of both (triangles + points / kappa, instances outside the view frustum
// skipped by both), their ratio, and the coverage of the hybrid frame
// against the full-resolution mask (both rendered offscreen: the triangles
// with MeshRenderer, the discs with DiscRenderer, depth-tested).
// Prints a markdown report (per-frame table and summary) to stdout.
//   bench_hybrid_flythrough [--kappa K] [--tau T] [--frames N] [--instances N]
//                           [--pixels P] [--backend egl|osmesa] [--size WxH]
//                           [--path diagonal|front] [--standoff D]
// --path front: a pass along the field's front edge at D (default 6) in front
// of its first row, looking at its centre: no instance nearer than about D,
// most of the field several times farther (the diagonal path flies into it).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <glm/gtc/matrix_transform.hpp>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "thinlod/common/core/rgba_image.h"
#include "thinlod/common/render/disc_renderer.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/render/offscreen_context.h"
#include "thinlod/common/render/render_target.h"
#include "thinlod/simplifier/hybrid_graph.h"

using namespace thinlod;
using namespace thinlod::simplifier;

namespace {

struct Instance {
  glm::dmat4 model{1.0};  // object -> world (rotation, uniform scale, translation)
  glm::dmat4 inverse{1.0};
  double scale = 1.0;
  glm::dvec3 centre{0.0};  // world bounding sphere
  double radius = 0.0;
};

// A field of instances: rows along the path's x axis, random yaw and size.
std::vector<Instance> placeInstances(int count, const BoundingSphere& sphere, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Instance> out;
  const int perRow = 10;
  for (int i = 0; i < count; ++i) {
    Instance inst;
    const int row = i / perRow, column = i % perRow;
    inst.scale = 0.8 + 0.4 * unit(rng);
    const glm::dvec3 at(1.6 * column + 0.4 * (unit(rng) - 0.5), 0.3 * (unit(rng) - 0.5),
                        -1.6 * row + 0.4 * (unit(rng) - 0.5));
    glm::dmat4 m = glm::translate(glm::dmat4(1.0), at);
    m = glm::rotate(m, 6.283185307 * unit(rng), glm::dvec3(0, 1, 0));
    m = glm::scale(m, glm::dvec3(inst.scale));
    m = glm::translate(m, -glm::dvec3(sphere.center));
    inst.model = m;
    inst.inverse = glm::inverse(m);
    inst.centre = at;
    inst.radius = sphere.radius * inst.scale;
    out.push_back(inst);
  }
  return out;
}

struct Pose {
  glm::dvec3 eye;
  glm::dvec3 target;
};

// From the field's front-left corner, descending diagonally to past its
// middle, always looking at its far corner: the instances the path passes
// fill the view, the far ones are a few pixels. (deploy/make-suite.py's
// parts_fly is the same path.)
Pose poseAt(int frame, int frames, double fieldLength, double fieldDepth) {
  const double u = frames > 1 ? static_cast<double>(frame) / (frames - 1) : 0.0;
  const glm::dvec3 start(-2.0, 1.2, 2.5), end(0.7 * fieldLength, 0.5, -0.6 * fieldDepth);
  const glm::dvec3 eye = start + (end - start) * u;
  const glm::dvec3 target(fieldLength + 1.0, 0.0, -fieldDepth - 1.0 + 2.0 * std::sin(6.28318 * u));
  return {eye, target};
}

// Along the field's front edge, `standoff` in front of its first row and
// 1.5 up, from a fifth of its length left of it to a fifth right, always
// looking at the field's centre.
Pose frontPoseAt(int frame, int frames, double fieldLength, double fieldDepth, double standoff) {
  const double u = frames > 1 ? static_cast<double>(frame) / (frames - 1) : 0.0;
  const glm::dvec3 eye(-0.2 * fieldLength + 1.4 * fieldLength * u, 1.5, standoff);
  const glm::dvec3 target(0.5 * fieldLength, 0.0, -0.5 * fieldDepth);
  return {eye, target};
}

bool inFrustum(const glm::dmat4& viewProjection, const Instance& inst) {
  // Conservative: the sphere against the six clip planes.
  const glm::dmat4 m = glm::transpose(viewProjection);
  const glm::dvec4 planes[6] = {m[3] + m[0], m[3] - m[0], m[3] + m[1],
                                m[3] - m[1], m[3] + m[2], m[3] - m[2]};
  for (const glm::dvec4& p : planes) {
    const double n = glm::length(glm::dvec3(p));
    if (glm::dot(glm::dvec3(p), inst.centre) + p.w < -inst.radius * n) return false;
  }
  return true;
}

struct Gl {
  std::unique_ptr<render::OffscreenContext> context;
  std::unique_ptr<render::RenderTarget> target;
  std::unique_ptr<render::MeshRenderer> meshes;
  std::unique_ptr<render::DiscRenderer> discs;
  ~Gl() {
    if (context) (void)context->makeCurrent();
    discs.reset();
    meshes.reset();
    target.reset();
    context.reset();
  }
};

// Pixels covered in the full-resolution mask and not in `other`
// (uncovered), and those of them with no covered pixel of `other` within
// `tolerance` pixels (holes: a cut within the tolerance may move a
// silhouette by that much, it may not leave a gap wider than it).
struct Holes {
  std::size_t full = 0;
  std::size_t uncovered = 0;
  std::size_t beyondTolerance = 0;
};
Holes countHoles(const RgbaImage& full, const RgbaImage& other, double tolerance) {
  Holes h;
  const int r = static_cast<int>(std::ceil(tolerance));
  for (int y = 0; y < full.height; ++y) {
    for (int x = 0; x < full.width; ++x) {
      if (full.at(x, y)[0] == 0) continue;
      ++h.full;
      if (other.at(x, y)[0] != 0) continue;
      ++h.uncovered;
      bool near = false;
      for (int dy = -r; dy <= r && !near; ++dy) {
        for (int dx = -r; dx <= r && !near; ++dx) {
          const int u = x + dx, v = y + dy;
          if (dx * dx + dy * dy > tolerance * tolerance || u < 0 || v < 0 || u >= full.width ||
              v >= full.height)
            continue;
          near = other.at(u, v)[0] != 0;
        }
      }
      h.beyondTolerance += !near;
    }
  }
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"hybrid fly-through: units vs triangles only and coverage per frame"};
  double kappa = 3.0, tau = 1.0, pixels = 3.0, standoff = 6.0;
  std::string path = "diagonal";
  int frames = 60, instances = 70, parts = 300;
  std::string backendName = "egl", size = "640x480";
  app.add_option("--kappa", kappa, "point rate / triangle rate of the hybrid graph");
  app.add_option("--tau", tau, "transition factor");
  app.add_option("--pixels", pixels, "screen-space tolerance");
  app.add_option("--frames", frames, "poses along the path");
  app.add_option("--instances", instances, "instances of the model");
  app.add_option("--parts", parts,
                 "parts of the generated model (generateScatteredParts(N, 2, 7))");
  app.add_option("--path", path, "diagonal (into the field, the default) or front (along it)");
  app.add_option("--standoff", standoff, "--path front: distance in front of the first row");
  app.add_option("--backend", backendName, "egl or osmesa");
  app.add_option("--size", size, "frame size WxH");
  CLI11_PARSE(app, argc, argv);
  int width = 0, height = 0;
  if (std::sscanf(size.c_str(), "%dx%d", &width, &height) != 2 || width < 16 || height < 16 ||
      width > 4096 || height > 4096 || frames < 1 || instances < 1 || parts < 1 || !(kappa > 1.0) ||
      !(tau > 0.0) || !(pixels > 0.0) || (path != "diagonal" && path != "front") ||
      !(standoff > 0.0)) {
    std::cerr << "bench_hybrid_flythrough: bad options\n";
    return 2;
  }
  const render::Backend backend =
      backendName == "osmesa" ? render::Backend::kOsMesa : render::Backend::kEgl;

  const IndexedMesh model = generateScatteredParts(parts, 2, 7);
  std::cerr << "building graphs of " << model.triangleCount() << " triangles\n";
  HybridOptions hybridOptions;
  hybridOptions.kappa = kappa;
  hybridOptions.tau = tau;
  Result<HybridGraph> hybrid = buildHybridGraph(model, hybridOptions);
  HybridOptions triangleOptions = hybridOptions;
  triangleOptions.enablePoints = false;
  Result<HybridGraph> trianglesOnly = buildHybridGraph(model, triangleOptions);
  if (!hybrid.ok() || !trianglesOnly.ok()) {
    std::cerr << (hybrid.ok() ? trianglesOnly.status() : hybrid.status()).toString() << "\n";
    return 1;
  }

  Gl gl;
  {
    auto context = render::createOffscreenContext(backend, width, height);
    if (!context.ok()) {
      std::cerr << context.status().toString() << "\n";
      return 1;
    }
    gl.context = std::move(context).value();
    auto target = render::RenderTarget::create(*gl.context, width, height);
    auto meshes = render::MeshRenderer::create(*gl.context);
    auto discs = render::DiscRenderer::create(*gl.context, render::DiscStyle::kPointSprites);
    if (!target.ok() || !meshes.ok() || !discs.ok()) {
      std::cerr << "GL set-up failed\n";
      return 1;
    }
    gl.target = std::move(target).value();
    gl.meshes = std::move(meshes).value();
    gl.discs = std::move(discs).value();
  }
  auto fullHandle = gl.meshes->uploadMesh(model);
  if (!fullHandle.ok()) {
    std::cerr << fullHandle.status().toString() << "\n";
    return 1;
  }
  render::Material white;
  white.lit = false;
  white.diffuse = glm::vec4(1.0f);

  const BoundingSphere sphere = model.boundingSphere();
  const std::vector<Instance> field = placeInstances(instances, sphere, 11);
  const double fieldLength = 1.6 * (std::min(instances, 10) - 1);
  const double fieldDepth = 1.6 * ((instances + 9) / 10);
  const double fovY = 60.0 * 3.14159265358979 / 180.0;
  const double pixelsPerRadian = height / (2.0 * std::tan(fovY / 2.0));

  std::printf(
      "### Fly-through: %d instances of scattered-%d (%zu triangles each), %d frames, "
      "%dx%d, fov 60 deg, %.3g-pixel tolerance, kappa %.3g, tau %.3g, path %s",
      instances, parts, model.triangleCount(), frames, width, height, pixels, kappa, tau,
      path.c_str());
  if (path == "front") std::printf(" (standoff %.3g)", standoff);
  std::printf("\n\n");
  // (Build times: bench_hybrid.)
  std::printf(
      "Graphs: hybrid %zu triangles, %zu points; triangles only %zu triangles; renderer: "
      "%s %s\n\n",
      hybrid->stats().graphTriangles, hybrid->stats().graphPoints,
      trianglesOnly->stats().graphTriangles, backendName.c_str(),
      gl.context->rendererName().c_str());
  std::printf(
      "| frame | in view | triangles-only units | hybrid triangles | hybrid points | "
      "hybrid units | reduction | full-res pixels | uncovered hybrid / tri-only | "
      "hybrid coverage %% | holes beyond tolerance hybrid / tri-only |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");

  HybridCut hybridCut(*hybrid);
  HybridCut triangleCut(*trianglesOnly);
  std::vector<double> reductions;
  // Units by the instance's distance from the eye (centre), summed over every
  // frame: does the reduction depend on distance, and which instances hold
  // the units? Bins [0, 2), [2, 4), [4, 8), [8, 16), [16, inf).
  constexpr int kBins = 5;
  const double binEdges[kBins + 1] = {0.0, 2.0, 4.0, 8.0, 16.0, 1e300};
  double binTriangleUnits[kBins] = {}, binHybridUnits[kBins] = {};
  std::size_t binInstances[kBins] = {};
  double minCoverage = 1.0;
  std::size_t totalHoles = 0, totalTriangleHoles = 0, totalUncovered = 0,
              totalTriangleUncovered = 0, totalFull = 0;
  for (int f = 0; f < frames; ++f) {
    const Pose pose = path == "front" ? frontPoseAt(f, frames, fieldLength, fieldDepth, standoff)
                                      : poseAt(f, frames, fieldLength, fieldDepth);
    render::Camera camera;
    camera.view = glm::lookAt(glm::vec3(pose.eye), glm::vec3(pose.target), glm::vec3(0, 1, 0));
    camera.projection = glm::perspective(static_cast<float>(fovY),
                                         static_cast<float>(width) / height, 0.02f, 100.0f);
    const glm::dmat4 viewProjection = glm::dmat4(camera.projection) * glm::dmat4(camera.view);

    double triangleUnits = 0.0, hybridUnits = 0.0;
    std::size_t hybridTriangles = 0, hybridPoints = 0, inView = 0;
    std::vector<render::DrawItem> fullItems;
    std::vector<render::MeshHandle> cutMeshes;
    std::vector<render::DrawItem> cutItems;
    std::vector<render::DrawItem> triangleItems;
    DiscPoints worldDiscs;
    for (const Instance& inst : field) {
      if (!inFrustum(viewProjection, inst)) continue;
      ++inView;
      HybridView view;
      view.eye = glm::dvec3(inst.inverse * glm::dvec4(pose.eye, 1.0));
      view.pixelsPerRadian = pixelsPerRadian;  // object-space errors and distances scale alike
      view.nearDistance = 1e-3;
      triangleCut.adaptToScreen(view, pixels);
      hybridCut.adaptToScreen(view, pixels);
      triangleUnits += triangleCut.units();
      hybridUnits += hybridCut.units();
      {
        const double distance = glm::length(inst.centre - pose.eye);
        int bin = 0;
        while (bin + 1 < kBins && distance >= binEdges[bin + 1]) ++bin;
        binTriangleUnits[bin] += triangleCut.units();
        binHybridUnits[bin] += hybridCut.units();
        ++binInstances[bin];
      }
      hybridTriangles += hybridCut.triangleCount();
      hybridPoints += hybridCut.pointCount();
      fullItems.push_back(render::DrawItem{*fullHandle, glm::mat4(inst.model), white});
      {
        auto handle = gl.meshes->uploadMesh(triangleCut.triangleMesh());
        if (!handle.ok()) {
          std::cerr << handle.status().toString() << "\n";
          return 1;
        }
        triangleItems.push_back(render::DrawItem{*handle, glm::mat4(inst.model), white});
      }
      HybridGeometry geometry = hybridGeometry(hybridCut);
      if (geometry.triangles.triangleCount() > 0) {
        auto handle = gl.meshes->uploadMesh(geometry.triangles);
        if (!handle.ok()) {
          std::cerr << handle.status().toString() << "\n";
          return 1;
        }
        cutMeshes.push_back(*handle);
        cutItems.push_back(render::DrawItem{*handle, glm::mat4(inst.model), white});
      }
      for (auto& c : geometry.points.colors) c = {255, 255, 255, 255};
      render::appendWorldDiscs(worldDiscs, geometry.points, glm::mat4(inst.model));
    }
    // Full-resolution mask, then the hybrid frame.
    RgbaImage full, cut;
    const glm::vec4 black(0.0f, 0.0f, 0.0f, 1.0f);
    bool ok =
        gl.meshes->beginFrame(*gl.target, black).ok() &&
        gl.meshes->draw(fullItems.data(), fullItems.size(), camera, render::Lighting()).ok() &&
        gl.target->readColor(full).ok();
    ok = ok && gl.meshes->beginFrame(*gl.target, black).ok() &&
         gl.meshes->draw(cutItems.data(), cutItems.size(), camera, render::Lighting()).ok();
    render::DiscHandle discHandle;
    if (ok && !worldDiscs.empty()) {
      auto uploaded = gl.discs->upload(worldDiscs);
      ok = uploaded.ok();
      if (ok) {
        discHandle = *uploaded;
        const render::DiscDrawItem item{discHandle, glm::mat4(1.0f)};
        ok = gl.discs->draw(&item, 1, camera).ok();
      }
    }
    ok = ok && gl.target->readColor(cut).ok();
    // The triangles-only cut's frame, for the same comparison.
    RgbaImage trianglesFrame;
    ok = ok && gl.meshes->beginFrame(*gl.target, black).ok() &&
         gl.meshes->draw(triangleItems.data(), triangleItems.size(), camera, render::Lighting())
             .ok() &&
         gl.target->readColor(trianglesFrame).ok();
    for (render::MeshHandle h : cutMeshes) gl.meshes->deleteMesh(h);
    for (const render::DrawItem& item : triangleItems) gl.meshes->deleteMesh(item.mesh);
    if (discHandle.valid()) gl.discs->remove(discHandle);
    if (!ok) {
      std::cerr << "rendering frame " << f << " failed\n";
      return 1;
    }
    const Holes hybridHoles = countHoles(full, cut, pixels);
    const Holes triangleHoles = countHoles(full, trianglesFrame, pixels);
    const std::size_t fullPixels = hybridHoles.full;
    const double coverage =
        fullPixels > 0 ? 1.0 - double(hybridHoles.uncovered) / double(fullPixels) : 1.0;
    const double reduction = hybridUnits > 0.0 ? triangleUnits / hybridUnits : 0.0;
    if (inView > 0) reductions.push_back(reduction);
    minCoverage = std::min(minCoverage, coverage);
    totalHoles += hybridHoles.beyondTolerance;
    totalTriangleHoles += triangleHoles.beyondTolerance;
    totalUncovered += hybridHoles.uncovered;
    totalTriangleUncovered += triangleHoles.uncovered;
    totalFull += fullPixels;
    std::printf(
        "| %d | %zu | %.0f | %zu | %zu | %.1f | %.2f | %zu | %zu / %zu | %.3f | %zu / %zu |\n", f,
        inView, triangleUnits, hybridTriangles, hybridPoints, hybridUnits, reduction, fullPixels,
        hybridHoles.uncovered, triangleHoles.uncovered, 100.0 * coverage,
        hybridHoles.beyondTolerance, triangleHoles.beyondTolerance);
    std::fflush(stdout);
  }
  gl.meshes->deleteMesh(*fullHandle);
  if (reductions.empty()) {
    std::printf("\nno frame had an instance in view\n");
    return 1;
  }
  double sum = 0.0;
  for (double r : reductions) sum += r;
  std::printf(
      "\nSummary: reduction (triangles-only units / hybrid units) mean %.2fx, min %.2fx, "
      "max %.2fx over %zu frames with instances in view; hybrid coverage of the "
      "full-resolution mask min %.3f %% (a frame), overall %.3f %% (triangles only "
      "%.3f %%); holes beyond the %.3g-pixel tolerance: hybrid %zu, triangles only %zu "
      "of %zu full-resolution pixels\n",
      sum / reductions.size(), *std::min_element(reductions.begin(), reductions.end()),
      *std::max_element(reductions.begin(), reductions.end()), reductions.size(),
      100.0 * minCoverage,
      totalFull > 0 ? 100.0 * (1.0 - double(totalUncovered) / double(totalFull)) : 100.0,
      totalFull > 0 ? 100.0 * (1.0 - double(totalTriangleUncovered) / double(totalFull)) : 100.0,
      pixels, totalHoles, totalTriangleHoles, totalFull);
  double allTriangleUnits = 0.0, allHybridUnits = 0.0;
  for (int b = 0; b < kBins; ++b) {
    allTriangleUnits += binTriangleUnits[b];
    allHybridUnits += binHybridUnits[b];
  }
  std::printf(
      "\nUnits by the instance's distance from the eye, summed over the frames (instances "
      "in view):\n\n| distance | instance-frames | triangles-only units | share | hybrid "
      "units | reduction |\n|---|---|---|---|---|---|\n");
  for (int b = 0; b < kBins; ++b) {
    if (binInstances[b] == 0) continue;
    const std::string range = b + 1 < kBins ? std::to_string(int(binEdges[b])) + "-" +
                                                  std::to_string(int(binEdges[b + 1]))
                                            : ">= " + std::to_string(int(binEdges[b]));
    std::printf("| %s | %zu | %.0f | %.1f %% | %.1f | %.2fx |\n", range.c_str(), binInstances[b],
                binTriangleUnits[b], 100.0 * binTriangleUnits[b] / allTriangleUnits,
                binHybridUnits[b], binTriangleUnits[b] / binHybridUnits[b]);
  }
  std::printf("| all | | %.0f | 100 %% | %.1f | %.2fx |\n", allTriangleUnits, allHybridUnits,
              allTriangleUnits / allHybridUnits);
  return 0;
}
