// The camera of one viewer pose, shared by the frontend and the reference
// renderer so both draw exactly the same view. Pure math (glm), no GL.
//
// Contract:
// - position: world metres; orientation: camera -> world rotation (any
//   non-zero quaternion, normalised here); the camera looks down its -z with
//   +y up, as render::Camera expects. fovY: vertical field of view, radians,
//   in (0, pi). width/height: the frame in pixels (aspect = width / height).
// - nearPlane/farPlane: metres, 0 < near < far.
// - The Pose overload takes a trace pose (common/trace.h: fov in degrees).
// - Errors: any non-finite or out-of-range value is kInvalidArgument naming it.
#pragma once

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "thinlod/common/core/status.h"
#include "thinlod/common/core/trace.h"
#include "thinlod/common/render/camera.h"

namespace thinlod::frontend {

struct ViewPlanes {
  float nearPlane = 0.05f;
  float farPlane = 500.0f;
};

Result<render::Camera> cameraFromPose(const glm::vec3& position, const glm::quat& orientation,
                                      float fovY, int width, int height,
                                      const ViewPlanes& planes = {});
Result<render::Camera> cameraFromPose(const Pose& pose, int width, int height,
                                      const ViewPlanes& planes = {});

}  // namespace thinlod::frontend
