#include "scene_setup.h"

#include <map>
#include <utility>

#include "thinlod/common/codec/encoding.h"
#include "thinlod/common/scene/scene_parser.h"
#include "thinlod/common/scene_render/scene_render.h"

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
  loaded.warnings = loaded.scene->warnings;
  // Scene textures for the reference, decoded once per file; one that fails
  // is a warning and its shapes are drawn untextured.
  std::map<std::string, std::shared_ptr<const RgbaImage>> textures;
  auto textureOf = [&](const std::string& path) -> std::shared_ptr<const RgbaImage> {
    if (path.empty()) return nullptr;
    const auto known = textures.find(path);
    if (known != textures.end()) return known->second;
    std::shared_ptr<const RgbaImage> image;
    Result<RgbaImage> decoded = codec::readImageFile(path);
    if (decoded.ok()) {
      image = std::make_shared<const RgbaImage>(std::move(decoded).value());
      ++loaded.textures;
    } else {
      loaded.warnings.push_back(decoded.status().message() + "; drawn untextured");
    }
    textures.emplace(path, image);
    return image;
  };
  // Position of each instance among its parent's children (pre-order lists
  // a parent's children in order), to tell an LOD's first level from the others.
  const std::vector<scene::NodeInstance> instances = scene::flattenInstances(*loaded.scene);
  std::vector<std::size_t> childIndex(instances.size(), 0);
  std::vector<std::size_t> childrenSeen(instances.size(), 0);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    if (instances[i].parent >= 0) {
      childIndex[i] = childrenSeen[static_cast<std::size_t>(instances[i].parent)]++;
    }
  }
  // Groups of LOD objects are numbered above every object id.
  const std::uint64_t lodGroupBase = std::uint64_t{1} << 40;
  for (const scene::SceneObject& object : loaded.objects) {
    bool laterLevel = false;
    int outermostLod = -1;
    for (int node = object.instance; node >= 0 && instances[node].parent >= 0;
         node = instances[node].parent) {
      const int parent = instances[node].parent;
      if (instances[parent].node->kind == scene::NodeKind::kLod) {
        outermostLod = parent;
        if (childIndex[node] != 0) laterLevel = true;
      }
    }
    ObjectExtent extent;
    extent.id = object.id;
    extent.group =
        outermostLod >= 0 ? lodGroupBase + static_cast<std::uint64_t>(outermostLod) : object.id;
    loaded.extents.push_back(extent);
    if (laterLevel) {
      ++loaded.laterLodLevelObjects;
      const render::Material material = scene::shapeMaterial(*object.shape);
      loaded.meshColors[object.id] = material.diffuse;
      continue;
    }
    const render::Material material = scene::shapeMaterial(*object.shape);
    loaded.meshColors[object.id] = material.diffuse;
    if (!material.lit) ++loaded.unlitObjects;
    ReferenceItem item;
    item.object.mesh = object.fullMesh;
    item.object.material = material;
    item.object.texture = textureOf(object.shape->appearance.texturePath);
    item.object.transform = object.objectToWorld;
    if (const auto& animation = object.shape->geometry.animation) {
      item.animation = animation.get();
      item.animationOffset = object.shape->geometry.animationOffset;
      // The palette skin, kept alive by the scene's animation.
      item.object.skin =
          std::shared_ptr<const std::vector<anim::VertexSkin>>(animation, &animation->palette.skin);
    }
    item.worldCentre = object.worldBounds.center();
    item.blended = material.alphaMode == render::AlphaMode::kBlend;
    item.extent = loaded.extents.size() - 1;
    loaded.referenceTriangles += object.fullMesh != nullptr ? object.fullMesh->triangleCount() : 0;
    loaded.reference.push_back(std::move(item));
  }
  return loaded;
}

}  // namespace thinlod::frontend::daemon
