// Private to surface_error*.cpp and white-box tests: exact point-triangle
// distance and a bounding-volume hierarchy over a mesh's triangles, with
// boxes of a second per-corner value for least-value searches.
// Precondition for TriangleBvh: a validated mesh with at least one triangle.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <vector>

#include "thinlod/common/core/indexed_mesh.h"

namespace thinlod::simplifier::detail {

using glm::dvec3;

constexpr std::uint32_t kLeafTriangles = 4;
constexpr int kSahBins = 16;
constexpr int kMaxBvhDepth = 96;  // deeper subtrees become one (large) leaf
constexpr int kTraversalStack = 2 * kMaxBvhDepth + 4;

struct Triangle {
  dvec3 a;
  dvec3 b;
  dvec3 c;
};

struct Box {
  dvec3 lo{std::numeric_limits<double>::infinity()};
  dvec3 hi{-std::numeric_limits<double>::infinity()};
  void extend(const dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  double halfArea() const {
    if (lo.x > hi.x) return 0.0;
    const dvec3 e = hi - lo;
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
};

// Node children are stored contiguously: left = first, right = first + 1.
struct BvhNode {
  Box box;
  std::uint32_t first = 0;
  std::uint32_t count = 0;  // > 0: leaf over triangles [first, first + count)
};

inline double squaredDistanceToBox(const dvec3& p, const Box& b) {
  const dvec3 d = glm::max(glm::max(b.lo - p, p - b.hi), dvec3(0.0));
  return glm::dot(d, d);
}

// Closest point on a triangle (Voronoi-region walk, Ericson, Real-Time
// Collision Detection 5.1.5), with a fallback for degenerate triangles whose
// barycentric denominator vanishes.
inline dvec3 closestPointOnSegment(const dvec3& p, const dvec3& a, const dvec3& b) {
  const dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  double t = len2 > 0.0 ? glm::dot(p - a, ab) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return a + t * ab;
}

inline double squaredDistanceToSegment(const dvec3& p, const dvec3& a, const dvec3& b) {
  const dvec3 d = p - closestPointOnSegment(p, a, b);
  return glm::dot(d, d);
}

inline dvec3 closestPointOnTriangle(const dvec3& p, const Triangle& tri) {
  const dvec3& a = tri.a;
  const dvec3& b = tri.b;
  const dvec3& c = tri.c;
  const dvec3 ab = b - a;
  const dvec3 ac = c - a;
  const dvec3 ap = p - a;
  const double d1 = glm::dot(ab, ap);
  const double d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp);
  const double d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return a + v * ab;
  }
  const dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp);
  const double d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return b + w * (c - b);
  }
  const double denom = va + vb + vc;
  if (!(denom > 0.0)) {
    // Degenerate: the closest of the three edges' closest points.
    const dvec3 candidates[3] = {closestPointOnSegment(p, a, b), closestPointOnSegment(p, b, c),
                                 closestPointOnSegment(p, c, a)};
    dvec3 best = candidates[0];
    double bestDistance = glm::dot(p - best, p - best);
    for (const dvec3& q : candidates) {
      const double d = glm::dot(p - q, p - q);
      if (d < bestDistance) {
        bestDistance = d;
        best = q;
      }
    }
    return best;
  }
  const double v = vb / denom;
  const double w = vc / denom;
  return a + ab * v + ac * w;
}

inline double squaredDistanceToTriangle(const dvec3& p, const Triangle& tri) {
  const dvec3 d = p - closestPointOnTriangle(p, tri);
  return glm::dot(d, d);
}

inline dvec3 toDouble(const glm::vec3& v) { return dvec3(v.x, v.y, v.z); }

// A bounding-volume hierarchy over a mesh's triangles, built with a binned
// surface-area heuristic; answers exact closest-distance queries.
class TriangleBvh {
 public:
  explicit TriangleBvh(const IndexedMesh& mesh) {
    const std::size_t n = mesh.triangleCount();
    std::vector<Triangle> source(n);
    std::vector<Box> boxes(n);
    std::vector<dvec3> centroids(n);
    for (std::size_t t = 0; t < n; ++t) {
      Triangle& tri = source[t];
      tri.a = toDouble(mesh.positions[mesh.indices[3 * t]]);
      tri.b = toDouble(mesh.positions[mesh.indices[3 * t + 1]]);
      tri.c = toDouble(mesh.positions[mesh.indices[3 * t + 2]]);
      boxes[t].extend(tri.a);
      boxes[t].extend(tri.b);
      boxes[t].extend(tri.c);
      centroids[t] = (tri.a + tri.b + tri.c) / 3.0;
    }
    order_.resize(n);
    for (std::size_t t = 0; t < n; ++t) order_[t] = static_cast<std::uint32_t>(t);
    nodes_.reserve(2 * n / kLeafTriangles + 1);
    nodes_.emplace_back();
    build(0, 0, static_cast<std::uint32_t>(n), 0, boxes, centroids);
    triangles_.resize(n);
    for (std::size_t i = 0; i < n; ++i) triangles_[i] = source[order_[i]];
  }

  // The mesh's triangle number of BVH-order triangle i.
  std::uint32_t sourceTriangle(std::uint32_t i) const { return order_[i]; }

  // Per node, the box of a second per-corner value over the node's triangles
  // (for example the uvs of a BVH built over positions): value(i, k) is
  // corner k of BVH-order triangle i. Children follow their parent in
  // nodes_, so one backward pass fills every box. Each box is grown by
  // 1e-9 of the largest value magnitude: a convex combination of corners
  // computed in doubles may leave the exact box by a few ulps.
  template <typename CornerValue>
  std::vector<Box> nodeBoxesOf(CornerValue value) const {
    std::vector<Box> boxes(nodes_.size());
    for (std::size_t n = nodes_.size(); n-- > 0;) {
      const BvhNode& node = nodes_[n];
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          for (int k = 0; k < 3; ++k) boxes[n].extend(value(i, k));
        }
      } else {
        boxes[n].extend(boxes[node.first]);
        boxes[n].extend(boxes[node.first + 1]);
      }
    }
    if (!boxes.empty()) {
      const dvec3 magnitude = glm::max(glm::abs(boxes[0].lo), glm::abs(boxes[0].hi));
      const dvec3 slack(1e-9 * std::max({magnitude.x, magnitude.y, magnitude.z}));
      for (Box& box : boxes) {
        box.lo -= slack;
        box.hi += slack;
      }
    }
    return boxes;
  }

  // Calls visit(i, triangle) for triangles (BVH order index i) within
  // squared distance radius2 of p, for a search that keeps the least of a
  // value taken inside each triangle (a point of the triangle, or an
  // attribute interpolated on it with barycentrics in the simplex), so the
  // value lies in the triangle's box of `valueBoxes` (nodeBoxesOf).
  // bestSquared() is the search's current least squared distance from
  // `target` to a value; a node whose value box lies no nearer than that
  // cannot lower it and is skipped, the nearer child first. The least value
  // found is the one visiting every triangle within the radius would give:
  // only triangles that cannot change it are left out.
  template <typename Best, typename Visit>
  void forEachWithinWhileNearer(const dvec3& p, double radius2, const std::vector<Box>& valueBoxes,
                                const dvec3& target, Best bestSquared, Visit visit) const {
    std::array<std::uint32_t, kTraversalStack> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const std::uint32_t index = stack[--top];
      const BvhNode& node = nodes_[index];
      if (squaredDistanceToBox(p, node.box) > radius2) continue;
      if (squaredDistanceToBox(target, valueBoxes[index]) >= bestSquared()) continue;
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          if (squaredDistanceToTriangle(p, triangles_[i]) <= radius2) visit(i, triangles_[i]);
        }
        continue;
      }
      const double dl = squaredDistanceToBox(target, valueBoxes[node.first]);
      const double dr = squaredDistanceToBox(target, valueBoxes[node.first + 1]);
      stack[top++] = dl <= dr ? node.first + 1 : node.first;  // farther first: popped last
      stack[top++] = dl <= dr ? node.first : node.first + 1;
    }
  }

  // Squared distance from p to the closest triangle. `hint` is a triangle
  // index (in BVH order) whose distance seeds the search bound; it is
  // updated to the closest triangle so coherent queries prune early.
  double squaredDistance(const dvec3& p, std::uint32_t& hint) const {
    double best = squaredDistanceToTriangle(p, triangles_[hint]);
    std::array<std::uint32_t, kTraversalStack> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const BvhNode& node = nodes_[stack[--top]];
      if (squaredDistanceToBox(p, node.box) >= best) continue;
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          const double d = squaredDistanceToTriangle(p, triangles_[i]);
          if (d < best) {
            best = d;
            hint = i;
          }
        }
        continue;
      }
      const double dl = squaredDistanceToBox(p, nodes_[node.first].box);
      const double dr = squaredDistanceToBox(p, nodes_[node.first + 1].box);
      // Push the farther child first so the nearer one is visited first.
      const std::uint32_t nearChild = dl <= dr ? node.first : node.first + 1;
      const std::uint32_t farChild = dl <= dr ? node.first + 1 : node.first;
      const double nearDist = std::min(dl, dr);
      const double farDist = std::max(dl, dr);
      if (farDist < best) stack[top++] = farChild;
      if (nearDist < best) stack[top++] = nearChild;
    }
    return best;
  }

 private:
  void build(std::uint32_t nodeIndex, std::uint32_t first, std::uint32_t count, int depth,
             const std::vector<Box>& boxes, const std::vector<dvec3>& centroids) {
    Box bounds;
    Box centroidBounds;
    for (std::uint32_t i = first; i < first + count; ++i) {
      bounds.extend(boxes[order_[i]]);
      centroidBounds.extend(centroids[order_[i]]);
    }
    nodes_[nodeIndex].box = bounds;
    const dvec3 extent = centroidBounds.hi - centroidBounds.lo;
    int axis = 0;
    if (extent.y > extent[axis]) axis = 1;
    if (extent.z > extent[axis]) axis = 2;
    if (count <= kLeafTriangles || depth >= kMaxBvhDepth || !(extent[axis] > 0.0)) {
      nodes_[nodeIndex].first = first;
      nodes_[nodeIndex].count = count;
      return;
    }

    // Binned SAH along the widest centroid axis.
    std::array<Box, kSahBins> binBoxes;
    std::array<std::uint32_t, kSahBins> binCounts{};
    const double scale = kSahBins / extent[axis];
    auto binOf = [&](std::uint32_t tri) {
      const int b = static_cast<int>((centroids[tri][axis] - centroidBounds.lo[axis]) * scale);
      return std::clamp(b, 0, kSahBins - 1);
    };
    for (std::uint32_t i = first; i < first + count; ++i) {
      const int b = binOf(order_[i]);
      binBoxes[b].extend(boxes[order_[i]]);
      ++binCounts[b];
    }
    std::array<double, kSahBins> rightCost{};
    Box acc;
    std::uint32_t accCount = 0;
    for (int b = kSahBins - 1; b > 0; --b) {
      acc.extend(binBoxes[b]);
      accCount += binCounts[b];
      rightCost[b] = acc.halfArea() * accCount;
    }
    Box left;
    std::uint32_t leftCount = 0;
    double bestCost = std::numeric_limits<double>::infinity();
    int bestSplit = kSahBins / 2;
    for (int b = 1; b < kSahBins; ++b) {
      left.extend(binBoxes[b - 1]);
      leftCount += binCounts[b - 1];
      if (leftCount == 0 || leftCount == count) continue;
      const double cost = left.halfArea() * leftCount + rightCost[b];
      if (cost < bestCost) {
        bestCost = cost;
        bestSplit = b;
      }
    }
    auto middle = std::partition(order_.begin() + first, order_.begin() + first + count,
                                 [&](std::uint32_t tri) { return binOf(tri) < bestSplit; });
    std::uint32_t leftSize = static_cast<std::uint32_t>(middle - (order_.begin() + first));
    if (leftSize == 0 || leftSize == count) {
      // All centroids fell in one bin (clustered data): split by count.
      leftSize = count / 2;
      std::nth_element(order_.begin() + first, order_.begin() + first + leftSize,
                       order_.begin() + first + count, [&](std::uint32_t x, std::uint32_t y) {
                         return centroids[x][axis] < centroids[y][axis];
                       });
    }
    const std::uint32_t children = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    nodes_.emplace_back();
    nodes_[nodeIndex].first = children;
    nodes_[nodeIndex].count = 0;
    build(children, first, leftSize, depth + 1, boxes, centroids);
    build(children + 1, first + leftSize, count - leftSize, depth + 1, boxes, centroids);
  }

  std::vector<BvhNode> nodes_;
  std::vector<std::uint32_t> order_;  // BVH slot -> input triangle index
  std::vector<Triangle> triangles_;   // in BVH slot order
};

}  // namespace thinlod::simplifier::detail
