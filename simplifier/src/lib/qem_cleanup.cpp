#include "qem_cleanup.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/common.hpp>
#include <string>

namespace thinlod::simplifier::qem {
namespace {

constexpr std::uint32_t kEmpty = 0xffffffffu;

std::uint64_t mix(std::uint64_t h) {
  // splitmix64 finaliser: cheap, good avalanche for packed integer keys.
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h;
}

std::size_t tableCapacity(std::size_t entries) {
  std::size_t capacity = 16;
  while (capacity < entries * 2) capacity *= 2;
  return capacity;
}

// Uniform grid over the bounding box; each cell heads a chain of the clean
// vertices inside it. Cells are much larger than the weld distance so that a
// query usually touches one cell (two when the point is near a cell face).
class WeldGrid {
 public:
  WeldGrid(const Bounds& bounds, double cellSize, std::size_t expectedVertices)
      : origin_(bounds.min), invCell_(1.0 / cellSize), slots_(tableCapacity(expectedVertices)) {}

  // Clean vertex within `epsilon` of p for which accept(v) holds, or kEmpty;
  // *near (when given) is set to the first clean vertex within `epsilon`
  // whether accepted or not (kEmpty when there is none).
  template <typename Accept>
  std::uint32_t find(const glm::vec3& p, double epsilon,
                     const std::vector<glm::vec3>& cleanPositions, Accept accept,
                     std::uint32_t* near = nullptr) const {
    const std::array<std::int64_t, 3> lo = cellOf(p, -epsilon);
    const std::array<std::int64_t, 3> hi = cellOf(p, epsilon);
    const double eps2 = epsilon * epsilon;
    if (near != nullptr) *near = kEmpty;
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
          for (std::uint32_t v = head({x, y, z}); v != kEmpty; v = next_[v]) {
            const glm::dvec3 d = glm::dvec3(cleanPositions[v]) - glm::dvec3(p);
            if (d.x * d.x + d.y * d.y + d.z * d.z > eps2) continue;
            if (near != nullptr && *near == kEmpty) *near = v;
            if (accept(v)) return v;
          }
        }
      }
    }
    return kEmpty;
  }

  void insert(const glm::vec3& p, std::uint32_t cleanVertex) {
    const std::array<std::int64_t, 3> cell = cellOf(p, 0.0);
    if (next_.size() <= cleanVertex) next_.resize(cleanVertex + 1, kEmpty);
    Slot& slot = slotFor(cell);
    next_[cleanVertex] = slot.head;
    slot.head = cleanVertex;
  }

 private:
  struct Slot {
    std::array<std::int64_t, 3> cell{};
    std::uint32_t head = kEmpty;
  };

  std::array<std::int64_t, 3> cellOf(const glm::vec3& p, double offset) const {
    return {static_cast<std::int64_t>(std::floor((p.x - origin_.x + offset) * invCell_)),
            static_cast<std::int64_t>(std::floor((p.y - origin_.y + offset) * invCell_)),
            static_cast<std::int64_t>(std::floor((p.z - origin_.z + offset) * invCell_))};
  }

  std::size_t hashOf(const std::array<std::int64_t, 3>& cell) const {
    const std::uint64_t h = mix(static_cast<std::uint64_t>(cell[0]) * 0x9E3779B97F4A7C15ull ^
                                mix(static_cast<std::uint64_t>(cell[1]) + 0x632BE59BD9B4E019ull) ^
                                static_cast<std::uint64_t>(cell[2]));
    return static_cast<std::size_t>(h) & (slots_.size() - 1);
  }

  std::uint32_t head(const std::array<std::int64_t, 3>& cell) const {
    for (std::size_t i = hashOf(cell);; i = (i + 1) & (slots_.size() - 1)) {
      const Slot& slot = slots_[i];
      if (slot.head == kEmpty) return kEmpty;
      if (slot.cell == cell) return slot.head;
    }
  }

  Slot& slotFor(const std::array<std::int64_t, 3>& cell) {
    for (std::size_t i = hashOf(cell);; i = (i + 1) & (slots_.size() - 1)) {
      Slot& slot = slots_[i];
      if (slot.head == kEmpty) {
        slot.cell = cell;
        return slot;
      }
      if (slot.cell == cell) return slot;
    }
  }

  glm::vec3 origin_;
  double invCell_;
  std::vector<Slot> slots_;  // at most half full: one slot per occupied cell
  std::vector<std::uint32_t> next_;
};

// Set of triangles keyed by their sorted vertex triple.
class TriangleSet {
 public:
  // kEmpty in the first corner marks a free slot (vertex ids are < kEmpty).
  explicit TriangleSet(std::size_t expected)
      : slots_(tableCapacity(expected), std::array<std::uint32_t, 3>{kEmpty, 0, 0}) {}

  // True when inserted, false when an equal vertex set was already present.
  bool insert(std::array<std::uint32_t, 3> t) {
    std::sort(t.begin(), t.end());
    const std::uint64_t h =
        mix((static_cast<std::uint64_t>(t[0]) << 32 | t[1]) ^ mix(t[2] + 0x9E3779B97F4A7C15ull));
    for (std::size_t i = static_cast<std::size_t>(h) & (slots_.size() - 1);;
         i = (i + 1) & (slots_.size() - 1)) {
      std::array<std::uint32_t, 3>& slot = slots_[i];
      if (slot[0] == kEmpty) {
        slot = t;
        return true;
      }
      if (slot == t) return false;
    }
  }

 private:
  std::vector<std::array<std::uint32_t, 3>> slots_;
};

// Interleaves the low 10 bits of x with two zero bits each.
std::uint32_t spreadBits(std::uint32_t x) {
  x &= 0x3ffu;
  x = (x | x << 16) & 0x030000ffu;
  x = (x | x << 8) & 0x0300f00fu;
  x = (x | x << 4) & 0x030c30c3u;
  x = (x | x << 2) & 0x09249249u;
  return x;
}

// Renumbers vertices along a Morton (Z-order) curve and orders triangles by
// their lowest vertex, in place. Simplification walks neighbourhoods; with
// neighbours close in memory it runs about a quarter faster than in the
// file's order on the shared models.
void sortSpatially(CleanMesh& mesh, const Bounds& bounds) {
  const std::size_t vertexCount = mesh.positions.size();
  const glm::vec3 extent = glm::max(bounds.max - bounds.min, glm::vec3(1e-30f));
  std::vector<std::uint64_t> keyed(vertexCount);
  for (std::size_t v = 0; v < vertexCount; ++v) {
    const glm::vec3 q = glm::clamp((mesh.positions[v] - bounds.min) / extent, 0.0f, 1.0f) * 1023.0f;
    const std::uint32_t morton = spreadBits(static_cast<std::uint32_t>(q.x)) |
                                 spreadBits(static_cast<std::uint32_t>(q.y)) << 1 |
                                 spreadBits(static_cast<std::uint32_t>(q.z)) << 2;
    keyed[v] = static_cast<std::uint64_t>(morton) << 32 | v;
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> newIndex(vertexCount);
  std::vector<glm::vec3> positions(vertexCount);
  std::vector<std::uint32_t> source(vertexCount);
  std::vector<std::uint32_t> group(vertexCount);
  for (std::size_t i = 0; i < vertexCount; ++i) {
    const auto old = static_cast<std::uint32_t>(keyed[i]);
    newIndex[old] = static_cast<std::uint32_t>(i);
    positions[i] = mesh.positions[old];
    source[i] = mesh.sourceVertex[old];
    group[i] = mesh.positionGroup[old];
  }
  mesh.positions = std::move(positions);
  mesh.sourceVertex = std::move(source);
  mesh.positionGroup = std::move(group);
  // Counting sort of the triangles by their lowest new vertex (stable).
  const std::size_t triangleCount = mesh.indices.size() / 3;
  std::vector<std::uint32_t> start(vertexCount + 1, 0);
  std::vector<std::uint32_t> lowest(triangleCount);
  for (std::size_t t = 0; t < triangleCount; ++t) {
    for (int k = 0; k < 3; ++k) mesh.indices[3 * t + k] = newIndex[mesh.indices[3 * t + k]];
    lowest[t] = std::min({mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]});
    ++start[lowest[t] + 1];
  }
  for (std::size_t v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
  std::vector<std::uint32_t> sorted(mesh.indices.size());
  for (std::size_t t = 0; t < triangleCount; ++t) {
    const std::uint32_t slot = start[lowest[t]]++;
    for (int k = 0; k < 3; ++k) sorted[3 * slot + k] = mesh.indices[3 * t + k];
  }
  mesh.indices = std::move(sorted);
}

// Whether input vertices a and b carry the same uv and colour (the
// attributes whose discontinuities are seams).
bool sameSeamAttributes(const IndexedMesh& mesh, std::uint32_t a, std::uint32_t b) {
  constexpr float kUvTolerance = 1e-6f;
  if (!mesh.uvs.empty()) {
    const glm::vec2 d = glm::abs(mesh.uvs[a] - mesh.uvs[b]);
    if (d.x > kUvTolerance || d.y > kUvTolerance) return false;
  }
  return mesh.colors.empty() || mesh.colors[a] == mesh.colors[b];
}

}  // namespace

Result<CleanMesh> cleanMesh(const IndexedMesh& mesh, float weldEpsilon, bool splitSeams,
                            const std::vector<std::uint64_t>& weldKeys) {
  THINLOD_RETURN_IF_ERROR(mesh.validate("input mesh"));
  if (mesh.indices.empty()) {
    return Status(ErrorCode::kInvalidArgument, "input mesh: has no triangles");
  }
  if (!(weldEpsilon >= 0.0f) || !std::isfinite(weldEpsilon)) {
    return Status(ErrorCode::kInvalidArgument,
                  "weld epsilon " + std::to_string(weldEpsilon) + " is not a finite value >= 0");
  }
  if (mesh.positions.size() >= kEmpty) {
    return Status(ErrorCode::kResourceExhausted, "input mesh: too many vertices");
  }

  // Bounds of the referenced vertices only: stray unused points must not
  // change the weld distance.
  std::vector<std::uint8_t> referenced(mesh.positions.size(), 0);
  for (std::uint32_t v : mesh.indices) referenced[v] = 1;
  Bounds bounds;
  std::size_t referencedCount = 0;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (referenced[v]) {
      bounds.extend(mesh.positions[v]);
      ++referencedCount;
    }
  }
  const double diagonal = bounds.diagonal();
  if (!(diagonal > 0.0)) {
    return Status(ErrorCode::kInvalidArgument,
                  "input mesh: all " + std::to_string(mesh.triangleCount()) +
                      " triangles are degenerate (every vertex at one point)");
  }

  CleanMesh clean;
  const double epsilon = static_cast<double>(weldEpsilon) * diagonal;
  const double cellSize = std::max(epsilon * 16.0, diagonal * 1e-5);
  WeldGrid grid(bounds, cellSize, referencedCount);
  std::vector<std::uint32_t> weldedIndex(mesh.positions.size(), kEmpty);
  clean.positions.reserve(referencedCount);
  clean.sourceVertex.reserve(referencedCount);
  clean.positionGroup.reserve(referencedCount);
  std::uint32_t groupCount = 0;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!referenced[v]) continue;
    const glm::vec3& p = mesh.positions[v];
    std::uint32_t near = kEmpty;
    const bool keyed = !weldKeys.empty();
    std::uint32_t target =
        splitSeams || keyed
            ? grid.find(
                  p, epsilon, clean.positions,
                  [&](std::uint32_t c) {
                    const std::uint32_t source = clean.sourceVertex[c];
                    return (!keyed || weldKeys[source] == weldKeys[v]) &&
                           (!splitSeams ||
                            sameSeamAttributes(mesh, source, static_cast<std::uint32_t>(v)));
                  },
                  &near)
            : grid.find(p, epsilon, clean.positions, [](std::uint32_t) { return true; });
    if (target == kEmpty) {
      target = static_cast<std::uint32_t>(clean.positions.size());
      if (near != kEmpty) {
        // A seam: same place, other attributes. The new clean vertex takes
        // its sibling's position exactly, so the two sides stay together.
        clean.positions.push_back(clean.positions[near]);
        clean.positionGroup.push_back(clean.positionGroup[near]);
        ++clean.seamVertices;
      } else {
        clean.positions.push_back(p);
        clean.positionGroup.push_back(groupCount++);
      }
      clean.sourceVertex.push_back(static_cast<std::uint32_t>(v));
      grid.insert(clean.positions.back(), target);
    } else {
      ++clean.weldedVertices;
    }
    weldedIndex[v] = target;
  }

  TriangleSet seen(mesh.triangleCount());
  clean.indices.reserve(mesh.indices.size());
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const std::array<std::uint32_t, 3> tri = {weldedIndex[mesh.indices[t]],
                                              weldedIndex[mesh.indices[t + 1]],
                                              weldedIndex[mesh.indices[t + 2]]};
    const std::uint32_t g0 = clean.positionGroup[tri[0]], g1 = clean.positionGroup[tri[1]],
                        g2 = clean.positionGroup[tri[2]];
    if (g0 == g1 || g1 == g2 || g0 == g2) {  // repeated corner, or two corners at one place
      ++clean.droppedDegenerate;
      continue;
    }
    if (!seen.insert(tri)) {
      ++clean.droppedDuplicate;
      continue;
    }
    clean.indices.insert(clean.indices.end(), tri.begin(), tri.end());
  }
  if (clean.indices.empty()) {
    return Status(ErrorCode::kInvalidArgument,
                  "input mesh: all " + std::to_string(mesh.triangleCount()) +
                      " triangles are degenerate after welding vertices closer than " +
                      std::to_string(epsilon));
  }

  // Drop vertices only degenerate triangles used; keep the order otherwise.
  std::vector<std::uint32_t> compact(clean.positions.size(), kEmpty);
  for (std::uint32_t v : clean.indices) compact[v] = 0;
  std::uint32_t kept = 0;
  for (std::size_t v = 0; v < compact.size(); ++v) {
    if (compact[v] == kEmpty) continue;
    compact[v] = kept;
    clean.positions[kept] = clean.positions[v];
    clean.sourceVertex[kept] = clean.sourceVertex[v];
    clean.positionGroup[kept] = clean.positionGroup[v];
    ++kept;
  }
  clean.positions.resize(kept);
  clean.sourceVertex.resize(kept);
  clean.positionGroup.resize(kept);
  for (std::uint32_t& v : clean.indices) v = compact[v];
  sortSpatially(clean, bounds);
  return clean;
}

}  // namespace thinlod::simplifier::qem
