// allFinite: every component of a glm vector or matrix is finite (no NaN, no
// infinity). The one check for input from outside (meshes, poses, cameras,
// lights, transforms). Header-only, pure.
#pragma once

#include <cmath>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace thinlod {

template <glm::length_t L, typename T, glm::qualifier Q>
bool allFinite(const glm::vec<L, T, Q>& v) {
  for (glm::length_t i = 0; i < L; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

template <glm::length_t C, glm::length_t R, typename T, glm::qualifier Q>
bool allFinite(const glm::mat<C, R, T, Q>& m) {
  for (glm::length_t c = 0; c < C; ++c) {
    if (!allFinite(m[c])) return false;
  }
  return true;
}

}  // namespace thinlod
