// Sampled two-sided Hausdorff distance between a surface and a hybrid cut
// (triangles + discs): measureSurfaceError's exact triangle BVH
// (surface_error_bvh.h) plus a small BVH over discs. See hybrid_graph.h.
#include <algorithm>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <limits>
#include <memory>
#include <random>
#include <string>

#include "surface_error_bvh.h"
#include "thinlod/simplifier/hybrid_graph.h"
#include "thinlod/simplifier/mesh_curve.h"

namespace thinlod::simplifier {
namespace {

using detail::Box;
using detail::dvec3;
using detail::squaredDistanceToBox;
using detail::TriangleBvh;

constexpr double kPi = 3.14159265358979323846;
constexpr int kRimPoints = 8;

double squaredDistanceToDisc(const dvec3& p, const HybridPoint& disc) {
  const dvec3 q = p - disc.centre;
  const double h = glm::dot(q, disc.normal);
  const double inPlane = glm::length(q - h * disc.normal);
  const double outside = std::max(inPlane - disc.radius, 0.0);
  return h * h + outside * outside;
}

class DiscBvh {
 public:
  explicit DiscBvh(const std::vector<HybridPoint>& discs) : discs_(discs) {
    order_.resize(discs.size());
    for (std::uint32_t i = 0; i < discs.size(); ++i) order_[i] = i;
    if (!discs.empty()) build(0, static_cast<std::uint32_t>(discs.size()));
  }
  bool empty() const { return discs_.empty(); }

  double squaredDistance(const dvec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    if (nodes_.empty()) return best;
    std::vector<std::uint32_t> stack = {0};
    while (!stack.empty()) {
      const Node& node = nodes_[stack.back()];
      stack.pop_back();
      if (squaredDistanceToBox(p, node.box) >= best) continue;
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          best = std::min(best, squaredDistanceToDisc(p, discs_[order_[i]]));
        }
        continue;
      }
      stack.push_back(node.left);
      stack.push_back(node.right);
    }
    return best;
  }

 private:
  struct Node {
    Box box;
    std::uint32_t first = 0, count = 0;  // leaf when count > 0
    std::uint32_t left = 0, right = 0;
  };

  std::uint32_t build(std::uint32_t first, std::uint32_t count) {
    const auto id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    Box box, centres;
    for (std::uint32_t i = first; i < first + count; ++i) {
      const HybridPoint& d = discs_[order_[i]];
      box.extend(d.centre - dvec3(d.radius));
      box.extend(d.centre + dvec3(d.radius));
      centres.extend(d.centre);
    }
    nodes_[id].box = box;
    const dvec3 extent = centres.hi - centres.lo;
    if (count <= 4 || !(std::max({extent.x, extent.y, extent.z}) > 0.0)) {
      nodes_[id].first = first;
      nodes_[id].count = count;
      return id;
    }
    const int axis =
        extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const std::uint32_t half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half,
                     order_.begin() + first + count, [&](std::uint32_t a, std::uint32_t b) {
                       return discs_[a].centre[axis] < discs_[b].centre[axis];
                     });
    const std::uint32_t left = build(first, half);
    const std::uint32_t right = build(first + half, count - half);
    nodes_[id].left = left;
    nodes_[id].right = right;
    return id;
  }

  const std::vector<HybridPoint>& discs_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

double unitDouble(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

dvec3 corner(const IndexedMesh& m, std::size_t t, int k) {
  return detail::toDouble(m.positions[m.indices[3 * t + k]]);
}

double triangleArea(const IndexedMesh& m, std::size_t t) {
  return 0.5 * glm::length(glm::cross(corner(m, t, 1) - corner(m, t, 0),
                                      corner(m, t, 2) - corner(m, t, 0)));
}

// Area-weighted random points, then every vertex and edge midpoint.
template <typename Visit>
void sampleMesh(const IndexedMesh& m, std::size_t samples, std::mt19937_64& rng,
                const Visit& visit) {
  const std::size_t n = m.triangleCount();
  if (n == 0) return;
  std::vector<double> cumulative(n);
  double sum = 0.0;
  for (std::size_t t = 0; t < n; ++t) {
    sum += triangleArea(m, t);
    cumulative[t] = sum;
  }
  for (std::size_t k = 0; k < samples && sum > 0.0; ++k) {
    const double target = unitDouble(rng) * sum;
    const std::size_t t = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), target) -
                                 cumulative.begin()),
        n - 1);
    const double s = std::sqrt(unitDouble(rng));
    const double r = unitDouble(rng);
    const dvec3 a = corner(m, t, 0);
    visit(a + s * (1.0 - r) * (corner(m, t, 1) - a) + s * r * (corner(m, t, 2) - a));
  }
  for (std::size_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) {
      visit(corner(m, t, k));
      visit(0.5 * (corner(m, t, k) + corner(m, t, (k + 1) % 3)));
    }
  }
}

}  // namespace

Result<SurfaceError> measureHybridSurfaceError(const IndexedMesh& original,
                                               const IndexedMesh& cutTriangles,
                                               const std::vector<HybridPoint>& cutDiscs,
                                               const SurfaceErrorOptions& options) {
  THINLOD_RETURN_IF_ERROR(original.validate("original mesh"));
  THINLOD_RETURN_IF_ERROR(cutTriangles.validate("cut triangles"));
  if (original.triangleCount() == 0 || options.samplesPerMesh == 0) {
    return Status(ErrorCode::kInvalidArgument,
                  "measureHybridSurfaceError: no original triangles or no samples");
  }
  if (cutTriangles.triangleCount() == 0 && cutDiscs.empty()) {
    return Status(ErrorCode::kInvalidArgument, "measureHybridSurfaceError: the cut is empty");
  }
  for (const HybridPoint& d : cutDiscs) {
    if (!std::isfinite(d.radius) || d.radius < 0.0 || !std::isfinite(glm::length(d.centre)) ||
        !(std::abs(glm::length(d.normal) - 1.0) < 1e-6)) {
      return Status(ErrorCode::kInvalidArgument,
                    "measureHybridSurfaceError: a disc has a bad radius, centre or normal");
    }
  }
  const TriangleBvh originalBvh(original);
  std::unique_ptr<TriangleBvh> cutBvh;
  if (cutTriangles.triangleCount() > 0) cutBvh = std::make_unique<TriangleBvh>(cutTriangles);
  const DiscBvh discBvh(cutDiscs);
  std::mt19937_64 rng(options.seed);
  SurfaceError error;
  error.diagonal = original.diameter();

  // Forward: original -> cut.
  std::uint32_t hintCut = 0, hintOriginal = 0;
  auto toCut = [&](const dvec3& p) {
    double d2 = discBvh.squaredDistance(p);
    if (cutBvh) d2 = std::min(d2, cutBvh->squaredDistance(p, hintCut));
    return d2;
  };
  double forward2 = 0.0;
  sampleMesh(original, options.samplesPerMesh, rng, [&](const dvec3& p) {
    forward2 = std::max(forward2, toCut(p));
    ++error.pointsForward;
  });
  error.maxForward = std::sqrt(forward2);

  // Backward: cut -> original. Samples split by area between the triangles
  // and the discs.
  double triangleArea = 0.0;
  for (std::size_t t = 0; t < cutTriangles.triangleCount(); ++t) {
    triangleArea +=
        0.5 * glm::length(glm::cross(corner(cutTriangles, t, 1) - corner(cutTriangles, t, 0),
                                     corner(cutTriangles, t, 2) - corner(cutTriangles, t, 0)));
  }
  double discArea = 0.0;
  std::vector<double> cumulative;
  for (const HybridPoint& d : cutDiscs) {
    discArea += kPi * d.radius * d.radius;
    cumulative.push_back(discArea);
  }
  const double total = triangleArea + discArea;
  const auto triangleSamples = static_cast<std::size_t>(
      total > 0.0 ? std::llround(static_cast<double>(options.samplesPerMesh) * triangleArea / total)
                  : 0);
  double backward2 = 0.0;
  auto toOriginal = [&](const dvec3& p) {
    backward2 = std::max(backward2, originalBvh.squaredDistance(p, hintOriginal));
    ++error.pointsBackward;
  };
  sampleMesh(cutTriangles, triangleSamples, rng, toOriginal);
  auto discPoint = [](const HybridPoint& d, double radius, double angle) {
    const dvec3 bitangent = glm::cross(d.normal, d.tangent);
    return d.centre + radius * (std::cos(angle) * d.tangent + std::sin(angle) * bitangent);
  };
  const std::size_t discSamples =
      options.samplesPerMesh - std::min(options.samplesPerMesh, triangleSamples);
  for (std::size_t k = 0; k < discSamples && discArea > 0.0; ++k) {
    const double target = unitDouble(rng) * discArea;
    const std::size_t i = std::min<std::size_t>(
        static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), target) -
                                 cumulative.begin()),
        cutDiscs.size() - 1);
    toOriginal(discPoint(cutDiscs[i], cutDiscs[i].radius * std::sqrt(unitDouble(rng)),
                         2.0 * kPi * unitDouble(rng)));
  }
  for (const HybridPoint& d : cutDiscs) {
    toOriginal(d.centre);
    for (int k = 0; k < kRimPoints; ++k)
      toOriginal(discPoint(d, d.radius, 2.0 * kPi * k / kRimPoints));
  }
  error.maxBackward = std::sqrt(backward2);
  return error;
}

std::vector<HybridCurveStep> hybridLadderSteps(const HybridGraph& graph, int levels) {
  const std::vector<HybridCurveStep> steps = graph.unitsVersusError();  // units decreasing
  if (steps.empty() || levels < 1) return {};
  const auto coarsest = static_cast<std::size_t>(std::max(1.0, std::ceil(steps.back().units)));
  const auto finest = static_cast<std::size_t>(std::max(1.0, std::floor(steps.front().units)));
  // Unit targets -> the finest step with at most that many units (steps are
  // in decreasing units: the first one at or below the target).
  std::vector<std::size_t> picked;
  for (std::size_t target : geometricLadder(coarsest, std::max(coarsest, finest), levels)) {
    std::size_t i = 0;
    while (i + 1 < steps.size() && steps[i].units > static_cast<double>(target)) ++i;
    if (picked.empty() || picked.back() != i) picked.push_back(i);
  }
  picked.push_back(0);  // the input, always (merged below if already there)
  // Increasing units = decreasing step index.
  std::sort(picked.begin(), picked.end(), std::greater<>());
  picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
  std::vector<HybridCurveStep> rungs;
  rungs.reserve(picked.size());
  for (std::size_t i : picked) rungs.push_back(steps[i]);
  return rungs;
}

Result<std::vector<HybridMeasuredLevel>> measureHybridLevels(const IndexedMesh& original,
                                                             const HybridGraph& graph, int levels,
                                                             const SurfaceErrorOptions& options) {
  if (levels < 1) {
    return Status(ErrorCode::kInvalidArgument,
                  "measureHybridLevels: levels " + std::to_string(levels) + " < 1");
  }
  const std::vector<HybridCurveStep> rungs = hybridLadderSteps(graph, levels);
  if (rungs.empty()) return Status(ErrorCode::kInvalidArgument, "measureHybridLevels: empty graph");
  std::vector<HybridMeasuredLevel> out;
  out.reserve(rungs.size());
  HybridCut cut(graph);
  for (const HybridCurveStep& step : rungs) {
    cut.adaptToError(step.error);
    Result<SurfaceError> error =
        measureHybridSurfaceError(original, cut.triangleMesh(), cut.pointList(), options);
    if (!error.ok()) return error.status();
    out.push_back(HybridMeasuredLevel{step, error->max()});
  }
  return out;
}

}  // namespace thinlod::simplifier
