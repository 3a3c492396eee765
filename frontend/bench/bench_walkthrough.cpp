// bench_walkthrough: the Gobbetti-Bouvier walkthrough (issue 14). A plane of
// cow replicas (Garland's cow, one QEM progressive mesh, its measured
// accuracy curve), a camera path that sees all of them, turns away so they
// leave the view, turns back in one frame so many appear at once, then backs
// off. Every frame is planned by the pure schedulers (backbone lib) for that
// frame's pose and drawn by the frontend's renderer offscreen (FrontendRenderer
// on EGL or OSMesa): no daemons.
//
//   bench_calibrate --backend osmesa --out frame_cost.toml
//   bench_walkthrough --backend osmesa --frame-cost frame_cost.toml --csv walk.csv
//
// Methods, each with its own renderer and PlannerState, in the same run:
// - full: every visible cow at full resolution (the accuracy-curve scheduler
//   with an unlimited polygon budget: the same culling); the baseline. The
//   target frame time is its median / --full-over-target unless --target-ms.
// - active-set: Budget::maxFrameSeconds = target, the calibrated constants.
// - accuracy-curve (time as resource): a polygon budget per frame equal to the
//   triangles the target leaves after the model's fixed part for the visible
//   set, (target - t_init - t_final - sum_visible (t_setup + [additive]
//   N_pix t_pix)) / t_tri: the frame-time constraint written in triangles
//   (exact for the additive model; ignores fill-bound objects for the max).
// Per frame: the plan (scheduling time: Plan::row.schedulingMicroseconds,
// the whole planning step of which the optimiser is a part), the first frame
// after the update (uploads + buffer rebuild) and a steady frame (draw +
// readback: what the cost model predicts, as in bench_calibrate). Predicted =
// predictFrameSeconds on the drawn triangle counts with N_pix of each cow's
// bounding sphere seen from the eye (the scheduler's estimate).
// Output: a summary table on stdout, one CSV row per frame and method (--csv).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "frame_time_model.h"  // backbone/src/lib: projectedSpherePixels
#include "thinlod/backbone/scheduler.h"
#include "thinlod/common/core/frame_cost.h"
#include "thinlod/common/mesh/mesh_io.h"
#include "thinlod/frontend/frontend_renderer.h"
#include "thinlod/simplifier/mesh_curve.h"
#include "thinlod/simplifier/progressive_mesh.h"

using namespace thinlod;
using namespace thinlod::frontend;

namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr double kFovY = 0.7853981633974483;  // 45 degrees
constexpr double kFrameSeconds = 0.05;        // the path's clock: 20 poses per second
constexpr double kCowRadius = 0.5;            // m: each replica scaled to this bounding radius

template <typename T>
T orDie(Result<T> result, const char* what) {
  if (!result.ok()) {
    std::fprintf(stderr, "bench_walkthrough: %s: %s\n", what, result.status().toString().c_str());
    std::exit(1);
  }
  return std::move(result).value();
}
void orDie(const Status& status, const char* what) {
  if (!status.ok()) {
    std::fprintf(stderr, "bench_walkthrough: %s: %s\n", what, status.toString().c_str());
    std::exit(1);
  }
}

struct Pose {
  glm::dvec3 eye;
  glm::dvec3 direction;
  const char* phase;
};

glm::dvec3 lerp(const glm::dvec3& a, const glm::dvec3& b, double t) { return a + (b - a) * t; }

glm::dvec3 yawed(const glm::dvec3& d, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  return {c * d.x - s * d.z, d.y, s * d.x + c * d.z};
}

// The path (20 poses/s): 30 frames seeing every cow while closing in,
// 30 turning 80 degrees away so they leave the view, one frame turning back
// (many appear at once) then 19 closing in on the herd, 40 backing off.
std::vector<Pose> walkPath() {
  std::vector<Pose> path;
  const glm::dvec3 origin(0.0);
  const glm::dvec3 start(0.0, 20.0, 55.0), seeAll(0.0, 18.0, 45.0), close(0.0, 10.0, 30.0),
      away(0.0, 25.0, 80.0);
  for (int i = 0; i < 30; ++i) {
    const glm::dvec3 eye = lerp(start, seeAll, i / 29.0);
    path.push_back({eye, origin - eye, "sees-all"});
  }
  for (int i = 1; i <= 30; ++i)
    path.push_back({seeAll, yawed(origin - seeAll, 1.3962634 * i / 30.0), "turns-away"});
  for (int i = 0; i < 20; ++i) {
    const glm::dvec3 eye = lerp(seeAll, close, i / 19.0);
    path.push_back({eye, origin - eye, i == 0 ? "sudden-turn" : "closes-in"});
  }
  for (int i = 1; i <= 40; ++i) {
    const glm::dvec3 eye = lerp(close, away, i / 40.0);
    path.push_back({eye, origin - eye, "backs-off"});
  }
  return path;
}

struct Cow {
  glm::dvec3 center;
  glm::mat4 transform;
};

// One simplified-mesh option per cow with the measured relative curve; a
// root group over all leaves (a few hundred: no need for a hierarchy).
backbone::SchedulingScene cowScene(const std::vector<Cow>& cows, const AccuracyCurve& curve) {
  backbone::SchedulingScene scene;
  backbone::SceneNode root;
  root.kind = backbone::SceneNodeKind::kGroup;
  glm::dvec3 mean(0.0);
  for (const Cow& c : cows) mean += c.center;
  mean /= double(cows.size());
  double radius = 0.0;
  for (const Cow& c : cows) radius = std::max(radius, glm::length(c.center - mean) + kCowRadius);
  root.bounds = {mean, radius * 1.001};
  root.firstChild = 0;
  root.childCount = static_cast<std::uint32_t>(cows.size());
  root.contentVersion = 1;
  scene.nodes.push_back(root);
  for (std::size_t i = 0; i < cows.size(); ++i) {
    backbone::RepresentationOption option;
    option.kind = backbone::OptionKind::kSimplifiedMesh;
    option.relativeTriangles = curve;
    option.relativeLinkBytes = curve;  // no link budget here: any valid curve
    backbone::SceneObject object;
    object.firstOption = static_cast<std::uint32_t>(scene.options.size());
    object.optionCount = 1;
    object.externalId = i + 1;
    scene.options.push_back(std::move(option));
    scene.objects.push_back(object);
    backbone::SceneNode leaf;
    leaf.kind = backbone::SceneNodeKind::kLeaf;
    leaf.bounds = {cows[i].center, kCowRadius};
    leaf.object = static_cast<std::uint32_t>(i);
    leaf.contentVersion = 1;
    scene.nodes.push_back(leaf);
    scene.children.push_back(static_cast<std::uint32_t>(i + 1));
    scene.childRanges.push_back(backbone::ValidityRange{});
  }
  backbone::updateSubtreeVersions(scene);
  orDie(backbone::validateScene(scene), "scene");
  return scene;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * double(v.size())));
  return v[k];
}

struct FrameResult {
  double steadyMs = 0.0;      // draw + readback of the planned frame
  double transitionMs = 0.0;  // the first frame after the update (uploads, rebuild)
  double predictedMs = 0.0;
  double planMicroseconds = 0.0;
  double triangles = 0.0;  // drawn
  std::size_t visible = 0;
  std::size_t drawn = 0;
  double minAccuracy = 0.0;  // rad^-1, the plan's lowest guaranteed accuracy
  double budgetTriangles = 0.0;
};

// One method: a renderer holding what its plans chose.
class Lane {
 public:
  Lane(const char* name, render::OffscreenContext& context, const render::Lighting& lighting)
      : name_(name), lighting_(lighting) {
    FrontendRendererOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.uploadBytesPerFrame = std::numeric_limits<std::size_t>::max();
    renderer_ = orDie(FrontendRenderer::create(context, options), "renderer");
    orDie(renderer_->warmUp(lighting_), "warm up");
  }
  const char* name() const { return name_; }

  // Shows `triangles` per cow (absent: not drawn) and times two frames.
  void show(const std::map<std::uint32_t, std::size_t>& triangles, const std::vector<Cow>& cows,
            const simplifier::ProgressiveMesh& pm, const render::Camera& camera, int repeats,
            FrameResult& out) {
    SceneBatch batch;
    batch.plan = ++plan_;
    for (auto it = held_.begin(); it != held_.end();) {
      if (!triangles.count(it->first)) {
        SceneOperation remove;
        remove.type = SceneOperation::Type::kRemove;
        remove.id = it->first + 1;
        batch.operations.push_back(std::move(remove));
        it = held_.erase(it);
      } else {
        ++it;
      }
    }
    for (const auto& [cow, count] : triangles) {
      const std::size_t actual = pm.triangleCountAt(count);
      auto held = held_.find(cow);
      if (held != held_.end() && held->second == actual) continue;
      SceneOperation add;
      add.id = cow + 1;
      add.representation.kind = RepresentationKind::kMesh;
      add.representation.mesh = meshAt(pm, actual);
      add.representation.transform = cows[cow].transform;
      add.representation.color = glm::vec4(0.85f, 0.75f, 0.6f, 1.0f);
      batch.operations.push_back(std::move(add));
      held_[cow] = actual;
    }
    out.drawn = held_.size();
    out.triangles = 0.0;
    for (const auto& [cow, count] : held_) out.triangles += double(count);
    if (!batch.operations.empty()) orDie(renderer_->submit(std::move(batch)), "submit");
    const FrameReport first = orDie(renderer_->renderFrame(camera, lighting_, frame_), "frame");
    // The steady frame: the median of `repeats` (the shared machine's load
    // varies from frame to frame).
    std::vector<double> steadyMs;
    FrameReport steady;
    for (int k = 0; k < repeats; ++k) {
      steady = orDie(renderer_->renderFrame(camera, lighting_, frame_), "frame");
      steadyMs.push_back(steady.timing.totalMs);
    }
    if (steady.uploadedObjects != 0 || first.pendingBatches != 0) {
      std::fprintf(stderr, "bench_walkthrough: %s: uploads left for the steady frame\n", name_);
      std::exit(1);
    }
    if (steady.triangles != static_cast<std::size_t>(out.triangles)) {
      std::fprintf(stderr, "bench_walkthrough: %s: drew %zu triangles, planned %.0f\n", name_,
                   steady.triangles, out.triangles);
      std::exit(1);
    }
    out.transitionMs = first.timing.totalMs;
    std::sort(steadyMs.begin(), steadyMs.end());
    out.steadyMs = steadyMs[steadyMs.size() / 2];
  }

 private:
  std::shared_ptr<const IndexedMesh> meshAt(const simplifier::ProgressiveMesh& pm,
                                            std::size_t triangles) {
    auto& slot = meshes_[triangles];
    if (!slot) {
      IndexedMesh mesh = pm.extract(triangles);
      mesh.computeNormals();
      slot = std::make_shared<const IndexedMesh>(std::move(mesh));
    }
    return slot;
  }

  const char* name_;
  render::Lighting lighting_;
  std::unique_ptr<FrontendRenderer> renderer_;
  std::map<std::uint32_t, std::size_t> held_;  // cow -> triangles shown
  std::map<std::size_t, std::shared_ptr<const IndexedMesh>> meshes_;
  std::uint64_t plan_ = 0;
  RgbaImage frame_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"thinlod walkthrough: time-critical (active-set) vs accuracy-curve on the renderer"};
  std::string backendName = "auto";
  std::string frameCostPath;
  std::string csvPath;
  std::string modelPath = std::string(THINLOD_SHARED_DIR) + "/models/cow.obj";
  int columns = 20, rows = 15;
  double spacing = 2.0;
  double targetMs = 0.0;
  double fullOverTarget = 5.0;
  int repeats = 3;
  app.add_option("--backend", backendName, "auto|egl|osmesa")
      ->check(CLI::IsMember({"auto", "egl", "osmesa"}));
  app.add_option("--frame-cost", frameCostPath,
                 "the renderer's constants (bench_calibrate --out, same back-end)")
      ->required();
  app.add_option("--csv", csvPath, "one row per frame and method");
  app.add_option("--model", modelPath, "the replicated mesh");
  app.add_option("--columns", columns, "cows along x")->check(CLI::Range(1, 200));
  app.add_option("--rows", rows, "cows along z")->check(CLI::Range(1, 200));
  app.add_option("--spacing", spacing, "metres between cows")->check(CLI::Range(1.0, 100.0));
  app.add_option("--target-ms", targetMs,
                 "target frame time (0: median full-detail time / "
                 "--full-over-target)");
  app.add_option("--full-over-target", fullOverTarget, "full detail / target when automatic")
      ->check(CLI::Range(1.0, 100.0));
  app.add_option("--repeats", repeats, "steady frames per planned frame (median)")
      ->check(CLI::Range(1, 50));
  CLI11_PARSE(app, argc, argv);

  const FrameCostConstants costs = orDie(loadFrameCostFile(frameCostPath), "frame cost");
  const render::Backend backend = backendName == "egl"      ? render::Backend::kEgl
                                  : backendName == "osmesa" ? render::Backend::kOsMesa
                                                            : render::Backend::kAuto;
  auto context = orDie(render::createOffscreenContext(backend, kWidth, kHeight), "context");
  std::fprintf(stderr, "bench_walkthrough: %s, %s\n", render::backendName(context->backend()),
               context->rendererName().c_str());

  // The cow: progressive mesh and measured relative accuracy curve.
  IndexedMesh cow = orDie(loadMeshFile(modelPath), "model").mesh;
  const BoundingSphere sphere = cow.boundingSphere();
  const simplifier::ProgressiveMesh pm = orDie(simplifier::ProgressiveMesh::build(cow), "pm");
  simplifier::MeshCurveOptions curveOptions;
  curveOptions.measureEncodedBytes = false;
  const simplifier::MeshCurves curves =
      orDie(simplifier::measureMeshCurves(cow, pm, curveOptions), "curve");
  const double fullTriangles = double(pm.maxTriangles());
  std::fprintf(stderr, "bench_walkthrough: %s: %zu..%zu triangles, %zu curve levels\n",
               modelPath.c_str(), pm.minTriangles(), pm.maxTriangles(), curves.levels.size());

  // The herd on the plane y = 0, random yaw (fixed seed), radius kCowRadius.
  std::vector<Cow> cows;
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double scale = kCowRadius / sphere.radius;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const glm::dvec3 center((c - 0.5 * (columns - 1)) * spacing, kCowRadius,
                              (r - 0.5 * (rows - 1)) * spacing);
      glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(center));
      m = glm::rotate(m, static_cast<float>(unit(rng) * 6.283185307), glm::vec3(0, 1, 0));
      m = glm::scale(m, glm::vec3(static_cast<float>(scale)));
      m = glm::translate(m, -sphere.center);
      cows.push_back({center, m});
    }
  }
  const backbone::SchedulingScene scene = cowScene(cows, curves.triangles);
  const std::vector<Pose> path = walkPath();

  backbone::SchedulerConfig config;
  config.maxSpeed = 20.0;  // m/s: the path's fastest leg is 15 m/s
  config.maxAngularSpeed = 1.0;
  config.plannedLifetime = kFrameSeconds;  // plan for this frame only (time-critical)
  config.linkDelay = 0.0;
  config.generationDelay = 0.0;
  backbone::SchedulerOptions options;
  options.config = config;
  options.timeCritical.viewportWidth = kWidth;
  options.timeCritical.viewportHeight = kHeight;
  options.timeCritical.costs = costs;
  auto curveScheduler = orDie(backbone::makeScheduler("accuracy-curve", options), "scheduler");
  auto activeSet = orDie(backbone::makeScheduler("active-set", options), "scheduler");

  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.3f);
  lighting.lights.push_back({render::Light::Type::kDirectional,
                             glm::normalize(glm::vec3(-0.4f, -1.0f, -0.6f)), glm::vec3(0.8f),
                             0.0f});
  const float aspect = static_cast<float>(kWidth) / kHeight;
  const double horizontalFov = 2.0 * std::atan(std::tan(0.5 * kFovY) * aspect);
  const backbone::ScreenProjection screen{double(kWidth), double(kHeight), kFovY};

  auto viewerAt = [&](std::size_t frame) {
    backbone::ViewerState v;
    v.frame = frame;
    v.timeSeconds = double(frame) * kFrameSeconds;
    v.position = path[frame].eye;
    v.viewDirection = path[frame].direction;
    v.horizontalFov = horizontalFov;
    v.verticalFov = kFovY;
    return v;
  };
  auto cameraAt = [&](std::size_t frame) {
    render::Camera camera;
    const glm::vec3 eye(path[frame].eye);
    camera.view = glm::lookAt(eye, eye + glm::vec3(glm::normalize(path[frame].direction)),
                              glm::vec3(0, 1, 0));
    camera.projection = glm::perspective(static_cast<float>(kFovY), aspect, 0.1f, 500.0f);
    return camera;
  };
  auto pixelsOf = [&](std::size_t frame, std::uint32_t cow) {
    return backbone::projectedSpherePixels(glm::length(cows[cow].center - path[frame].eye),
                                           kCowRadius, screen);
  };
  auto predictMs = [&](std::size_t frame, const std::map<std::uint32_t, std::size_t>& shown) {
    std::vector<DrawnObjectLoad> loads;
    for (const auto& [cow, count] : shown)
      loads.push_back({double(pm.triangleCountAt(count)), pixelsOf(frame, cow)});
    return predictFrameSeconds(costs, loads) * 1e3;
  };
  // Triangles per visible object of a plan (rendered decisions only).
  auto shownBy = [&](const backbone::Plan& plan) {
    std::map<std::uint32_t, std::size_t> shown;
    for (const backbone::ObjectDecision& d : plan.decisions)
      if (d.action != backbone::ObjectAction::kRemove && d.triangles > 0.0)
        shown[d.object] =
            static_cast<std::size_t>(std::llround(std::min(d.triangles, fullTriangles)));
    return shown;
  };

  // Pass 1: full detail (sets the target).
  const std::size_t frames = path.size();
  std::vector<FrameResult> full(frames);
  {
    Lane lane("full", *context, lighting);
    backbone::PlannerState state;
    backbone::Budget unlimited;
    unlimited.maxTriangles = 1e12;
    for (std::size_t f = 0; f < frames; ++f) {
      const backbone::Plan plan =
          orDie(curveScheduler->plan(scene, viewerAt(f), unlimited, state), "plan full");
      std::map<std::uint32_t, std::size_t> shown;
      for (const auto& [cow, count] : shownBy(plan)) shown[cow] = pm.maxTriangles();
      full[f].visible = plan.stats.visibleObjects;
      full[f].planMicroseconds = plan.row.schedulingMicroseconds;
      full[f].minAccuracy = plan.achievedMinAccuracy;
      full[f].predictedMs = predictMs(f, shown);
      lane.show(shown, cows, pm, cameraAt(f), repeats, full[f]);
    }
  }
  std::vector<double> fullMs;
  for (const FrameResult& r : full)
    if (r.drawn > 0) fullMs.push_back(r.steadyMs);
  if (targetMs <= 0.0) targetMs = quantile(fullMs, 0.5) / fullOverTarget;
  const double target = targetMs * 1e-3;
  std::fprintf(stderr, "bench_walkthrough: target %.2f ms (full detail median %.1f ms)\n", targetMs,
               quantile(fullMs, 0.5));

  // Pass 2: the two schedulers, frame by frame, in the same run.
  std::vector<FrameResult> timeCritical(frames), curve(frames);
  {
    Lane activeLane("active-set", *context, lighting);
    Lane curveLane("accuracy-curve", *context, lighting);
    backbone::PlannerState activeState, curveState;
    backbone::Budget timeBudget;
    timeBudget.maxFrameSeconds = target;
    for (std::size_t f = 0; f < frames; ++f) {
      const backbone::ViewerState viewer = viewerAt(f);
      const backbone::Plan a =
          orDie(activeSet->plan(scene, viewer, timeBudget, activeState), "plan active-set");
      const std::map<std::uint32_t, std::size_t> activeShown = shownBy(a);
      FrameResult& ra = timeCritical[f];
      ra.visible = a.stats.visibleObjects;
      ra.planMicroseconds = a.row.schedulingMicroseconds;
      ra.minAccuracy = a.achievedMinAccuracy;
      ra.predictedMs = predictMs(f, activeShown);
      activeLane.show(activeShown, cows, pm, cameraAt(f), repeats, ra);

      // The time budget in triangles for this frame's visible set (that of the
      // unlimited plan of pass 1: the same culling).
      double fixedSeconds = costs.initSeconds + costs.finalSeconds;
      {
        backbone::PlannerState probe;
        backbone::Budget unlimited;
        unlimited.maxTriangles = 1e12;
        const backbone::Plan all =
            orDie(curveScheduler->plan(scene, viewer, unlimited, probe), "plan visible set");
        for (const auto& [cow, count] : shownBy(all))
          fixedSeconds +=
              costs.setupSeconds + (costs.additive ? pixelsOf(f, cow) * costs.pixelSeconds : 0.0);
      }
      backbone::Budget triangles;
      triangles.maxTriangles = std::max(1.0, (target - fixedSeconds) / costs.triangleSeconds);
      const backbone::Plan c =
          orDie(curveScheduler->plan(scene, viewer, triangles, curveState), "plan accuracy-curve");
      const std::map<std::uint32_t, std::size_t> curveShown = shownBy(c);
      FrameResult& rc = curve[f];
      rc.visible = c.stats.visibleObjects;
      rc.planMicroseconds = c.row.schedulingMicroseconds;
      rc.minAccuracy = c.achievedMinAccuracy;
      rc.budgetTriangles = *triangles.maxTriangles;
      rc.predictedMs = predictMs(f, curveShown);
      curveLane.show(curveShown, cows, pm, cameraAt(f), repeats, rc);
    }
  }

  if (!csvPath.empty()) {
    std::ofstream csv(csvPath);
    csv << "frame,phase,method,visible,drawn,triangles,budget_triangles,predicted_ms,steady_ms,"
           "transition_ms,target_ms,plan_us,min_accuracy\n";
    const std::pair<const char*, const std::vector<FrameResult>*> lanes[] = {
        {"full", &full}, {"active-set", &timeCritical}, {"accuracy-curve", &curve}};
    for (std::size_t f = 0; f < frames; ++f)
      for (const auto& [name, results] : lanes) {
        const FrameResult& r = (*results)[f];
        char line[512];
        std::snprintf(
            line, sizeof line, "%zu,%s,%s,%zu,%zu,%.0f,%.0f,%.3f,%.3f,%.3f,%.3f,%.1f,%.6g\n", f,
            path[f].phase, name, r.visible, r.drawn, r.triangles, r.budgetTriangles, r.predictedMs,
            r.steadyMs, r.transitionMs, targetMs, r.planMicroseconds, r.minAccuracy);
        csv << line;
      }
  }

  // Summary.
  std::printf("walkthrough: %zu cows (%dx%d, %.1f m apart), %zu frames, %s, target %.2f ms\n",
              cows.size(), columns, rows, spacing, frames, render::backendName(context->backend()),
              targetMs);
  std::printf(
      "constants: t_init+t_final %.3f ms, t_setup %.3g us, t_tri %.4g ns, t_pix %.4g ns, %s\n",
      (costs.initSeconds + costs.finalSeconds) * 1e3, costs.setupSeconds * 1e6,
      costs.triangleSeconds * 1e9, costs.pixelSeconds * 1e9, costs.additive ? "additive" : "max");
  std::vector<double> ratio;
  for (std::size_t f = 0; f < frames; ++f)
    if (2 * full[f].drawn >= cows.size()) ratio.push_back(full[f].steadyMs / targetMs);
  std::printf(
      "full detail / target: median %.2f, min %.2f, max %.2f (%zu frames with at least half the "
      "herd in view)\n",
      quantile(ratio, 0.5), quantile(ratio, 0.0), quantile(ratio, 1.0), ratio.size());
  std::printf(
      "| method | median ms | p95 ms | max ms | over target | over 1.2x | predicted/measured "
      "(median) | |pred-meas| median ms | speed-up vs full (median) | plan us median | plan us "
      "max | median triangles | median min accuracy | transition ms median / max |\n");
  std::printf(
      "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  const std::pair<const char*, const std::vector<FrameResult>*> lanes[] = {
      {"full detail", &full}, {"active-set", &timeCritical}, {"accuracy-curve (time)", &curve}};
  for (const auto& [name, results] : lanes) {
    std::vector<double> ms, predRatio, predError, speedUp, plan, tris, accuracy, transition;
    int over = 0, over12 = 0, counted = 0;
    for (std::size_t f = 0; f < frames; ++f) {
      const FrameResult& r = (*results)[f];
      if (full[f].drawn == 0) continue;  // nothing in view: not a frame to budget
      ++counted;
      ms.push_back(r.steadyMs);
      transition.push_back(r.transitionMs);
      over += r.steadyMs > targetMs ? 1 : 0;
      over12 += r.steadyMs > 1.2 * targetMs ? 1 : 0;
      predRatio.push_back(r.predictedMs / r.steadyMs);
      predError.push_back(std::abs(r.predictedMs - r.steadyMs));
      speedUp.push_back(full[f].steadyMs / r.steadyMs);
      plan.push_back(r.planMicroseconds);
      tris.push_back(r.triangles);
      accuracy.push_back(r.minAccuracy);
    }
    std::printf(
        "| %s | %.2f | %.2f | %.2f | %d of %d | %d | %.3f | %.2f | %.2f | %.0f | %.0f | %.0f | "
        "%.4g | %.1f / %.1f |\n",
        name, quantile(ms, 0.5), quantile(ms, 0.95), quantile(ms, 1.0), over, counted, over12,
        quantile(predRatio, 0.5), quantile(predError, 0.5), quantile(speedUp, 0.5),
        quantile(plan, 0.5), quantile(plan, 1.0), quantile(tris, 0.5), quantile(accuracy, 0.5),
        quantile(transition, 0.5), quantile(transition, 1.0));
  }
  // Per phase: median steady ms and frames over target.
  std::printf(
      "\n| phase | frames | visible (median) | full ms | active-set ms (over) | "
      "accuracy-curve ms (over) |\n| --- | --- | --- | --- | --- | --- |\n");
  for (const char* phase : {"sees-all", "turns-away", "sudden-turn", "closes-in", "backs-off"}) {
    std::vector<double> visible, f0, f1, f2;
    int over1 = 0, over2 = 0;
    for (std::size_t f = 0; f < frames; ++f) {
      if (std::string(path[f].phase) != phase) continue;
      visible.push_back(double(full[f].visible));
      f0.push_back(full[f].steadyMs);
      f1.push_back(timeCritical[f].steadyMs);
      f2.push_back(curve[f].steadyMs);
      over1 += timeCritical[f].steadyMs > targetMs ? 1 : 0;
      over2 += curve[f].steadyMs > targetMs ? 1 : 0;
    }
    std::printf("| %s | %zu | %.0f | %.1f | %.1f (%d) | %.1f (%d) |\n", phase, f0.size(),
                quantile(visible, 0.5), quantile(f0, 0.5), quantile(f1, 0.5), over1,
                quantile(f2, 0.5), over2);
  }
  // The sudden turn: the frame where many cows appear at once.
  for (std::size_t f = 0; f < frames; ++f) {
    if (std::string(path[f].phase) != "sudden-turn") continue;
    std::printf(
        "sudden turn (frame %zu, %zu visible, %zu the frame before): full %.1f ms, active-set "
        "%.2f ms (transition %.1f), accuracy-curve %.2f ms (transition %.1f), target %.2f\n",
        f, full[f].visible, f > 0 ? full[f - 1].visible : 0, full[f].steadyMs,
        timeCritical[f].steadyMs, timeCritical[f].transitionMs, curve[f].steadyMs,
        curve[f].transitionMs, targetMs);
  }
  return 0;
}
