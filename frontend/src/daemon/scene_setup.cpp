#include "scene_setup.h"

#include <utility>

#include "thinlod/common/scene_parser.h"
#include "thinlod/common/scene_render.h"

namespace thinlod::frontend::daemon {

Result<LoadedScene> loadFrontendScene(const std::string& scenePath, const std::string& modelsDir) {
  scene::SceneLoadOptions loadOptions;
  if (!modelsDir.empty()) loadOptions.meshSearchPaths.push_back(modelsDir);
  Result<scene::Scene> parsed = scene::loadSceneFile(scenePath, loadOptions);
  if (!parsed.ok()) return parsed.status();

  LoadedScene loaded;
  loaded.scene = std::make_unique<scene::Scene>(std::move(parsed).value());
  Result<std::vector<scene::SceneObject>> objects = scene::collectSceneObjects(*loaded.scene);
  if (!objects.ok()) {
    return Status(objects.status().code(), scenePath + ": " + objects.status().message());
  }
  loaded.objects = std::move(objects).value();
  loaded.lighting = scene::sceneLighting(*loaded.scene, &loaded.droppedLights);
  for (const scene::SceneObject& object : loaded.objects) {
    const render::Material material = scene::shapeMaterial(*object.shape);
    loaded.meshColors[object.id] = material.diffuse;
    if (!material.lit) ++loaded.unlitObjects;
    ReferenceItem item;
    item.object.mesh = object.fullMesh;
    item.object.material = material;
    item.object.transform = object.objectToWorld;
    item.worldCentre = object.worldBounds.center();
    item.blended = material.alphaMode == render::AlphaMode::kBlend;
    loaded.referenceTriangles += object.fullMesh != nullptr ? object.fullMesh->triangleCount() : 0;
    loaded.reference.push_back(std::move(item));
  }
  return loaded;
}

}  // namespace thinlod::frontend::daemon
