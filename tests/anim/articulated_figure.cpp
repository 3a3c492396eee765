// The generated articulated figure (articulated_figure.h).
#include "articulated_figure.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <stdexcept>

namespace thinlod::anim::testing {
namespace {

constexpr float kPi = 3.14159265358979f;

glm::quat about(float degrees, const glm::vec3& axis) {
  return glm::angleAxis(degrees * kPi / 180.0f, glm::normalize(axis));
}

}  // namespace

ArticulatedFigure makeArticulatedFigure(const FigureShape& shape) {
  ArticulatedFigure f;
  const int rings = 3 * shape.ringsPerUnit + 1;
  const int around = shape.around;
  const float s = shape.scale;
  for (int r = 0; r < rings; ++r) {
    const float x = 3.0f * static_cast<float>(r) / static_cast<float>(rings - 1);
    for (int a = 0; a < around; ++a) {
      const float angle = 2.0f * kPi * static_cast<float>(a) / static_cast<float>(around);
      f.mesh.positions.emplace_back(s * x, s * shape.radius * std::cos(angle),
                                    s * shape.radius * std::sin(angle));
    }
  }
  const auto ring = [&](int r, int a) {
    return static_cast<std::uint32_t>(r * around + ((a % around) + around) % around);
  };
  for (int r = 0; r + 1 < rings; ++r) {
    for (int a = 0; a < around; ++a) {
      f.mesh.indices.insert(f.mesh.indices.end(), {ring(r, a), ring(r + 1, a), ring(r + 1, a + 1)});
      f.mesh.indices.insert(f.mesh.indices.end(), {ring(r, a), ring(r + 1, a + 1), ring(r, a + 1)});
    }
  }
  // Caps: a centre vertex at each end, fanned to the end ring (closed surface).
  const auto capCentre = static_cast<std::uint32_t>(f.mesh.positions.size());
  f.mesh.positions.emplace_back(0.0f, 0.0f, 0.0f);
  f.mesh.positions.emplace_back(s * 3.0f, 0.0f, 0.0f);
  for (int a = 0; a < around; ++a) {
    f.mesh.indices.insert(f.mesh.indices.end(), {capCentre, ring(0, a + 1), ring(0, a)});
    f.mesh.indices.insert(f.mesh.indices.end(),
                          {capCentre + 1, ring(rings - 1, a), ring(rings - 1, a + 1)});
  }

  // Bones: a chain at x = 0, 1, 2 (scaled); inverse bind = inverse global rest.
  for (int b = 0; b < 3; ++b) {
    Bone bone;
    bone.name = "segment" + std::to_string(b);
    bone.parent = b - 1;
    bone.restLocal =
        b == 0 ? glm::mat4(1.0f) : glm::translate(glm::mat4(1.0f), glm::vec3(s, 0.0f, 0.0f));
    bone.inverseBind =
        glm::translate(glm::mat4(1.0f), glm::vec3(-s * static_cast<float>(b), 0.0f, 0.0f));
    f.skeleton.bones.push_back(bone);
  }

  // Skin: rigid on the segment's bone away from the joints; deformable near
  // the joints at x = 1 and x = 2 with path-length weights.
  const std::size_t n = f.mesh.vertexCount();
  f.skin.assign(n, VertexSkin{});
  for (std::uint32_t joint = 1; joint <= 2; ++joint) {
    std::vector<bool> inRegion(n, false);
    std::vector<std::uint32_t> borderA, borderB;
    const float jx = s * static_cast<float>(joint), half = s * shape.joint;
    for (std::uint32_t v = 0; v < n; ++v) {
      const float x = f.mesh.positions[v].x;
      if (std::abs(x - jx) < half) inRegion[v] = true;
    }
    // Borders: the rings just outside the region on either side.
    for (int r = 0; r < rings; ++r) {
      const float x = s * 3.0f * static_cast<float>(r) / static_cast<float>(rings - 1);
      const float xPrev = s * 3.0f * static_cast<float>(r - 1) / static_cast<float>(rings - 1);
      const float xNext = s * 3.0f * static_cast<float>(r + 1) / static_cast<float>(rings - 1);
      const bool outsideLeft = x <= jx - half && xNext > jx - half;
      const bool outsideRight = x >= jx + half && xPrev < jx + half;
      for (int a = 0; a < around; ++a) {
        if (outsideLeft) borderA.push_back(ring(r, a));
        if (outsideRight) borderB.push_back(ring(r, a));
      }
    }
    const Result<std::vector<float>> weights =
        pathLengthWeights(f.mesh, inRegion, borderA, borderB);
    if (!weights.ok()) throw std::runtime_error(weights.status().toString());
    for (std::uint32_t v = 0; v < n; ++v) {
      if (inRegion[v]) f.skin[v] = {joint - 1, joint, (*weights)[v]};
    }
  }
  for (std::uint32_t v = 0; v < n; ++v) {
    if (f.skin[v].boneA != f.skin[v].boneB) continue;
    const float x = f.mesh.positions[v].x / s;
    const std::uint32_t bone = x < 1.0f ? 0u : (x < 2.0f ? 1u : 2u);
    f.skin[v] = {bone, bone, 0.0f};
  }

  // The clip: root travel and roll, the joints bending about z and y.
  f.clip.name = "wave";
  f.clip.duration = 2.0;
  BoneChannel root;
  root.bone = 0;
  const float travel = s * shape.rootTravel;
  root.positions = {{0.0, glm::vec3(0.0f)},
                    {1.0, glm::vec3(travel, 0.4f * travel, 0.0f)},
                    {2.0, glm::vec3(0.0f)}};
  root.rotations = {
      {0.0, glm::quat(1, 0, 0, 0)}, {1.2, about(40.0f, {1, 0, 0})}, {2.0, glm::quat(1, 0, 0, 0)}};
  BoneChannel elbow;
  elbow.bone = 1;
  elbow.rotations = {{0.0, glm::quat(1, 0, 0, 0)},
                     {1.0, about(shape.bendDegrees, {0, 0, 1})},
                     {2.0, glm::quat(1, 0, 0, 0)}};
  elbow.positions = {{0.0, glm::vec3(s, 0, 0)}};  // the rest offset, keyed
  BoneChannel wrist;
  wrist.bone = 2;
  wrist.rotations = {{0.0, glm::quat(1, 0, 0, 0)},
                     {0.7, about(-shape.bendDegrees, {0, 1, 0})},
                     {1.6, about(0.5f * shape.bendDegrees, {0, 1, 1})},
                     {2.0, glm::quat(1, 0, 0, 0)}};
  f.clip.channels = {root, elbow, wrist};
  return f;
}

}  // namespace thinlod::anim::testing
