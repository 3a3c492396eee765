// Builds the hybrid multiresolution graph (Cohen-Aliaga-Zhang section 5):
// one priority queue of half-edge collapses (value tau * error increase /
// units removed) and point replacements (radius / (1 - points / kappa)),
// then octree point merging up to one root. Error bounds: docs/hybrid.md.
//
// Collapse bound (after Cohen, Manocha & Olano 1997, "successive mappings"):
// the star of an interior vertex u and the new fan of w are projected onto
// the plane normal to the star's area-weighted normal n; the collapse is
// legal only when every old and new triangle faces n (cos > kMinFacing) and
// the old star winds once around u, so the projection maps both patches
// one-to-one onto the same simple polygon. Pairing points with the same
// projection is then a bijection between the patches that moves each point
// along n by the difference of two piecewise-linear height functions; that
// difference is linear on each cell of the overlay of the two
// triangulations, so its maximum |.| over the patch (delta) is attained at
// an overlay vertex: u, or a crossing of an old edge (u, l_j) with a new
// edge (w, l_m) (link vertices and w do not move). Composing with the
// mappings of the consumed triangles gives the new triangles the bound
// max(consumed bounds) + delta, valid in both directions of the Hausdorff
// distance because the composed mapping is onto.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <queue>
#include <string>
#include <unordered_map>

#include "thinlod/simplifier/hybrid_graph.h"

namespace thinlod::simplifier {

using glm::dvec3;

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Old and new triangles must face the projection direction by at least this
// cosine: the mapping stays one-to-one with margin for rounding.
constexpr double kMinFacing = 0.05;
constexpr double kTwoPi = 6.283185307179586476925286766559;

struct QueueEntry {
  double key;
  std::uint32_t id;       // vertex (collapse) or triangle (replacement)
  std::uint32_t version;  // vertex version when queued; unused for triangles
  bool collapse;
  bool operator>(const QueueEntry& o) const { return key > o.key; }
};

struct Sphere {
  dvec3 centre{0.0};
  double radius = 0.0;
};

struct CollapseCandidate {
  double key = kInfinity;
  std::uint32_t target = 0;
  double delta = 0.0;
};

struct Replacement {
  double key = kInfinity;
  double d = 0.0;
};

}  // namespace

class HybridGraphBuilder {
 public:
  explicit HybridGraphBuilder(const HybridOptions& options) : options_(options) {}

  Result<HybridGraph> build(const IndexedMesh& mesh) {
    THINLOD_RETURN_IF_ERROR(mesh.validate("hybrid input mesh"));
    if (!(options_.tau > 0.0) || !std::isfinite(options_.tau) || !std::isfinite(options_.kappa)) {
      return Status(ErrorCode::kInvalidArgument, "hybrid: tau must be > 0 and kappa finite");
    }
    g_.kappa_ = options_.kappa > 0.0 ? options_.kappa : 1.0;
    // At most floor(kappa) points, and fewer than kappa (benefit > 0).
    maxPoints_ = options_.enablePoints && options_.kappa > 1.0
                     ? static_cast<std::size_t>(std::floor(options_.kappa))
                     : 0;
    if (maxPoints_ > 0 && static_cast<double>(maxPoints_) >= options_.kappa) --maxPoints_;
    clean(mesh);
    if (g_.triangles_.empty()) {
      return Status(ErrorCode::kInvalidArgument,
                    "hybrid input mesh: no triangle with three distinct corners and positive area");
    }
    const std::size_t inputTriangles = g_.triangles_.size();
    g_.stats_.inputTriangles = inputTriangles;
    // Drain.
    std::vector<std::uint32_t> produced(inputTriangles);
    star_.assign(g_.vertices_.size(), {});
    version_.assign(g_.vertices_.size(), 0);
    for (std::uint32_t t = 0; t < inputTriangles; ++t) {
      produced[t] = addTrianglePrimitive(t, 0.0);
      for (std::uint32_t v : g_.triangles_[t]) star_[v].push_back(t);
    }
    addNode(HybridNodeKind::kDrain, {}, produced);
    for (std::uint32_t t = 0; t < inputTriangles; ++t) queueReplacement(t);
    for (std::uint32_t v = 0; v < g_.vertices_.size(); ++v) queueCollapse(v);
    runQueue();
    if (maxPoints_ > 0) mergeOctree();
    // Source: consumes everything still live.
    std::vector<std::uint32_t> remaining;
    for (std::uint32_t p = 0; p < g_.primitives_.size(); ++p) {
      if (g_.primitives_[p].consumer == kUnconsumed) remaining.push_back(p);
    }
    addNode(HybridNodeKind::kSource, remaining, {});
    g_.nodes_.back().error = kInfinity;
    for (std::uint32_t p : remaining) g_.primitives_[p].consumer = g_.sourceNode();
    g_.stats_.graphTriangles = g_.triangles_.size();
    g_.stats_.graphPoints = g_.points_.size();
    return std::move(g_);
  }

 private:
  static constexpr std::uint32_t kUnconsumed = 0xffffffffu;

  void clean(const IndexedMesh& mesh) {
    // Weld exactly equal positions (loaders split vertices at attribute seams).
    std::unordered_map<std::string, std::uint32_t> index;
    std::vector<std::uint32_t> remap(mesh.positions.size());
    const bool colors = !mesh.colors.empty();
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      const glm::vec3& p = mesh.positions[v];
      std::string key(reinterpret_cast<const char*>(&p), sizeof(p));
      auto [it, inserted] = index.emplace(key, static_cast<std::uint32_t>(g_.vertices_.size()));
      if (inserted) {
        g_.vertices_.emplace_back(p.x, p.y, p.z);
        if (colors) g_.colors_.push_back(mesh.colors[v]);
      }
      remap[v] = it->second;
    }
    Bounds bounds;
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      const std::array<std::uint32_t, 3> tri = {remap[mesh.indices[3 * t]],
                                                remap[mesh.indices[3 * t + 1]],
                                                remap[mesh.indices[3 * t + 2]]};
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) continue;
      if (!(glm::length(areaVector(tri)) > 0.0)) continue;
      g_.triangles_.push_back(tri);
      for (std::uint32_t v : tri) bounds.extend(glm::vec3(g_.vertices_[v]));
    }
    g_.diagonal_ = bounds.diagonal();
  }

  dvec3 areaVector(const std::array<std::uint32_t, 3>& t) const {
    const dvec3& a = g_.vertices_[t[0]];
    return glm::cross(g_.vertices_[t[1]] - a, g_.vertices_[t[2]] - a);
  }

  std::uint32_t addTrianglePrimitive(std::uint32_t triangle, double error) {
    HybridPrimitive p;
    p.kind = HybridPrimitiveKind::kTriangle;
    p.index = triangle;
    p.error = error;
    p.consumer = kUnconsumed;
    p.producer = static_cast<std::uint32_t>(g_.nodes_.size());  // the node added next
    g_.primitives_.push_back(p);
    triPrimitive_.resize(g_.triangles_.size(), kUnconsumed);
    triPrimitive_[triangle] = static_cast<std::uint32_t>(g_.primitives_.size() - 1);
    return triPrimitive_[triangle];
  }

  std::uint32_t addPointPrimitive(const HybridPoint& point, double error) {
    g_.points_.push_back(point);
    HybridPrimitive p;
    p.kind = HybridPrimitiveKind::kPoint;
    p.index = static_cast<std::uint32_t>(g_.points_.size() - 1);
    p.error = error;
    p.consumer = kUnconsumed;
    p.producer = static_cast<std::uint32_t>(g_.nodes_.size());
    g_.primitives_.push_back(p);
    return static_cast<std::uint32_t>(g_.primitives_.size() - 1);
  }

  Sphere primitiveSphere(const HybridPrimitive& p) const {
    if (p.kind == HybridPrimitiveKind::kPoint) {
      const HybridPoint& q = g_.points_[p.index];
      return {q.centre, q.radius};
    }
    const auto& t = g_.triangles_[p.index];
    const dvec3 c = (g_.vertices_[t[0]] + g_.vertices_[t[1]] + g_.vertices_[t[2]]) / 3.0;
    double r = 0.0;
    for (std::uint32_t v : t) r = std::max(r, glm::length(g_.vertices_[v] - c));
    return {c, r};
  }

  // Appends a node; its produced primitives were added just before with
  // producer = this node's id. Error = max(produced, child nodes); sphere
  // contains the consumed primitives and the child nodes' spheres.
  void addNode(HybridNodeKind kind, const std::vector<std::uint32_t>& consumed,
               const std::vector<std::uint32_t>& produced) {
    const auto id = static_cast<std::uint32_t>(g_.nodes_.size());
    HybridNode node;
    node.kind = kind;
    node.consumedBegin = static_cast<std::uint32_t>(g_.consumed_.size());
    for (std::uint32_t p : consumed) {
      g_.consumed_.push_back(p);
      g_.primitives_[p].consumer = id;
    }
    node.consumedEnd = static_cast<std::uint32_t>(g_.consumed_.size());
    node.producedBegin = static_cast<std::uint32_t>(g_.produced_.size());
    for (std::uint32_t p : produced) g_.produced_.push_back(p);
    node.producedEnd = static_cast<std::uint32_t>(g_.produced_.size());
    double error = 0.0;
    for (std::uint32_t p : produced) error = std::max(error, g_.primitives_[p].error);
    std::vector<Sphere> spheres;
    const std::vector<std::uint32_t>& geometry = consumed.empty() ? produced : consumed;
    for (std::uint32_t p : geometry) spheres.push_back(primitiveSphere(g_.primitives_[p]));
    for (std::uint32_t p : consumed) {
      const HybridNode& child = g_.nodes_[g_.primitives_[p].producer];
      error = std::max(error, child.error);
      spheres.push_back({child.sphereCentre, child.sphereRadius});
    }
    dvec3 centre(0.0);
    for (const Sphere& s : spheres) centre += s.centre;
    if (!spheres.empty()) centre /= static_cast<double>(spheres.size());
    double radius = 0.0;
    for (const Sphere& s : spheres)
      radius = std::max(radius, glm::length(s.centre - centre) + s.radius);
    node.error = error;
    node.sphereCentre = centre;
    node.sphereRadius = radius * (1.0 + 1e-9);  // nested despite rounding
    g_.nodes_.push_back(node);
  }

  // ---- Point replacement ---------------------------------------------------

  Replacement bestReplacement(std::uint32_t t) const {
    Replacement best;
    if (maxPoints_ == 0) return best;
    const auto& tri = g_.triangles_[t];
    const dvec3 &a = g_.vertices_[tri[0]], &b = g_.vertices_[tri[1]], &c = g_.vertices_[tri[2]];
    // Paper 5.3.2: the smallest d for each step s < kappa; value = cost /
    // benefit = (d / sqrt 2) / (1 - count / kappa).
    for (std::size_t s = 1; s <= maxPoints_; ++s) {
      const double d = smallestSampleDistance(a, b, c, s, options_.sampleDistanceTolerance);
      const std::size_t count = countTriangleSamples(a, b, c, d);
      if (count == 0 || count > maxPoints_) continue;
      const double benefit = 1.0 - static_cast<double>(count) / g_.kappa_;
      const double key = (d / std::sqrt(2.0)) / benefit;
      if (key < best.key) best = {key, d};
    }
    return best;
  }

  void queueReplacement(std::uint32_t t) {
    const Replacement r = bestReplacement(t);
    if (r.key < kInfinity) queue_.push({r.key, t, 0, false});
  }

  void replaceTriangle(std::uint32_t t) {
    const Replacement r = bestReplacement(t);
    const auto& tri = g_.triangles_[t];
    const dvec3 &a = g_.vertices_[tri[0]], &b = g_.vertices_[tri[1]], &c = g_.vertices_[tri[2]];
    const std::vector<TriangleSample> samples = sampleTriangle(a, b, c, r.d);
    const std::uint32_t consumed = triPrimitive_[t];
    const double triangleError = g_.primitives_[consumed].error;
    const double radius = r.d / std::sqrt(2.0);
    const dvec3 normal = glm::normalize(areaVector(tri));
    // Row direction: the longest edge.
    dvec3 tangent = b - a;
    if (glm::length(c - b) > glm::length(tangent)) tangent = c - b;
    if (glm::length(a - c) > glm::length(tangent)) tangent = a - c;
    tangent = glm::normalize(tangent);
    std::vector<std::uint32_t> produced;
    for (const TriangleSample& s : samples) {
      HybridPoint p;
      p.centre = s.centre;
      p.normal = normal;
      p.tangent = tangent;
      p.radius = radius;
      p.area = s.cellArea;
      if (!g_.colors_.empty()) {
        for (int k = 0; k < 4; ++k) {
          const double v = s.barycentric.x * g_.colors_[tri[0]][k] +
                           s.barycentric.y * g_.colors_[tri[1]][k] +
                           s.barycentric.z * g_.colors_[tri[2]][k];
          p.color[k] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
        }
      }
      // Paper 5.3.1: point error = radius + the triangle's bound.
      produced.push_back(addPointPrimitive(p, radius + triangleError));
    }
    addNode(HybridNodeKind::kPointReplacement, {consumed}, produced);
    ++g_.stats_.pointReplacements;
    killTriangle(t);
    for (std::uint32_t v : tri) {
      ++version_[v];
      queueCollapse(v);
    }
  }

  void killTriangle(std::uint32_t t) {
    for (std::uint32_t v : g_.triangles_[t]) {
      auto& s = star_[v];
      s.erase(std::find(s.begin(), s.end(), t));
    }
    triDead_.resize(g_.triangles_.size(), 0);
    triDead_[t] = 1;
  }

  bool dead(std::uint32_t t) const { return t < triDead_.size() && triDead_[t] != 0; }

  // ---- Edge collapse ----------------------------------------------------

  // The link of u in winding order (l_j, l_{j+1} span the j-th triangle of
  // the star), or empty when u is not an interior manifold vertex.
  bool orderedLink(std::uint32_t u, std::vector<std::uint32_t>& link) const {
    link.clear();
    const auto& s = star_[u];
    if (s.size() < 3) return false;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> next;  // a -> b
    for (std::uint32_t t : s) {
      const auto& tri = g_.triangles_[t];
      const int k = tri[0] == u ? 0 : (tri[1] == u ? 1 : 2);
      next.push_back({tri[(k + 1) % 3], tri[(k + 2) % 3]});
    }
    std::uint32_t current = next.front().first;
    for (std::size_t step = 0; step < next.size(); ++step) {
      std::uint32_t found = kUnconsumed;
      int matches = 0;
      for (const auto& e : next) {
        if (e.first == current) {
          found = e.second;
          ++matches;
        }
      }
      if (matches != 1) return false;
      link.push_back(current);
      current = found;
    }
    if (current != link.front()) return false;
    // Every link vertex once: one closed fan.
    std::vector<std::uint32_t> sorted = link;
    std::sort(sorted.begin(), sorted.end());
    return std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
  }

  // delta of u -> link[i] (see the file comment), or infinity when illegal.
  double collapseDelta(std::uint32_t u, const std::vector<std::uint32_t>& link, std::size_t i) {
    const std::size_t k = link.size();
    const std::uint32_t w = link[i];
    const std::size_t prev = (i + k - 1) % k, next = (i + 1) % k;
    // Link condition: u and w share exactly the two opposite corners.
    neighbours_.clear();
    for (std::uint32_t t : star_[w]) {
      for (std::uint32_t x : g_.triangles_[t]) {
        if (x != w) neighbours_.push_back(x);
      }
    }
    for (std::size_t j = 0; j < k; ++j) {
      if (j == i || j == prev || j == next) continue;
      if (std::find(neighbours_.begin(), neighbours_.end(), link[j]) != neighbours_.end()) {
        return kInfinity;
      }
    }
    // New triangles (w, l_j, l_{j+1}) for j = i+1 .. i-2; none may already exist.
    newTriangles_.clear();
    for (std::size_t step = 1; step + 1 < k; ++step) {
      const std::size_t j = (i + step) % k;
      newTriangles_.push_back({w, link[j], link[(j + 1) % k]});
    }
    for (const auto& nt : newTriangles_) {
      for (std::uint32_t t : star_[w]) {
        const auto& tri = g_.triangles_[t];
        if (std::find(tri.begin(), tri.end(), nt[1]) != tri.end() &&
            std::find(tri.begin(), tri.end(), nt[2]) != tri.end()) {
          return kInfinity;
        }
      }
    }
    // Projection direction and frame.
    const dvec3 pu = g_.vertices_[u];
    dvec3 n(0.0);
    for (std::uint32_t t : star_[u]) n += areaVector(g_.triangles_[t]);
    const double nl = glm::length(n);
    if (!(nl > 0.0)) return kInfinity;
    n /= nl;
    auto faces = [&](const std::array<std::uint32_t, 3>& tri) {
      const dvec3 av = areaVector(tri);
      const double l = glm::length(av);
      return l > 0.0 && glm::dot(av, n) > kMinFacing * l;
    };
    for (std::uint32_t t : star_[u]) {
      if (!faces(g_.triangles_[t])) return kInfinity;
    }
    for (const auto& nt : newTriangles_) {
      if (!faces(nt)) return kInfinity;
    }
    const dvec3 helper = std::abs(n.x) < 0.9 ? dvec3(1.0, 0.0, 0.0) : dvec3(0.0, 1.0, 0.0);
    const dvec3 e1 = glm::normalize(glm::cross(n, helper));
    const dvec3 e2 = glm::cross(n, e1);
    proj_.resize(k);
    height_.resize(k);
    for (std::size_t j = 0; j < k; ++j) {
      const dvec3 q = g_.vertices_[link[j]] - pu;
      proj_[j] = {glm::dot(q, e1), glm::dot(q, e2)};
      height_[j] = glm::dot(q, n);
    }
    // The old star must wind once around u (u projects to the origin).
    double angle = 0.0;
    for (std::size_t j = 0; j < k; ++j) {
      const auto& a = proj_[j];
      const auto& b = proj_[(j + 1) % k];
      angle += std::atan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1]);
    }
    if (std::abs(angle - kTwoPi) > 1e-6) return kInfinity;
    // Overlay vertex u: height 0 on the old star, the new fan's height there.
    const auto& pw = proj_[i];
    const double hw = height_[i];
    double delta = 0.0;
    bool located = false;
    double bestInside = -kInfinity;
    double heightAtU = 0.0;
    for (std::size_t step = 1; step + 1 < k; ++step) {
      const std::size_t j = (i + step) % k, j1 = (j + 1) % k;
      // Barycentrics of the origin in (w, l_j, l_j1).
      const double x1 = proj_[j][0] - pw[0], y1 = proj_[j][1] - pw[1];
      const double x2 = proj_[j1][0] - pw[0], y2 = proj_[j1][1] - pw[1];
      const double det = x1 * y2 - x2 * y1;
      if (!(det > 0.0)) return kInfinity;
      const double px = -pw[0], py = -pw[1];
      const double b1 = (px * y2 - x2 * py) / det;
      const double b2 = (x1 * py - px * y1) / det;
      const double b0 = 1.0 - b1 - b2;
      const double inside = std::min({b0, b1, b2});
      if (inside > bestInside) {
        bestInside = inside;
        heightAtU = b0 * hw + b1 * height_[j] + b2 * height_[j1];
        located = true;
      }
    }
    if (!located) return kInfinity;
    delta = std::abs(heightAtU);
    // Crossings of old edges (u, l_j) with new edges (w, l_m).
    for (std::size_t j = 0; j < k; ++j) {
      if (j == i) continue;
      for (std::size_t m = 0; m < k; ++m) {
        if (m == i || m == prev || m == next || m == j) continue;
        // origin + s * P(l_j) == P(w) + t * (P(l_m) - P(w))
        const double ax = proj_[j][0], ay = proj_[j][1];
        const double bx = proj_[m][0] - pw[0], by = proj_[m][1] - pw[1];
        const double det = ax * (-by) - (-bx) * ay;
        if (std::abs(det) < 1e-300) continue;
        const double rx = pw[0], ry = pw[1];
        const double s = (rx * (-by) - (-bx) * ry) / det;
        const double t = (ax * ry - ay * rx) / det;
        if (s < 0.0 || s > 1.0 || t < 0.0 || t > 1.0) continue;
        const double oldHeight = s * height_[j];
        const double newHeight = hw + t * (height_[m] - hw);
        delta = std::max(delta, std::abs(oldHeight - newHeight));
      }
    }
    return delta;
  }

  CollapseCandidate bestCollapse(std::uint32_t u) {
    CollapseCandidate best;
    if (!orderedLink(u, link_)) return best;
    const std::vector<std::uint32_t> link = link_;
    for (std::size_t i = 0; i < link.size(); ++i) {
      const double delta = collapseDelta(u, link, i);
      if (!(delta < kInfinity)) continue;
      // Error increase per unit removed (k -> k - 2 triangles), times tau.
      const double key = options_.tau * delta / 2.0;
      if (key < best.key) best = {key, link[i], delta};
    }
    return best;
  }

  void queueCollapse(std::uint32_t u) {
    const CollapseCandidate c = bestCollapse(u);
    if (c.key < kInfinity) queue_.push({c.key, u, version_[u], true});
  }

  void collapse(std::uint32_t u, const CollapseCandidate& c) {
    orderedLink(u, link_);
    const std::vector<std::uint32_t> link = link_;
    const std::size_t k = link.size();
    const std::size_t i =
        static_cast<std::size_t>(std::find(link.begin(), link.end(), c.target) - link.begin());
    std::vector<std::uint32_t> consumed;
    double consumedError = 0.0;
    const std::vector<std::uint32_t> oldStar = star_[u];
    for (std::uint32_t t : oldStar) {
      consumed.push_back(triPrimitive_[t]);
      consumedError = std::max(consumedError, g_.primitives_[triPrimitive_[t]].error);
    }
    for (std::uint32_t t : oldStar) killTriangle(t);
    const double error = consumedError + c.delta;
    std::vector<std::uint32_t> produced;
    std::vector<std::uint32_t> created;
    for (std::size_t step = 1; step + 1 < k; ++step) {
      const std::size_t j = (i + step) % k;
      g_.triangles_.push_back({c.target, link[j], link[(j + 1) % k]});
      const auto t = static_cast<std::uint32_t>(g_.triangles_.size() - 1);
      produced.push_back(addTrianglePrimitive(t, error));
      for (std::uint32_t v : g_.triangles_[t]) star_[v].push_back(t);
      created.push_back(t);
    }
    addNode(HybridNodeKind::kEdgeCollapse, consumed, produced);
    ++g_.stats_.edgeCollapses;
    ++version_[u];
    for (std::uint32_t t : created) queueReplacement(t);
    ++version_[c.target];
    queueCollapse(c.target);
    for (std::uint32_t v : link) {
      if (v == c.target) continue;
      ++version_[v];
      queueCollapse(v);
    }
  }

  void runQueue() {
    while (!queue_.empty()) {
      const QueueEntry e = queue_.top();
      queue_.pop();
      if (!e.collapse) {
        if (!dead(e.id)) replaceTriangle(e.id);
        continue;
      }
      if (e.version != version_[e.id]) continue;
      // Changes near the target may have made the move dearer or illegal.
      const CollapseCandidate c = bestCollapse(e.id);
      if (!(c.key < kInfinity)) continue;
      if (c.key <= e.key) {
        collapse(e.id, c);
      } else {
        queue_.push({c.key, e.id, version_[e.id], true});
      }
    }
  }

  // ---- Octree point merging ------------------------------------------------

  std::uint32_t mergeGroup(const std::vector<std::uint32_t>& group) {
    std::vector<HybridPoint> children;
    std::vector<double> errors;
    for (std::uint32_t p : group) {
      children.push_back(g_.points_[g_.primitives_[p].index]);
      errors.push_back(g_.primitives_[p].error);
    }
    const MergedPoint m = mergePoints(children, errors);
    const std::uint32_t id = addPointPrimitive(m.point, m.error);
    addNode(HybridNodeKind::kPointMerge, group, {id});
    ++g_.stats_.pointMerges;
    return id;
  }

  std::uint32_t mergeCell(std::vector<std::uint32_t> members, const dvec3& lo, double size,
                          int depth) {
    if (members.size() == 1) return members.front();
    if (depth >= options_.octreeMaxDepth || !(size > 0.0)) {
      // Coincident centres: merge in chains of up to eight.
      while (members.size() > 1) {
        std::vector<std::uint32_t> group(
            members.begin(), members.begin() + std::min<std::size_t>(8, members.size()));
        const std::uint32_t merged = mergeGroup(group);
        members.erase(members.begin(), members.begin() + static_cast<long>(group.size()));
        members.push_back(merged);
      }
      return members.front();
    }
    const double half = 0.5 * size;
    std::array<std::vector<std::uint32_t>, 8> child;
    for (std::uint32_t p : members) {
      const dvec3& c = g_.points_[g_.primitives_[p].index].centre;
      const int octant = (c.x >= lo.x + half ? 1 : 0) | (c.y >= lo.y + half ? 2 : 0) |
                         (c.z >= lo.z + half ? 4 : 0);
      child[octant].push_back(p);
    }
    std::vector<std::uint32_t> representatives;
    for (int o = 0; o < 8; ++o) {
      if (child[o].empty()) continue;
      const dvec3 childLo(lo.x + ((o & 1) ? half : 0.0), lo.y + ((o & 2) ? half : 0.0),
                          lo.z + ((o & 4) ? half : 0.0));
      representatives.push_back(mergeCell(std::move(child[o]), childLo, half, depth + 1));
    }
    if (representatives.size() == 1) return representatives.front();
    return mergeGroup(representatives);
  }

  void mergeOctree() {
    std::vector<std::uint32_t> live;
    dvec3 lo(kInfinity), hi(-kInfinity);
    for (std::uint32_t p = 0; p < g_.primitives_.size(); ++p) {
      const HybridPrimitive& prim = g_.primitives_[p];
      if (prim.consumer != kUnconsumed || prim.kind != HybridPrimitiveKind::kPoint) continue;
      live.push_back(p);
      lo = glm::min(lo, g_.points_[prim.index].centre);
      hi = glm::max(hi, g_.points_[prim.index].centre);
    }
    if (live.size() < 2) return;
    const dvec3 extent = hi - lo;
    const double size = std::max({extent.x, extent.y, extent.z}) * (1.0 + 1e-9);
    mergeCell(std::move(live), lo, size, 0);
  }

  const HybridOptions options_;
  std::size_t maxPoints_ = 0;
  HybridGraph g_;
  std::vector<std::vector<std::uint32_t>> star_;  // live triangles per vertex
  std::vector<std::uint32_t> version_;
  std::vector<std::uint32_t> triPrimitive_;
  std::vector<std::uint8_t> triDead_;
  std::priority_queue<QueueEntry, std::vector<QueueEntry>, std::greater<QueueEntry>> queue_;
  // Scratch.
  std::vector<std::uint32_t> link_;
  std::vector<std::uint32_t> neighbours_;
  std::vector<std::array<std::uint32_t, 3>> newTriangles_;
  std::vector<std::array<double, 2>> proj_;
  std::vector<double> height_;
};

Result<HybridGraph> buildHybridGraph(const IndexedMesh& mesh, const HybridOptions& options) {
  HybridGraphBuilder builder(options);
  return builder.build(mesh);
}

}  // namespace thinlod::simplifier
