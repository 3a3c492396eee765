#include "thinlod/common/scene/scene_objects.h"

#include <glm/geometric.hpp>
#include <map>

#include "thinlod/common/core/relative_accuracy.h"
#include "thinlod/common/mesh/mesh_regions.h"
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

SceneObject makeObject(std::uint64_t id, const ShapeNode& shape, int instance,
                       const glm::mat4& objectToWorld, std::shared_ptr<const IndexedMesh> mesh) {
  SceneObject object;
  object.id = id;
  object.shape = &shape;
  object.instance = instance;
  object.objectToWorld = objectToWorld;
  object.fullMesh = std::move(mesh);
  IndexedMesh world;
  world.positions.reserve(object.fullMesh->positions.size());
  for (const glm::vec3& p : object.fullMesh->positions) {
    world.positions.push_back(glm::vec3(object.objectToWorld * glm::vec4(p, 1.0f)));
  }
  object.worldBounds = world.bounds();
  object.contentSphere = shape.geometry.kind == GeometryKind::kPrimitive
                             ? primitiveReferenceSphere(shape.geometry.primitive)
                             : referenceSphere(*object.fullMesh);
  if (const SkinnedAnimation* animation = shape.geometry.animation.get()) {
    // The deformed mesh stays within motionBound of the stored one.
    const auto reach = static_cast<float>(animation->motionBound);
    object.contentSphere.radius += reach;
    const glm::vec3 grow(reach * maxScale(object.objectToWorld));
    object.worldBounds.extend(object.worldBounds.min - grow);
    object.worldBounds.extend(object.worldBounds.max + grow);
  }
  object.worldSphere = mapReferenceSphere(object.contentSphere, object.objectToWorld,
                                          maxScale(object.objectToWorld));
  return object;
}

using RegionCache = std::map<const ShapeNode*, std::vector<std::shared_ptr<const IndexedMesh>>>;

// The region submeshes of a Shape with `regions N`, split once per Shape
// (a Shape USEd twice shares them, as it shares its mesh).
Result<const std::vector<std::shared_ptr<const IndexedMesh>>*> regionMeshes(const Scene& scene,
                                                                            const ShapeNode& shape,
                                                                            const IndexedMesh& mesh,
                                                                            RegionCache& cache) {
  auto found = cache.find(&shape);
  if (found != cache.end()) return &found->second;
  Result<std::vector<MeshRegion>> split = splitMeshIntoRegions(mesh, shape.geometry.regionCount);
  if (!split.ok()) {
    return Status(split.status().code(), scene.sourceName + ":" +
                                             std::to_string(shape.sourceLocation.line) + ":" +
                                             std::to_string(shape.sourceLocation.column) +
                                             ": Inline " + split.status().message());
  }
  std::vector<std::shared_ptr<const IndexedMesh>> meshes;
  for (MeshRegion& region : *split)
    meshes.push_back(std::make_shared<const IndexedMesh>(std::move(region.mesh)));
  return &cache.emplace(&shape, std::move(meshes)).first->second;
}

}  // namespace

Result<std::vector<SceneObject>> collectSceneObjects(const Scene& scene,
                                                     const SceneObjectOptions& options) {
  std::vector<SceneObject> objects;
  RegionCache regionCache;
  const std::vector<NodeInstance> instances = flattenInstances(scene);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const ShapeNode* shape = instances[i].node->as<ShapeNode>();
    if (shape == nullptr) continue;
    Result<std::shared_ptr<const IndexedMesh>> mesh = shapeMesh(*shape, options);
    if (!mesh.ok()) return mesh.status();
    if (!*mesh || (*mesh)->triangleCount() == 0) continue;
    const Geometry& g = shape->geometry;
    if (g.kind == GeometryKind::kMeshFile && g.regionCount >= 2 && !g.animation) {
      auto parts = regionMeshes(scene, *shape, **mesh, regionCache);
      if (!parts.ok()) return parts.status();
      for (std::size_t r = 0; r < (*parts)->size(); ++r) {
        objects.push_back(makeObject(objects.size() + 1, *shape, static_cast<int>(i),
                                     instances[i].contentToWorld, (**parts)[r]));
        objects.back().region = static_cast<std::uint32_t>(r);
        objects.back().regionCount = static_cast<std::uint32_t>((*parts)->size());
      }
      continue;
    }
    objects.push_back(makeObject(objects.size() + 1, *shape, static_cast<int>(i),
                                 instances[i].contentToWorld, *mesh));
  }
  return objects;
}

bool isTextured(const SceneObject& object) {
  return object.shape != nullptr && object.fullMesh != nullptr && !object.fullMesh->uvs.empty() &&
         !object.shape->appearance.texturePath.empty();
}

const SceneObject* findSceneObject(const std::vector<SceneObject>& objects, std::uint64_t id) {
  if (id == 0 || id > objects.size()) return nullptr;
  return &objects[id - 1];
}

}  // namespace thinlod::scene
