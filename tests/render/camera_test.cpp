// projectToPixel / unprojectPixel: pixel convention and round trips; validateLighting (no GL).
#include "thinlod/common/render/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>
#include <string>

namespace thinlod::render {
namespace {

Camera perspectiveCamera() {
  Camera c;
  c.view = glm::lookAt(glm::vec3(1, 2, 6), glm::vec3(0), glm::vec3(0, 1, 0));
  c.projection = glm::perspective(glm::radians(40.0f), 4.0f / 3.0f, 0.5f, 50.0f);
  return c;
}

TEST(Camera, LookAtTargetProjectsToImageCentre) {
  const glm::vec3 p = projectToPixel(perspectiveCamera(), glm::vec3(0), 640, 480);
  EXPECT_NEAR(p.x, 320.0f, 1e-3f);
  EXPECT_NEAR(p.y, 240.0f, 1e-3f);
  EXPECT_GT(p.z, 0.0f);
  EXPECT_LT(p.z, 1.0f);
}

TEST(Camera, PixelRowsCountFromTheTop) {
  Camera c;
  c.view = glm::lookAt(glm::vec3(0, 0, 5), glm::vec3(0), glm::vec3(0, 1, 0));
  c.projection = glm::ortho(-1.0f, 1.0f, -1.0f, 1.0f, 1.0f, 9.0f);
  const glm::vec3 up = projectToPixel(c, glm::vec3(0, 1, 0), 100, 100);
  EXPECT_NEAR(up.y, 0.0f, 1e-4f);
  const glm::vec3 right = projectToPixel(c, glm::vec3(1, 0, 0), 100, 100);
  EXPECT_NEAR(right.x, 100.0f, 1e-4f);
}

TEST(Camera, UnprojectInvertsProjectOnRandomPoints) {
  const Camera camera = perspectiveCamera();
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> coordinate(-2.0f, 2.0f);
  for (int i = 0; i < 200; ++i) {
    const glm::vec3 world(coordinate(rng), coordinate(rng), coordinate(rng));
    const glm::vec3 window = projectToPixel(camera, world, 640, 480);
    const glm::vec3 back = unprojectPixel(camera, window.x, window.y, window.z, 640, 480);
    EXPECT_NEAR(glm::length(back - world), 0.0f, 2e-3f) << i;
  }
}

TEST(ValidateLighting, AcceptsTheDefaultsAndNamesEachProblem) {
  EXPECT_TRUE(validateLighting(Lighting(), "draw").ok());
  Lighting lighting;
  lighting.lights.resize(kMaxLights);
  EXPECT_TRUE(validateLighting(lighting, "draw").ok());
  lighting.lights.resize(kMaxLights + 1);
  EXPECT_NE(validateLighting(lighting, "draw").message().find("draw: 5 lights, at most 4"),
            std::string::npos);
  const float nan = std::nanf("");
  auto rejected = [](const Lighting& l) {
    const Status status = validateLighting(l, "renderFrame");
    return status.code() == ErrorCode::kInvalidArgument &&
           status.message().rfind("renderFrame: ", 0) == 0;
  };
  Lighting bad;
  bad.ambient = glm::vec3(nan, 0.0f, 0.0f);
  EXPECT_TRUE(rejected(bad));
  bad.ambient = glm::vec3(-0.1f, 0.0f, 0.0f);
  EXPECT_TRUE(rejected(bad));
  bad = Lighting();
  Light light;
  light.vector = glm::vec3(0.0f);  // a directional light needs a direction
  bad.lights = {light};
  EXPECT_TRUE(rejected(bad));
  light.type = Light::Type::kPoint;  // a point light at the origin is fine
  bad.lights = {light};
  EXPECT_FALSE(rejected(bad));
  light.attenuation = -1.0f;
  bad.lights = {light};
  EXPECT_TRUE(rejected(bad));
  light.attenuation = 0.0f;
  light.color = glm::vec3(1.0f, -1.0f, 0.0f);
  bad.lights = {light};
  EXPECT_TRUE(rejected(bad));
  light.color = glm::vec3(std::numeric_limits<float>::infinity());
  bad.lights = {light};
  EXPECT_TRUE(rejected(bad));
}

}  // namespace
}  // namespace thinlod::render
