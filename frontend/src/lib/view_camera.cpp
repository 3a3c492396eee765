#include "thinlod/frontend/view_camera.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <string>

namespace thinlod::frontend {

Result<render::Camera> cameraFromPose(const glm::vec3& position, const glm::quat& orientation,
                                      float fovY, int width, int height, const ViewPlanes& planes) {
  auto bad = [](const std::string& what) {
    return Status(ErrorCode::kInvalidArgument, "cameraFromPose: " + what);
  };
  if (!std::isfinite(position.x) || !std::isfinite(position.y) || !std::isfinite(position.z)) {
    return bad("position is not finite");
  }
  const float norm2 = orientation.x * orientation.x + orientation.y * orientation.y +
                      orientation.z * orientation.z + orientation.w * orientation.w;
  if (!std::isfinite(norm2) || norm2 < 1e-12f) return bad("orientation is zero or not finite");
  if (!std::isfinite(fovY) || fovY <= 0.0f || fovY >= 3.14159265f) {
    return bad("fovY " + std::to_string(fovY) + " outside (0, pi)");
  }
  if (width < 1 || height < 1) {
    return bad("frame " + std::to_string(width) + "x" + std::to_string(height) + " is empty");
  }
  if (!std::isfinite(planes.nearPlane) || !std::isfinite(planes.farPlane) ||
      planes.nearPlane <= 0.0f || planes.farPlane <= planes.nearPlane) {
    return bad("near/far planes " + std::to_string(planes.nearPlane) + "/" +
               std::to_string(planes.farPlane) + " need 0 < near < far");
  }
  const glm::quat unit = orientation / std::sqrt(norm2);
  const glm::mat4 cameraToWorld = glm::translate(glm::mat4(1.0f), position) * glm::mat4_cast(unit);
  render::Camera camera;
  camera.view = glm::inverse(cameraToWorld);
  camera.projection = glm::perspective(fovY, static_cast<float>(width) / static_cast<float>(height),
                                       planes.nearPlane, planes.farPlane);
  return camera;
}

Result<render::Camera> cameraFromPose(const Pose& pose, int width, int height,
                                      const ViewPlanes& planes) {
  return cameraFromPose(pose.position, pose.orientation, pose.fovYRadians(), width, height, planes);
}

}  // namespace thinlod::frontend
