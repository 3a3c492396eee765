// The scene file as the frontend daemon needs it: object ids numbered as
// every daemon numbers them (scene::collectSceneObjects), the full-quality
// reference objects (full meshes, scene materials, object -> world), the
// scene's lights, and each object's colour for the meshes the backbone sends.
// An LOD's full quality is its first level: objects reached through a later
// level of any LOD are not drawn in the reference (the paper's Figure 10
// pattern USEs the same Shape in every level, which would otherwise be drawn
// once per level), and all objects under one outermost LOD form one group
// for the completeness check (ObjectExtent::group).
// Reference objects carry their shape's base-colour texture (decoded once per
// file; a file that fails is a warning and draws untextured).
// Reads files (the scene, its meshes and textures); errors name the path.
#pragma once

#include <cstddef>
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "thinlod/common/core/status.h"
#include "thinlod/common/render/camera.h"
#include "thinlod/common/scene/scene.h"
#include "thinlod/common/scene/scene_objects.h"
#include "thinlod/frontend/reference_renderer.h"
#include "thinlod/frontend/shown_frames.h"
#include "wire_conversion.h"

namespace thinlod::frontend::daemon {

struct ReferenceItem {
  ReferenceObject object;
  glm::vec3 worldCentre{0.0f};  // for back-to-front order of blended materials
  bool blended = false;
  std::size_t extent = 0;  // index into LoadedScene::extents (coverage colour)
  // An animated object: its clip, played on the frame's pose time to give
  // object.bones (GlFrameProducer), so the reference moves as the frontend's
  // levels do. object.skin is its palette skin.
  const scene::SkinnedAnimation* animation = nullptr;
  float animationOffset = 0.0f;  // its Inline's: the clip plays at pose time + this
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
  std::size_t laterLodLevelObjects = 0;  // left out of the reference
  std::vector<ObjectExtent> extents;     // every object, for completeness
  std::size_t textures = 0;              // texture files decoded for the reference
  std::vector<std::string> warnings;     // the scene's, then texture decoding's
};

Result<LoadedScene> loadFrontendScene(const std::string& scenePath, const std::string& modelsDir);

}  // namespace thinlod::frontend::daemon
