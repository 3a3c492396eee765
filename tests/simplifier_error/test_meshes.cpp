#include "test_meshes.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <glm/geometric.hpp>
#include <map>
#include <sstream>
#include <utility>

namespace thinlod::testing {

IndexedMesh makeGrid(int cells, float size, float height) {
  IndexedMesh mesh;
  const int n = cells + 1;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      mesh.positions.emplace_back(size * x / cells, size * y / cells, height);
    }
  }
  for (int y = 0; y < cells; ++y) {
    for (int x = 0; x < cells; ++x) {
      const std::uint32_t v = static_cast<std::uint32_t>(y * n + x);
      mesh.indices.insert(mesh.indices.end(), {v, v + 1, v + n + 1, v, v + n + 1, v + n});
    }
  }
  return mesh;
}

IndexedMesh makeIcosphere(int level, float radius) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                              {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                              {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::uint32_t> f = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                  1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                  3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                  4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};
  for (glm::vec3& v : p) v = glm::normalize(v);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      p.push_back(glm::normalize(p[a] + p[b]));
      const std::uint32_t idx = static_cast<std::uint32_t>(p.size() - 1);
      midpoint.emplace(key, idx);
      return idx;
    };
    std::vector<std::uint32_t> next;
    for (std::size_t i = 0; i < f.size(); i += 3) {
      const std::uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(next);
  }
  IndexedMesh mesh;
  for (const glm::vec3& v : p) mesh.positions.push_back(v * radius);
  mesh.indices = f;
  return mesh;
}

double maxSagitta(const IndexedMesh& sphere, float radius) {
  double worst = 0.0;
  for (std::size_t i = 0; i < sphere.indices.size(); i += 3) {
    const glm::dvec3 a(sphere.positions[sphere.indices[i]]);
    const glm::dvec3 b(sphere.positions[sphere.indices[i + 1]]);
    const glm::dvec3 c(sphere.positions[sphere.indices[i + 2]]);
    const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
    // Icosphere faces are acute, so the foot of the perpendicular from the
    // centre (the circumcentre) lies inside the face.
    worst = std::max(worst, radius - std::abs(glm::dot(n, a)));
  }
  return worst;
}

std::string sharedModelPath(const std::string& name) {
  return std::string(THINLOD_SHARED_DIR) + "/models/" + name;
}

Result<IndexedMesh> readObjPositions(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Status(ErrorCode::kNotFound, path + ": cannot open");
  IndexedMesh mesh;
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    std::istringstream fields(line);
    std::string tag;
    fields >> tag;
    if (tag == "v") {
      glm::vec3 v;
      if (!(fields >> v.x >> v.y >> v.z)) {
        return Status(ErrorCode::kParseError, path + ":" + std::to_string(lineNumber) + ": bad v");
      }
      mesh.positions.push_back(v);
    } else if (tag == "f") {
      std::vector<std::uint32_t> polygon;
      std::string ref;
      while (fields >> ref) {
        const long index = std::stol(ref.substr(0, ref.find('/')));
        const long resolved =
            index > 0 ? index - 1 : static_cast<long>(mesh.positions.size()) + index;
        if (resolved < 0) {
          return Status(ErrorCode::kParseError,
                        path + ":" + std::to_string(lineNumber) + ": bad f");
        }
        polygon.push_back(static_cast<std::uint32_t>(resolved));
      }
      for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        mesh.indices.insert(mesh.indices.end(), {polygon[0], polygon[k], polygon[k + 1]});
      }
    }
  }
  THINLOD_RETURN_IF_ERROR(mesh.validate(path));
  return mesh;
}

IndexedMesh simplifyWithMeshoptimizer(const IndexedMesh& mesh, std::size_t targetTriangles) {
  IndexedMesh out;
  out.positions = mesh.positions;
  out.indices.resize(mesh.indices.size());
  float resultError = 0.0f;
  const std::size_t count = meshopt_simplify(
      out.indices.data(), mesh.indices.data(), mesh.indices.size(), &mesh.positions[0].x,
      mesh.positions.size(), sizeof(glm::vec3), targetTriangles * 3, 1.0f, 0, &resultError);
  out.indices.resize(count);
  return out;
}

}  // namespace thinlod::testing
