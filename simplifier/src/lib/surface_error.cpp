#include "thinlod/simplifier/surface_error.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "surface_error_bvh.h"

namespace thinlod::simplifier {
namespace {

using detail::dvec3;
using detail::toDouble;
using detail::TriangleBvh;

// A point on a triangle of the sampled mesh: p = a + u (b - a) + v (c - a),
// kept with its triangle and barycentrics so the worst ones can be refined.
struct SurfacePoint {
  std::uint32_t triangle = 0;
  double u = 0.0;
  double v = 0.0;
};

struct SamplePoints {
  std::vector<SurfacePoint> random;    // area-weighted; these define the mean
  std::vector<SurfacePoint> features;  // vertices and edge points; max only
};

// Edge samples per direction, as a fraction of samplesPerMesh, spread by
// length (so a coarse mesh's few long edges are sampled densely; a fine
// mesh's many short edges get their midpoint).
constexpr double kEdgeSampleFraction = 0.25;
// The worst samples of each direction are refined by a local pattern search
// on their triangle: the max of a finite sample set underestimates narrow
// peaks (bunny 10%: 100k samples found 86% of the 4M-sample max).
constexpr std::size_t kRefinedSamples = 16;
constexpr double kRefineStartStep = 0.125;  // barycentric units
constexpr double kRefineEndStep = 1.0 / 4096.0;
constexpr int kRefineMaxMoves = 256;

class MeshGeometry {
 public:
  explicit MeshGeometry(const IndexedMesh& mesh) : mesh_(mesh) {}
  const IndexedMesh& mesh() const { return mesh_; }
  dvec3 corner(std::size_t triangle, int k) const {
    return toDouble(mesh_.positions[mesh_.indices[3 * triangle + k]]);
  }
  dvec3 at(const SurfacePoint& s) const {
    const dvec3 a = corner(s.triangle, 0);
    return a + s.u * (corner(s.triangle, 1) - a) + s.v * (corner(s.triangle, 2) - a);
  }
  double area(std::size_t triangle) const {
    const dvec3 a = corner(triangle, 0);
    return 0.5 * glm::length(glm::cross(corner(triangle, 1) - a, corner(triangle, 2) - a));
  }

 private:
  const IndexedMesh& mesh_;
};

// Uniform double in [0, 1) from the top 53 bits (portable, unlike
// std::uniform_real_distribution whose algorithm is implementation-defined).
double unitDouble(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Barycentrics (u, v) of the point at fraction w along edge k of a triangle
// (edge k runs from corner k to corner k+1).
SurfacePoint pointOnEdge(std::uint32_t triangle, int k, double w) {
  static constexpr double kCornerU[3] = {0.0, 1.0, 0.0};
  static constexpr double kCornerV[3] = {0.0, 0.0, 1.0};
  const int next = (k + 1) % 3;
  return {triangle, (1.0 - w) * kCornerU[k] + w * kCornerU[next],
          (1.0 - w) * kCornerV[k] + w * kCornerV[next]};
}

SamplePoints samplePoints(const MeshGeometry& geometry, const std::vector<double>& cumulativeArea,
                          const SurfaceErrorOptions& options) {
  const IndexedMesh& mesh = geometry.mesh();
  SamplePoints points;
  const std::size_t triangles = mesh.triangleCount();
  const double totalArea = cumulativeArea.back();
  // Stratified sampling: one uniform point in each of N equal slices of the
  // cumulative area. Samples come out in triangle order (coherent queries).
  std::mt19937_64 rng(options.seed);
  points.random.reserve(options.samplesPerMesh);
  std::size_t t = 0;
  const double n = static_cast<double>(options.samplesPerMesh);
  for (std::size_t k = 0; k < options.samplesPerMesh; ++k) {
    const double target = std::min((static_cast<double>(k) + unitDouble(rng)) / n, 1.0) * totalArea;
    while (t + 1 < triangles && cumulativeArea[t] <= target) ++t;
    const double s = std::sqrt(unitDouble(rng));
    const double r = unitDouble(rng);
    points.random.push_back({static_cast<std::uint32_t>(t), s * (1.0 - r), s * r});
  }
  if (!options.includeVerticesAndEdges) return points;

  // Every referenced vertex (as a corner of its first triangle).
  std::vector<bool> seen(mesh.vertexCount(), false);
  for (std::uint32_t tri = 0; tri < triangles; ++tri) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.indices[3 * tri + k];
      if (seen[v]) continue;
      seen[v] = true;
      points.features.push_back(pointOnEdge(tri, k, 0.0));
    }
  }
  // Unique edges, each remembered with one triangle and local edge number.
  struct Edge {
    std::uint64_t key;
    std::uint32_t triangle;
    int local;
    double length;
  };
  std::vector<Edge> edges;
  edges.reserve(mesh.indices.size());
  for (std::uint32_t tri = 0; tri < triangles; ++tri) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.indices[3 * tri + k];
      const std::uint32_t b = mesh.indices[3 * tri + (k + 1) % 3];
      if (a == b) continue;
      const std::uint64_t key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
      edges.push_back({key, tri, k, 0.0});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.key < y.key; });
  edges.erase(std::unique(edges.begin(), edges.end(),
                          [](const Edge& x, const Edge& y) { return x.key == y.key; }),
              edges.end());
  double totalLength = 0.0;
  for (Edge& e : edges) {
    e.length = glm::length(geometry.corner(e.triangle, (e.local + 1) % 3) -
                           geometry.corner(e.triangle, e.local));
    totalLength += e.length;
  }
  const double spacing = totalLength / (kEdgeSampleFraction * n);
  for (const Edge& e : edges) {
    // Evenly spaced at (i + 0.5) / count: count == 1 is the midpoint.
    const double wanted = spacing > 0.0 ? std::ceil(e.length / spacing) : 1.0;
    const int count = static_cast<int>(std::clamp(wanted, 1.0, 1.0e6));
    for (int i = 0; i < count; ++i) {
      points.features.push_back(pointOnEdge(e.triangle, e.local, (i + 0.5) / count));
    }
  }
  return points;
}

Result<std::vector<double>> cumulativeAreas(const MeshGeometry& geometry, const char* what) {
  const IndexedMesh& mesh = geometry.mesh();
  THINLOD_RETURN_IF_ERROR(mesh.validate(what));
  if (mesh.triangleCount() == 0) {
    return Status(ErrorCode::kInvalidArgument, std::string(what) + ": mesh has no triangles");
  }
  std::vector<double> cumulative(mesh.triangleCount());
  double sum = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    sum += geometry.area(t);
    cumulative[t] = sum;
  }
  if (!(sum > 0.0) || !std::isfinite(sum)) {
    return Status(ErrorCode::kInvalidArgument,
                  std::string(what) + ": mesh has zero or non-finite surface area");
  }
  return cumulative;
}

// Both meshes validated and their cumulative areas (original first).
struct BothAreas {
  std::vector<double> original;
  std::vector<double> simplified;
};

Result<BothAreas> cumulativeAreasOfBoth(const MeshGeometry& original,
                                        const MeshGeometry& simplified) {
  Result<std::vector<double>> o = cumulativeAreas(original, "original mesh");
  if (!o.ok()) return o.status();
  Result<std::vector<double>> s = cumulativeAreas(simplified, "simplified mesh");
  if (!s.ok()) return s.status();
  return BothAreas{std::move(o).value(), std::move(s).value()};
}

struct ScoredPoint {
  double squaredDistance;
  SurfacePoint point;
};

// Hill-climbs the distance over the sample's triangle with a shrinking
// compass pattern in barycentric space; returns the best squared distance.
double refineOnTriangle(const MeshGeometry& from, const TriangleBvh& to, ScoredPoint start,
                        std::uint32_t& hint) {
  static constexpr double kDirections[6][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, -1}, {-1, 1}};
  SurfacePoint current = start.point;
  double best = start.squaredDistance;
  double step = kRefineStartStep;
  int moves = 0;
  while (step >= kRefineEndStep && moves < kRefineMaxMoves) {
    bool moved = false;
    for (const auto& d : kDirections) {
      SurfacePoint candidate = current;
      candidate.u = std::max(0.0, current.u + step * d[0]);
      candidate.v = std::max(0.0, current.v + step * d[1]);
      const double sum = candidate.u + candidate.v;
      if (sum > 1.0) {  // scale back onto the triangle's far edge
        candidate.u /= sum;
        candidate.v /= sum;
      }
      const double d2 = to.squaredDistance(from.at(candidate), hint);
      if (d2 > best) {
        best = d2;
        current = candidate;
        moved = true;
      }
    }
    if (moved) {
      ++moves;
    } else {
      step *= 0.5;
    }
  }
  return best;
}

struct DirectionalError {
  double max = 0.0;
  double mean = 0.0;
  std::size_t points = 0;
};

DirectionalError measureDirection(const MeshGeometry& from, const SamplePoints& samples,
                                  const TriangleBvh& to) {
  DirectionalError result;
  std::uint32_t hint = 0;
  double sum = 0.0;
  // A min-heap of the worst samples seen, for refinement.
  std::vector<ScoredPoint> worst;
  auto byDistanceDescending = [](const ScoredPoint& x, const ScoredPoint& y) {
    return x.squaredDistance > y.squaredDistance;
  };
  auto consider = [&](const SurfacePoint& s) {
    const double d2 = to.squaredDistance(from.at(s), hint);
    if (worst.size() < kRefinedSamples) {
      worst.push_back({d2, s});
      std::push_heap(worst.begin(), worst.end(), byDistanceDescending);
    } else if (d2 > worst.front().squaredDistance) {
      std::pop_heap(worst.begin(), worst.end(), byDistanceDescending);
      worst.back() = {d2, s};
      std::push_heap(worst.begin(), worst.end(), byDistanceDescending);
    }
    return d2;
  };
  for (const SurfacePoint& s : samples.random) sum += std::sqrt(consider(s));
  for (const SurfacePoint& s : samples.features) consider(s);

  double maxSquared = 0.0;
  for (const ScoredPoint& candidate : worst) {
    maxSquared = std::max(maxSquared, refineOnTriangle(from, to, candidate, hint));
  }
  result.max = std::sqrt(maxSquared);
  result.mean = samples.random.empty() ? 0.0 : sum / static_cast<double>(samples.random.size());
  result.points = samples.random.size() + samples.features.size();
  return result;
}

}  // namespace

Result<SurfaceError> measureSurfaceError(const IndexedMesh& original, const IndexedMesh& simplified,
                                         const SurfaceErrorOptions& options) {
  if (options.samplesPerMesh == 0) {
    return Status(ErrorCode::kInvalidArgument, "measureSurfaceError: samplesPerMesh is 0");
  }
  const MeshGeometry originalGeometry(original);
  const MeshGeometry simplifiedGeometry(simplified);
  Result<BothAreas> areas = cumulativeAreasOfBoth(originalGeometry, simplifiedGeometry);
  if (!areas.ok()) return areas.status();

  const TriangleBvh originalBvh(original);
  const TriangleBvh simplifiedBvh(simplified);
  const DirectionalError forward = measureDirection(
      originalGeometry, samplePoints(originalGeometry, areas->original, options), simplifiedBvh);
  const DirectionalError backward =
      measureDirection(simplifiedGeometry,
                       samplePoints(simplifiedGeometry, areas->simplified, options), originalBvh);

  SurfaceError error;
  error.maxForward = forward.max;
  error.meanForward = forward.mean;
  error.pointsForward = forward.points;
  error.maxBackward = backward.max;
  error.meanBackward = backward.mean;
  error.pointsBackward = backward.points;
  error.diagonal = original.diameter();
  return error;
}

}  // namespace thinlod::simplifier

namespace thinlod::simplifier {

double uvArea(const IndexedMesh& mesh) {
  if (mesh.uvs.size() != mesh.positions.size()) return 0.0;
  double area = 0.0;
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const glm::dvec2 a(mesh.uvs[mesh.indices[t]]);
    const glm::dvec2 e1 = glm::dvec2(mesh.uvs[mesh.indices[t + 1]]) - a;
    const glm::dvec2 e2 = glm::dvec2(mesh.uvs[mesh.indices[t + 2]]) - a;
    area += 0.5 * std::abs(e1.x * e2.y - e1.y * e2.x);
  }
  return area;
}

namespace {

// Barycentrics (of corners b and c) of point p on the plane of tri; false
// for a zero-area triangle. Clamped into the simplex: p is a point of the
// triangle (its closest point to something), so only rounding - large on a
// sliver - can put them outside, and the interpolated value then stays in
// the corners' box (what forEachWithinWhileNearer's pruning relies on).
bool barycentrics(const detail::Triangle& tri, const dvec3& p, double& wb, double& wc) {
  const dvec3 n = glm::cross(tri.b - tri.a, tri.c - tri.a);
  const double n2 = glm::dot(n, n);
  if (!(n2 > 0.0)) return false;
  wb = std::max(0.0, glm::dot(glm::cross(p - tri.a, tri.c - tri.a), n) / n2);
  wc = std::max(0.0, glm::dot(glm::cross(tri.b - tri.a, p - tri.a), n) / n2);
  if (wb + wc > 1.0) {
    const double sum = wb + wc;
    wb /= sum;
    wc /= sum;
  }
  return std::isfinite(wb) && std::isfinite(wc);
}

double percentile95(std::vector<double>& values) {
  if (values.empty()) return 0.0;
  const std::size_t k = (values.size() * 95) / 100;
  std::nth_element(values.begin(),
                   values.begin() + static_cast<std::ptrdiff_t>(std::min(k, values.size() - 1)),
                   values.end());
  return values[std::min(k, values.size() - 1)];
}

}  // namespace

Result<UvError> measureUvError(const IndexedMesh& original, const IndexedMesh& simplified,
                               const UvErrorOptions& options) {
  if (options.samples == 0) {
    return Status(ErrorCode::kInvalidArgument, "measureUvError: samples is 0");
  }
  if (!(options.tieTolerance >= 0.0) || !std::isfinite(options.tieTolerance) ||
      !(options.tieFactor >= 0.0) || !std::isfinite(options.tieFactor) ||
      !(options.texelTolerance >= 0.0) || !std::isfinite(options.texelTolerance)) {
    return Status(ErrorCode::kInvalidArgument,
                  "measureUvError: tieFactor, tieTolerance and texelTolerance must be finite "
                  "and >= 0");
  }
  const MeshGeometry originalGeometry(original);
  const MeshGeometry simplifiedGeometry(simplified);
  Result<BothAreas> areas = cumulativeAreasOfBoth(originalGeometry, simplifiedGeometry);
  if (!areas.ok()) return areas.status();
  if (original.uvs.empty() || simplified.uvs.empty()) {
    return Status(ErrorCode::kInvalidArgument, "measureUvError: both meshes need uvs");
  }
  if (!(uvArea(original) > 0.0)) {
    return Status(ErrorCode::kInvalidArgument, "measureUvError: the original's uv area is zero");
  }
  auto uvOf = [](const IndexedMesh& mesh, std::size_t triangle, int k) {
    return glm::dvec2(mesh.uvs[mesh.indices[3 * triangle + k]]);
  };
  auto pointOf = [&](std::size_t triangle, double wb, double wc) {
    const dvec3 a = originalGeometry.corner(triangle, 0);
    return a + wb * (originalGeometry.corner(triangle, 1) - a) +
           wc * (originalGeometry.corner(triangle, 2) - a);
  };

  UvError error;
  error.diagonal = original.diameter();
  const double tie = options.tieTolerance * error.diagonal;
  SurfaceErrorOptions sampling;
  sampling.samplesPerMesh = options.samples;
  sampling.seed = options.seed;
  sampling.includeVerticesAndEdges = false;
  const SamplePoints points = samplePoints(simplifiedGeometry, areas->simplified, sampling);
  const TriangleBvh bvh(original);
  // The original laid out in uv space (z = 0), for the texel's preimage.
  IndexedMesh uvLayout;
  uvLayout.positions.reserve(original.vertexCount());
  for (const glm::vec2& uv : original.uvs) uvLayout.positions.emplace_back(uv.x, uv.y, 0.0f);
  uvLayout.indices = original.indices;
  const TriangleBvh uvBvh(uvLayout);
  // The candidates' least uv distance (and least displacement) is searched
  // with the other value's boxes: at coarse levels the tie radius 2 d holds
  // a large share of the mesh, and most of it lies far from s in uv.
  const std::vector<detail::Box> uvBoxes = bvh.nodeBoxesOf([&](std::uint32_t i, int k) {
    const glm::dvec2 uv = uvOf(original, bvh.sourceTriangle(i), k);
    return dvec3(uv.x, uv.y, 0.0);
  });
  const std::vector<detail::Box> positionBoxes = uvBvh.nodeBoxesOf(
      [&](std::uint32_t i, int k) { return originalGeometry.corner(uvBvh.sourceTriangle(i), k); });
  std::uint32_t hint = 0, uvHint = 0;
  std::vector<double> uvErrors, displacements;
  uvErrors.reserve(points.random.size());
  displacements.reserve(points.random.size());
  for (const SurfacePoint& sp : points.random) {
    const dvec3 q = simplifiedGeometry.at(sp);
    const glm::dvec2 a = uvOf(simplified, sp.triangle, 0);
    const glm::dvec2 s = a + sp.u * (uvOf(simplified, sp.triangle, 1) - a) +
                         sp.v * (uvOf(simplified, sp.triangle, 2) - a);
    // uv distance at the closest point, ties by distance taken at the best uv.
    const double nearest = std::sqrt(bvh.squaredDistance(q, hint));
    const double radius = (1.0 + options.tieFactor) * nearest + tie;
    double bestUv = std::numeric_limits<double>::infinity();
    const dvec3 s3(s.x, s.y, 0.0);
    auto bestUvSquared = [&] { return bestUv * bestUv; };
    bvh.forEachWithinWhileNearer(q, radius * radius, uvBoxes, s3, bestUvSquared,
                                 [&](std::uint32_t i, const detail::Triangle& tri) {
      const std::uint32_t t = bvh.sourceTriangle(i);
      double wb = 0.0, wc = 0.0;
      glm::dvec2 o = uvOf(original, t, 0);  // zero area: no interpolation to speak of
      if (barycentrics(tri, detail::closestPointOnTriangle(q, tri), wb, wc)) {
        o += wb * (uvOf(original, t, 1) - o) + wc * (uvOf(original, t, 2) - o);
      }
      bestUv = std::min(bestUv, glm::length(s - o));
    });
    // Texture displacement: where the texel s is on the original.
    const dvec3 su(s.x, s.y, 0.0);
    const double uvNearest = std::sqrt(uvBvh.squaredDistance(su, uvHint));
    const double uvRadius = uvNearest + options.texelTolerance;
    double bestDisplacement = std::numeric_limits<double>::infinity();
    auto bestDisplacementSquared = [&] { return bestDisplacement * bestDisplacement; };
    uvBvh.forEachWithinWhileNearer(su, uvRadius * uvRadius, positionBoxes, q,
                                   bestDisplacementSquared,
                                   [&](std::uint32_t i, const detail::Triangle& tri) {
      const std::uint32_t t = uvBvh.sourceTriangle(i);
      double wb = 0.0, wc = 0.0;
      const dvec3 p = barycentrics(tri, detail::closestPointOnTriangle(su, tri), wb, wc)
                          ? pointOf(t, wb, wc)
                          : originalGeometry.corner(t, 0);
      bestDisplacement = std::min(bestDisplacement, glm::length(p - q));
    });
    // Both are finite: the nearest triangle is always within its radius.
    if (!std::isfinite(bestUv) || !std::isfinite(bestDisplacement)) continue;
    uvErrors.push_back(bestUv);
    displacements.push_back(bestDisplacement);
  }
  error.samples = uvErrors.size();
  if (error.samples > 0) {
    const double n = static_cast<double>(error.samples);
    for (std::size_t k = 0; k < error.samples; ++k) {
      error.meanUv += uvErrors[k] / n;
      error.meanDisplacement += displacements[k] / n;
      error.maxUv = std::max(error.maxUv, uvErrors[k]);
      error.maxDisplacement = std::max(error.maxDisplacement, displacements[k]);
    }
    error.p95Uv = percentile95(uvErrors);
    error.p95Displacement = percentile95(displacements);
  }
  return error;
}

}  // namespace thinlod::simplifier
