#include "thinlod/backbone/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <random>
#include <string>

namespace thinlod::backbone {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Piecewise-linear curve through (accuracy, resources) knots.
AccuracyCurve through(const std::vector<double>& a, const std::vector<double>& r) {
  std::vector<CurveSegment> segments;
  for (std::size_t i = 0; i + 1 < a.size(); ++i)
    segments.push_back({a[i], r[i], (r[i + 1] - r[i]) / (a[i + 1] - a[i])});
  Result<AccuracyCurve> curve = AccuracyCurve::fromSegments(std::move(segments), a.back());
  return curve.ok() ? std::move(curve).value() : AccuracyCurve::point(a.back(), r.back());
}

std::uint64_t spread(std::uint64_t v) {  // 21 bits -> every third bit
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

struct Draft {
  SceneNodeKind kind;
  Sphere bounds;
  std::vector<std::uint32_t> children;
  std::vector<ValidityRange> ranges;  // LOD levels
  std::uint32_t object = 0;
};

Sphere enclose(const std::vector<Draft>& drafts, const std::vector<std::uint32_t>& kids) {
  glm::dvec3 center(0.0);
  for (std::uint32_t k : kids) center += drafts[k].bounds.center;
  center /= double(kids.size());
  double radius = 0.0;
  for (std::uint32_t k : kids)
    radius =
        std::max(radius, glm::length(drafts[k].bounds.center - center) + drafts[k].bounds.radius);
  return {center, radius * (1.0 + 1e-12) + 1e-12};
}

}  // namespace

Result<SchedulingScene> makeSyntheticScene(const SyntheticSceneOptions& o) {
  if (o.objects == 0 || o.objects > 50'000'000)
    return Status(ErrorCode::kInvalidArgument, "SyntheticSceneOptions.objects must be in [1, 5e7]");
  if (!(o.worldSize > 0.0) || !(o.minRadius > 0.0) || !(o.maxRadius >= o.minRadius) ||
      !std::isfinite(o.worldSize) || !std::isfinite(o.maxRadius))
    return Status(ErrorCode::kInvalidArgument,
                  "SyntheticSceneOptions: worldSize > 0 and 0 < minRadius <= maxRadius, finite");
  if (o.fanout < 2) return Status(ErrorCode::kInvalidArgument, "SyntheticSceneOptions.fanout >= 2");
  if (!(o.minTriangles > 0.0) || !(o.maxTriangles >= o.minTriangles) ||
      !std::isfinite(o.maxTriangles))
    return Status(ErrorCode::kInvalidArgument,
                  "SyntheticSceneOptions: 0 < minTriangles <= maxTriangles, finite");
  if (!(o.lodShare >= 0.0 && o.lodShare <= 1.0))
    return Status(ErrorCode::kInvalidArgument, "SyntheticSceneOptions.lodShare in [0, 1]");

  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  SchedulingScene scene;
  std::vector<Draft> drafts;
  std::vector<std::uint32_t> tops;  // one per placed object (leaf or LOD)

  auto addObject = [&](const Sphere& bounds, bool coarseOnly) {
    SceneObject object;
    object.firstOption = static_cast<std::uint32_t>(scene.options.size());
    object.externalId = scene.objects.size();
    const double full =
        coarseOnly ? 2.0 : o.minTriangles * std::pow(o.maxTriangles / o.minTriangles, unit(rng));
    auto meshBytes = [](double t) { return 1.5 * t + 500.0; };
    if (coarseOnly) {
      RepresentationOption point;
      point.kind = OptionKind::kSimpleImpostor;
      point.relativeTriangles = AccuracyCurve::point(15.0, 2.0);
      point.relativeLinkBytes = AccuracyCurve::point(15.0, 4000.0);
      scene.options.push_back(std::move(point));
    } else {
      RepresentationOption simplified;
      simplified.kind = OptionKind::kSimplifiedMesh;
      const std::vector<double> a{4.0, 40.0, 400.0};
      const std::vector<double> t{8.0, std::max(20.0, 0.05 * full), std::max(40.0, 0.6 * full)};
      simplified.relativeTriangles = through(a, t);
      simplified.relativeLinkBytes =
          through(a, {meshBytes(t[0]), meshBytes(t[1]), meshBytes(t[2])});
      scene.options.push_back(std::move(simplified));
      if (o.originalMesh) {
        RepresentationOption original;
        original.kind = OptionKind::kOriginalMesh;
        original.relativeTriangles = AccuracyCurve::point(1000.0, full);
        original.relativeLinkBytes = AccuracyCurve::point(1000.0, meshBytes(full));
        scene.options.push_back(std::move(original));
      }
      if (o.meshedImpostor) {
        RepresentationOption meshed;
        meshed.kind = OptionKind::kMeshedImpostor;
        const std::vector<double> ma{5.0, 50.0, 150.0};
        const std::vector<double> mt{8.0, 200.0, 2000.0};
        meshed.relativeTriangles = through(ma, mt);
        meshed.relativeLinkBytes =
            through(ma, {6000.0 + 4 * mt[0], 6000.0 + 4 * mt[1], 6000.0 + 4 * mt[2]});
        meshed.validity = ConicRange::make(bounds.center, 4.0 * bounds.radius,
                                           std::numeric_limits<double>::infinity(), {0, 0, 1}, kPi)
                              .value();
        scene.options.push_back(std::move(meshed));
      }
      if (o.simpleImpostor) {
        RepresentationOption simple;
        simple.kind = OptionKind::kSimpleImpostor;
        simple.relativeTriangles = AccuracyCurve::point(30.0, 2.0);
        simple.relativeLinkBytes = AccuracyCurve::point(30.0, 6000.0);
        simple.validity = ConicRange::make(bounds.center, 10.0 * bounds.radius,
                                           std::numeric_limits<double>::infinity(), {0, 0, 1}, kPi)
                              .value();
        scene.options.push_back(std::move(simple));
      }
    }
    object.optionCount = static_cast<std::uint32_t>(scene.options.size()) - object.firstOption;
    scene.objects.push_back(object);
    Draft leaf;
    leaf.kind = SceneNodeKind::kLeaf;
    leaf.bounds = bounds;
    leaf.object = static_cast<std::uint32_t>(scene.objects.size() - 1);
    drafts.push_back(std::move(leaf));
    return static_cast<std::uint32_t>(drafts.size() - 1);
  };

  for (std::size_t i = 0; i < o.objects; ++i) {
    Sphere bounds;
    bounds.center = glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * o.worldSize;
    bounds.radius = o.minRadius * std::pow(o.maxRadius / o.minRadius, unit(rng));
    const bool lod = unit(rng) < o.lodShare;
    const std::uint32_t detailed = addObject(bounds, false);
    if (!lod) {
      tops.push_back(detailed);
      continue;
    }
    Sphere inner{bounds.center, bounds.radius * 0.999};
    const std::uint32_t coarse = addObject(inner, true);
    Draft level;
    level.kind = SceneNodeKind::kLod;
    level.bounds = bounds;
    level.children = {detailed, coarse};
    level.ranges = {ConicRange::everywhere(),
                    ConicRange::make(bounds.center, 6.0 * bounds.radius,
                                     std::numeric_limits<double>::infinity(), {0, 0, 1}, kPi)
                        .value()};
    drafts.push_back(std::move(level));
    tops.push_back(static_cast<std::uint32_t>(drafts.size() - 1));
  }

  // Spatial grouping: Morton order, then groups of `fanout` per level.
  const double half = 0.5 * o.worldSize;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
  keyed.reserve(tops.size());
  for (std::uint32_t t : tops) {
    const glm::dvec3 c = (drafts[t].bounds.center + half) / o.worldSize;
    auto q = [](double v) {
      return static_cast<std::uint64_t>(std::clamp(v, 0.0, 1.0) * 2097151.0);
    };
    keyed.push_back({spread(q(c.x)) | spread(q(c.y)) << 1 | spread(q(c.z)) << 2, t});
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> level;
  for (const auto& [key, t] : keyed) level.push_back(t);
  while (level.size() > 1) {
    std::vector<std::uint32_t> next;
    for (std::size_t i = 0; i < level.size(); i += o.fanout) {
      Draft group;
      group.kind = SceneNodeKind::kGroup;
      group.children.assign(level.begin() + i,
                            level.begin() + std::min(level.size(), i + o.fanout));
      group.bounds = enclose(drafts, group.children);
      drafts.push_back(std::move(group));
      next.push_back(static_cast<std::uint32_t>(drafts.size() - 1));
    }
    level = std::move(next);
  }
  if (drafts[level.front()].kind != SceneNodeKind::kGroup) {
    Draft root;
    root.kind = SceneNodeKind::kGroup;
    root.children = {level.front()};
    root.bounds = enclose(drafts, root.children);
    drafts.push_back(std::move(root));
    level = {static_cast<std::uint32_t>(drafts.size() - 1)};
  }

  // Preorder numbering: parents before children, siblings contiguous.
  std::vector<std::uint32_t> order;
  order.reserve(drafts.size());
  std::vector<std::uint32_t> stack{level.front()};
  while (!stack.empty()) {
    const std::uint32_t d = stack.back();
    stack.pop_back();
    order.push_back(d);
    for (auto it = drafts[d].children.rbegin(); it != drafts[d].children.rend(); ++it)
      stack.push_back(*it);
  }
  std::vector<std::uint32_t> newIndex(drafts.size(), 0);
  for (std::uint32_t i = 0; i < order.size(); ++i) newIndex[order[i]] = i;
  scene.nodes.resize(order.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) {
    const Draft& d = drafts[order[i]];
    SceneNode& n = scene.nodes[i];
    n.kind = d.kind;
    n.bounds = d.bounds;
    n.object = d.object;
    n.contentVersion = 1;
    n.firstChild = static_cast<std::uint32_t>(scene.children.size());
    n.childCount = static_cast<std::uint32_t>(d.children.size());
    for (std::size_t c = 0; c < d.children.size(); ++c) {
      scene.children.push_back(newIndex[d.children[c]]);
      scene.childRanges.push_back(d.kind == SceneNodeKind::kLod ? d.ranges[c]
                                                                : ConicRange::everywhere());
    }
  }
  updateSubtreeVersions(scene);
  return scene;
}

}  // namespace thinlod::backbone
