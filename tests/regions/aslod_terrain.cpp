#include "aslod_terrain.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <unordered_map>

#include "thinlod/common/core/relative_accuracy.h"

namespace thinlod::aslodterrain {

using backbone::Plan;
using backbone::SceneNode;
using backbone::SceneNodeKind;
using backbone::SceneObject;
using backbone::SchedulingScene;
using backbone::Sphere;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::uint64_t planKey(const glm::vec3& p) {
  std::uint32_t x = 0, y = 0;
  std::memcpy(&x, &p.x, sizeof x);
  std::memcpy(&y, &p.y, sizeof y);
  return std::uint64_t{x} << 32 | y;
}

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32 | b) : (std::uint64_t{b} << 32 | a);
}

}  // namespace

double terrainHeight(double x, double y, double side) {
  return side * (0.08 * std::sin(6.1 * x) * std::cos(4.3 * y) +
                 0.03 * std::sin(17.0 * x + 3.0 * y) + 0.01 * std::cos(41.0 * y - 13.0 * x));
}

Terrain makeTerrain(int n, int cells, double side) {
  Terrain t;
  t.n = n;
  t.cells = cells;
  t.side = side;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = static_cast<double>(i) / (n - 1), y = static_cast<double>(j) / (n - 1);
      t.mesh.positions.push_back({static_cast<float>(side * x), static_cast<float>(side * y),
                                  static_cast<float>(terrainHeight(x, y, side))});
      const int ci = std::min(cells - 1, i * cells / (n - 1));
      const int cj = std::min(cells - 1, j * cells / (n - 1));
      t.labels.push_back(static_cast<std::uint32_t>(cj * cells + ci));
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * n + i), b = a + 1,
                 c = a + static_cast<std::uint32_t>(n), d = c + 1;
      t.mesh.indices.insert(t.mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return t;
}

Result<std::vector<RegionLeaf>> measureRegionLeaves(const simplifier::RegionMesh& regions,
                                                    const simplifier::MeshCurveOptions& options) {
  std::vector<RegionLeaf> leaves;
  for (std::size_t r = 0; r < regions.regionCount(); ++r) {
    Result<simplifier::MeshCurves> curves = simplifier::measureRegionCurves(regions, r, options);
    if (!curves.ok()) return curves.status();
    RegionLeaf leaf;
    leaf.curves = std::move(curves).value();
    const BoundingSphere s = referenceSphere(regions.extractRegion(r, regions.maxTriangles(r)));
    leaf.sphere = {glm::dvec3(s.center), static_cast<double>(s.radius)};
    leaves.push_back(std::move(leaf));
  }
  return leaves;
}

Result<SchedulingScene> regionScene(const std::vector<RegionLeaf>& leaves) {
  if (leaves.empty()) return Status(ErrorCode::kInvalidArgument, "regionScene: no regions");
  SchedulingScene scene;
  SceneNode root;
  root.kind = SceneNodeKind::kGroup;
  root.firstChild = 0;
  root.childCount = static_cast<std::uint32_t>(leaves.size());
  root.contentVersion = 1;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const RegionLeaf& l : leaves) {
    lo = glm::min(lo, l.sphere.center - l.sphere.radius);
    hi = glm::max(hi, l.sphere.center + l.sphere.radius);
  }
  root.bounds.center = 0.5 * (lo + hi);
  for (const RegionLeaf& l : leaves) {
    root.bounds.radius = std::max(
        root.bounds.radius, glm::length(l.sphere.center - root.bounds.center) + l.sphere.radius);
  }
  root.bounds.radius *= 1.0 + 1e-6;
  scene.nodes.push_back(root);
  for (std::size_t r = 0; r < leaves.size(); ++r) {
    backbone::RepresentationOption option;
    option.kind = backbone::OptionKind::kSimplifiedMesh;
    option.relativeTriangles = leaves[r].curves.triangles;
    option.relativeLinkBytes = option.relativeTriangles.affineResources(kBytesOverhead, kBytesPerTriangle);
    SceneObject object;
    object.firstOption = static_cast<std::uint32_t>(scene.options.size());
    object.optionCount = 1;
    object.externalId = r;
    scene.options.push_back(std::move(option));
    scene.objects.push_back(object);
    SceneNode leaf;
    leaf.kind = SceneNodeKind::kLeaf;
    leaf.bounds = leaves[r].sphere;
    leaf.object = static_cast<std::uint32_t>(r);
    leaf.contentVersion = 1;
    scene.nodes.push_back(leaf);
    scene.children.push_back(static_cast<std::uint32_t>(r + 1));
    scene.childRanges.push_back(ConicRange::everywhere());
  }
  backbone::updateSubtreeVersions(scene);
  THINLOD_RETURN_IF_ERROR(backbone::validateScene(scene));
  return scene;
}

void deliver(SchedulingScene& scene, const Plan& plan) {
  for (const backbone::Removal& r : plan.removals) {
    scene.options[r.option].atFrontend.present = false;
    ++scene.nodes[r.object + 1].contentVersion;
  }
  for (const backbone::RepresentationRequest& r : plan.requests) {
    const SceneObject& object = scene.objects[r.object];
    for (std::uint32_t k = 0; k < object.optionCount; ++k)
      scene.options[object.firstOption + k].atFrontend.present = false;
    backbone::RepresentationCopy& copy = scene.options[r.option].atFrontend;
    copy.present = true;
    copy.id = r.requestId;
    copy.relativeAccuracy = r.relativeAccuracy;
    copy.triangles = r.expectedTriangles;
    copy.encodedBytes = r.expectedBytes;
    copy.validity = ConicRange::everywhere();  // a mesh is valid from everywhere
    ++scene.nodes[r.object + 1].contentVersion;
  }
  backbone::updateSubtreeVersions(scene);
}

RegionLevels levelsOfPlan(std::size_t regionCount, const Plan& plan) {
  RegionLevels levels;
  levels.targets.assign(regionCount, 0);
  levels.rendered.assign(regionCount, false);
  for (const backbone::ObjectDecision& d : plan.decisions) {
    if (d.action == backbone::ObjectAction::kRemove || d.object >= regionCount) continue;
    levels.rendered[d.object] = true;
    levels.targets[d.object] = static_cast<std::size_t>(std::floor(std::max(0.0, d.triangles)));
  }
  return levels;
}

double sphereSolidAngle(double radius, double distanceToSurface) {
  const double x = radius / (std::max(0.0, distanceToSurface) + radius);
  return 2.0 * kPi * x * x / (1.0 + std::sqrt(std::max(0.0, 1.0 - x * x)));
}

CrackCheck checkCracks(const IndexedMesh& assembled, const simplifier::RegionMesh& regions) {
  CrackCheck c;
  const IndexedMesh& input = regions.mesh();
  c.trianglesPerRegion.assign(regions.regionCount(), 0);
  std::unordered_map<std::uint64_t, std::uint32_t> inputVertex;
  inputVertex.reserve(input.positions.size());
  glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (std::uint32_t v = 0; v < input.positions.size(); ++v) {
    inputVertex.emplace(planKey(input.positions[v]), v);
    lo = glm::min(lo, glm::dvec2(input.positions[v]));
    hi = glm::max(hi, glm::dvec2(input.positions[v]));
  }
  c.perimeter = 2.0 * ((hi.x - lo.x) + (hi.y - lo.y));
  c.domainArea = (hi.x - lo.x) * (hi.y - lo.y);
  // Region of every assembled vertex (through its input vertex).
  std::vector<std::uint32_t> regionOf(assembled.positions.size(), 0);
  for (std::size_t v = 0; v < assembled.positions.size(); ++v) {
    const auto it = inputVertex.find(planKey(assembled.positions[v]));
    if (it == inputVertex.end()) {
      ++c.unknownVertices;
      continue;
    }
    regionOf[v] = regions.regionOf(it->second);
  }
  c.triangles = assembled.triangleCount();
  std::vector<std::uint64_t> directed;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> undirected;  // edge, owner region
  directed.reserve(assembled.indices.size());
  undirected.reserve(assembled.indices.size());
  std::vector<bool> used(assembled.positions.size(), false);
  for (std::size_t t = 0; t + 2 < assembled.indices.size(); t += 3) {
    const std::uint32_t v[3] = {assembled.indices[t], assembled.indices[t + 1],
                                assembled.indices[t + 2]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++c.degenerateTriangles;
    const std::uint32_t owner =
        simplifier::triangleRegion(regionOf[v[0]], regionOf[v[1]], regionOf[v[2]]);
    ++c.trianglesPerRegion[owner];
    const glm::dvec2 a(assembled.positions[v[0]]), b(assembled.positions[v[1]]),
        d(assembled.positions[v[2]]);
    c.projectedArea += 0.5 * ((b.x - a.x) * (d.y - a.y) - (b.y - a.y) * (d.x - a.x));
    for (int k = 0; k < 3; ++k) {
      used[v[k]] = true;
      directed.push_back(std::uint64_t{v[k]} << 32 | v[(k + 1) % 3]);
      undirected.push_back({edgeKey(v[k], v[(k + 1) % 3]), owner});
    }
  }
  c.vertices = static_cast<std::size_t>(std::count(used.begin(), used.end(), true));
  std::sort(directed.begin(), directed.end());
  for (std::size_t i = 1; i < directed.size(); ++i)
    c.duplicateDirectedEdges += directed[i] == directed[i - 1];
  std::sort(undirected.begin(), undirected.end());
  auto side = [&](const glm::vec3& p) {  // bit mask of the border sides p lies on
    return (p.x == float(lo.x) ? 1u : 0u) | (p.x == float(hi.x) ? 2u : 0u) |
           (p.y == float(lo.y) ? 4u : 0u) | (p.y == float(hi.y) ? 8u : 0u);
  };
  std::vector<std::uint32_t> boundaryDegree(assembled.positions.size(), 0);
  std::vector<std::uint32_t> piece(assembled.positions.size());  // union-find over boundary edges
  for (std::uint32_t v = 0; v < piece.size(); ++v) piece[v] = v;
  auto find = [&](std::uint32_t v) {
    while (piece[v] != v) v = piece[v] = piece[piece[v]];
    return v;
  };
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i;
    while (j < undirected.size() && undirected[j].first == undirected[i].first) ++j;
    ++c.edges;
    const std::size_t count = j - i;
    const auto p = static_cast<std::uint32_t>(undirected[i].first >> 32);
    const auto q = static_cast<std::uint32_t>(undirected[i].first & 0xffffffffu);
    if (count == 1) {
      ++c.boundaryEdges;
      // In the xy plane: the border's heights vary, its plan length does not.
      c.boundaryLength +=
          glm::length(glm::dvec2(assembled.positions[p]) - glm::dvec2(assembled.positions[q]));
      ++boundaryDegree[p];
      ++boundaryDegree[q];
      piece[find(p)] = find(q);
      const std::uint32_t sp = side(assembled.positions[p]), sq = side(assembled.positions[q]);
      if (sp == 0 || sq == 0) {
        if (c.boundaryEdgesInside++ == 0) {
          c.insideExample[0] = assembled.positions[p];
          c.insideExample[1] = assembled.positions[q];
        }
      } else if ((sp & sq) == 0) {
        ++c.boundaryEdgesCuttingCorners;
      }
    } else if (count == 2) {
      c.regionBorderEdges += undirected[i].second != undirected[i + 1].second;
    } else {
      ++c.edgesOnMoreThanTwo;
    }
    i = j;
  }
  for (std::uint32_t v = 0; v < boundaryDegree.size(); ++v) {
    if (boundaryDegree[v] == 0) continue;
    c.boundaryVerticesNotOnTwo += boundaryDegree[v] != 2;
    c.boundaryLoops += find(v) == v;
  }
  c.euler = static_cast<long long>(c.vertices) - static_cast<long long>(c.edges) +
            static_cast<long long>(c.triangles);
  return c;
}

}  // namespace thinlod::aslodterrain
