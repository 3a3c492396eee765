#include "thinlod/common/render/camera.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "thinlod/common/core/finite.h"

namespace thinlod::render {
namespace {

bool colour(const glm::vec3& c) {
  return allFinite(c) && c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f;
}

}  // namespace

Status validateLighting(const Lighting& lighting, const std::string& what) {
  if (lighting.lights.size() > static_cast<std::size_t>(kMaxLights)) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": " + std::to_string(lighting.lights.size()) + " lights, at most " +
                      std::to_string(kMaxLights));
  }
  if (!colour(lighting.ambient)) {
    return Status(ErrorCode::kInvalidArgument,
                  what + ": ambient light is not a finite, non-negative colour");
  }
  for (std::size_t i = 0; i < lighting.lights.size(); ++i) {
    const Light& light = lighting.lights[i];
    if (!allFinite(light.vector) || !colour(light.color) || !std::isfinite(light.attenuation) ||
        light.attenuation < 0.0f ||
        (light.type == Light::Type::kDirectional && glm::length(light.vector) == 0.0f)) {
      return Status(ErrorCode::kInvalidArgument,
                    what + ": light " + std::to_string(i) +
                        " has a non-finite or zero vector, a negative or non-finite colour, or "
                        "a negative or non-finite attenuation");
    }
  }
  return Status();
}

glm::vec3 unprojectPixel(const Camera& camera, float px, float py, float depth, int width,
                         int height) {
  // Window -> normalised device coordinates; y is flipped because pixel rows count from the top.
  const glm::vec4 ndc(2.0f * px / static_cast<float>(width) - 1.0f,
                      1.0f - 2.0f * py / static_cast<float>(height), 2.0f * depth - 1.0f, 1.0f);
  const glm::vec4 world = glm::inverse(camera.projection * camera.view) * ndc;
  return glm::vec3(world) / world.w;
}

glm::vec3 projectToPixel(const Camera& camera, const glm::vec3& world, int width, int height) {
  const glm::vec4 clip = camera.projection * camera.view * glm::vec4(world, 1.0f);
  const glm::vec3 ndc = glm::vec3(clip) / clip.w;
  return glm::vec3((ndc.x + 1.0f) * 0.5f * static_cast<float>(width),
                   (1.0f - ndc.y) * 0.5f * static_cast<float>(height), (ndc.z + 1.0f) * 0.5f);
}

}  // namespace thinlod::render
