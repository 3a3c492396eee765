// Helpers for the scheduler tests: hand-built scenes, a simulated frontend
// that applies plans, and the exact (no hysteresis, no caching slack) config.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <random>
#include <vector>

#include "thinlod/backbone/scheduler.h"
#include "thinlod/backbone/synthetic_scene.h"

namespace thinlod::backbone::testing {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kInf = std::numeric_limits<double>::infinity();

inline AccuracyCurve curveThrough(const std::vector<double>& a, const std::vector<double>& r) {
  std::vector<CurveSegment> segments;
  for (std::size_t i = 0; i + 1 < a.size(); ++i)
    segments.push_back({a[i], r[i], (r[i + 1] - r[i]) / (a[i + 1] - a[i])});
  return AccuracyCurve::fromSegments(std::move(segments), a.back()).value();
}

inline ValidityRange fromDistance(const glm::dvec3& center, double minDistance) {
  return ConicRange::make(center, minDistance, kInf, {0, 0, 1}, kPi).value();
}

// A polygon-mesh option: triangles linear in accuracy on [a0, a1].
inline RepresentationOption meshOption(double a0, double t0, double a1, double t1,
                                       double bytesPerTriangle = 2.0) {
  RepresentationOption o;
  o.kind = OptionKind::kSimplifiedMesh;
  o.relativeTriangles = curveThrough({a0, a1}, {t0, t1});
  o.relativeLinkBytes = curveThrough({a0, a1}, {t0 * bytesPerTriangle, t1 * bytesPerTriangle});
  return o;
}

inline RepresentationOption pointOption(OptionKind kind, double accuracy, double triangles,
                                        double bytes) {
  RepresentationOption o;
  o.kind = kind;
  o.relativeTriangles = AccuracyCurve::point(accuracy, triangles);
  o.relativeLinkBytes = AccuracyCurve::point(accuracy, bytes);
  return o;
}

// Builds a scene tree; group/LOD bounds enclose their children unless given.
class SceneBuilder {
 public:
  int group(int parent, ValidityRange range = ConicRange::everywhere()) {
    return add(parent, SceneNodeKind::kGroup, Sphere{}, {}, range);
  }
  int lod(int parent, ValidityRange range = ConicRange::everywhere()) {
    return add(parent, SceneNodeKind::kLod, Sphere{}, {}, range);
  }
  int leaf(int parent, Sphere bounds, std::vector<RepresentationOption> options,
           ValidityRange range = ConicRange::everywhere()) {
    return add(parent, SceneNodeKind::kLeaf, bounds, std::move(options), range);
  }

  SchedulingScene build() {
    for (std::size_t i = drafts_.size(); i-- > 0;) {
      Draft& d = drafts_[i];
      if (d.kind == SceneNodeKind::kLeaf || d.children.empty()) {
        if (d.bounds.radius <= 0.0) d.bounds.radius = 1.0;
        continue;
      }
      glm::dvec3 c(0.0);
      for (int k : d.children) c += drafts_[k].bounds.center;
      c /= double(d.children.size());
      double r = 0.0;
      for (int k : d.children)
        r = std::max(r, glm::length(drafts_[k].bounds.center - c) + drafts_[k].bounds.radius);
      d.bounds = {c, r * (1 + 1e-12) + 1e-12};
    }
    SchedulingScene scene;
    std::vector<int> order;
    std::vector<int> stack{0};
    while (!stack.empty()) {
      const int d = stack.back();
      stack.pop_back();
      order.push_back(d);
      for (auto it = drafts_[d].children.rbegin(); it != drafts_[d].children.rend(); ++it)
        stack.push_back(*it);
    }
    std::vector<std::uint32_t> index(drafts_.size());
    for (std::size_t i = 0; i < order.size(); ++i) index[order[i]] = static_cast<std::uint32_t>(i);
    for (int d : order) {
      const Draft& draft = drafts_[d];
      SceneNode n;
      n.kind = draft.kind;
      n.bounds = draft.bounds;
      n.contentVersion = 1;
      n.firstChild = static_cast<std::uint32_t>(scene.children.size());
      n.childCount = static_cast<std::uint32_t>(draft.children.size());
      for (int c : draft.children) {
        scene.children.push_back(index[c]);
        scene.childRanges.push_back(drafts_[c].range);
      }
      if (draft.kind == SceneNodeKind::kLeaf) {
        n.object = static_cast<std::uint32_t>(scene.objects.size());
        SceneObject o;
        o.firstOption = static_cast<std::uint32_t>(scene.options.size());
        o.optionCount = static_cast<std::uint32_t>(draft.options.size());
        o.externalId = static_cast<std::uint64_t>(d);
        scene.objects.push_back(o);
        for (const RepresentationOption& opt : draft.options) scene.options.push_back(opt);
      }
      scene.nodes.push_back(n);
    }
    updateSubtreeVersions(scene);
    return scene;
  }

 private:
  struct Draft {
    SceneNodeKind kind;
    Sphere bounds;
    std::vector<RepresentationOption> options;
    ValidityRange range;
    std::vector<int> children;
  };
  int add(int parent, SceneNodeKind kind, Sphere bounds, std::vector<RepresentationOption> options,
          ValidityRange range) {
    drafts_.push_back({kind, bounds, std::move(options), range, {}});
    const int id = static_cast<int>(drafts_.size() - 1);
    if (parent >= 0) drafts_[parent].children.push_back(id);
    return id;
  }
  std::vector<Draft> drafts_;
};

// Config without hysteresis, caching slack or merging: the plain model.
inline SchedulerConfig exactConfig() {
  SchedulerConfig c;
  c.maxSpeed = 0.1;
  c.maxAngularSpeed = 0.5;
  c.plannedLifetime = 1.0;
  c.linkDelay = 0.05;
  c.generationDelay = 0.1;
  return withoutApproximations(c);
}

inline ViewerState viewerAt(glm::dvec3 position, glm::dvec3 direction, double time = 0.0,
                            std::uint64_t frame = 0) {
  ViewerState v;
  v.position = position;
  v.viewDirection = direction;
  v.timeSeconds = time;
  v.frame = frame;
  return v;
}

// The frontend as the tests model it: a delivered copy replaces whatever the
// object displayed; removals drop copies. Delivery is immediate.
inline void applyPlan(SchedulingScene& scene, const Plan& plan) {
  std::vector<std::uint32_t> touched;
  for (const Removal& r : plan.removals) {
    scene.options[r.option].atFrontend.present = false;
    touched.push_back(r.object);
  }
  for (const ObjectDecision& d : plan.decisions) {
    if (d.action != ObjectAction::kRequest && d.action != ObjectAction::kSend) continue;
    const SceneObject& object = scene.objects[d.object];
    for (std::uint32_t k = 0; k < object.optionCount; ++k)
      scene.options[object.firstOption + k].atFrontend.present = false;
    touched.push_back(d.object);
  }
  for (const RepresentationRequest& r : plan.requests) {
    RepresentationOption& option = scene.options[r.option];
    RepresentationCopy& copy = option.atFrontend;
    copy.present = true;
    copy.id = r.requestId;
    copy.relativeAccuracy = r.relativeAccuracy;
    copy.triangles = r.expectedTriangles;
    copy.encodedBytes = r.expectedBytes;
    const bool impostor = option.kind == OptionKind::kMeshedImpostor ||
                          option.kind == OptionKind::kSimpleImpostor;
    copy.validity = impostor ? ConicRange::ball(r.viewRegion.center, r.viewRegion.radius)
                             : ConicRange::everywhere();
  }
  for (const ObjectDecision& d : plan.decisions) {
    if (d.action != ObjectAction::kSend) continue;
    RepresentationOption& option = scene.options[static_cast<std::uint32_t>(d.option)];
    option.atFrontend = option.atBackbone;
  }
  std::vector<std::uint32_t> leafOf(scene.objects.size(), 0);
  for (std::uint32_t n = 0; n < scene.nodes.size(); ++n)
    if (scene.nodes[n].kind == SceneNodeKind::kLeaf) leafOf[scene.nodes[n].object] = n;
  for (std::uint32_t o : touched) ++scene.nodes[leafOf[o]].contentVersion;
  updateSubtreeVersions(scene);
}

inline std::unique_ptr<Scheduler> curveScheduler(const SchedulerConfig& config) {
  auto made = makeAccuracyCurveScheduler(config);
  EXPECT_TRUE(made.ok()) << made.status().toString();
  return std::move(made).value();
}

inline std::unique_ptr<Scheduler> bruteScheduler(const SchedulerConfig& config) {
  auto made = makeBruteForceScheduler(config, BruteForceConfig{});
  EXPECT_TRUE(made.ok()) << made.status().toString();
  return std::move(made).value();
}

}  // namespace thinlod::backbone::testing
