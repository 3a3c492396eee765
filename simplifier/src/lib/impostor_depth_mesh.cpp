// Depth mesh of a meshed impostor: a regular grid over the covered pixels of
// the z-buffer, unprojected to object space, with triangles split wherever
// the depth jumps (so no "rubber sheet" joins a foreground part to what lies
// behind it).
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>
#include <limits>
#include <string>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

struct Node {
  int px = 0;  // pixel the node sits on (after snapping), top-down rows
  int py = 0;
  bool valid = false;
  float eyeDepth = 0.0f;  // along framing.forward, metres
  glm::vec3 position{0.0f};
  std::uint32_t vertex = kNoVertex;
};

}  // namespace

Result<IndexedMesh> buildDepthMesh(const std::vector<float>& depth, const ImpostorFraming& framing,
                                   const MeshedImpostorOptions& options, DepthMeshStats* stats) {
  const int n = framing.textureSize;
  if (n < 2 || depth.size() != static_cast<std::size_t>(n) * n) {
    return Status(ErrorCode::kInvalidArgument, "depth mesh: " + std::to_string(depth.size()) +
                                                   " depth values for a " + std::to_string(n) +
                                                   "x" + std::to_string(n) + " texture");
  }
  const int step = options.gridStep;
  if (step < 1 || step > n / 2) {
    return Status(ErrorCode::kInvalidArgument, "depth mesh: grid step " + std::to_string(step) +
                                                   " outside 1.." + std::to_string(n / 2));
  }
  if (!std::isfinite(options.maxSlope) || options.maxSlope <= 0.0f) {
    return Status(ErrorCode::kInvalidArgument, "depth mesh: maxSlope must be positive");
  }
  DepthMeshStats localStats;
  DepthMeshStats& st = stats ? *stats : localStats;
  st = DepthMeshStats();

  const glm::mat4 inverse = glm::inverse(framing.camera.projection * framing.camera.view);
  auto covered = [&](int x, int y) { return depth[static_cast<std::size_t>(y) * n + x] < 1.0f; };
  auto unproject = [&](int x, int y) {
    const float d = depth[static_cast<std::size_t>(y) * n + x];
    const glm::vec4 ndc(2.0f * (x + 0.5f) / n - 1.0f, 1.0f - 2.0f * (y + 0.5f) / n, 2.0f * d - 1.0f,
                        1.0f);
    const glm::vec4 world = inverse * ndc;
    return glm::vec3(world) / world.w;
  };

  const int cells = (n - 1 + step - 1) / step;  // grid nodes per row = cells + 1
  const int nodesPerRow = cells + 1;
  std::vector<Node> nodes(static_cast<std::size_t>(nodesPerRow) * nodesPerRow);
  const int snapRadius = options.snapToSilhouette ? step / 2 : 0;
  for (int gy = 0; gy < nodesPerRow; ++gy) {
    for (int gx = 0; gx < nodesPerRow; ++gx) {
      Node& node = nodes[static_cast<std::size_t>(gy) * nodesPerRow + gx];
      const int x = std::min(gx * step, n - 1);
      const int y = std::min(gy * step, n - 1);
      int bestX = -1;
      int bestY = -1;
      if (covered(x, y)) {
        bestX = x;
        bestY = y;
      } else if (snapRadius > 0) {
        // The nearest covered pixel within half a cell keeps the mesh's rim
        // close to the true silhouette instead of up to a cell inside it.
        int bestDistance = std::numeric_limits<int>::max();
        for (int sy = std::max(0, y - snapRadius); sy <= std::min(n - 1, y + snapRadius); ++sy) {
          for (int sx = std::max(0, x - snapRadius); sx <= std::min(n - 1, x + snapRadius); ++sx) {
            const int distance = (sx - x) * (sx - x) + (sy - y) * (sy - y);
            if (distance < bestDistance && covered(sx, sy)) {
              bestDistance = distance;
              bestX = sx;
              bestY = sy;
            }
          }
        }
      }
      if (bestX < 0) continue;
      node.px = bestX;
      node.py = bestY;
      node.valid = true;
      node.position = unproject(bestX, bestY);
      node.eyeDepth = glm::dot(node.position - framing.viewpoint, framing.forward);
    }
  }

  // Two nodes belong to one surface when their depth differs by at most
  // maxSlope times their lateral distance (at the nearer depth), plus the
  // depth buffer's own resolution there (24 bits of 1/z).
  const double pixelWidth = framing.quad.width / n / framing.planeDistance;
  const double pixelHeight = framing.quad.height / n / framing.planeDistance;
  const double zNear = framing.nearDepth * 0.999;
  const double zFar = framing.farDepth * 1.001;
  auto connected = [&](const Node& a, const Node& b, bool countSplit) {
    const double nearer = std::min(a.eyeDepth, b.eyeDepth);
    const double dx = (a.px - b.px) * pixelWidth * nearer;
    const double dy = (a.py - b.py) * pixelHeight * nearer;
    const double lateral = std::sqrt(dx * dx + dy * dy);
    const double quantum = 4.0 * nearer * nearer * (1.0 / zNear - 1.0 / zFar) / 16777216.0;
    const double jump = std::fabs(static_cast<double>(a.eyeDepth) - b.eyeDepth);
    const bool ok = jump <= options.maxSlope * lateral + quantum;
    if (!ok && countSplit) {
      ++st.splitEdges;
      st.maxDepthJump = std::max(st.maxDepthJump, jump);
    }
    return ok;
  };
  // Split statistics over the grid edges (horizontal, vertical) between valid nodes.
  for (int gy = 0; gy < nodesPerRow; ++gy) {
    for (int gx = 0; gx < nodesPerRow; ++gx) {
      const Node& a = nodes[static_cast<std::size_t>(gy) * nodesPerRow + gx];
      if (!a.valid) continue;
      if (gx + 1 < nodesPerRow) {
        const Node& b = nodes[static_cast<std::size_t>(gy) * nodesPerRow + gx + 1];
        if (b.valid) connected(a, b, true);
      }
      if (gy + 1 < nodesPerRow) {
        const Node& b = nodes[static_cast<std::size_t>(gy + 1) * nodesPerRow + gx];
        if (b.valid) connected(a, b, true);
      }
    }
  }

  IndexedMesh mesh;
  auto vertexOf = [&](Node& node) {
    if (node.vertex == kNoVertex) {
      node.vertex = static_cast<std::uint32_t>(mesh.positions.size());
      mesh.positions.push_back(node.position);
      mesh.uvs.push_back(glm::vec2((node.px + 0.5f) / n, 1.0f - (node.py + 0.5f) / n));
    }
    return node.vertex;
  };
  // A triangle needs three valid nodes pairwise on one surface; snapping can
  // move two nodes onto one pixel, which would make it degenerate.
  auto usable = [&](const Node& a, const Node& b, const Node& c) {
    if (!a.valid || !b.valid || !c.valid) return false;
    if ((a.px == b.px && a.py == b.py) || (b.px == c.px && b.py == c.py) ||
        (a.px == c.px && a.py == c.py)) {
      return false;
    }
    return connected(a, b, false) && connected(b, c, false) && connected(a, c, false);
  };
  for (int gy = 0; gy < cells; ++gy) {
    for (int gx = 0; gx < cells; ++gx) {
      // a b   (rows top-down)
      // d c
      Node& a = nodes[static_cast<std::size_t>(gy) * nodesPerRow + gx];
      Node& b = nodes[static_cast<std::size_t>(gy) * nodesPerRow + gx + 1];
      Node& c = nodes[static_cast<std::size_t>(gy + 1) * nodesPerRow + gx + 1];
      Node& d = nodes[static_cast<std::size_t>(gy + 1) * nodesPerRow + gx];
      // Counter-clockwise as seen from the viewpoint (image y grows downwards).
      const bool acd = usable(a, d, c);
      const bool acb = usable(a, c, b);
      const bool bda = usable(a, d, b);
      const bool bdc = usable(b, d, c);
      const int viaAc = acd + acb;
      const int viaBd = bda + bdc;
      bool useAc = viaAc > viaBd;
      if (viaAc == viaBd && viaAc > 0) {
        // Same count: cut along the diagonal whose ends are closer in depth (follows creases).
        const float jumpAc = std::fabs(a.eyeDepth - c.eyeDepth);
        const float jumpBd = std::fabs(b.eyeDepth - d.eyeDepth);
        useAc = jumpAc <= jumpBd;
      }
      auto emit = [&](Node& p, Node& q, Node& r) {
        mesh.indices.push_back(vertexOf(p));
        mesh.indices.push_back(vertexOf(q));
        mesh.indices.push_back(vertexOf(r));
      };
      if (useAc) {
        if (acd) emit(a, d, c);
        if (acb) emit(a, c, b);
      } else {
        if (bda) emit(a, d, b);
        if (bdc) emit(b, d, c);
      }
    }
  }
  st.gridNodes = mesh.positions.size();
  mesh.computeNormals();
  return mesh;
}

}  // namespace thinlod::simplifier
