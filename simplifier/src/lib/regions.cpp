// Regions (regions.h): partition, per-region progressive meshes under the
// border rule, the foreign-vertex lookup and the assembly of one frame.
//
// Why the border rule is enough (docs/regions.md has the long form): a
// region's collapse u -> w reads and changes only the triangles around u,
// and its validity (link condition, duplicate and flip checks) reads the
// neighbour sets of u and w. Under the rule, a vertex that may move has no
// neighbour in a region with a lower id, and each of its neighbours in a
// higher region is kept there. So (1) no triangle holds movable vertices of
// two regions, and (2) a movable vertex of the non-owner side of a border has
// no neighbour on the owner side at all: the owner's collapses never add or
// remove a neighbour of it. Both facts survive every collapse (a collapse
// gives w the neighbours of u, which are w's region or kept foreign
// vertices), hence no region's collapse sees another region's level, and
// every combination of levels is a valid sequence of collapses of the whole
// mesh. The paper's rule (both sides collapse along the border) lacks (2): a
// counterexample (a fold between two independently valid collapses) is in
// docs/regions.md.
#include "thinlod/simplifier/regions.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>
#include <string>

#include "qem_cleanup.h"

namespace thinlod::simplifier {
namespace {

constexpr std::uint32_t kUnmapped = 0xffffffffu;

template <typename T>
std::vector<T> gather(const std::vector<T>& values, const std::vector<std::uint32_t>& source) {
  std::vector<T> out;
  if (values.empty()) return out;
  out.reserve(source.size());
  for (std::uint32_t s : source) out.push_back(values[s]);
  return out;
}

Result<IndexedMesh> cleanedMesh(const IndexedMesh& mesh, const RegionBuildOptions& options,
                                std::vector<std::uint32_t>* sourceVertex) {
  Result<qem::CleanMesh> cleaned = qem::cleanMesh(mesh, options.mesh.weldEpsilon);
  if (!cleaned.ok()) return cleaned.status();
  qem::CleanMesh& clean = cleaned.value();
  IndexedMesh out;
  out.positions = std::move(clean.positions);
  out.normals = gather(mesh.normals, clean.sourceVertex);
  out.uvs = gather(mesh.uvs, clean.sourceVertex);
  out.colors = gather(mesh.colors, clean.sourceVertex);
  out.indices = std::move(clean.indices);
  *sourceVertex = std::move(clean.sourceVertex);
  return out;
}

}  // namespace

// triangleRegion and partitionVertices live in common/mesh/mesh_regions.h
// (the scene splits region objects with them too).

Result<RegionMesh> RegionMesh::build(const IndexedMesh& mesh,
                                     const std::vector<std::uint32_t>& labels,
                                     std::size_t regionCount, const RegionBuildOptions& options) {
  if (labels.size() != mesh.positions.size()) {
    return Status(ErrorCode::kInvalidArgument,
                  "regions: " + std::to_string(labels.size()) + " labels for " +
                      std::to_string(mesh.positions.size()) + " vertices");
  }
  std::vector<std::uint32_t> source;
  Result<IndexedMesh> clean = cleanedMesh(mesh, options, &source);
  if (!clean.ok()) return clean.status();
  std::vector<std::uint32_t> cleanLabels;
  cleanLabels.reserve(source.size());
  for (std::uint32_t s : source) cleanLabels.push_back(labels[s]);
  return buildClean(std::move(clean.value()), std::move(cleanLabels), regionCount, options);
}

Result<RegionMesh> RegionMesh::buildPartitioned(const IndexedMesh& mesh, std::size_t regionCount,
                                                const RegionBuildOptions& options) {
  std::vector<std::uint32_t> source;
  Result<IndexedMesh> clean = cleanedMesh(mesh, options, &source);
  if (!clean.ok()) return clean.status();
  Result<std::vector<std::uint32_t>> labels = partitionVertices(clean->positions, regionCount);
  if (!labels.ok()) return labels.status();
  return buildClean(std::move(clean.value()), std::move(labels.value()), regionCount, options);
}

Result<RegionMesh> RegionMesh::buildClean(IndexedMesh clean, std::vector<std::uint32_t> labels,
                                          std::size_t regionCount,
                                          const RegionBuildOptions& options) {
  if (!options.mesh.vertexConstraints.empty() || options.mesh.stopAtTriangles != 0) {
    return Status(ErrorCode::kInvalidArgument,
                  "regions: vertexConstraints and stopAtTriangles are set by the region builder");
  }
  if (regionCount == 0) {
    return Status(ErrorCode::kInvalidArgument, "regions: region count must be >= 1");
  }
  const std::size_t vertexCount = clean.positions.size();
  if (regionCount > vertexCount) {
    return Status(ErrorCode::kInvalidArgument, "regions: " + std::to_string(regionCount) +
                                                   " regions for " + std::to_string(vertexCount) +
                                                   " vertices after cleanup");
  }
  std::vector<std::size_t> verticesPerRegion(regionCount, 0);
  for (std::size_t v = 0; v < vertexCount; ++v) {
    if (labels[v] >= regionCount) {
      return Status(ErrorCode::kInvalidArgument, "regions: vertex " + std::to_string(v) +
                                                     " has label " + std::to_string(labels[v]) +
                                                     ", not below the region count " +
                                                     std::to_string(regionCount));
    }
    ++verticesPerRegion[labels[v]];
  }
  for (std::size_t r = 0; r < regionCount; ++r) {
    if (verticesPerRegion[r] == 0) {
      return Status(ErrorCode::kInvalidArgument,
                    "regions: region " + std::to_string(r) + " has no vertex after cleanup");
    }
  }

  // Kept vertices: per pair of corners in different regions, the higher
  // region's corner (both, or none, under the other rules).
  const std::size_t triangleCount = clean.indices.size() / 3;
  std::vector<std::uint8_t> kept(vertexCount, 0);
  for (std::size_t t = 0; t < triangleCount; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = clean.indices[3 * t + k];
      const std::uint32_t b = clean.indices[3 * t + (k + 1) % 3];
      if (labels[a] == labels[b]) continue;
      switch (options.borderRule) {
        case BorderRule::kLowerIdSide:
          kept[labels[a] > labels[b] ? a : b] = 1;
          break;
        case BorderRule::kBothSidesKept:
          kept[a] = kept[b] = 1;
          break;
        case BorderRule::kPaperUnchecked:
          break;
      }
    }
  }

  // Each region's triangles: every triangle with a corner in it.
  std::vector<std::vector<std::uint32_t>> trianglesOf(regionCount);
  for (std::size_t t = 0; t < triangleCount; ++t) {
    const std::uint32_t* c = &clean.indices[3 * t];
    const std::uint32_t ra = labels[c[0]], rb = labels[c[1]], rc = labels[c[2]];
    trianglesOf[ra].push_back(static_cast<std::uint32_t>(t));
    if (rb != ra) trianglesOf[rb].push_back(static_cast<std::uint32_t>(t));
    if (rc != ra && rc != rb) trianglesOf[rc].push_back(static_cast<std::uint32_t>(t));
  }

  RegionMesh out;
  out.regions_.resize(regionCount);
  out.tomOfVertex_.assign(vertexCount, kUnmapped);
  std::vector<std::uint32_t> localOf(vertexCount, kUnmapped);
  for (std::size_t r = 0; r < regionCount; ++r) {
    Region& region = out.regions_[r];
    IndexedMesh sub;
    std::vector<std::uint32_t> globalOf;
    BuildOptions buildOptions = options.mesh;
    buildOptions.weldEpsilon = 0.0f;  // the whole mesh is welded already
    buildOptions.progress = {};
    for (std::uint32_t t : trianglesOf[r]) {
      const std::uint32_t* c = &clean.indices[3 * t];
      if (triangleRegion(labels[c[0]], labels[c[1]], labels[c[2]]) != r) ++region.foreignOwned;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t g = c[k];
        if (localOf[g] == kUnmapped) {
          localOf[g] = static_cast<std::uint32_t>(globalOf.size());
          globalOf.push_back(g);
          VertexConstraint constraint = VertexConstraint::kFree;
          if (labels[g] != r) {
            constraint = VertexConstraint::kPin;
          } else if (kept[g]) {
            constraint = VertexConstraint::kKeep;
            ++region.keptVertices;
          }
          buildOptions.vertexConstraints.push_back(constraint);
        }
        sub.indices.push_back(localOf[g]);
      }
    }
    sub.positions = gather(clean.positions, globalOf);
    if (buildOptions.attributeWeight > 0.0f) {  // attribute quadrics read them
      sub.uvs = gather(clean.uvs, globalOf);
      sub.colors = gather(clean.colors, globalOf);
    }
    Result<ProgressiveMesh> pm = ProgressiveMesh::build(sub, buildOptions);
    if (!pm.ok()) {
      return Status(pm.status().code(),
                    "regions: region " + std::to_string(r) + ": " + pm.status().message());
    }
    region.pm = std::move(pm.value());
    if (region.pm.vertexCount() != globalOf.size() ||
        region.pm.maxTriangles() != trianglesOf[r].size()) {
      return Status(ErrorCode::kInternal, "regions: region " + std::to_string(r) +
                                              ": the progressive mesh changed the cleaned input");
    }
    region.vertexOfTom.resize(globalOf.size());
    region.ownRank.assign(globalOf.size() + 1, 0);
    for (std::uint32_t tom = 0; tom < globalOf.size(); ++tom) {
      const std::uint32_t g = globalOf[region.pm.sourceVertexOf(tom)];
      region.vertexOfTom[tom] = g;
      region.ownRank[tom + 1] = region.ownRank[tom] + (labels[g] == r ? 1 : 0);
      if (labels[g] == r) out.tomOfVertex_[g] = tom;
    }
    for (std::uint32_t g : globalOf) localOf[g] = kUnmapped;
  }
  for (std::size_t r = 0; r < regionCount; ++r) {
    Region& region = out.regions_[r];
    region.corners.resize(region.vertexOfTom.size());
    for (std::size_t tom = 0; tom < region.vertexOfTom.size(); ++tom) {
      const std::uint32_t g = region.vertexOfTom[tom];
      region.corners[tom] = {labels[g], labels[g] == r ? region.ownRank[tom] : out.tomOfVertex_[g]};
    }
  }
  out.mesh_ = std::move(clean);
  out.regionOfVertex_ = std::move(labels);
  return out;
}

std::size_t RegionMesh::maxTriangles(std::size_t r) const {
  return regions_[r].pm.maxTriangles() - regions_[r].foreignOwned;
}

std::size_t RegionMesh::minTriangles(std::size_t r) const {
  return regions_[r].pm.minTriangles() - regions_[r].foreignOwned;
}

std::size_t RegionMesh::pmTarget(std::size_t r, std::size_t targetTriangles) const {
  // Other regions' triangles in region r's progressive mesh are never
  // removed (a collapse removes triangles with two corners of the region),
  // so owned = pm triangles - foreignOwned at every level.
  const Region& region = regions_[r];
  if (targetTriangles >= maxTriangles(r)) return region.pm.maxTriangles();
  return targetTriangles + region.foreignOwned;
}

std::size_t RegionMesh::triangleCountAt(std::size_t r, std::size_t targetTriangles) const {
  return regions_[r].pm.triangleCountAt(pmTarget(r, targetTriangles)) - regions_[r].foreignOwned;
}

std::uint32_t RegionMesh::lookupForeign(std::uint32_t vertex, std::size_t targetTriangles) const {
  const Region& region = regions_[regionOfVertex_[vertex]];
  const std::size_t live =
      region.pm.vertexCountAt(pmTarget(regionOfVertex_[vertex], targetTriangles));
  const std::uint32_t rep = region.pm.representative(tomOfVertex_[vertex], live);
  // A vertex on another region's triangle keeps a triangle in its own
  // region's mesh (that triangle is never removed there), so it always has
  // a representative.
  assert(rep != ProgressiveMesh::kNoRepresentative);
  return rep == ProgressiveMesh::kNoRepresentative ? vertex : region.vertexOfTom[rep];
}

void RegionMesh::compactInto(const std::vector<std::uint32_t>& indices, IndexedMesh& out) const {
  std::vector<std::uint32_t> outIndex(mesh_.positions.size(), kUnmapped);
  out.positions.clear();
  out.normals.clear();
  out.uvs.clear();
  out.colors.clear();
  out.indices.resize(indices.size());
  for (std::size_t i = 0; i < indices.size(); ++i) {
    const std::uint32_t g = indices[i];
    if (outIndex[g] == kUnmapped) {
      outIndex[g] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(mesh_.positions[g]);
      if (!mesh_.normals.empty()) out.normals.push_back(mesh_.normals[g]);
      if (!mesh_.uvs.empty()) out.uvs.push_back(mesh_.uvs[g]);
      if (!mesh_.colors.empty()) out.colors.push_back(mesh_.colors[g]);
    }
    out.indices[i] = outIndex[g];
  }
}

Result<IndexedMesh> RegionMesh::assemble(const std::vector<std::size_t>& targets,
                                         AssembleStats* stats) const {
  IndexedMesh out;
  THINLOD_RETURN_IF_ERROR(assembleInto(targets, out, stats));
  return out;
}

Status RegionMesh::assembleInto(const std::vector<std::size_t>& targets, IndexedMesh& out,
                                AssembleStats* stats) const {
  if (targets.size() != regions_.size()) {
    return Status(ErrorCode::kInvalidArgument, "regions: " + std::to_string(targets.size()) +
                                                   " levels for " +
                                                   std::to_string(regions_.size()) + " regions");
  }
  // Output vertices: region by region, the own vertices of each live prefix
  // in TOM order, so a vertex's output index is offset[s] + ownRank[tom]
  // without a vertex-sized remap table.
  const std::size_t regionCount = regions_.size();
  std::vector<std::size_t> pmTargets(regionCount), live(regionCount);
  std::vector<std::uint32_t> offset(regionCount + 1, 0);
  for (std::size_t r = 0; r < regionCount; ++r) {
    pmTargets[r] = pmTarget(r, targets[r]);
    live[r] = regions_[r].pm.vertexCountAt(pmTargets[r]);
    offset[r + 1] = offset[r] + regions_[r].ownRank[live[r]];
  }
  out.positions.clear();
  out.normals.clear();
  out.uvs.clear();
  out.colors.clear();
  out.positions.reserve(offset[regionCount]);
  std::size_t corners = 0;
  for (std::size_t r = 0; r < regionCount; ++r) {
    const Region& region = regions_[r];
    corners += 3 * region.pm.triangleCountAt(pmTargets[r]);
    for (std::size_t tom = 0; tom < live[r]; ++tom) {
      if (region.corners[tom].region != r) continue;
      const std::uint32_t g = region.vertexOfTom[tom];
      out.positions.push_back(mesh_.positions[g]);
      if (!mesh_.normals.empty()) out.normals.push_back(mesh_.normals[g]);
      if (!mesh_.uvs.empty()) out.uvs.push_back(mesh_.uvs[g]);
      if (!mesh_.colors.empty()) out.colors.push_back(mesh_.colors[g]);
    }
  }
  out.indices.resize(corners);  // an upper bound: foreign-owned triangles are dropped
  std::uint32_t* write = out.indices.data();
  IndexedMesh scratch;
  std::size_t lookups = 0, moved = 0, dropped = 0;
  for (std::size_t r = 0; r < regionCount; ++r) {
    const Region& region = regions_[r];
    region.pm.extractInto(pmTargets[r], scratch);
    const std::uint32_t self = static_cast<std::uint32_t>(r);
    const std::uint32_t base = offset[r];
    const Region::Corner* info = region.corners.data();
    const std::uint32_t* corner = scratch.indices.data();
    for (std::size_t i = 0; i < scratch.indices.size(); i += 3) {
      const Region::Corner c[3] = {info[corner[i]], info[corner[i + 1]], info[corner[i + 2]]};
      if (triangleRegion(c[0].region, c[1].region, c[2].region) != self) {
        ++dropped;
        continue;
      }
      for (const Region::Corner& k : c) {
        if (k.region == self) {
          *write++ = base + k.index;
          continue;
        }
        // The crack-free lookup: the foreign corner's representative in
        // its own region's current level.
        const Region& other = regions_[k.region];
        const std::uint32_t rep = other.pm.representative(k.index, live[k.region]);
        assert(rep != ProgressiveMesh::kNoRepresentative);
        const std::uint32_t mapped = rep == ProgressiveMesh::kNoRepresentative ? k.index : rep;
        ++lookups;
        moved += mapped != k.index ? 1 : 0;
        *write++ = offset[k.region] + other.ownRank[mapped];
      }
    }
  }
  out.indices.resize(static_cast<std::size_t>(write - out.indices.data()));
  if (stats) {
    stats->foreignLookups += lookups;
    stats->lookupsThatMoved += moved;
    stats->droppedForeignOwned += dropped;
  }
  return Status::okStatus();
}

IndexedMesh RegionMesh::extractRegion(std::size_t r, std::size_t targetTriangles) const {
  // One region with its foreign corners at full resolution: the pinned
  // foreign vertices are live in its own mesh, so no lookup is needed.
  IndexedMesh scratch, out;
  const Region& region = regions_[r];
  region.pm.extractInto(pmTarget(r, targetTriangles), scratch);
  std::vector<std::uint32_t> indices;
  indices.reserve(scratch.indices.size());
  const std::uint32_t self = static_cast<std::uint32_t>(r);
  for (std::size_t i = 0; i < scratch.indices.size(); i += 3) {
    const std::uint32_t* c = &scratch.indices[i];
    if (triangleRegion(region.corners[c[0]].region, region.corners[c[1]].region,
                       region.corners[c[2]].region) != self) {
      continue;
    }
    for (int k = 0; k < 3; ++k) indices.push_back(region.vertexOfTom[c[k]]);
  }
  compactInto(indices, out);
  return out;
}

std::size_t RegionMesh::memoryBytes() const {
  std::size_t bytes = regionOfVertex_.capacity() * sizeof(std::uint32_t) +
                      tomOfVertex_.capacity() * sizeof(std::uint32_t) +
                      mesh_.positions.capacity() * sizeof(glm::vec3) +
                      mesh_.normals.capacity() * sizeof(glm::vec3) +
                      mesh_.uvs.capacity() * sizeof(glm::vec2) + mesh_.colors.capacity() * 4 +
                      mesh_.indices.capacity() * sizeof(std::uint32_t);
  for (const Region& region : regions_) {
    bytes += region.pm.memoryBytes() +
             (region.vertexOfTom.capacity() + region.ownRank.capacity()) * sizeof(std::uint32_t) +
             region.corners.capacity() * sizeof(Region::Corner);
  }
  return bytes;
}

Result<MeshCurves> measureRegionCurves(const RegionMesh& regions, std::size_t r,
                                       const MeshCurveOptions& options) {
  if (r >= regions.regionCount()) {
    return Status(ErrorCode::kInvalidArgument, "regions: no region " + std::to_string(r));
  }
  if (regions.maxTriangles(r) == 0) {
    return Status(ErrorCode::kInvalidArgument,
                  "regions: region " + std::to_string(r) + " owns no triangle (no curve)");
  }
  const IndexedMesh original = regions.extractRegion(r, regions.maxTriangles(r));
  // The ladder starts at the region's fewest owned triangles above zero. A
  // region can collapse to owning none (kPaperUnchecked: its neighbours'
  // border triangles cover it); a ladder from 1 then extracted an empty mesh
  // and the measurement failed. triangleCountAt(t) is 0 exactly while no
  // state owns 1..t triangles, so the first t with a count is that count.
  std::size_t lowest = std::max<std::size_t>(1, regions.minTriangles(r));
  while (lowest < regions.maxTriangles(r) && regions.triangleCountAt(r, lowest) == 0) ++lowest;
  return measureMeshCurves(
      original, lowest, regions.maxTriangles(r),
      [&regions, r](std::size_t n) { return regions.extractRegion(r, n); }, options);
}

}  // namespace thinlod::simplifier
