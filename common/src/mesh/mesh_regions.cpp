#include "thinlod/common/mesh/mesh_regions.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <string>
#include <unordered_map>

namespace thinlod {
namespace {

void bisect(const std::vector<glm::vec3>& positions, std::uint32_t* begin, std::uint32_t* end,
            std::uint32_t firstLabel, std::size_t regions, std::vector<std::uint32_t>& labels) {
  if (regions == 1) {
    for (std::uint32_t* it = begin; it != end; ++it) labels[*it] = firstLabel;
    return;
  }
  Bounds bounds;
  for (std::uint32_t* it = begin; it != end; ++it) bounds.extend(positions[*it]);
  const glm::vec3 extent = bounds.max - bounds.min;
  int axis = 0;
  if (extent.y > extent[axis]) axis = 1;
  if (extent.z > extent[axis]) axis = 2;
  const std::size_t count = static_cast<std::size_t>(end - begin);
  const std::size_t leftRegions = (regions + 1) / 2;
  // count >= regions, so both sides keep at least one vertex per region.
  const std::size_t leftCount = count * leftRegions / regions;
  std::uint32_t* middle = begin + leftCount;
  std::nth_element(begin, middle, end, [&](std::uint32_t a, std::uint32_t b) {
    const float pa = positions[a][axis], pb = positions[b][axis];
    return pa < pb || (pa == pb && a < b);
  });
  bisect(positions, begin, middle, firstLabel, leftRegions, labels);
  bisect(positions, middle, end, firstLabel + static_cast<std::uint32_t>(leftRegions),
         regions - leftRegions, labels);
}

struct PositionKey {
  std::uint32_t x, y, z;
  bool operator==(const PositionKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PositionHash {
  std::size_t operator()(const PositionKey& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint32_t v : {k.x, k.y, k.z}) h = (h ^ v) * 1099511628211ull;
    return static_cast<std::size_t>(h);
  }
};
PositionKey keyOf(const glm::vec3& p) {
  // +0 and -0 are one place.
  const glm::vec3 q(p.x == 0.0f ? 0.0f : p.x, p.y == 0.0f ? 0.0f : p.y, p.z == 0.0f ? 0.0f : p.z);
  PositionKey k{};
  std::memcpy(&k.x, &q.x, 4);
  std::memcpy(&k.y, &q.y, 4);
  std::memcpy(&k.z, &q.z, 4);
  return k;
}

// Per vertex, the first vertex at the same exact position.
std::vector<std::uint32_t> positionClasses(const std::vector<glm::vec3>& positions) {
  std::unordered_map<PositionKey, std::uint32_t, PositionHash> first;
  first.reserve(positions.size());
  std::vector<std::uint32_t> cls(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    cls[v] = first.emplace(keyOf(positions[v]), static_cast<std::uint32_t>(v)).first->second;
  }
  return cls;
}

template <typename T>
void gatherInto(const std::vector<T>& values, const std::vector<std::uint32_t>& source,
                std::vector<T>& out) {
  out.clear();
  if (values.empty()) return;
  out.reserve(source.size());
  for (std::uint32_t s : source) out.push_back(values[s]);
}

}  // namespace

std::uint32_t triangleRegion(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a == b || a == c) return a;
  if (b == c) return b;
  return std::min({a, b, c});
}

Result<std::vector<std::uint32_t>> partitionVertices(const std::vector<glm::vec3>& positions,
                                                     std::size_t regionCount) {
  if (regionCount == 0) {
    return Status(ErrorCode::kInvalidArgument, "partition: region count must be >= 1");
  }
  if (regionCount > positions.size()) {
    return Status(ErrorCode::kInvalidArgument, "partition: " + std::to_string(regionCount) +
                                                   " regions for " +
                                                   std::to_string(positions.size()) +
                                                   " vertices (at most one region per vertex)");
  }
  if (positions.size() >= 0xffffffffu) {
    return Status(ErrorCode::kResourceExhausted, "partition: too many vertices");
  }
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const glm::vec3& p = positions[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return Status(ErrorCode::kInvalidArgument,
                    "partition: vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  std::vector<std::uint32_t> order(positions.size());
  std::iota(order.begin(), order.end(), 0u);
  std::vector<std::uint32_t> labels(positions.size(), 0);
  bisect(positions, order.data(), order.data() + order.size(), 0, regionCount, labels);
  return labels;
}

Result<std::vector<MeshRegion>> splitMeshIntoRegions(const IndexedMesh& mesh,
                                                     std::size_t regionCount) {
  THINLOD_RETURN_IF_ERROR(mesh.validate("regions"));
  // Partition the distinct referenced positions (one representative each).
  const std::vector<std::uint32_t> cls = positionClasses(mesh.positions);
  std::vector<std::uint32_t> placeOf(mesh.positions.size(), 0xffffffffu);
  std::vector<glm::vec3> places;
  for (std::uint32_t index : mesh.indices) {
    const std::uint32_t c = cls[index];
    if (placeOf[c] == 0xffffffffu) {
      placeOf[c] = static_cast<std::uint32_t>(places.size());
      places.push_back(mesh.positions[c]);
    }
  }
  if (regionCount > places.size()) {
    return Status(ErrorCode::kInvalidArgument,
                  "regions " + std::to_string(regionCount) + ": the mesh has only " +
                      std::to_string(places.size()) + " distinct vertices");
  }
  Result<std::vector<std::uint32_t>> labels = partitionVertices(places, regionCount);
  if (!labels.ok()) return labels.status();
  auto labelOf = [&](std::uint32_t v) { return (*labels)[placeOf[cls[v]]]; };

  // Triangles by owner, input order kept within a region.
  std::vector<std::vector<std::uint32_t>> owned(regionCount);
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const std::uint32_t* v = &mesh.indices[3 * t];
    owned[triangleRegion(labelOf(v[0]), labelOf(v[1]), labelOf(v[2]))].push_back(
        static_cast<std::uint32_t>(t));
  }
  std::vector<MeshRegion> regions(regionCount);
  std::vector<std::uint32_t> local(mesh.positions.size(), 0);
  std::vector<std::uint32_t> stamp(mesh.positions.size(), 0xffffffffu);  // region of `local`
  for (std::size_t r = 0; r < regionCount; ++r) {
    MeshRegion& region = regions[r];
    region.mesh.indices.reserve(3 * owned[r].size());
    for (std::uint32_t t : owned[r]) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = mesh.indices[3 * t + k];
        if (stamp[v] != r) {
          stamp[v] = static_cast<std::uint32_t>(r);
          local[v] = static_cast<std::uint32_t>(region.sourceVertex.size());
          region.sourceVertex.push_back(v);
        }
        region.mesh.indices.push_back(local[v]);
      }
    }
  }
  for (std::size_t r = 0; r < regionCount; ++r) {
    MeshRegion& region = regions[r];
    if (region.mesh.indices.empty()) {
      return Status(ErrorCode::kInvalidArgument, "regions " + std::to_string(regionCount) +
                                                     ": region " + std::to_string(r) +
                                                     " owns no triangle (use fewer regions)");
    }
    gatherInto(mesh.positions, region.sourceVertex, region.mesh.positions);
    gatherInto(mesh.normals, region.sourceVertex, region.mesh.normals);
    gatherInto(mesh.uvs, region.sourceVertex, region.mesh.uvs);
    gatherInto(mesh.colors, region.sourceVertex, region.mesh.colors);
  }
  return regions;
}

std::vector<bool> openBoundaryVertices(const IndexedMesh& mesh) {
  const std::vector<std::uint32_t> cls = positionClasses(mesh.positions);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> uses;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t a = cls[mesh.indices[3 * t + k]];
      std::uint32_t b = cls[mesh.indices[3 * t + (k + 1) % 3]];
      if (a == b) continue;  // degenerate edge
      if (a > b) std::swap(a, b);
      ++uses[{a, b}];
    }
  }
  std::vector<bool> boundaryPlace(mesh.positions.size(), false);
  for (const auto& [edge, count] : uses) {
    if (count == 1) boundaryPlace[edge.first] = boundaryPlace[edge.second] = true;
  }
  std::vector<bool> out(mesh.positions.size(), false);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) out[v] = boundaryPlace[cls[v]];
  return out;
}

}  // namespace thinlod
