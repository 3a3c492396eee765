// Impostor framing (the paper's autosize/autocenter, section 3.6): an off-axis
// perspective frustum from the viewpoint that hugs the object's projected
// vertices, and the quad that shows the resulting texture.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <string>

#include "thinlod/simplifier/impostor.h"

namespace thinlod::simplifier {
namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

IndexedMesh ImpostorQuad::mesh() const {
  const glm::vec3 halfRight = right * (0.5f * width);
  const glm::vec3 halfUp = up * (0.5f * height);
  IndexedMesh quad;
  // Counter-clockwise seen from the viewpoint (on the +normal side).
  quad.positions = {center - halfRight - halfUp, center + halfRight - halfUp,
                    center + halfRight + halfUp, center - halfRight + halfUp};
  quad.normals.assign(4, normal);
  quad.uvs = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
  quad.indices = {0, 1, 2, 0, 2, 3};
  return quad;
}

Result<ImpostorFraming> frameImpostor(const std::vector<glm::vec3>& points,
                                      const glm::vec3& viewpoint, const ImpostorOptions& options) {
  if (points.empty()) return Status(ErrorCode::kInvalidArgument, "impostor: no vertices to frame");
  if (!finite(viewpoint)) {
    return Status(ErrorCode::kInvalidArgument, "impostor: viewpoint is not finite");
  }
  if (!finite(options.up) || glm::length(options.up) == 0.0f) {
    return Status(ErrorCode::kInvalidArgument, "impostor: up vector is zero or not finite");
  }
  const int size = options.textureSize;
  if (size < 8 || size > 4096) {
    return Status(ErrorCode::kInvalidArgument,
                  "impostor: texture size " + std::to_string(size) + " outside 8..4096");
  }
  if (!std::isfinite(options.paddingPixels) || options.paddingPixels < 0.0f ||
      options.paddingPixels * 4.0f >= static_cast<float>(size)) {
    return Status(ErrorCode::kInvalidArgument, "impostor: padding must be in [0, textureSize/4)");
  }

  // Bounding sphere: box centre and the farthest point from it (>= the minimal sphere).
  Bounds bounds;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!finite(points[i])) {
      return Status(ErrorCode::kInvalidArgument,
                    "impostor: vertex " + std::to_string(i) + " is not finite");
    }
    bounds.extend(points[i]);
  }
  ImpostorFraming f;
  f.viewpoint = viewpoint;
  f.textureSize = size;
  f.objectCenter = bounds.center();
  float radius2 = 0.0f;
  for (const glm::vec3& p : points) {
    const glm::vec3 d = p - f.objectCenter;
    radius2 = std::max(radius2, glm::dot(d, d));
  }
  f.objectRadius = std::sqrt(radius2);
  const glm::vec3 toCenter = f.objectCenter - viewpoint;
  const float centerDistance = glm::length(toCenter);
  // Inside (or nearly touching) the bounding sphere no frustum can hold the
  // whole object; the caller should render geometry instead.
  if (!(centerDistance > 1.05f * f.objectRadius) || centerDistance == 0.0f) {
    return Status(ErrorCode::kInvalidArgument,
                  "impostor: viewpoint is " + std::to_string(centerDistance) +
                      " m from the object centre, within 1.05 x its bounding radius " +
                      std::to_string(f.objectRadius) + " m");
  }
  f.forward = toCenter / centerDistance;
  glm::vec3 up = glm::normalize(options.up);
  if (glm::length(glm::cross(f.forward, up)) < 1e-3f) {  // looking along `up`: pick another
    up = std::fabs(f.forward.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  }
  const glm::vec3 right = glm::normalize(glm::cross(f.forward, up));
  const glm::vec3 imageUp = glm::cross(right, f.forward);

  // Depth range along `forward`, then the projected extent on the plane at
  // the middle depth (that plane minimises the largest parallax offset).
  float nearDepth = std::numeric_limits<float>::max();
  float farDepth = 0.0f;
  for (const glm::vec3& p : points) {
    const float z = glm::dot(p - viewpoint, f.forward);
    nearDepth = std::min(nearDepth, z);
    farDepth = std::max(farDepth, z);
  }
  const float minExtent = 1e-4f * std::max(f.objectRadius, 1e-6f);
  if (farDepth - nearDepth < minExtent) farDepth = nearDepth + minExtent;  // flat, facing us
  f.nearDepth = nearDepth;
  f.farDepth = farDepth;
  f.planeDistance = 0.5f * (nearDepth + farDepth);
  float x0 = std::numeric_limits<float>::max();
  float x1 = -x0;
  float y0 = x0;
  float y1 = -x0;
  for (const glm::vec3& p : points) {
    const glm::vec3 d = p - viewpoint;
    const float scale = f.planeDistance / glm::dot(d, f.forward);
    const float x = glm::dot(d, right) * scale;
    const float y = glm::dot(d, imageUp) * scale;
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  // Degenerate extents (a line seen end on) get a minimal width so the frustum exists.
  if (x1 - x0 < minExtent) {
    const float mid = 0.5f * (x0 + x1);
    x0 = mid - 0.5f * minExtent;
    x1 = mid + 0.5f * minExtent;
  }
  if (y1 - y0 < minExtent) {
    const float mid = 0.5f * (y0 + y1);
    y0 = mid - 0.5f * minExtent;
    y1 = mid + 0.5f * minExtent;
  }
  // A fixed frame (paper Figure 9, autocenter / autosize FALSE): the centre
  // projected onto the plane; with it alone the half extents reach the
  // farthest point from it, with a fixed size they are the size's halves.
  if (options.fixedCenter || options.fixedSize.x > 0.0f || options.fixedSize.y > 0.0f) {
    if (options.fixedCenter && !finite(*options.fixedCenter)) {
      return Status(ErrorCode::kInvalidArgument, "impostor: fixed centre is not finite");
    }
    if (!(options.fixedSize.x >= 0.0f) || !(options.fixedSize.y >= 0.0f) ||
        !std::isfinite(options.fixedSize.x) || !std::isfinite(options.fixedSize.y)) {
      return Status(ErrorCode::kInvalidArgument, "impostor: fixed size must be finite, >= 0");
    }
    float cx = 0.5f * (x0 + x1);
    float cy = 0.5f * (y0 + y1);
    if (options.fixedCenter) {
      const glm::vec3 d = *options.fixedCenter - viewpoint;
      const float along = glm::dot(d, f.forward);
      if (!(along > 0.0f)) {
        return Status(ErrorCode::kInvalidArgument,
                      "impostor: fixed centre is behind the viewpoint");
      }
      const float scale = f.planeDistance / along;
      cx = glm::dot(d, right) * scale;
      cy = glm::dot(d, imageUp) * scale;
    }
    float hx = std::max(cx - x0, x1 - cx);
    float hy = std::max(cy - y0, y1 - cy);
    float clipped = 0.0f;
    if (options.fixedSize.x > 0.0f && options.fixedSize.y > 0.0f) {
      const float fx = 0.5f * options.fixedSize.x;
      const float fy = 0.5f * options.fixedSize.y;
      clipped = std::max(0.0f, std::max(hx - fx, hy - fy));
      hx = fx;
      hy = fy;
    }
    f.clippedExtent = clipped;
    x0 = cx - hx;
    x1 = cx + hx;
    y0 = cy - hy;
    y1 = cy + hy;
  }
  // Padding: p empty pixels each side of N means the object spans N - 2p pixels.
  const float grow =
      static_cast<float>(size) / (static_cast<float>(size) - 2.0f * options.paddingPixels);
  const float padX = 0.5f * (x1 - x0) * (grow - 1.0f);
  const float padY = 0.5f * (y1 - y0) * (grow - 1.0f);
  x0 -= padX;
  x1 += padX;
  y0 -= padY;
  y1 += padY;

  // Clip planes just outside the depth range, so no vertex is clipped and the
  // 24-bit depth buffer spends its precision on the object.
  const float zNear = nearDepth * 0.999f;
  const float zFar = farDepth * 1.001f + minExtent;
  const float toNear = zNear / f.planeDistance;
  f.camera.view = glm::lookAt(viewpoint, viewpoint + f.forward, imageUp);
  f.camera.projection =
      glm::frustum(x0 * toNear, x1 * toNear, y0 * toNear, y1 * toNear, zNear, zFar);

  f.quad.right = right;
  f.quad.up = imageUp;
  f.quad.normal = -f.forward;
  f.quad.width = x1 - x0;
  f.quad.height = y1 - y0;
  f.quad.center = viewpoint + f.forward * f.planeDistance + right * (0.5f * (x0 + x1)) +
                  imageUp * (0.5f * (y0 + y1));
  return f;
}

}  // namespace thinlod::simplifier
