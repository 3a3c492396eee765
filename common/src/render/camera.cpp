#include "thinlod/common/render/camera.h"

#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

namespace thinlod::render {

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
