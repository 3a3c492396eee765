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
// A collapse may turn a triangle's normal by at most acos(0.1) ~ 84 degrees
// (bound on the squared cosine); beyond that the triangle counts as flipped.
constexpr double kMinFlipCos2 = 0.01;
// Weights of the fan term (see fanCost): the area-weighted sum (relative to
// the quadric) and the largest single distance, counted as if it spanned
// kFarthestWeight mean-sized triangles so that a small but tall feature (a
// one-vertex spike, a thin tip) is not cheap to cut. Chosen on the shared
// models against meshoptimizer: the sum alone lowered the mean surface error
// by ~10% at equal max error; the farthest term then lowered the max error by
// ~11% for ~5% of mean (docs/results/simplifier.md).
constexpr double kFanWeight = 1.0;
constexpr double kFarthestWeight = 100.0;
// Valence above which a vertex's fan counts as huge (see rekeyAround).
constexpr std::size_t kLargeFan = 64;

// Corners and removal step in one 16-byte record: the adjacency walks read
// both, one cache line instead of two.
struct Triangle {
  std::uint32_t v[3];
  std::uint32_t removedAt;  // collapse step that removed it, 0 while live

  bool has(std::uint32_t x) const { return v[0] == x || v[1] == x || v[2] == x; }
};

// Adjacency entries name a corner: triangle << 2 | k, where v[k] is the
// owner of the list. Renaming u to w keeps k, so entries move between lists
// unchanged, and the two other corners are found without searching.
constexpr std::uint32_t kNextCorner[3] = {1, 2, 0};
constexpr std::uint32_t kPrevCorner[3] = {2, 0, 1};
inline std::uint32_t triangleOf(std::uint32_t entry) { return entry >> 2; }
inline std::uint32_t cornerOf(std::uint32_t entry) { return entry & 3u; }

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
  // One side of a seam (a place where the uv or colour jumps): a border
  // vertex whose place holds exactly one other vertex, its sibling, with
  // the same two border edges on the other side. The pair moves together,
  // along the seam only (see seamCandidates).
  kSeam,
};

class Collapser {
 public:
  Collapser(const CleanMesh& mesh, const VertexAttributes& attributes,
            const std::vector<VertexConstraint>& constraints, const BuildOptions& options)
      : options_(options), attributes_(attributes), constraints_(constraints) {
    const std::size_t vertexCount = mesh.positions.size();
    const std::size_t triangleCount = mesh.indices.size() / 3;
    // Quadrics in coordinates centred on the bounding box: costs are
    // translation invariant and the centred values keep more precision.
    Bounds bounds;
    for (const glm::vec3& p : mesh.positions) bounds.extend(p);
    const glm::dvec3 centre = glm::dvec3(bounds.center());
    diagonal_ = bounds.diagonal();
    point_.resize(vertexCount);
    for (std::size_t v = 0; v < vertexCount; ++v) {
      point_[v].p = glm::dvec3(mesh.positions[v]) - centre;
    }
    triangle_.resize(triangleCount);
    for (std::size_t t = 0; t < triangleCount; ++t) {
      triangle_[t] = {{mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]}, 0};
    }
    liveTriangles_ = triangleCount;
    inputNormal_.resize(triangleCount);
    for (std::size_t t = 0; t < triangleCount; ++t) {
      const glm::dvec3 n = areaNormal(triangle_[t]);
      const double length = glm::length(n);
      inputNormal_[t] = length > 0.0 ? glm::vec3(n / length) : glm::vec3(0.0f);
    }
    // Area-weighted input vertex normals (unit; zero where undefined).
    vertexNormal_.assign(vertexCount, glm::vec3(0.0f));
    for (const Triangle& t : triangle_) {
      const glm::vec3 n(areaNormal(t));
      for (std::uint32_t v : t.v) vertexNormal_[v] += n;
    }
    for (glm::vec3& n : vertexNormal_) {
      const float length = glm::length(n);
      n = length > 0.0f ? n / length : glm::vec3(0.0f);
    }
    // Seam siblings: the clean vertices that share a place.
    sibling_.assign(vertexCount, kNone);
    groupSize_.assign(vertexCount, 1);
    group_ = mesh.positionGroup;
    if (group_.size() != vertexCount) {  // no groups given: every vertex its own place
      group_.resize(vertexCount);
      for (std::uint32_t v = 0; v < vertexCount; ++v) group_[v] = v;
    }
    {
      std::uint32_t groups = 0;
      for (std::uint32_t g : group_) groups = std::max(groups, g + 1);
      std::vector<std::uint32_t> first(groups, kNone), count(groups, 0);
      for (std::uint32_t v = 0; v < vertexCount; ++v) {
        const std::uint32_t g = group_[v];
        if (first[g] == kNone) first[g] = v;
        ++count[g];
      }
      for (std::uint32_t v = 0; v < vertexCount; ++v) {
        groupSize_[v] = count[group_[v]];
        if (count[group_[v]] == 2) {
          const std::uint32_t f = first[group_[v]];
          if (f != v) {
            sibling_[v] = f;
            sibling_[f] = v;
          }
        }
      }
    }
    pairTarget_.assign(vertexCount, kNone);
    vertex_.assign(vertexCount, VertexState());
    slot_.assign(vertexCount, 0);
    gatherMark_.assign(vertexCount, 0);
    buildAdjacency(vertexCount);
    buildQuadrics();
    heap_.reset(vertexCount);
  }

  // Greedy by cost. Heap keys are estimates (cheapest quadric cost plus the
  // fan term of that target, no legality check); the vertex at the top gets
  // its exact key (all candidates, full cost, legal only) and is collapsed
  // once an exact key is the smallest.
  CollapseRecord run() {
    for (std::uint32_t v = 0; v < point_.size(); ++v) {
      if (isSeamFollower(v)) continue;  // its leader stands for the pair
      const double key = chooseTarget(v, /*exact=*/false);
      if (key < kInfinity) heap_.push(v, key);
    }
    const std::size_t removable =
        triangle_.size() - std::min(triangle_.size(), options_.stopAtTriangles);
    const std::size_t reportEvery = std::max<std::size_t>(removable / 100, 1);
    std::size_t nextReport = triangle_.size() - reportEvery;
    while (!heap_.empty() && liveTriangles_ > options_.stopAtTriangles) {
      if (options_.progress && liveTriangles_ <= nextReport) {
        options_.progress(static_cast<double>(triangle_.size() - liveTriangles_) /
                          static_cast<double>(removable));
        nextReport = liveTriangles_ > reportEvery ? liveTriangles_ - reportEvery : 0;
      }
      const std::uint32_t u = heap_.top();
      if (vertex_[u].exact) {
        // Changes nearby since the key was computed may have made the move
        // illegal or dearer: re-check, collapse only at no more than the key.
        const std::uint32_t w = vertex_[u].target;
        const double key = heap_.topKey();
        compact(u);
        if (isValidMove(u, w)) {
          const double cost = moveCost(u, w);
          if (cost <= key) {
            collapse(u, w, cost);
          } else {
            heap_.update(u, cost);
          }
          continue;
        }
      }
      // Replace the estimate by the exact key; collapse right away when it
      // stays at the top (it was just validated).
      const double key = chooseTarget(u, /*exact=*/true);
      rekey(u, key);
      if (key < kInfinity && heap_.top() == u) collapse(u, vertex_[u].target, key);
    }
    if (options_.progress) options_.progress(1.0);
    CollapseRecord record = std::move(record_);
    record.triangleRemovedAtStep.resize(triangle_.size());
    for (std::size_t t = 0; t < triangle_.size(); ++t) {
      record.triangleRemovedAtStep[t] = triangle_[t].removedAt;
    }
    return record;
  }

 private:
  void buildAdjacency(std::size_t vertexCount) {
    // Lists in vertex order: start = the number of corners of lower vertices.
    for (const Triangle& t : triangle_) {
      for (std::uint32_t v : t.v) ++vertex_[v].liveCount;
    }
    std::uint32_t start = 0;
    for (std::size_t v = 0; v < vertexCount; ++v) {
      vertex_[v].listStart = start;
      start += vertex_[v].liveCount;
    }
    // Headroom for the lists rebuilt on collapses (about 12 entries each).
    pool_.reserve(triangle_.size() * 9);
    pool_.resize(triangle_.size() * 3);
    for (std::uint32_t t = 0; t < triangle_.size(); ++t) {
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t v = triangle_[t].v[k];
        pool_[vertex_[v].listStart + vertex_[v].listSize++] = t << 2 | k;
      }
    }
  }

  void buildQuadrics() {
    quadric_.assign(point_.size(), Quadric());
    // Plane weights are area / mean area: area weighting resists uneven
    // sampling, the normalisation keeps costs in squared length units.
    double totalArea = 0.0;
    for (const Triangle& t : triangle_) totalArea += 0.5 * glm::length(areaNormal(t));
    meanArea_ = totalArea > 0.0 ? totalArea / static_cast<double>(triangle_.size()) : 1.0;
    for (const Triangle& t : triangle_) {
      const glm::dvec3 n2 = areaNormal(t);
      const double length = glm::length(n2);
      if (!(length > 0.0)) continue;  // zero area: no plane
      const glm::dvec3 n = n2 / length;
      const Quadric q =
          Quadric::fromPlane(n, -glm::dot(n, point_[t.v[0]].p), 0.5 * length / meanArea_);
      for (std::uint32_t v : t.v) quadric_[v] += q;
    }
    classifyAndAddBoundaryPlanes();
    classifySeams();
    if (attributes_.dimension > 0) buildAttributeQuadrics();

    for (std::size_t v = 0; v < point_.size(); ++v)
      point_[v].selfCost = quadric_[v].eval(point_[v].p);
  }

  // Classifies every vertex (one neighbour gather each) and adds the
  // Garland-Heckbert boundary constraint: a plane through each border edge,
  // perpendicular to its triangle, so that collapses keep the border in place.
  void classifyAndAddBoundaryPlanes() {
    for (std::uint32_t v = 0; v < point_.size(); ++v) {
      gather(v, neighborsU_);
      vertex_[v].kind = classify(neighborsU_);
      // A kept or pinned vertex never moves; its quadric is built as usual
      // (it still prices the collapses onto it).
      const bool interior = vertex_[v].kind == VertexKind::kInterior;
      if (!constraints_.empty() && constraints_[v] != VertexConstraint::kFree) {
        vertex_[v].kind = VertexKind::kLocked;
      }
      if (interior || !options_.preserveBoundaries) continue;
      for (const Neighbor& nb : neighborsU_) {
        // Each border edge once, from its lower vertex.
        if (nb.triangles != 1 || nb.vertex < v) continue;
        const Triangle& t = triangle_[triangleOn(v, nb.vertex)];
        const glm::dvec3 edge = point_[nb.vertex].p - point_[v].p;
        glm::dvec3 n = glm::cross(edge, areaNormal(t));
        const double length = glm::length(n);
        if (!(length > 0.0)) continue;
        n /= length;
        const double weight = options_.boundaryWeight * glm::dot(edge, edge) / meanArea_;
        const Quadric q = Quadric::fromPlane(n, -glm::dot(n, point_[v].p), weight);
        quadric_[v] += q;
        quadric_[nb.vertex] += q;
      }
    }
  }

  // Seams (CleanMesh::positionGroup): a vertex sharing its place with others
  // is kSeam when it and its one sibling are border vertices whose border
  // edges match (each leads to the same place on both sides); any other
  // shared place (three or more sides meet, a seam meeting a true border,
  // coincident interior vertices) is kLocked. A border vertex alone at its
  // place whose two border edges lead to one place is the closed end of a
  // seam (the sides part there): kLocked too, or moving it would drag one
  // side's attributes onto the other.
  void classifySeams() {
    for (std::uint32_t v = 0; v < point_.size(); ++v) {
      if (vertex_[v].kind == VertexKind::kLocked) continue;
      if (groupSize_[v] == 1) {
        if (vertex_[v].kind != VertexKind::kBoundary) continue;
        gather(v, neighborsU_);
        std::uint32_t places[2] = {kNone, kNone};
        int found = 0;
        for (const Neighbor& nb : neighborsU_) {
          if (nb.triangles == 1 && found < 2) places[found++] = group_[nb.vertex];
        }
        if (found == 2 && places[0] == places[1]) vertex_[v].kind = VertexKind::kLocked;
        continue;
      }
      const std::uint32_t s = sibling_[v];
      if (s == kNone || vertex_[v].kind != VertexKind::kBoundary ||
          vertex_[s].kind == VertexKind::kLocked ||
          (!constraints_.empty() && constraints_[s] != VertexConstraint::kFree)) {
        vertex_[v].kind = VertexKind::kLocked;
        continue;
      }
      gather(v, neighborsU_);
      gather(s, neighborsS_);
      bool matched = true;
      for (const Neighbor& nb : neighborsU_) {
        if (nb.triangles != 1) continue;
        if (borderNeighborAt(neighborsS_, group_[nb.vertex]) == kNone) matched = false;
      }
      if (!matched) vertex_[v].kind = VertexKind::kLocked;
    }
    // A pair is a seam only when both sides qualified.
    for (std::uint32_t v = 0; v < point_.size(); ++v) {
      if (sibling_[v] == kNone || vertex_[v].kind != VertexKind::kBoundary) continue;
      vertex_[v].kind = vertex_[sibling_[v]].kind == VertexKind::kLocked ? VertexKind::kLocked
                                                                         : VertexKind::kSeam;
    }
    for (std::uint32_t v = 0; v < point_.size(); ++v) {
      if (vertex_[v].kind == VertexKind::kSeam && vertex_[sibling_[v]].kind != VertexKind::kSeam) {
        vertex_[v].kind = VertexKind::kLocked;
      }
    }
  }

  // The neighbour across a border edge (one live triangle) in `neighbors`
  // whose place is `place`, kNone when there is none.
  std::uint32_t borderNeighborAt(const std::vector<Neighbor>& neighbors,
                                 std::uint32_t place) const {
    for (const Neighbor& nb : neighbors) {
      if (nb.triangles == 1 && group_[nb.vertex] == place) return nb.vertex;
    }
    return kNone;
  }

  // The pair's leader (the lower index) is the one in the heap.
  bool isSeamFollower(std::uint32_t v) const {
    return vertex_[v].kind == VertexKind::kSeam && sibling_[v] < v;
  }
  std::uint32_t heapVertex(std::uint32_t v) const { return isSeamFollower(v) ? sibling_[v] : v; }

  // For a seam leader u and a border neighbour w: the vertex u's sibling
  // moves onto, the sibling's border neighbour at w's place (kNone: none,
  // or w is alone at its place, the closed end of the seam, which a pair
  // never reaches: the two sides would have to be glued there, see
  // docs/simplifier.md "Seams"). Gathers (so compacts) the sibling.
  std::uint32_t counterpart(std::uint32_t u, std::uint32_t w) {
    if (groupSize_[w] == 1) return kNone;
    gather(sibling_[u], neighborsS_);
    const std::uint32_t sw = borderNeighborAt(neighborsS_, group_[w]);
    return sw != kNone && sw != w && mayTarget(sw) ? sw : kNone;
  }

  // A move of u onto w, with u's sibling when u is a seam leader; u's list
  // is compacted.
  bool isValidMove(std::uint32_t u, std::uint32_t w) {
    if (vertex_[u].kind != VertexKind::kSeam) return isValidCollapse(u, w);
    if (w == kNone || edgeTriangleCount(u, w) != 1) return false;
    const std::uint32_t sw = counterpart(u, w);
    if (sw == kNone || !isValidCollapse(sibling_[u], sw)) return false;
    pairTarget_[u] = sw;
    return isValidCollapse(u, w);
  }

  // After isValidMove(u, w) (the pair's target is set).
  double moveCost(std::uint32_t u, std::uint32_t w) const {
    double cost = fullCost(u, w);
    if (vertex_[u].kind == VertexKind::kSeam) cost += fullCost(sibling_[u], pairTarget_[u]);
    return cost;
  }

  // A live triangle on edge ab (precondition: there is one).
  std::uint32_t triangleOn(std::uint32_t a, std::uint32_t b) const {
    std::uint32_t i = vertex_[a].listStart;
    while (triangle_[triangleOf(pool_[i])].removedAt != 0 ||
           !triangle_[triangleOf(pool_[i])].has(b)) {
      ++i;
    }
    return triangleOf(pool_[i]);
  }

  // Live triangles on edge ab.
  std::uint32_t edgeTriangleCount(std::uint32_t a, std::uint32_t b) const {
    std::uint32_t count = 0;
    for (std::uint32_t i = vertex_[a].listStart, end = i + vertex_[a].listSize; i < end; ++i) {
      const Triangle& t = triangle_[triangleOf(pool_[i])];
      count += t.removedAt == 0 && t.has(b) ? 1u : 0u;
    }
    return count;
  }

  glm::dvec3 areaNormal(const Triangle& t) const {
    const glm::dvec3& a = point_[t.v[0]].p;
    return glm::cross(point_[t.v[1]].p - a, point_[t.v[2]].p - a);
  }

  // Drops dead triangles from v's list (lazy deletion).
  void compact(std::uint32_t v) {
    const std::uint32_t start = vertex_[v].listStart;
    std::uint32_t write = start;
    for (std::uint32_t i = start, end = start + vertex_[v].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      pool_[write] = entry;
      write += triangle_[triangleOf(entry)].removedAt == 0 ? 1u : 0u;
    }
    vertex_[v].listSize = write - start;
  }

  // compact(v), then lists v's neighbours with the number of live triangles
  // on each edge (quadratic in the valence: for classification and borders).
  void gather(std::uint32_t v, std::vector<Neighbor>& out) {
    out.clear();
    const std::uint32_t start = vertex_[v].listStart;
    std::uint32_t write = start;
    // Small fans: linear search. Large ones (poles, cone apexes with
    // thousands of triangles) index their neighbours through stamped slots.
    const bool large = vertex_[v].listSize > 32;
    const std::uint32_t stamp = large ? ++gatherStamp_ : 0;
    auto add = [&](std::uint32_t x) {
      if (large) {
        if (gatherMark_[x] == stamp) {
          ++out[slot_[x]].triangles;
        } else {
          gatherMark_[x] = stamp;
          slot_[x] = static_cast<std::uint32_t>(out.size());
          out.push_back({x, 1});
        }
        return;
      }
      for (Neighbor& n : out) {
        if (n.vertex == x) {
          ++n.triangles;
          return;
        }
      }
      out.push_back({x, 1});
    };
    for (std::uint32_t i = start, end = start + vertex_[v].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      if (t.removedAt != 0) continue;
      pool_[write++] = entry;
      add(t.v[kNextCorner[cornerOf(entry)]]);
      add(t.v[kPrevCorner[cornerOf(entry)]]);
    }
    vertex_[v].listSize = write - start;
  }

  // Attribute quadric part of u -> w: u's and w's attribute planes at
  // (p_w, s_w), scaled so that attributeWeight is relative to geometry (a
  // full-range attribute error weighs like a distance of sqrt(weight) *
  // diagonal).
  double attributeCost(std::uint32_t u, std::uint32_t w) const {
    const std::size_t dimension = attributes_.dimension;
    double sum = attributeSelfCost_[w];
    for (std::size_t k = 0; k < dimension; ++k) {
      sum += attributeQuadric_[u * dimension + k].eval(point_[w].p,
                                                       attributes_.values[w * dimension + k]);
    }
    return attributeScale_ * std::max(sum, 0.0);
  }

  double attributeSelfCost(std::uint32_t w) const {
    const std::size_t dimension = attributes_.dimension;
    double sum = 0.0;
    for (std::size_t k = 0; k < dimension; ++k) {
      sum += attributeQuadric_[w * dimension + k].eval(point_[w].p,
                                                       attributes_.values[w * dimension + k]);
    }
    return sum;
  }

  void buildAttributeQuadrics() {
    const std::size_t dimension = attributes_.dimension;
    attributeScale_ = options_.attributeWeight * diagonal_ * diagonal_;
    attributeQuadric_.assign(point_.size() * dimension, AttributeQuadric());
    for (const Triangle& t : triangle_) {
      const glm::dvec3& p0 = point_[t.v[0]].p;
      const glm::dvec3 e1 = point_[t.v[1]].p - p0;
      const glm::dvec3 e2 = point_[t.v[2]].p - p0;
      const glm::dvec3 n = glm::cross(e1, e2);
      const double n2 = glm::dot(n, n);
      if (!(n2 > 0.0)) continue;
      // Gradient in the triangle's plane: g . e1 = ds1, g . e2 = ds2, g . n = 0.
      const glm::dvec3 along1 = glm::cross(e2, n) / n2;
      const glm::dvec3 along2 = glm::cross(n, e1) / n2;
      const double weight = 0.5 * std::sqrt(n2) / meanArea_;
      for (std::size_t k = 0; k < dimension; ++k) {
        const double s0 = attributes_.values[t.v[0] * dimension + k];
        const double ds1 = attributes_.values[t.v[1] * dimension + k] - s0;
        const double ds2 = attributes_.values[t.v[2] * dimension + k] - s0;
        const glm::dvec3 g = ds1 * along1 + ds2 * along2;
        const AttributeQuadric q = AttributeQuadric::fromGradient(g, s0 - glm::dot(g, p0), weight);
        for (std::uint32_t v : t.v) attributeQuadric_[v * dimension + k] += q;
      }
    }
    attributeSelfCost_.resize(point_.size());
    for (std::uint32_t v = 0; v < point_.size(); ++v) attributeSelfCost_[v] = attributeSelfCost(v);
  }

  // Quadric part of the cost of u -> w: (Q_u + Q_w)(p_w); w keeps its place.
  double quadricCost(std::uint32_t u, std::uint32_t w) const {
    double cost = quadric_[u].eval(point_[w].p) + point_[w].selfCost;
    if (attributes_.dimension > 0) cost += attributeCost(u, w);
    return std::max(cost, 0.0);  // rounding can make a zero cost slightly negative
  }

  // Area-weighted squared distances from p_u to the planes of the triangles
  // u's fan becomes, plus the largest one (see kFarthestWeight). This is
  // what the quadric misses when u is the tip of a thin feature: all of u's
  // planes pass near p_w, yet the tip is cut off.
  // Skips dead triangles, so u's list need not be compacted.
  // With a limit: most callers only ask whether base + fanCost < limit (a
  // move priced against the best so far or a heap key; about 60% are
  // rejected on the bunny). Once the farthest term alone takes base to the
  // limit, the rest of the fan is skipped and that partial value, for which
  // base + value >= limit too, is returned: every term only grows the result
  // (sums and maxima of non-negative values, rounding is monotone), so the
  // caller's comparison, hence every decision, is the same as with the full
  // value.
  double fanCost(std::uint32_t u, std::uint32_t w, double base = 0.0,
                 double limit = kInfinity) const {
    const glm::dvec3 pw = point_[w].p;
    const glm::dvec3 pu = point_[u].p;
    const glm::dvec3 toU = pu - pw;  // the same value in every term; GCC did not hoist it
    double fan = 0.0, farthest = 0.0;
    for (std::uint32_t i = vertex_[u].listStart, end = i + vertex_[u].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      const std::uint32_t a = t.v[kNextCorner[cornerOf(entry)]];
      const std::uint32_t b = t.v[kPrevCorner[cornerOf(entry)]];
      if (t.removedAt != 0 || a == w || b == w) continue;
      const glm::dvec3 after = glm::cross(point_[a].p - pw, point_[b].p - pw);
      const double afterLength2 = glm::dot(after, after);
      if (afterLength2 > 0.0) {
        const double d = glm::dot(after, toU);
        // The bound first: the triangle that decides skips its square root.
        farthest = std::max(farthest, d * d / afterLength2);
        if (base + kFarthestWeight * farthest >= limit) return kFarthestWeight * farthest;
        fan += 0.5 * d * d / std::sqrt(afterLength2);  // area * squared distance
      }
    }
    // A border vertex also takes its stretch of border with it: the border
    // runs straight from w to u's other border neighbour afterwards. Its
    // distance to that segment is the border's version of the fan term;
    // the boundary planes alone miss it where the border edges are short
    // (their weight scales with edge length squared): a tiny ear on a hole
    // of the bunny went first at almost no cost and stayed its 50% max.
    // Fans above kLargeFan skip it: the neighbour search is quadratic.
    if ((vertex_[u].kind == VertexKind::kBoundary || vertex_[u].kind == VertexKind::kSeam) &&
        vertex_[u].listSize <= kLargeFan) {
      const std::uint32_t y = otherBorderNeighbor(u, w);
      if (y != kNone) farthest = std::max(farthest, squaredDistanceToSegment(pu, pw, point_[y].p));
    }
    return kFanWeight * fan / meanArea_ + kFarthestWeight * farthest;
  }

  // For a border vertex u (two border edges, oriented manifold fan) and one
  // of its border neighbours w: the other one, kNone if not found. In the
  // fan, u -> next corner and previous corner -> u are the half-edges; a
  // border neighbour is a next corner that is nobody's previous corner or
  // the reverse. Skips dead triangles. O(valence^2), border fans are small.
  std::uint32_t otherBorderNeighbor(std::uint32_t u, std::uint32_t w) const {
    const std::uint32_t start = vertex_[u].listStart, end = start + vertex_[u].listSize;
    for (std::uint32_t i = start; i < end; ++i) {
      const Triangle& t = triangle_[triangleOf(pool_[i])];
      if (t.removedAt != 0) continue;
      const std::uint32_t next = t.v[kNextCorner[cornerOf(pool_[i])]];
      const std::uint32_t prev = t.v[kPrevCorner[cornerOf(pool_[i])]];
      bool nextMatched = false, prevMatched = false;
      for (std::uint32_t j = start; j < end; ++j) {
        const Triangle& o = triangle_[triangleOf(pool_[j])];
        if (j == i || o.removedAt != 0) continue;
        nextMatched = nextMatched || o.v[kPrevCorner[cornerOf(pool_[j])]] == next;
        prevMatched = prevMatched || o.v[kNextCorner[cornerOf(pool_[j])]] == prev;
      }
      if (!nextMatched && next != w) return next;
      if (!prevMatched && prev != w) return prev;
    }
    return kNone;
  }

  static double squaredDistanceToSegment(const glm::dvec3& p, const glm::dvec3& a,
                                         const glm::dvec3& b) {
    const glm::dvec3 ab = b - a;
    const double length2 = glm::dot(ab, ab);
    const double s = length2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / length2, 0.0, 1.0) : 0.0;
    const glm::dvec3 d = p - (a + s * ab);
    return glm::dot(d, d);
  }

  double fullCost(std::uint32_t u, std::uint32_t w) const {
    return quadricCost(u, w) + fanCost(u, w);
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

  // Picks vertex_[u].target and returns its key (infinity when u must stay) and
  // compacts u's list. Estimate (exact == false): the cheapest quadric cost
  // among the moves u's kind allows, plus that move's fan term. Exact: the
  // cheapest full cost among the legal moves.
  double chooseTarget(std::uint32_t u, bool exact) {
    vertex_[u].target = kNone;
    vertex_[u].exact = exact;
    if (vertex_[u].kind == VertexKind::kUnknown) {
      gather(u, neighborsU_);
      vertex_[u].kind = classify(neighborsU_);
    }
    const VertexKind kind = vertex_[u].kind;
    if (kind == VertexKind::kLocked || isSeamFollower(u)) return kInfinity;
    candidateVertices_.clear();
    if (kind == VertexKind::kSeam) return chooseSeamTarget(u, exact);
    if (kind == VertexKind::kBoundary) {
      gather(u, neighborsU_);
      for (const Neighbor& nb : neighborsU_) {
        // Stay on the border: only along border edges.
        if (nb.triangles == 1 && mayTarget(nb.vertex)) candidateVertices_.push_back(nb.vertex);
      }
    } else {
      // Interior of an oriented manifold: every neighbour is the next
      // corner of exactly one triangle of the fan, no deduplication needed.
      compact(u);
      for (std::uint32_t i = vertex_[u].listStart, end = i + vertex_[u].listSize; i < end; ++i) {
        const std::uint32_t entry = pool_[i];
        const std::uint32_t w = triangle_[triangleOf(entry)].v[kNextCorner[cornerOf(entry)]];
        if (mayTarget(w)) candidateVertices_.push_back(w);
      }
    }
    if (!exact) {
      double best = kInfinity;
      for (std::uint32_t w : candidateVertices_) {
        const double cost = quadricCost(u, w);
        if (cost < best) {
          best = cost;
          vertex_[u].target = w;
        }
      }
      return best < kInfinity ? best + fanCost(u, vertex_[u].target) : kInfinity;
    }
    // In quadric order; the quadric cost is a lower bound of the full cost,
    // so candidates past the best legal full cost need no fan term.
    candidates_.resize(candidateVertices_.size());
    for (std::size_t i = 0; i < candidateVertices_.size(); ++i) {
      candidates_[i].cost = quadricCost(u, candidateVertices_[i]);
      candidates_[i].vertex = candidateVertices_[i];
    }
    std::sort(candidates_.begin(), candidates_.end());
    // Huge fans: only the kLargeFan cheapest by quadric get the O(valence)
    // fan term, or one exact evaluation would cost O(valence^2).
    if (candidates_.size() > kLargeFan) candidates_.resize(kLargeFan);
    double best = kInfinity;
    for (const Candidate& c : candidates_) {
      if (c.cost >= best) break;
      const double cost = c.cost + fanCost(u, c.vertex, c.cost, best);
      if (cost < best && isValidCollapse(u, c.vertex)) {
        best = cost;
        vertex_[u].target = c.vertex;
      }
    }
    return best;
  }

  // chooseTarget for a seam leader: along the seam edges only, the pair's
  // cost is the sum of both sides' costs.
  double chooseSeamTarget(std::uint32_t u, bool exact) {
    gather(u, neighborsU_);
    for (const Neighbor& nb : neighborsU_) {
      if (nb.triangles == 1 && mayTarget(nb.vertex)) candidateVertices_.push_back(nb.vertex);
    }
    const std::uint32_t s = sibling_[u];
    double best = kInfinity;
    std::uint32_t bestPair = kNone;
    for (std::uint32_t w : candidateVertices_) {
      const std::uint32_t sw = counterpart(u, w);
      if (sw == kNone) continue;
      double cost = quadricCost(u, w) + quadricCost(s, sw);
      if (cost >= best) continue;
      cost += fanCost(u, w) + fanCost(s, sw);
      if (cost >= best) continue;
      if (exact && !(isValidCollapse(s, sw) && isValidCollapse(u, w))) continue;
      best = cost;
      vertex_[u].target = w;
      bestPair = sw;
    }
    pairTarget_[u] = bestPair;
    return best;
  }

  // Topology and geometry checks for u -> w; u's list is compacted.
  bool isValidCollapse(std::uint32_t u, std::uint32_t w) {
    if (w == kNone || !mayTarget(w)) return false;
    // Opposite corners of the triangles on edge uw (they die with it).
    opposite_.clear();
    const std::uint32_t uStart = vertex_[u].listStart, uEnd = uStart + vertex_[u].listSize;
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      const std::uint32_t a = t.v[kNextCorner[cornerOf(entry)]];
      const std::uint32_t b = t.v[kPrevCorner[cornerOf(entry)]];
      if (a == w) opposite_.push_back(b);
      if (b == w) opposite_.push_back(a);
    }
    if (opposite_.empty()) return false;  // not an edge any more
    // Link condition: every common neighbour of u and w must be the opposite
    // corner of a triangle on uw; otherwise the collapse would glue two
    // sheets (non-manifold edge) or close a hole. Common neighbours are the
    // corners of w's triangles marked as u's neighbours.
    const std::uint32_t neighborOfU = ++stamp_;
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      vertex_[t.v[kNextCorner[cornerOf(entry)]]].mark = neighborOfU;
      vertex_[t.v[kPrevCorner[cornerOf(entry)]]].mark = neighborOfU;
    }
    const std::uint32_t common = ++stamp_;
    for (std::uint32_t i = vertex_[w].listStart, end = i + vertex_[w].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      if (t.removedAt != 0) continue;
      for (std::uint32_t x :
           {t.v[kNextCorner[cornerOf(entry)]], t.v[kPrevCorner[cornerOf(entry)]]}) {
        if (x == u || vertex_[x].mark != neighborOfU) continue;
        if (std::find(opposite_.begin(), opposite_.end(), x) == opposite_.end()) return false;
        vertex_[x].mark = common;
      }
    }
    const glm::dvec3 pu = point_[u].p;
    const glm::dvec3 pw = point_[w].p;
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      // The triangle (u, a, b) becomes (w, a, b) in the same winding.
      const std::uint32_t a = t.v[kNextCorner[cornerOf(entry)]];
      const std::uint32_t b = t.v[kPrevCorner[cornerOf(entry)]];
      if (a == w || b == w) continue;
      // A triangle w already has on a and b would be duplicated (the last
      // collapse of a tetrahedron). Needs a and b both common neighbours.
      if (vertex_[a].mark == common && vertex_[b].mark == common && hasTriangleOn(w, a, b))
        return false;
      if (!options_.preventFlips) continue;
      const glm::dvec3& pa = point_[a].p;
      const glm::dvec3& pb = point_[b].p;
      const glm::dvec3 after = glm::cross(pa - pw, pb - pw);
      // Small turns add up: stay on the front side of the triangle's input
      // orientation too (each live triangle is an input triangle with
      // corners renamed), so no triangle ends up facing against the input.
      const glm::dvec3 inputNormal(inputNormal_[triangleOf(entry)]);
      if (glm::dot(after, inputNormal) <= 0.0 && inputNormal != glm::dvec3(0.0)) return false;
      // Where the input surface is smooth at the new triangle's corners
      // (their input vertex normals agree), the triangle must face their way.
      const glm::dvec3 nw(vertexNormal_[w]), na(vertexNormal_[a]), nb(vertexNormal_[b]);
      if (glm::dot(nw, na) > 0.0 && glm::dot(na, nb) > 0.0 && glm::dot(nw, nb) > 0.0 &&
          glm::dot(after, nw + na + nb) <= 0.0) {
        return false;
      }
      const glm::dvec3 before = glm::cross(pa - pu, pb - pu);
      const double beforeLength2 = glm::dot(before, before);
      if (beforeLength2 == 0.0) continue;  // a zero-area triangle has no orientation to keep
      const double d = glm::dot(before, after);
      if (d <= 0.0 || d * d < kMinFlipCos2 * beforeLength2 * glm::dot(after, after)) return false;
    }
    return true;
  }

  // A pinned vertex absorbs no neighbour (BuildOptions::vertexConstraints).
  bool mayTarget(std::uint32_t w) const {
    return constraints_.empty() || constraints_[w] != VertexConstraint::kPin;
  }

  bool hasTriangleOn(std::uint32_t w, std::uint32_t a, std::uint32_t b) const {
    for (std::uint32_t i = vertex_[w].listStart, end = i + vertex_[w].listSize; i < end; ++i) {
      const Triangle& t = triangle_[triangleOf(pool_[i])];
      if (t.removedAt == 0 && t.has(a) && t.has(b)) return true;
    }
    return false;
  }

  void removeVertex(std::uint32_t v, std::uint32_t parent) {
    vertex_[v].removed = 1;
    record_.removedVertex.push_back(v);
    record_.removedParent.push_back(parent);
    heap_.remove(v);
  }

  // One step: u -> w, and u's sibling onto pairTarget_[u] when u leads a
  // seam pair. u's list (and the sibling's) is compacted: every caller
  // gathered them since the last change.
  void collapse(std::uint32_t u, std::uint32_t w, double cost) {
    const std::uint32_t step = static_cast<std::uint32_t>(record_.costOfStep.size()) + 1;
    const bool pair = vertex_[u].kind == VertexKind::kSeam;
    const std::uint32_t s = pair ? sibling_[u] : kNone;
    const std::uint32_t sw = pair ? pairTarget_[u] : kNone;
    collapseEdge(u, w, step);
    // The sides share no triangle (a triangle with two corners at one
    // place is dropped by the cleanup), so the first half left s's list
    // compact and its checks true.
    if (pair) collapseEdge(s, sw, step);
    record_.removalsAfterStep.push_back(static_cast<std::uint32_t>(record_.removedVertex.size()));
    record_.trianglesAfterStep.push_back(static_cast<std::uint32_t>(liveTriangles_));
    record_.costOfStep.push_back(static_cast<float>(cost));
    if (!vertex_[w].removed) rekeyAround(u, w);
    if (pair && !vertex_[sw].removed) rekeyAround(s, sw);
  }

  void collapseEdge(std::uint32_t u, std::uint32_t w, std::uint32_t step) {
    // Kill the triangles on edge uw first so that w's new list skips them.
    opposite_.clear();
    const std::uint32_t uStart = vertex_[u].listStart, uEnd = uStart + vertex_[u].listSize;
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t entry = pool_[i];
      Triangle& t = triangle_[triangleOf(entry)];
      const std::uint32_t a = t.v[kNextCorner[cornerOf(entry)]];
      const std::uint32_t b = t.v[kPrevCorner[cornerOf(entry)]];
      if (t.removedAt != 0 || (a != w && b != w)) continue;
      t.removedAt = step;
      --liveTriangles_;
      for (std::uint32_t x : t.v) --vertex_[x].liveCount;
      opposite_.push_back(a == w ? b : a);
    }
    // w's new list: its live triangles, then u's survivors renamed to w.
    // Written at the end of the pool (in place when w's list is already last).
    const std::uint32_t wStart = vertex_[w].listStart, wEnd = wStart + vertex_[w].listSize;
    std::uint32_t newStart;
    if (wEnd == pool_.size()) {
      std::uint32_t write = wStart;
      for (std::uint32_t i = wStart; i < wEnd; ++i) {
        if (triangle_[triangleOf(pool_[i])].removedAt == 0) pool_[write++] = pool_[i];
      }
      pool_.resize(write);
      newStart = wStart;
    } else {
      newStart = static_cast<std::uint32_t>(pool_.size());
      for (std::uint32_t i = wStart; i < wEnd; ++i) {
        const std::uint32_t entry = pool_[i];
        if (triangle_[triangleOf(entry)].removedAt == 0) pool_.push_back(entry);
      }
    }
    for (std::uint32_t i = uStart; i < uEnd; ++i) {
      const std::uint32_t entry = pool_[i];
      Triangle& t = triangle_[triangleOf(entry)];
      if (t.removedAt != 0) continue;
      t.v[cornerOf(entry)] = w;
      pool_.push_back(entry);
      ++vertex_[w].liveCount;
    }
    vertex_[u].liveCount = 0;
    vertex_[w].listStart = newStart;
    vertex_[w].listSize = static_cast<std::uint32_t>(pool_.size()) - newStart;
    vertex_[u].listSize = 0;

    quadric_[w] += quadric_[u];
    point_[w].selfCost = quadric_[w].eval(point_[w].p);
    if (attributes_.dimension > 0) {
      for (std::size_t k = 0; k < attributes_.dimension; ++k) {
        attributeQuadric_[w * attributes_.dimension + k] +=
            attributeQuadric_[u * attributes_.dimension + k];
      }
      attributeSelfCost_[w] = attributeSelfCost(w);
    }
    removeVertex(u, w);
    // Vertices left without triangles leave the mesh too (parent kNone).
    if (vertex_[w].listSize == 0) removeVertex(w, kNone);
    for (std::uint32_t x : opposite_) {
      if (!vertex_[x].removed && vertex_[x].liveCount == 0) removeVertex(x, kNone);
    }
  }

  // After u -> w only w's quadric and w's fan changed. Re-choose w and the
  // vertices that targeted u or w. Any other neighbour x of w keeps its key
  // (its target's quadric cost is unchanged; a changed fan term is caught
  // when x reaches the top) unless its new option x -> w is cheaper.
  void rekeyAround(std::uint32_t u, std::uint32_t w) {
    // The loop below prices every neighbour x of w: x's record and quadric
    // are cache misses (collapses jump around the mesh). Asking for them all
    // up front lets the misses overlap with each other and with w's own
    // re-choice (3-5% of the build in paired runs on the bunny and the ogre,
    // near the noise of this machine). No effect on results.
    for (std::uint32_t i = vertex_[w].listStart, end = i + vertex_[w].listSize; i < end; ++i) {
      for (std::uint32_t x : triangle_[triangleOf(pool_[i])].v) {
        __builtin_prefetch(&vertex_[x]);
        __builtin_prefetch(&quadric_[x]);
        __builtin_prefetch(reinterpret_cast<const char*>(&quadric_[x]) + 64);
      }
    }
    const std::uint32_t lead = heapVertex(w);
    rekey(lead, chooseTarget(lead, /*exact=*/false));
    compact(w);
    // Second stage, now that the records are in: the start of each
    // neighbour's corner list, which its fan term walks (another 5-8% in
    // paired runs on the bunny and the ogre).
    for (std::uint32_t i = vertex_[w].listStart, end = i + vertex_[w].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      const std::uint32_t x = triangle_[triangleOf(entry)].v[kNextCorner[cornerOf(entry)]];
      __builtin_prefetch(pool_.data() + vertex_[x].listStart);
    }
    const bool wMayTarget = mayTarget(w);
    const std::uint32_t seen = ++stamp_;
    for (std::uint32_t i = vertex_[w].listStart, end = i + vertex_[w].listSize; i < end; ++i) {
      const std::uint32_t entry = pool_[i];
      const Triangle& t = triangle_[triangleOf(entry)];
      for (std::uint32_t corner :
           {t.v[kNextCorner[cornerOf(entry)]], t.v[kPrevCorner[cornerOf(entry)]]}) {
        const std::uint32_t x = heapVertex(corner);
        if (vertex_[x].mark == seen) continue;
        vertex_[x].mark = seen;
        // A seam pair's cost spans both sides: always re-chosen.
        if (vertex_[x].target == u || vertex_[x].target == w || vertex_[x].target == kNone ||
            !heap_.contains(x) || vertex_[x].kind == VertexKind::kSeam) {
          rekey(x, chooseTarget(x, /*exact=*/false));
          continue;
        }
        if (vertex_[x].kind == VertexKind::kLocked || !wMayTarget) continue;
        // A huge fan (a pole, a cone apex) would pay O(valence) here on every
        // collapse around it; its key may stay high until it is re-chosen.
        if (vertex_[x].liveCount > kLargeFan) continue;
        if (vertex_[x].kind == VertexKind::kBoundary && edgeTriangleCount(x, w) != 1) continue;
        double cost = quadricCost(x, w);
        if (cost < heap_.key(x)) cost += fanCost(x, w, cost, heap_.key(x));
        if (cost < heap_.key(x)) {
          vertex_[x].target = w;
          vertex_[x].exact = false;
          heap_.update(x, cost);
        }
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
  const std::vector<VertexConstraint>& constraints_;  // empty or per vertex
  double diagonal_ = 0.0;
  double meanArea_ = 1.0;
  // Position and the vertex's own quadric error there, side by side: a
  // candidate's cost reads both.
  struct Point {
    glm::dvec3 p;
    double selfCost = 0.0;  // quadric_[v].eval(p)
  };
  std::vector<Point> point_;
  std::vector<Quadric> quadric_;
  // With attributes: dimension quadrics per vertex, and their value at the
  // vertex itself.
  std::vector<AttributeQuadric> attributeQuadric_;
  std::vector<double> attributeSelfCost_;
  double attributeScale_ = 0.0;
  std::vector<Triangle> triangle_;
  std::vector<glm::vec3> inputNormal_;   // unit normal of each triangle in the input
  std::vector<glm::vec3> vertexNormal_;  // unit area-weighted normal of each input vertex
  std::size_t liveTriangles_ = 0;
  // Vertex -> corner lists: pool_[vertex_[v].listStart .. + vertex_[v].listSize], may hold
  // dead triangles until the next gather of v.
  // The per-vertex state the collapse loop reads for every vertex it visits,
  // in one 24-byte record: a visit costs one cache line instead of one per
  // array.
  struct VertexState {
    std::uint32_t listStart = 0;
    std::uint32_t listSize = 0;
    std::uint32_t liveCount = 0;  // live triangles (the list lags behind)
    std::uint32_t target = kNone;
    std::uint32_t mark = 0;  // stamp_ of the last visit
    VertexKind kind = VertexKind::kUnknown;
    std::uint8_t exact = 0;  // heap key is the exact, validated cost of target
    std::uint8_t removed = 0;
  };
  std::vector<VertexState> vertex_;
  std::vector<std::uint32_t> pool_;
  // Seams: place of each vertex, vertices at that place, the other vertex
  // of a two-vertex place (kNone otherwise), and where a seam leader's
  // sibling goes when the leader moves onto its target.
  std::vector<std::uint32_t> group_;
  std::vector<std::uint32_t> groupSize_;
  std::vector<std::uint32_t> sibling_;
  std::vector<std::uint32_t> pairTarget_;
  IndexedMinHeap heap_;
  CollapseRecord record_;
  // Scratch, reused to avoid allocation per collapse.
  std::vector<Neighbor> neighborsU_;
  std::vector<Neighbor> neighborsS_;
  std::vector<std::uint32_t> opposite_;
  struct Candidate {
    double cost;
    std::uint32_t vertex;
    bool operator<(const Candidate& o) const {
      return cost < o.cost || (cost == o.cost && vertex < o.vertex);
    }
  };
  std::vector<std::uint32_t> candidateVertices_;
  std::vector<Candidate> candidates_;
  // Gather of large fans: stamp and index in the output per neighbour.
  std::vector<std::uint32_t> gatherMark_;
  std::vector<std::uint32_t> slot_;
  std::uint32_t gatherStamp_ = 0;
  std::uint32_t stamp_ = 0;
};

}  // namespace

CollapseRecord runCollapses(const CleanMesh& mesh, const VertexAttributes& attributes,
                            const std::vector<VertexConstraint>& constraints,
                            const BuildOptions& options) {
  Collapser collapser(mesh, attributes, constraints, options);
  return collapser.run();
}

}  // namespace thinlod::simplifier::qem
