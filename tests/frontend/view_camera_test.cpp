// cameraFromPose: orientation convention, aspect, and rejected inputs.
#include "thinlod/frontend/view_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <limits>

namespace thinlod::frontend {
namespace {

TEST(ViewCamera, IdentityLooksDownMinusZ) {
  auto camera = cameraFromPose(glm::vec3(1, 2, 3), glm::quat(1, 0, 0, 0), 1.0f, 640, 480);
  ASSERT_TRUE(camera.ok()) << camera.status().toString();
  const glm::vec3 centre = render::projectToPixel(*camera, glm::vec3(1, 2, -7), 640, 480);
  EXPECT_NEAR(centre.x, 320.0f, 1e-3f);
  EXPECT_NEAR(centre.y, 240.0f, 1e-3f);
  // +x is right, +y is up (pixel y counts from the top).
  const glm::vec3 right = render::projectToPixel(*camera, glm::vec3(2, 2, -7), 640, 480);
  const glm::vec3 up = render::projectToPixel(*camera, glm::vec3(1, 3, -7), 640, 480);
  EXPECT_GT(right.x, 320.0f);
  EXPECT_LT(up.y, 240.0f);
}

TEST(ViewCamera, YawTurnsTheView) {
  // 90 degrees about +y: the camera's -z becomes world -x.
  const glm::quat yaw = glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0));
  auto camera = cameraFromPose(glm::vec3(0), yaw, 1.0f, 100, 100);
  ASSERT_TRUE(camera.ok());
  const glm::vec3 p = render::projectToPixel(*camera, glm::vec3(-5, 0, 0), 100, 100);
  EXPECT_NEAR(p.x, 50.0f, 1e-3f);
  EXPECT_NEAR(p.y, 50.0f, 1e-3f);
  EXPECT_GT(p.z, 0.0f);
  EXPECT_LT(p.z, 1.0f);
}

TEST(ViewCamera, UnnormalisedQuaternionIsNormalised) {
  auto a = cameraFromPose(glm::vec3(0), glm::quat(2, 0, 0, 0), 1.0f, 64, 48);
  auto b = cameraFromPose(glm::vec3(0), glm::quat(1, 0, 0, 0), 1.0f, 64, 48);
  ASSERT_TRUE(a.ok() && b.ok());
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(a->view[c][r], b->view[c][r], 1e-6f);
  }
}

TEST(ViewCamera, VerticalFovSpansTheFrameHeight) {
  const float fov = glm::radians(60.0f);
  auto camera = cameraFromPose(glm::vec3(0), glm::quat(1, 0, 0, 0), fov, 640, 480);
  ASSERT_TRUE(camera.ok());
  const float y = std::tan(fov / 2.0f) * 10.0f;  // top edge at distance 10
  EXPECT_NEAR(render::projectToPixel(*camera, glm::vec3(0, y, -10), 640, 480).y, 0.0f, 1e-2f);
}

TEST(ViewCamera, TracePoseMatchesItsViewMatrix) {
  Pose pose;
  pose.position = glm::vec3(2, 1, 6);
  pose.orientation = lookAtOrientation(pose.position, glm::vec3(0, 0.5f, 0));
  pose.fovYDegrees = 50.0f;
  auto camera = cameraFromPose(pose, 640, 480);
  ASSERT_TRUE(camera.ok());
  const glm::mat4 expected = viewMatrix(pose);
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) EXPECT_NEAR(camera->view[c][r], expected[c][r], 1e-5f);
  }
  const glm::vec3 target = render::projectToPixel(*camera, glm::vec3(0, 0.5f, 0), 640, 480);
  EXPECT_NEAR(target.x, 320.0f, 1e-2f);
  EXPECT_NEAR(target.y, 240.0f, 1e-2f);
}

TEST(ViewCamera, RejectsBadInputs) {
  const glm::quat id(1, 0, 0, 0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(cameraFromPose(glm::vec3(nan), id, 1.0f, 64, 48).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(cameraFromPose(glm::vec3(0), glm::quat(0, 0, 0, 0), 1.0f, 64, 48).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(cameraFromPose(glm::vec3(0), id, 0.0f, 64, 48).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(cameraFromPose(glm::vec3(0), id, 3.2f, 64, 48).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(cameraFromPose(glm::vec3(0), id, 1.0f, 0, 48).status().code(),
            ErrorCode::kInvalidArgument);
  EXPECT_EQ(cameraFromPose(glm::vec3(0), id, 1.0f, 64, 48, ViewPlanes{1.0f, 0.5f}).status().code(),
            ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace thinlod::frontend
