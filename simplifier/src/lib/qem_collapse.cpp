#include "qem_collapse.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "qem_heap.h"
#include "qem_quadric.h"

namespace thinlod::simplifier::qem {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Corners and removal step in one 16-byte record: the adjacency walks read
// both, one cache line instead of two.
struct Triangle {
  std::uint32_t v[3];
  std::uint32_t removedAt;  // collapse step that removed it, 0 while live

  bool has(std::uint32_t x) const { return v[0] == x || v[1] == x || v[2] == x; }
};

struct Neighbor {
  std::uint32_t vertex;
  std::uint32_t triangles;  // live triangles on the edge to `vertex`
};

// What a vertex may do. Stable while the vertex has triangles: the link
// condition never merges two border edges into an interior one or the
// reverse, so it is computed once, on the first gather.
enum class VertexKind : std::uint8_t {
  kUnknown,
  kInterior,  // collapses onto any neighbour
  kBoundary,  // slides along its border only
  kLocked,    // on a non-manifold edge or a pinched border: never moves
};

class Collapser {
 public:
  Collapser(const CleanMesh& mesh, const VertexAttributes& attributes, const BuildOptions& options)
      : options_(options), attributes_(attributes) {
    const std::size_t vertexCount = mesh.positions.size();
    const std::size_t triangleCount = mesh.indices.size() / 3;
    // Quadrics in coordinates centred on the bounding box: costs are
    // translation invariant and the centred values keep more precision.
    Bounds bounds;
    for (const glm::vec3& p : mesh.positions) bounds.extend(p);
    const glm::dvec3 centre = glm::dvec3(bounds.center());
    diagonal_ = bounds.diagonal();
    position_.resize(vertexCount);
    for (std::size_t v = 0; v < vertexCount; ++v) {
      position_[v] = glm::dvec3(mesh.positions[v]) - centre;
    }
    triangle_.resize(triangleCount);
    for (std::size_t t = 0; t < triangleCount; ++t) {
      triangle_[t] = {{mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]}, 0};
    }
    liveTriangles_ = triangleCount;
    removed_.assign(vertexCount, 0);
    kind_.assign(vertexCount, VertexKind::kUnknown);
    target_.assign(vertexCount, kNone);
    mark_.assign(vertexCount, 0);
    buildAdjacency(vertexCount);
    buildQuadrics();
    heap_.reset(vertexCount);
  }

  CollapseRecord run() {
    for (std::uint32_t v = 0; v < position_.size(); ++v) {
      const double key = chooseTarget(v, /*validate=*/false);
      if (key < kInfinity) heap_.push(v, key);
    }
    while (!heap_.empty() && liveTriangles_ > options_.stopAtTriangles) {
      const std::uint32_t u = heap_.top();
      const std::uint32_t w = target_[u];
      const double key = heap_.topKey();
      gather(u, neighborsU_);
      if (!isValidCollapse(u, w)) {
        // The optimistic choice was illegal: look for the cheapest legal one.
        const double validKey = chooseTarget(u, /*validate=*/true);
        if (validKey < kInfinity) {
          heap_.update(u, validKey);
        } else {
          heap_.remove(u);
        }
        continue;
      }
      collapse(u, w, key);
    }
    CollapseRecord record = std::move(record_);
    record.triangleRemovedAtStep.resize(triangle_.size());
    for (std::size_t t = 0; t < triangle_.size(); ++t) {
      record.triangleRemovedAtStep[t] = triangle_[t].removedAt;
    }
    return record;
  }

 private:
  void buildAdjacency(std::size_t vertexCount) {
    listStart_.assign(vertexCount + 1, 0);
    for (const Triangle& t : triangle_) {
      for (std::uint32_t v : t.v) ++listStart_[v + 1];
    }
    for (std::size_t v = 0; v < vertexCount; ++v) listStart_[v + 1] += listStart_[v];
    listSize_.assign(vertexCount, 0);
    // Headroom for the lists rebuilt on collapses (about 12 entries each).
    pool_.reserve(triangle_.size() * 9);
    pool_.resize(triangle_.size() * 3);
    for (std::uint32_t t = 0; t < triangle_.size(); ++t) {
      for (std::uint32_t v : triangle_[t].v) pool_[listStart_[v] + listSize_[v]++] = t;
    }
    listStart_.resize(vertexCount);
  }

  void buildQuadrics() {
    quadric_.assign(position_.size(), Quadric());
    areaWeight_.assign(position_.size(), 0.0);
    // Plane weights are area / mean area: area weighting resists uneven
    // sampling, the normalisation keeps costs in squared length units.
    double totalArea = 0.0;
    for (const Triangle& t : triangle_) totalArea += 0.5 * glm::length(areaNormal(t));
    const double meanArea =
        totalArea > 0.0 ? totalArea / static_cast<double>(triangle_.size()) : 1.0;
    for (const Triangle& t : triangle_) {
      const glm::dvec3 n2 = areaNormal(t);
      const double length = glm::length(n2);
      if (!(length > 0.0)) continue;  // zero area: no plane
      const glm::dvec3 n = n2 / length;
      const double weight = 0.5 * length / meanArea;
      const Quadric q = Quadric::fromPlane(n, -glm::dot(n, position_[t.v[0]]), weight);
      for (std::uint32_t v : t.v) {
        quadric_[v] += q;
        areaWeight_[v] += weight / 3.0;
      }
    }
    if (options_.preserveBoundaries) addBoundaryPlanes(meanArea);
    selfCost_.resize(position_.size());
    for (std::size_t v = 0; v < position_.size(); ++v)
      selfCost_[v] = quadric_[v].eval(position_[v]);
  }

  // Garland-Heckbert boundary constraint: a plane through each border edge,
  // perpendicular to its triangle, so that collapses keep the border in place.
  void addBoundaryPlanes(double meanArea) {
    for (std::uint32_t v = 0; v < position_.size(); ++v) {
      gather(v, neighborsU_);
      for (const Neighbor& nb : neighborsU_) {
        if (nb.triangles != 1 || nb.vertex < v) continue;  // each border edge once
        const Triangle& t = triangle_[triangleOnEdge(v, nb.vertex)];
        const glm::dvec3 edge = position_[nb.vertex] - position_[v];
        glm::dvec3 n = glm::cross(edge, areaNormal(t));
        const double length = glm::length(n);
        if (!(length > 0.0)) continue;
        n /= length;
        const double weight = options_.boundaryWeight * glm::dot(edge, edge) / meanArea;
        const Quadric q = Quadric::fromPlane(n, -glm::dot(n, position_[v]), weight);
        quadric_[v] += q;
        quadric_[nb.vertex] += q;
      }
    }
  }

  glm::dvec3 areaNormal(const Triangle& t) const {
    const glm::dvec3& a = position_[t.v[0]];
    return glm::cross(position_[t.v[1]] - a, position_[t.v[2]] - a);
  }

  // A live triangle with corners a and b (they are known to share one).
  std::uint32_t triangleOnEdge(std::uint32_t a, std::uint32_t b) const {
    std::uint32_t i = listStart_[a];
    while (triangle_[pool_[i]].removedAt != 0 || !triangle_[pool_[i]].has(b)) ++i;
    return pool_[i];
  }

  // Drops dead triangles from v's list (lazy deletion) and lists v's
  // neighbours with the number of live triangles on each edge.
  void gather(std::uint32_t v, std::vector<Neighbor>& out) {
    out.clear();
    const std::uint32_t start = listStart_[v];
    std::uint32_t write = start;
    for (std::uint32_t i = start, end = start + listSize_[v]; i < end; ++i) {
      const std::uint32_t t = pool_[i];
      const Triangle& tri = triangle_[t];
      if (tri.removedAt != 0) continue;
      pool_[write++] = t;
      for (std::uint32_t x : tri.v) {
        if (x == v) continue;
        auto it =
            std::find_if(out.begin(), out.end(), [x](const Neighbor& n) { return n.vertex == x; });
        if (it == out.end()) {
          out.push_back({x, 1});
        } else {
          ++it->triangles;
        }
      }
    }
    listSize_[v] = write - start;
  }

  double attributeCost(std::uint32_t u, std::uint32_t w) const {
    const std::size_t d = attributes_.dimension;
    double sum = 0.0;
    for (std::size_t k = 0; k < d; ++k) {
      const double diff = attributes_.values[u * d + k] - attributes_.values[w * d + k];
      sum += diff * diff;
    }
    // Attributes are in [0, 1]: scale to squared length so that the weight
    // is relative to geometric error over the region u stands for.
    return options_.attributeWeight * diagonal_ * diagonal_ * areaWeight_[u] * sum;
  }

  // (Q_u + Q_w)(p_w): w keeps its position.
  double collapseCost(std::uint32_t u, std::uint32_t w) const {
    double cost = quadric_[u].eval(position_[w]) + selfCost_[w];
    if (attributes_.dimension > 0) cost += attributeCost(u, w);
    return std::max(cost, 0.0);  // rounding can make a zero cost slightly negative
  }

  static VertexKind classify(const std::vector<Neighbor>& neighbors) {
    int borderEdges = 0;
    for (const Neighbor& nb : neighbors) {
      if (nb.triangles > 2) return VertexKind::kLocked;  // non-manifold edge
      if (nb.triangles == 1) ++borderEdges;
    }
    if (borderEdges > 2) return VertexKind::kLocked;  // several borders pinched together
    return borderEdges > 0 ? VertexKind::kBoundary : VertexKind::kInterior;
  }

  // Picks target_[u] and returns its cost (infinity when u must stay).
  // Leaves u's gather in neighborsU_. Without `validate` only the cheap rules
  // apply; the top of the heap is validated before it is collapsed.
  double chooseTarget(std::uint32_t u, bool validate) {
    gather(u, neighborsU_);
    target_[u] = kNone;
    if (kind_[u] == VertexKind::kUnknown) kind_[u] = classify(neighborsU_);
    const VertexKind kind = kind_[u];
    if (kind == VertexKind::kLocked) return kInfinity;
    candidates_.clear();
    for (const Neighbor& nb : neighborsU_) {
      if (kind == VertexKind::kBoundary && nb.triangles != 1) continue;  // stay on the border
      candidates_.push_back({collapseCost(u, nb.vertex), nb.vertex});
    }
    if (candidates_.empty()) return kInfinity;
    if (!validate) {
      const auto best = std::min_element(candidates_.begin(), candidates_.end());
      target_[u] = best->second;
      return best->first;
    }
    std::sort(candidates_.begin(), candidates_.end());
    for (const auto& [cost, w] : candidates_) {
      if (isValidCollapse(u, w)) {
        target_[u] = w;
        return cost;
      }
    }
    return kInfinity;
  }

  // Topology and geometry checks for u -> w; neighborsU_ holds u's gather.
  bool isValidCollapse(std::uint32_t u, std::uint32_t w) {
    if (w == kNone) return false;
    // Opposite corners of the triangles on edge uw (they die with it).
    opposite_.clear();
    const std::uint32_t uStart = listStart_[u], uEnd = uStart + listSize_[u];
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const Triangle& t = triangle_[pool_[i]];
      if (!t.has(w)) continue;
      for (std::uint32_t x : t.v) {
        if (x != u && x != w) opposite_.push_back(x);
      }
    }
    if (opposite_.empty()) return false;  // not an edge any more
    // Link condition: every common neighbour of u and w must be the opposite
    // corner of a triangle on uw; otherwise the collapse would glue two
    // sheets (non-manifold edge) or close a hole.
    gather(w, neighborsW_);
    ++stamp_;
    for (const Neighbor& nb : neighborsW_) mark_[nb.vertex] = stamp_;
    for (const Neighbor& nb : neighborsU_) {
      if (nb.vertex == w || mark_[nb.vertex] != stamp_) continue;
      if (std::find(opposite_.begin(), opposite_.end(), nb.vertex) == opposite_.end()) return false;
    }
    const glm::dvec3& pu = position_[u];
    const glm::dvec3& pw = position_[w];
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const Triangle& t = triangle_[pool_[i]];
      if (t.has(w)) continue;
      // The triangle (u, a, b) becomes (w, a, b) in the same winding.
      const int k = t.v[0] == u ? 0 : (t.v[1] == u ? 1 : 2);
      const std::uint32_t a = t.v[(k + 1) % 3];
      const std::uint32_t b = t.v[(k + 2) % 3];
      // A triangle w already has on a and b would be duplicated (the last
      // collapse of a tetrahedron). Needs a and b both common neighbours.
      if (mark_[a] == stamp_ && mark_[b] == stamp_ && hasTriangleOn(w, a, b)) return false;
      if (options_.preventFlips) {
        const glm::dvec3& pa = position_[a];
        const glm::dvec3& pb = position_[b];
        const glm::dvec3 before = glm::cross(pa - pu, pb - pu);
        const glm::dvec3 after = glm::cross(pa - pw, pb - pw);
        const double beforeLength2 = glm::dot(before, before);
        if (beforeLength2 == 0.0) continue;  // a zero-area input triangle has no orientation
        // Reject flips and near-flips: the normal may turn by at most ~84 deg.
        const double d = glm::dot(before, after);
        if (d <= 0.0 || d * d < 0.01 * beforeLength2 * glm::dot(after, after)) return false;
      }
    }
    return true;
  }

  bool hasTriangleOn(std::uint32_t w, std::uint32_t a, std::uint32_t b) const {
    for (std::uint32_t i = listStart_[w], end = i + listSize_[w]; i < end; ++i) {
      const Triangle& t = triangle_[pool_[i]];
      if (t.removedAt == 0 && t.has(a) && t.has(b)) return true;
    }
    return false;
  }

  bool hasLiveTriangle(std::uint32_t v) const {
    for (std::uint32_t i = listStart_[v], end = i + listSize_[v]; i < end; ++i) {
      if (triangle_[pool_[i]].removedAt == 0) return true;
    }
    return false;
  }

  void removeVertex(std::uint32_t v, std::uint32_t parent) {
    removed_[v] = 1;
    record_.removedVertex.push_back(v);
    record_.removedParent.push_back(parent);
    heap_.remove(v);
  }

  void collapse(std::uint32_t u, std::uint32_t w, double cost) {
    const std::uint32_t step = static_cast<std::uint32_t>(record_.costOfStep.size()) + 1;
    // Kill the triangles on edge uw first so that w's new list skips them.
    opposite_.clear();
    const std::uint32_t uStart = listStart_[u], uEnd = uStart + listSize_[u];
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      Triangle& t = triangle_[pool_[i]];
      if (!t.has(w)) continue;
      t.removedAt = step;
      --liveTriangles_;
      for (std::uint32_t x : t.v) {
        if (x != u && x != w) opposite_.push_back(x);
      }
    }
    // w's new list: its live triangles, then u's survivors renamed to w.
    // Written at the end of the pool (in place when w's list is already last).
    const std::uint32_t wStart = listStart_[w], wEnd = wStart + listSize_[w];
    std::uint32_t newStart;
    if (wEnd == pool_.size()) {
      std::uint32_t write = wStart;
      for (std::uint32_t i = wStart; i < wEnd; ++i) {
        if (triangle_[pool_[i]].removedAt == 0) pool_[write++] = pool_[i];
      }
      pool_.resize(write);
      newStart = wStart;
    } else {
      newStart = static_cast<std::uint32_t>(pool_.size());
      for (std::uint32_t i = wStart; i < wEnd; ++i) {
        const std::uint32_t t = pool_[i];
        if (triangle_[t].removedAt == 0) pool_.push_back(t);
      }
    }
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t t = pool_[i];
      Triangle& tri = triangle_[t];
      if (tri.removedAt != 0) continue;
      for (std::uint32_t& x : tri.v) {
        if (x == u) x = w;
      }
      pool_.push_back(t);
    }
    listStart_[w] = newStart;
    listSize_[w] = static_cast<std::uint32_t>(pool_.size()) - newStart;
    listSize_[u] = 0;

    quadric_[w] += quadric_[u];
    areaWeight_[w] += areaWeight_[u];
    selfCost_[w] = quadric_[w].eval(position_[w]);
    removeVertex(u, w);
    // Vertices left without triangles leave the mesh too (parent kNone).
    if (listSize_[w] == 0) removeVertex(w, kNone);
    for (std::uint32_t x : opposite_) {
      if (!removed_[x] && !hasLiveTriangle(x)) removeVertex(x, kNone);
    }
    record_.removalsAfterStep.push_back(static_cast<std::uint32_t>(record_.removedVertex.size()));
    record_.trianglesAfterStep.push_back(static_cast<std::uint32_t>(liveTriangles_));
    record_.costOfStep.push_back(static_cast<float>(cost));
    if (!removed_[w]) rekeyAround(u, w);
  }

  // After u -> w only w's quadric and fan changed. A neighbour x of w whose
  // best target was neither u nor w keeps that target's cost; its only new
  // option is x -> w. Everything else is recomputed.
  void rekeyAround(std::uint32_t u, std::uint32_t w) {
    rekey(w, chooseTarget(w, /*validate=*/false));
    std::swap(neighborsW_, neighborsU_);  // w's gather, kept while the neighbours are re-keyed
    for (const Neighbor& nb : neighborsW_) {
      const std::uint32_t x = nb.vertex;
      const std::uint32_t old = target_[x];
      if (old == u || old == w || old == kNone || kind_[x] == VertexKind::kUnknown ||
          !heap_.contains(x)) {
        rekey(x, chooseTarget(x, /*validate=*/false));
        continue;
      }
      if (kind_[x] == VertexKind::kLocked) continue;
      if (kind_[x] == VertexKind::kBoundary && nb.triangles != 1) continue;
      const double cost = collapseCost(x, w);
      if (cost < heap_.key(x)) {
        target_[x] = w;
        heap_.update(x, cost);
      }
    }
  }

  void rekey(std::uint32_t v, double key) {
    if (key < kInfinity) {
      heap_.update(v, key);
    } else {
      heap_.remove(v);
    }
  }

  const BuildOptions& options_;
  const VertexAttributes& attributes_;
  double diagonal_ = 0.0;
  std::vector<glm::dvec3> position_;
  std::vector<Quadric> quadric_;
  std::vector<double> selfCost_;    // quadric_[v].eval(position_[v])
  std::vector<double> areaWeight_;  // area (in mean-area units) each vertex stands for
  std::vector<Triangle> triangle_;
  std::size_t liveTriangles_ = 0;
  // Vertex -> triangle lists: pool_[listStart_[v] .. + listSize_[v]], may
  // hold dead triangles until the next gather of v.
  std::vector<std::uint32_t> listStart_;
  std::vector<std::uint32_t> listSize_;
  std::vector<std::uint32_t> pool_;
  std::vector<std::uint8_t> removed_;
  std::vector<VertexKind> kind_;
  std::vector<std::uint32_t> target_;
  IndexedMinHeap heap_;
  CollapseRecord record_;
  // Scratch, reused to avoid allocation per collapse.
  std::vector<Neighbor> neighborsU_;
  std::vector<Neighbor> neighborsW_;
  std::vector<std::uint32_t> opposite_;
  std::vector<std::pair<double, std::uint32_t>> candidates_;
  std::vector<std::uint32_t> mark_;
  std::uint32_t stamp_ = 0;
};

}  // namespace

CollapseRecord runCollapses(const CleanMesh& mesh, const VertexAttributes& attributes,
                            const BuildOptions& options) {
  Collapser collapser(mesh, attributes, options);
  return collapser.run();
}

}  // namespace thinlod::simplifier::qem
