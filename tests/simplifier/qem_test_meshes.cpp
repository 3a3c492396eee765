#include "qem_test_meshes.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <random>

#include "test_meshes.h"  // tests/simplifier_error: shared test meshes
#include "thinlod/common/mesh/mesh_io.h"

namespace thinlod::qemtest {

IndexedMesh makeGrid(int cells) {
  IndexedMesh m;
  for (int y = 0; y <= cells; ++y) {
    for (int x = 0; x <= cells; ++x) {
      m.positions.push_back({static_cast<float>(x) / cells, static_cast<float>(y) / cells, 0.0f});
    }
  }
  const auto at = [cells](int x, int y) { return static_cast<std::uint32_t>(y * (cells + 1) + x); };
  for (int y = 0; y < cells; ++y) {
    for (int x = 0; x < cells; ++x) {
      m.indices.insert(m.indices.end(), {at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      m.indices.insert(m.indices.end(), {at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  }
  return m;
}

IndexedMesh makeIcosphere(int level, const glm::vec3& centre) {
  // The same subdivided icosahedron as the error tests' (one construction).
  IndexedMesh m = testing::makeIcosphere(level, 1.0f);
  for (glm::vec3& v : m.positions) v += centre;
  return m;
}

ChartedSphere makeChartedSphere(int chartsPerSide, int cellsPerChart, float bump) {
  ChartedSphere out;
  const int charts = 6 * chartsPerSide * chartsPerSide;
  out.atlasColumns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(charts))));
  const float cell = 1.0f / static_cast<float>(out.atlasColumns);
  out.padding = 0.1f * cell;
  static const glm::vec3 kNormal[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                       {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
  static const glm::vec3 kAxisA[6] = {{0, 0, -1}, {0, 0, 1}, {1, 0, 0},
                                      {1, 0, 0},  {1, 0, 0}, {-1, 0, 0}};
  IndexedMesh& mesh = out.mesh;
  const int n = chartsPerSide * cellsPerChart;  // quads per face side
  int chart = 0;
  for (int face = 0; face < 6; ++face) {
    const glm::vec3 normal = kNormal[face];
    const glm::vec3 a = kAxisA[face];
    const glm::vec3 b = glm::cross(normal, a);  // counter-clockwise seen from outside
    for (int cy = 0; cy < chartsPerSide; ++cy) {
      for (int cx = 0; cx < chartsPerSide; ++cx, ++chart) {
        const glm::vec2 origin(static_cast<float>(chart % out.atlasColumns) * cell + out.padding,
                               static_cast<float>(chart / out.atlasColumns) * cell + out.padding);
        const float island = cell - 2.0f * out.padding;
        const auto first = static_cast<std::uint32_t>(mesh.positions.size());
        for (int j = 0; j <= cellsPerChart; ++j) {
          for (int i = 0; i <= cellsPerChart; ++i) {
            // Face coordinates as (2k - n) / n: a point shared by two faces
            // whose coordinates run in opposite directions comes out as
            // exactly the negated value, so every chart computes it bit for bit.
            const float s = static_cast<float>(2 * (cx * cellsPerChart + i) - n) / n;
            const float t = static_cast<float>(2 * (cy * cellsPerChart + j) - n) / n;
            const glm::vec3 d = glm::normalize(normal + s * a + t * b);
            const float r = 1.0f + bump * std::sin(3.0f * d.x) * std::sin(4.0f * d.y + 1.0f) *
                                       std::sin(5.0f * d.z + 2.0f);
            mesh.positions.push_back(r * d);
            mesh.uvs.push_back(origin + island * glm::vec2(static_cast<float>(i) / cellsPerChart,
                                                           static_cast<float>(j) / cellsPerChart));
            out.chartOf.push_back(static_cast<std::uint32_t>(chart));
          }
        }
        const auto row = static_cast<std::uint32_t>(cellsPerChart + 1);
        for (int j = 0; j < cellsPerChart; ++j) {
          for (int i = 0; i < cellsPerChart; ++i) {
            const std::uint32_t v =
                first + static_cast<std::uint32_t>(j) * row + static_cast<std::uint32_t>(i);
            mesh.indices.insert(mesh.indices.end(),
                                {v, v + 1, v + row + 1, v, v + row + 1, v + row});
          }
        }
      }
    }
  }
  return out;
}

IndexedMesh makeBumpySphere(int level, float amplitude, std::uint32_t seed) {
  IndexedMesh m = makeIcosphere(level);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> bump(-amplitude, amplitude);
  for (glm::vec3& p : m.positions) p *= 1.0f + bump(rng);
  return m;
}

IndexedMesh concatenate(const IndexedMesh& a, const IndexedMesh& b) {
  IndexedMesh m = a;
  const auto offset = static_cast<std::uint32_t>(a.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (std::uint32_t i : b.indices) m.indices.push_back(i + offset);
  return m;
}

IndexedMesh unweld(const IndexedMesh& mesh) {
  IndexedMesh m;
  for (std::uint32_t i : mesh.indices) {
    m.indices.push_back(static_cast<std::uint32_t>(m.positions.size()));
    m.positions.push_back(mesh.positions[i]);
  }
  return m;
}

Result<IndexedMesh> loadSharedModel(const std::string& name) {
  Result<LoadedMesh> loaded = loadMeshFile(std::string(THINLOD_SHARED_DIR) + "/models/" + name);
  if (!loaded.ok()) return loaded.status();
  IndexedMesh m;
  m.positions = std::move(loaded->mesh.positions);
  m.indices = std::move(loaded->mesh.indices);
  return m;
}

std::map<Edge, int> edgeTriangleCounts(const IndexedMesh& mesh) {
  std::map<Edge, int> counts;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.indices[t + k], b = mesh.indices[t + (k + 1) % 3];
      ++counts[{std::min(a, b), std::max(a, b)}];
    }
  }
  return counts;
}

int countEdgesWithMoreThanTwoTriangles(const IndexedMesh& mesh) {
  int count = 0;
  for (const auto& [edge, triangles] : edgeTriangleCounts(mesh)) count += triangles > 2 ? 1 : 0;
  return count;
}

std::set<std::uint32_t> nonManifoldVertices(const IndexedMesh& mesh) {
  std::set<std::uint32_t> out;
  for (const auto& [edge, triangles] : edgeTriangleCounts(mesh)) {
    if (triangles > 2) out.insert({edge.first, edge.second});
  }
  // Fans: union the triangles around each vertex that share an edge at it.
  std::vector<std::vector<std::size_t>> around(mesh.vertexCount());
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (int k = 0; k < 3; ++k) around[mesh.indices[t + k]].push_back(t);
  }
  for (std::uint32_t v = 0; v < mesh.vertexCount(); ++v) {
    const std::vector<std::size_t>& fan = around[v];
    std::vector<std::size_t> group(fan.size());
    for (std::size_t i = 0; i < fan.size(); ++i) group[i] = i;
    const auto root = [&group](std::size_t i) {
      while (group[i] != i) i = group[i] = group[group[i]];
      return i;
    };
    for (std::size_t i = 0; i < fan.size(); ++i) {
      for (std::size_t j = i + 1; j < fan.size(); ++j) {
        int shared = 0;  // corners other than v in common
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) {
            const std::uint32_t x = mesh.indices[fan[i] + a];
            if (x != v && x == mesh.indices[fan[j] + b]) ++shared;
          }
        }
        if (shared > 0) group[root(i)] = root(j);
      }
    }
    std::set<std::size_t> roots;
    for (std::size_t i = 0; i < fan.size(); ++i) roots.insert(root(i));
    if (roots.size() > 1) out.insert(v);
  }
  return out;
}

std::set<std::uint32_t> borderVertices(const IndexedMesh& mesh) {
  std::set<std::uint32_t> border;
  for (const auto& [edge, triangles] : edgeTriangleCounts(mesh)) {
    if (triangles == 1) {
      border.insert(edge.first);
      border.insert(edge.second);
    }
  }
  return border;
}

std::multiset<PositionTriangle> positionTriangles(const IndexedMesh& mesh) {
  std::multiset<PositionTriangle> out;
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    PositionTriangle tri;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = mesh.positions[mesh.indices[t + k]];
      tri[k] = {p.x, p.y, p.z};
    }
    std::sort(tri.begin(), tri.end());
    out.insert(tri);
  }
  return out;
}

std::vector<std::uint32_t> matchVertices(const IndexedMesh& mesh, const IndexedMesh& reference) {
  std::map<std::array<float, 3>, std::uint32_t> byPosition;
  for (std::size_t v = 0; v < reference.positions.size(); ++v) {
    const glm::vec3& p = reference.positions[v];
    byPosition.emplace(std::array<float, 3>{p.x, p.y, p.z}, static_cast<std::uint32_t>(v));
  }
  std::vector<std::uint32_t> out;
  for (const glm::vec3& p : mesh.positions) {
    auto it = byPosition.find({p.x, p.y, p.z});
    out.push_back(it == byPosition.end() ? UINT32_MAX : it->second);
  }
  return out;
}

}  // namespace thinlod::qemtest
