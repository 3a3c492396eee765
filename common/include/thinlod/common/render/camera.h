// Camera and lights for MeshRenderer, plus the pixel <-> world mapping that
// impostors and tests use. Pure math (glm only), no GL.
//
// Contract:
// - Camera holds a glm view matrix (world -> eye, right-handed, looking down
//   -z) and a glm projection matrix (eye -> clip, OpenGL depth range [-1, 1]).
// - Pixel coordinates: x from the left edge, y from the TOP edge (matching the
//   top-down readback), pixel (i, j) has its centre at (i + 0.5, j + 0.5).
//   Window depth is in [0, 1] as returned by RenderTarget::readDepth.
// - Light vectors are in world space. Directional lights store the direction
//   the light TRAVELS (e.g. (0,-1,0) = light from above); point lights store a
//   position and fall off with 1/(1 + k d^2) where k = `attenuation`.
// - Colours are linear RGB in [0, inf); intensity is folded into the colour.
//   validateLighting() is the one check every renderer applies.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"

namespace thinlod::render {

struct Camera {
  glm::mat4 view{1.0f};
  glm::mat4 projection{1.0f};
};

struct Light {
  enum class Type { kDirectional, kPoint };
  Type type = Type::kDirectional;
  glm::vec3 vector{0.0f, 0.0f, -1.0f};  // directional: travel direction; point: position
  glm::vec3 color{1.0f};
  float attenuation = 0.0f;  // point lights only
};

constexpr int kMaxLights = 4;

struct Lighting {
  glm::vec3 ambient{0.2f};
  std::vector<Light> lights;  // at most kMaxLights; more is kInvalidArgument at draw time
};

// kInvalidArgument (message starting with `what`) for more than kMaxLights
// lights, an ambient or light colour that is negative or not finite, or a
// light with a non-finite (directional: zero) vector or a negative or
// non-finite attenuation; ok otherwise.
Status validateLighting(const Lighting& lighting, const std::string& what);

// World position of pixel (px, py) (y from the top) at window depth `depth`.
glm::vec3 unprojectPixel(const Camera& camera, float px, float py, float depth, int width,
                         int height);
// Window position (x from the left, y from the top, z = window depth in [0,1]) of a world point.
glm::vec3 projectToPixel(const Camera& camera, const glm::vec3& world, int width, int height);

}  // namespace thinlod::render
