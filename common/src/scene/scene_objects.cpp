#include "thinlod/common/scene/scene_objects.h"

#include <glm/geometric.hpp>

#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/mesh/primitives.h"

namespace thinlod::scene {
namespace {

Result<std::shared_ptr<const IndexedMesh>> shapeMesh(const ShapeNode& shape,
                                                     const SceneObjectOptions& options) {
  const Geometry& geometry = shape.geometry;
  switch (geometry.kind) {
    case GeometryKind::kNone:
      return std::shared_ptr<const IndexedMesh>();
    case GeometryKind::kMeshFile:
    case GeometryKind::kIndexedFaceSet:
      if (!geometry.mesh) {
        const std::string url = geometry.urls.empty() ? std::string("?") : geometry.urls.front();
        return Status(ErrorCode::kNotFound,
                      "Shape " + std::to_string(shape.id) + ": mesh '" + url + "' is not loaded");
      }
      return geometry.mesh;
    case GeometryKind::kPrimitive: {
      THINLOD_RETURN_IF_ERROR(validatePrimitive(geometry.primitive));
      const TessellationParams params =
          chooseTessellation(geometry.primitive, options.primitiveTriangles);
      return std::shared_ptr<const IndexedMesh>(
          std::make_shared<IndexedMesh>(tessellate(geometry.primitive, params)));
    }
  }
  return Status(ErrorCode::kInternal, "unknown geometry kind");
}

}  // namespace

Result<std::vector<SceneObject>> collectSceneObjects(const Scene& scene,
                                                     const SceneObjectOptions& options) {
  std::vector<SceneObject> objects;
  const std::vector<NodeInstance> instances = flattenInstances(scene);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const ShapeNode* shape = instances[i].node->as<ShapeNode>();
    if (shape == nullptr) continue;
    Result<std::shared_ptr<const IndexedMesh>> mesh = shapeMesh(*shape, options);
    if (!mesh.ok()) return mesh.status();
    if (!*mesh || (*mesh)->triangleCount() == 0) continue;
    SceneObject object;
    object.id = objects.size() + 1;
    object.shape = shape;
    object.instance = static_cast<int>(i);
    object.objectToWorld = instances[i].contentToWorld;
    object.fullMesh = *mesh;
    IndexedMesh world;
    world.positions.reserve((*mesh)->positions.size());
    for (const glm::vec3& p : (*mesh)->positions) {
      world.positions.push_back(glm::vec3(object.objectToWorld * glm::vec4(p, 1.0f)));
    }
    object.worldBounds = world.bounds();
    object.contentSphere = shape->geometry.kind == GeometryKind::kPrimitive
                               ? primitiveReferenceSphere(shape->geometry.primitive)
                               : referenceSphere(**mesh);
    if (const SkinnedAnimation* animation = shape->geometry.animation.get()) {
      // The deformed mesh stays within motionBound of the stored one.
      const auto reach = static_cast<float>(animation->motionBound);
      object.contentSphere.radius += reach;
      const glm::vec3 grow(reach * maxScale(object.objectToWorld));
      object.worldBounds.extend(object.worldBounds.min - grow);
      object.worldBounds.extend(object.worldBounds.max + grow);
    }
    object.worldSphere = mapReferenceSphere(object.contentSphere, object.objectToWorld,
                                            maxScale(object.objectToWorld));
    objects.push_back(std::move(object));
  }
  return objects;
}

const SceneObject* findSceneObject(const std::vector<SceneObject>& objects, std::uint64_t id) {
  if (id == 0 || id > objects.size()) return nullptr;
  return &objects[id - 1];
}

}  // namespace thinlod::scene
