// The scene file as the frontend daemon needs it: object ids numbered as
// every daemon numbers them (scene::collectSceneObjects), the full-quality
// reference objects (full meshes, scene materials, object -> world), the
// scene's lights, and each object's colour for the meshes the backbone sends.
// Reads files (the scene and its meshes); errors name the path.
#pragma once

#include <cstddef>
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/render/camera.h"
#include "thinlod/common/scene.h"
#include "thinlod/common/scene_objects.h"
#include "thinlod/common/status.h"
#include "thinlod/frontend/reference_renderer.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {

struct ReferenceItem {
  ReferenceObject object;
  glm::vec3 worldCentre{0.0f};  // for back-to-front order of blended materials
  bool blended = false;
};

struct LoadedScene {
  std::unique_ptr<scene::Scene> scene;  // the objects point into it
  std::vector<scene::SceneObject> objects;
  render::Lighting lighting;
  std::size_t droppedLights = 0;
  MeshColors meshColors;         // object id -> material diffuse (RGBA)
  std::size_t unlitObjects = 0;  // objects without a Material (drawn lit by the frontend)
  std::vector<ReferenceItem> reference;
  std::size_t referenceTriangles = 0;
};

Result<LoadedScene> loadFrontendScene(const std::string& scenePath, const std::string& modelsDir);

}  // namespace thinlod::frontend::daemon
